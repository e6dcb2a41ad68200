//! Tests of the exporters: files written, panels, legends and axes as drawn.

use std::path::Path;

use tempfile::TempDir;

use super::canvas::{Drawn, PanelSpec};
use super::creep::{creep_panels, draw_creep_curves};
use super::facet::tests::alloy617;
use super::geom::{plottable, within};
use super::profile::draw_profile;
use super::residuals::{curve_residual_panels, draw_residuals};
use super::style::{Dash, MarkerShape, Swatch};
use super::sweep::{counts_note, draw_parameters, draw_waterfall};
use super::ticks::{label_format, label_value};
use super::xy::{draw_xy, xy_panel};
use super::*;
use crate::error::Error;

const PNG_SIGNATURE: [u8; 8] = [0x89, b'P', b'N', b'G', 0x0D, 0x0A, 0x1A, 0x0A];

fn assert_png(path: &Path) {
    let bytes = std::fs::read(path).expect("plot written");
    assert_eq!(
        &bytes[..8],
        &PNG_SIGNATURE,
        "{} is not a PNG",
        path.display()
    );
    assert!(
        bytes.len() > 10_000,
        "{} is only {} bytes",
        path.display(),
        bytes.len()
    );
}

/// A KHD-like creep curve: primary, secondary and tertiary creep up to rupture at `tf`.
fn creep_curve(tf: f64, eps_f: f64, n: usize) -> Vec<(f64, f64)> {
    (0..=n)
        .map(|i| {
            let t = tf * i as f64 / n as f64;
            let x = t / tf;
            let strain =
                eps_f * (0.15 * (1.0 - (-20.0 * x).exp()) + 0.35 * x) + eps_f * 0.5 * x.powi(8);
            (t, strain)
        })
        .collect()
}

fn id(t: f64, s: f64, sp: Option<&str>) -> CurveId {
    CurveId {
        temperature_c: t,
        stress_mpa: s,
        specimen: sp.map(str::to_string),
    }
}

fn example_curves() -> Vec<CurvePlot> {
    [
        (100.0, 9000.0, 12.0),
        (120.0, 3500.0, 14.0),
        (140.0, 1200.0, 16.0),
        (160.0, 450.0, 18.0),
    ]
    .iter()
    .map(|&(stress, tf, eps_f)| CurvePlot {
        id: id(550.0, stress, None),
        measured: creep_curve(tf * 1.05, eps_f * 0.95, 25)
            .into_iter()
            .skip(1)
            .collect(),
        predicted: creep_curve(tf, eps_f, 400),
    })
    .collect()
}

/// The 34 Alloy 617 tests with made-up curves: life falling with stress and temperature.
fn alloy617_curves() -> Vec<CurvePlot> {
    alloy617()
        .into_iter()
        .map(|id| {
            let tf =
                1e4 * (40.0 / id.stress_mpa).powi(4) * (-(id.temperature_c - 850.0) / 60.0).exp();
            CurvePlot {
                measured: creep_curve(tf, 30.0, 300),
                predicted: creep_curve(tf * 0.8, 25.0, 200),
                id,
            }
        })
        .collect()
}

/// Every plottable point of every layer lies inside its panel's axes.
fn axes_cover_every_layer(p: &PanelSpec) {
    for l in &p.layers {
        for &q in l.line.iter().chain(&l.points).filter(|q| plottable(**q)) {
            assert!(
                within(q, p.x.range, p.y.range),
                "{}: {q:?} outside {:?} × {:?}",
                p.caption,
                p.x.range,
                p.y.range
            );
        }
    }
}

/// The drawn legend of each panel is its whole entry list; each legend box lies beside its
/// chart (right of it) and inside the image.
fn legends_complete_and_beside(d: &Drawn, panels: &[PanelSpec]) {
    assert_eq!(d.panels.len(), panels.len());
    for (dp, p) in d.panels.iter().zip(panels) {
        let want: Vec<String> = p.entries.iter().map(|e| e.label.clone()).collect();
        assert_eq!(dp.legend, want, "{}", p.caption);
        if let Some(((lx0, lx1), (ly0, ly1))) = dp.legend_px {
            let ((_, px1), (py0, _)) = dp.plot_px;
            assert!(
                lx0 >= px1,
                "legend {:?} overlaps the chart {:?}",
                dp.legend_px,
                dp.plot_px
            );
            assert!(ly0 >= py0 - 40, "{:?}", dp.legend_px);
            assert!(
                lx1 <= d.size.0 as i32 && ly1 <= d.size.1 as i32,
                "{:?} in {:?}",
                dp.legend_px,
                d.size
            );
        }
        assert!(
            dp.x_labels.len() >= 2 || p.no_data,
            "{}: {:?}",
            p.caption,
            dp.x_labels
        );
        assert!(
            dp.y_labels.len() >= 2 || p.no_data,
            "{}: {:?}",
            p.caption,
            dp.y_labels
        );
        for labels in [&dp.x_labels, &dp.y_labels] {
            let formats: Vec<_> = labels.iter().filter_map(|l| label_format(l)).collect();
            assert!(
                formats.windows(2).all(|w| w[0] == w[1]),
                "mixed formats {labels:?}"
            );
        }
    }
}

#[test]
fn creep_curves_png_with_text() {
    let dir = TempDir::new().unwrap();
    let curves = example_curves();
    let with_title = dir.path().join("curves.png");
    let without_title = dir.path().join("curves_untitled.png");
    plot_creep_curves(&with_title, "Creep curves at 550 °C", &curves).unwrap();
    plot_creep_curves(&without_title, "", &curves).unwrap();
    assert_png(&with_title);
    assert_png(&without_title);
    // The title is rendered text, so the images must differ.
    assert_ne!(
        std::fs::read(&with_title).unwrap(),
        std::fs::read(&without_title).unwrap()
    );
    let other = dir.path().join("curves_other.png");
    plot_creep_curves(&other, "Creep curves at 600 °C", &curves).unwrap();
    assert_ne!(
        std::fs::read(&with_title).unwrap(),
        std::fs::read(&other).unwrap()
    );
}

#[test]
fn thirty_four_curves_in_panels_with_complete_legends() {
    let curves = alloy617_curves();
    let panels = creep_panels(&curves);
    assert_eq!(panels.len(), 8);
    // Every test named exactly once, with temperature, stress and specimen.
    let mut named: Vec<String> = panels
        .iter()
        .flat_map(|p| p.entries.iter().map(|e| e.label.clone()))
        .filter(|l| l.contains("MPa"))
        .collect();
    named.sort();
    let mut want: Vec<String> = curves.iter().map(|c| c.id.label()).collect();
    want.sort();
    assert_eq!(named, want);
    assert!(want.contains(&"850 °C, 30 MPa, KAERI2-a".to_string()));
    for p in &panels {
        axes_cover_every_layer(p);
        // Distinct colours within a panel.
        let colors: Vec<Rgb> = p
            .entries
            .iter()
            .filter(|e| e.label.contains("MPa"))
            .map(|e| match e.swatch {
                Swatch::Style(s) => s.color,
                _ => panic!("a curve's swatch is its style"),
            })
            .collect();
        for (i, c) in colors.iter().enumerate() {
            assert!(
                !colors[i + 1..].contains(c),
                "{}: colour repeats",
                p.caption
            );
        }
        // The style keys: points for measured, a line for predicted.
        let measured = p.entries.iter().find(|e| e.label == "measured").unwrap();
        let Swatch::Style(s) = measured.swatch else {
            panic!()
        };
        assert!(s.line.is_none() && s.marker.is_some());
        let predicted = p.entries.iter().find(|e| e.label == "predicted").unwrap();
        let Swatch::Style(s) = predicted.swatch else {
            panic!()
        };
        assert!(s.line.is_some() && s.marker.is_none());
    }
    let dir = TempDir::new().unwrap();
    let path = dir.path().join("fit.png");
    let d = draw_creep_curves(&path, "34 curves", &curves).unwrap();
    assert_png(&path);
    legends_complete_and_beside(&d, &panels);
    assert_eq!(d.size, (2 * PANEL_WIDTH, 50 + 4 * PANEL_HEIGHT));
}

#[test]
fn predictions_past_the_data_are_inside_the_axes_or_cut_and_marked() {
    let measured = creep_curve(1000.0, 20.0, 50);
    // Ruptures at twice the measured life: drawn whole, the axis reaches its rupture.
    let late = CurvePlot {
        id: id(600.0, 100.0, Some("A")),
        measured: measured.clone(),
        predicted: creep_curve(2000.0, 25.0, 200),
    };
    let p = &creep_panels(std::slice::from_ref(&late))[0];
    axes_cover_every_layer(p);
    assert!(p.x.range.1 >= 2000.0, "{:?}", p.x.range);
    assert!(!p.entries.iter().any(|e| e.label.contains("cut")));
    // Runs away to 100× the measured life: cut at 3× and marked with an arrow and an entry.
    let runaway = CurvePlot {
        predicted: creep_curve(1e5, 25.0, 2000),
        ..late
    };
    let p = &creep_panels(&[runaway])[0];
    axes_cover_every_layer(p);
    assert!(
        p.x.range.1 >= 3000.0 && p.x.range.1 < 3200.0,
        "{:?}",
        p.x.range
    );
    let arrow = p
        .layers
        .iter()
        .find(|l| {
            l.style
                .marker
                .is_some_and(|m| m.shape == MarkerShape::Arrow)
        })
        .expect("an arrow marks the cut");
    assert!(
        (arrow.points[0].0 - 3000.0).abs() < 1e-6,
        "{:?}",
        arrow.points
    );
    let key = p.entries.iter().find(|e| e.label.contains("cut")).unwrap();
    assert!(
        matches!(key.swatch, Swatch::Style(s) if s.marker.is_some_and(|m| m.shape == MarkerShape::Arrow))
    );
}

#[test]
fn residuals_png() {
    let dir = TempDir::new().unwrap();
    let series: Vec<Series> = (0..4)
        .map(|k| Series {
            label: format!("{} MPa", 100 + 20 * k),
            points: (0..40)
                .map(|i| {
                    let x = i as f64 / 39.0;
                    (
                        x,
                        0.05 * ((k as f64 + 1.0) * 6.0 * x).sin() + 0.01 * k as f64,
                    )
                })
                .collect(),
        })
        .collect();
    let path = dir.path().join("residuals.png");
    plot_residuals(
        &path,
        "Residuals",
        &series,
        "life fraction t/t_f",
        "residual",
    )
    .unwrap();
    assert_png(&path);
}

#[test]
fn curve_residuals_of_34_curves_in_panels() {
    let series: Vec<CurveSeries> = alloy617()
        .into_iter()
        .enumerate()
        .map(|(k, id)| CurveSeries {
            id,
            points: (0..60)
                .map(|i| {
                    let x = i as f64 / 59.0;
                    (x, 10.0 * (k as f64 + 1.0) * (3.0 * x).sin())
                })
                .collect(),
        })
        .collect();
    let panels = curve_residual_panels(&series, "t / t_f", "predicted − measured");
    assert_eq!(panels.len(), 8);
    let mut named: Vec<String> = panels
        .iter()
        .flat_map(|p| p.entries.iter().map(|e| e.label.clone()))
        .collect();
    named.sort();
    let mut want: Vec<String> = series.iter().map(|s| s.id.label()).collect();
    want.sort();
    assert_eq!(named, want);
    for p in &panels {
        axes_cover_every_layer(p);
        assert!(p.y.range.0 <= 0.0 && p.y.range.1 >= 0.0);
    }
    let dir = TempDir::new().unwrap();
    let path = dir.path().join("residuals_base.png");
    plot_curve_residuals(
        &path,
        "residuals",
        &series,
        "t / t_f",
        "predicted − measured",
    )
    .unwrap();
    assert_png(&path);
}

#[test]
fn waterfall_png() {
    let dir = TempDir::new().unwrap();
    let objectives: Vec<f64> = (0..64)
        .map(|i| 1e-3 * (1.0 + (i as f64 / 8.0).powi(3)))
        .collect();
    let path = dir.path().join("waterfall.png");
    plot_waterfall(&path, "Multistart objectives", &objectives).unwrap();
    assert_png(&path);
}

#[test]
fn parameters_png() {
    let dir = TempDir::new().unwrap();
    let names: Vec<String> = ["A", "B", "h", "H*", "Kc", "C", "D"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    let solutions: Vec<Vec<f64>> = (0..10)
        .map(|r| {
            (0..names.len())
                .map(|j| {
                    (0.2 + 0.08 * j as f64 + 0.03 * r as f64 * ((j + r) as f64).sin())
                        .clamp(0.0, 1.0)
                })
                .collect()
        })
        .collect();
    let path = dir.path().join("parameters.png");
    plot_parameters(&path, "Best 10 solutions within bounds", &names, &solutions).unwrap();
    assert_png(&path);
}

fn good_profile() -> ProfilePlot {
    ProfilePlot {
        x_label: "log10 A (A in 1/h)".into(),
        points: (0..12)
            .map(|i| (-10.0 + 0.1 * i as f64, (0.3 * i as f64 - 1.5).powi(2)))
            .collect(),
        failed: vec![],
        estimate: -9.5,
        bounds: (-10.0, -9.0),
        thresholds: vec![("68 %".into(), 1.0), ("95 %".into(), 3.84)],
    }
}

#[test]
fn profile_png_and_degenerate_profiles() {
    let dir = TempDir::new().unwrap();
    let good = good_profile();
    let path = dir.path().join("profile_A.png");
    plot_profile(&path, "A", &good).unwrap();
    assert_png(&path);
    for (k, bad) in [
        ProfilePlot::default(),
        ProfilePlot {
            points: vec![(f64::NAN, 1.0), (1.0, f64::INFINITY)],
            estimate: f64::NAN,
            failed: vec![f64::NAN, 2.0],
            bounds: (f64::NEG_INFINITY, f64::NAN),
            ..good.clone()
        },
        ProfilePlot {
            points: vec![(3.0, 0.0); 5],
            estimate: 3.0,
            ..good.clone()
        },
    ]
    .iter()
    .enumerate()
    {
        let path = dir.path().join(format!("bad{k}.png"));
        plot_profile(&path, "degenerate", bad).unwrap();
        assert_png(&path);
    }
}

#[test]
fn degenerate_inputs_do_not_panic() {
    let dir = TempDir::new().unwrap();
    let p = |name: &str| dir.path().join(format!("{name}.png"));
    let nan = f64::NAN;
    let inf = f64::INFINITY;
    let c = |label: &str, measured: Vec<(f64, f64)>, predicted: Vec<(f64, f64)>| CurvePlot {
        id: id(500.0, 100.0, Some(label)),
        measured,
        predicted,
    };

    // Creep curves.
    let cases: Vec<Vec<CurvePlot>> = vec![
        vec![],
        vec![CurvePlot::default()],
        vec![c("one", vec![(1.0, 1.0)], vec![(1.0, 1.0)])],
        vec![c("flat", vec![(5.0, 2.0); 4], vec![(5.0, 2.0); 10])],
        vec![c(
            "nan",
            vec![(nan, 1.0), (1.0, inf), (2.0, 1.0), (-inf, nan)],
            vec![(0.0, 0.0), (nan, nan), (1.0, 1.0), (2.0, 1e300), (3.0, 2.0)],
        )],
        vec![c(
            "all nan",
            vec![(nan, nan)],
            vec![(inf, -inf), (nan, 0.0)],
        )],
        vec![c(
            "runaway",
            vec![(0.0, 0.0), (10.0, 1.0)],
            vec![(0.0, 0.0), (10.0, 1.0), (10.5, 1e9), (1e12, 1e12)],
        )],
        vec![c("negative", vec![(-1.0, -2.0), (1.0, -1.0)], vec![])],
        vec![c(
            "zero strain",
            vec![(0.0, 0.0), (1.0, 0.0)],
            vec![(0.0, 0.0), (2.0, 1.0)],
        )],
        (0..25)
            .map(|i| CurvePlot {
                id: id(500.0 + (i % 3) as f64, i as f64, None),
                measured: vec![(i as f64, 1e-20 * i as f64)],
                predicted: vec![],
            })
            .collect(),
    ];
    for (i, curves) in cases.iter().enumerate() {
        plot_creep_curves(&p(&format!("creep{i}")), "degenerate", curves)
            .unwrap_or_else(|e| panic!("creep case {i}: {e}"));
        for panel in creep_panels(curves) {
            axes_cover_every_layer(&panel);
        }
    }

    // Residuals.
    let cases: Vec<Vec<Series>> = vec![
        vec![],
        vec![Series::default()],
        vec![Series {
            label: "one".into(),
            points: vec![(0.5, 0.0)],
        }],
        vec![Series {
            label: "flat".into(),
            points: vec![(0.5, 3.0); 5],
        }],
        vec![Series {
            label: "nan".into(),
            points: vec![(nan, 1.0), (0.2, inf), (0.4, -0.1), (0.6, 0.2), (inf, inf)],
        }],
    ];
    for (i, series) in cases.iter().enumerate() {
        plot_residuals(&p(&format!("res{i}")), "", series, "x", "y")
            .unwrap_or_else(|e| panic!("residual case {i}: {e}"));
    }
    plot_curve_residuals(&p("curve_res_empty"), "", &[], "x", "y").unwrap();

    // Waterfall.
    let cases: Vec<Vec<f64>> = vec![
        vec![],
        vec![1.0],
        vec![0.0],
        vec![-1.0, 0.0],
        vec![2.0; 10],
        vec![nan, inf, -inf],
        vec![0.0, 1e-300, 1e-5, 1.0, 1e300, nan, f64::MAX],
        (0..5000).map(|i| 1.0 + i as f64).collect(),
    ];
    for (i, objectives) in cases.iter().enumerate() {
        plot_waterfall(&p(&format!("water{i}")), "w", objectives)
            .unwrap_or_else(|e| panic!("waterfall case {i}: {e}"));
    }

    // Parameters.
    let names = |n: usize| -> Vec<String> { (0..n).map(|i| format!("c{i}")).collect() };
    let cases: Vec<(Vec<String>, Vec<Vec<f64>>)> = vec![
        (vec![], vec![]),
        (names(3), vec![]),
        (vec![], vec![vec![]]),
        (names(1), vec![vec![0.5]]),
        (names(2), vec![vec![0.5, 0.5], vec![0.5, 0.5]]),
        (names(3), vec![vec![nan, -3.0, 7.0], vec![inf, 0.5, nan]]),
        (names(3), (0..200).map(|_| vec![0.0, 1.0, 0.5]).collect()),
    ];
    for (i, (names, sols)) in cases.iter().enumerate() {
        plot_parameters(&p(&format!("par{i}")), "p", names, sols)
            .unwrap_or_else(|e| panic!("parameter case {i}: {e}"));
    }
    // Mismatched lengths are the caller's error.
    let err = plot_parameters(&p("par_bad"), "p", &names(3), &[vec![0.5; 2]]).unwrap_err();
    assert!(matches!(err, Error::Invalid(_)), "{err}");

    // XY with nothing, with only non-positive values on log axes, with key-only groups.
    let axes = XyAxes {
        x_label: "x",
        y_label: "y",
        x_scale: AxisScale::Log,
        y_scale: AxisScale::Log,
    };
    for (i, groups) in [
        vec![],
        vec![XyGroup::points(
            "neg",
            vec![(-1.0, 0.0)],
            Rgb::BLACK,
            MarkerShape::Circle,
        )],
        vec![XyGroup::key("key", Rgb::BLACK, Some(Dash::Dashed), None)],
    ]
    .iter()
    .enumerate()
    {
        plot_xy(&p(&format!("xy{i}")), "", axes, groups)
            .unwrap_or_else(|e| panic!("xy case {i}: {e}"));
    }
}

#[test]
fn missing_directory_is_an_error() {
    let dir = TempDir::new().unwrap();
    let path = dir.path().join("no/such/dir/plot.png");
    let err = plot_creep_curves(&path, "t", &example_curves()).unwrap_err();
    assert!(matches!(err, Error::Plot { .. }), "{err}");
    assert!(err.to_string().starts_with("plot "), "{err}");
    assert!(plot_residuals(&path, "t", &[], "x", "y").is_err());
    assert!(plot_waterfall(&path, "t", &[1.0, 2.0]).is_err());
    assert!(plot_parameters(&path, "t", &["a".to_string()], &[vec![0.5]]).is_err());
    assert!(!path.exists());
}

#[test]
fn non_png_name_is_an_error() {
    let dir = TempDir::new().unwrap();
    let path = dir.path().join("plot.svg");
    assert!(matches!(
        plot_waterfall(&path, "t", &[1.0]),
        Err(Error::Plot { .. })
    ));
    assert!(!path.exists());
    let upper = dir.path().join("plot.PNG");
    plot_waterfall(&upper, "t", &[1.0, 2.0]).unwrap();
    assert!(upper.exists());
}

#[test]
fn waterfall_counts_add_up_and_a_narrow_log_axis_is_labelled() {
    // The 590 °C sweep's shape: 2211 fits, 11 of them failed (ranked last), two minima
    // 0.07 % apart; and the 560 °C one: minima 0.2527 and 0.3809.
    let mut obj: Vec<f64> = (0..2200)
        .map(|i| if i < 1100 { 1.125188 } else { 1.12596 })
        .collect();
    obj.extend([f64::NAN; 11]);
    let c = run_counts(&obj);
    assert_eq!((c.ran, c.finite, c.failed), (2211, 2200, 11));
    assert_eq!(
        counts_note(c),
        "2211 fits ran: 2200 finite, 11 failed (no objective, not drawn)"
    );
    let dir = TempDir::new().unwrap();
    let drawn = draw_waterfall(&dir.path().join("w590.png"), "590", &obj).unwrap();
    let panel = &drawn.panels[0];
    assert!(panel.y_labels.len() >= 2, "{:?}", panel.y_labels);
    let obj560: Vec<f64> = (0..610)
        .map(|i| if i < 251 { 0.252655 } else { 0.38094 })
        .collect();
    let drawn = draw_waterfall(&dir.path().join("w560.png"), "560", &obj560).unwrap();
    let panel = &drawn.panels[0];
    assert!(panel.y_labels.len() >= 3, "{:?}", panel.y_labels);
    assert!(
        panel.y_labels.contains(&"0.25".to_string()),
        "{:?}",
        panel.y_labels
    );
    assert!(
        panel.y_labels.contains(&"0.40".to_string()),
        "{:?}",
        panel.y_labels
    );
    assert!(panel.x_labels.len() >= 2, "{:?}", panel.x_labels);
    assert_eq!(
        counts_note(run_counts(&obj560)),
        "610 fits ran: 610 finite, 0 failed"
    );
}

#[test]
fn every_plot_labels_both_axes_and_keeps_its_legend_outside_the_data() {
    let dir = TempDir::new().unwrap();
    let p = |n: &str| dir.path().join(format!("{n}.png"));
    let narrow: Vec<Series> = (0..3)
        .map(|k| Series {
            label: format!("{} MPa", 85 + 10 * k),
            points: (0..30)
                .map(|i| (i as f64 / 29.0, 1e-7 * ((i + k) as f64).sin()))
                .collect(),
        })
        .collect();
    let drawings = [
        (
            "creep",
            draw_creep_curves(&p("creep"), "t", &example_curves()).unwrap(),
        ),
        (
            "residuals",
            draw_residuals(&p("res"), "t", &narrow, "t / t_f", "predicted − measured").unwrap(),
        ),
        (
            "waterfall",
            draw_waterfall(&p("water"), "t", &[1e-3, 2e-3, 5e-1, f64::NAN]).unwrap(),
        ),
        (
            "profile",
            draw_profile(&p("prof"), "t", &good_profile()).unwrap(),
        ),
        (
            "parameters",
            draw_parameters(
                &p("par"),
                "t",
                &["A".to_string(), "B".to_string()],
                &[vec![0.2, 0.9], vec![0.3, 0.8], vec![0.5, 0.5]],
            )
            .unwrap(),
        ),
    ];
    for (what, d) in &drawings {
        assert_eq!(d.panels.len(), 1, "{what}");
        let panel = &d.panels[0];
        assert!(
            panel.x_labels.len() >= 2,
            "{what}: x labels {:?}",
            panel.x_labels
        );
        assert!(
            panel.y_labels.len() >= 2,
            "{what}: y labels {:?}",
            panel.y_labels
        );
        let ((px0, px1), (py0, py1)) = panel.plot_px;
        assert!(
            px1 - px0 > 500 && py1 - py0 > 400,
            "{what}: plot area {:?}",
            panel.plot_px
        );
        let ((lx0, lx1), (ly0, ly1)) = panel.legend_px.expect("a legend");
        assert!(
            lx0 >= px1,
            "{what}: legend {:?} overlaps the plot {:?}",
            panel.legend_px,
            panel.plot_px
        );
        assert!(
            lx1 <= WIDTH as i32 && ly0 < ly1 && ly1 <= HEIGHT as i32,
            "{what}"
        );
    }
    // The narrow residual range (1e-7 wide) gets distinct labels, all powers of ten.
    let res = &drawings[1].1.panels[0];
    let mut labels = res.y_labels.clone();
    labels.dedup();
    assert_eq!(labels.len(), res.y_labels.len());
    assert!(
        res.y_labels
            .iter()
            .all(|l| l == "0" || l.contains("×10") || l.contains("10⁻")),
        "{:?}",
        res.y_labels
    );
}

#[test]
fn a_long_legend_is_never_cut() {
    // 40 labelled groups: the old legend stopped at "… and N more"; now the image grows.
    let groups: Vec<XyGroup> = (0..40)
        .map(|i| {
            XyGroup::points(
                format!("{} °C, {} MPa, specimen S{i}", 500 + 10 * (i / 5), 50 + i),
                vec![(i as f64 + 1.0, 1.0 + i as f64)],
                Rgb::palette(i),
                MarkerShape::Circle,
            )
        })
        .collect();
    let axes = XyAxes {
        x_label: "x",
        y_label: "y",
        x_scale: AxisScale::Linear,
        y_scale: AxisScale::Linear,
    };
    let dir = TempDir::new().unwrap();
    let d = draw_xy(&dir.path().join("many.png"), "many", axes, &groups).unwrap();
    let panel = xy_panel(axes, &groups);
    legends_complete_and_beside(&d, &[panel]);
    assert_eq!(d.panels[0].legend.len(), 40);
    assert!(d.size.1 > HEIGHT, "{:?}", d.size);
    let (_, (_, ly1)) = d.panels[0].legend_px.unwrap();
    assert!(ly1 <= d.size.1 as i32);
}

#[test]
fn xy_swatches_are_the_groups_styles_and_axes_cover_every_group() {
    // The stress–rupture look: measured points, a model line, a dashed baseline, and keys.
    let groups = vec![
        XyGroup::points(
            "750 °C",
            vec![(1500.0, 137.0), (7800.0, 95.0)],
            Rgb::palette(0),
            MarkerShape::Circle,
        ),
        XyGroup::line(
            "",
            vec![(800.0, 150.0), (12000.0, 85.0)],
            Rgb::palette(0),
            Dash::Solid,
        ),
        XyGroup::line(
            "",
            vec![(600.0, 150.0), (20000.0, 85.0)],
            Rgb::palette(0),
            Dash::Dashed,
        ),
        XyGroup::key("creepfit", Rgb::BLACK, Some(Dash::Solid), None),
        XyGroup::key("Larson–Miller", Rgb::BLACK, Some(Dash::Dashed), None),
        XyGroup::key("measured", Rgb::BLACK, None, Some(MarkerShape::Circle)),
    ];
    let axes = XyAxes {
        x_label: "rupture time (h)",
        y_label: "stress (MPa)",
        x_scale: AxisScale::Log,
        y_scale: AxisScale::Log,
    };
    let panel = xy_panel(axes, &groups);
    axes_cover_every_layer(&panel);
    // 20,000 h (log10 4.3) is inside the axes: no curve ends beyond them.
    assert!(panel.x.range.1 >= 20000f64.log10());
    let labels: Vec<&str> = panel.entries.iter().map(|e| e.label.as_str()).collect();
    assert_eq!(labels, ["750 °C", "creepfit", "Larson–Miller", "measured"]);
    let swatch = |label: &str| match panel
        .entries
        .iter()
        .find(|e| e.label == label)
        .unwrap()
        .swatch
    {
        Swatch::Style(s) => s,
        _ => panic!("{label}"),
    };
    assert_eq!(swatch("Larson–Miller").line.unwrap().dash, Dash::Dashed);
    assert_eq!(swatch("creepfit").line.unwrap().dash, Dash::Solid);
    assert!(swatch("measured").line.is_none());
    assert_eq!(
        swatch("measured").marker.unwrap().shape,
        MarkerShape::Circle
    );
    assert!(
        swatch("750 °C").line.is_none(),
        "a points group's swatch is a point"
    );
    // Tick labels state their values, one format per axis.
    for t in [&panel.x.ticks, &panel.y.ticks] {
        for (v, l) in t.values.iter().zip(&t.labels) {
            let parsed = label_value(l).unwrap();
            assert!((parsed.log10() - v).abs() < 1e-9, "{l} at {v}");
        }
    }
    let dir = TempDir::new().unwrap();
    let d = draw_xy(&dir.path().join("sr.png"), "sr", axes, &groups).unwrap();
    legends_complete_and_beside(&d, &[panel]);
}
