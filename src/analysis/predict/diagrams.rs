//! The diagrams a creep engineer reads first, drawn by `fit`, `predict` and `holdout` from a
//! calibrated model and the measured tests, one colour per temperature (cool to hot):
//! - `stress_rupture.png`: stress against rupture time, both log: measured points, the
//!   model's line, the Larson–Miller baseline dashed;
//! - `norton.png`: minimum creep rate against stress, both log (Norton plot): measured
//!   points, the model's line;
//! - `larson_miller.png` (needs the baseline, i.e. rupture tests at two or more
//!   temperatures): stress (log) against the Larson–Miller parameter: measured points, the
//!   model's line per temperature, the fitted master curve dashed.
//!
//! The model's lines are simulations at 40 stresses per temperature (evenly in log stress
//! over the tested and asked stresses there, widened by 10 %), to rupture within `predict`'s
//! horizon; a stress without rupture leaves a gap in the rupture-time line. Only PNGs are
//! written: no number of any output file changes.

use std::path::Path;

use super::{horizon, simulate_at};
use crate::config::RunConfig;
use crate::data::Condition;
use crate::data::Dataset;
use crate::lmp::{self, LarsonMiller};
use crate::model::Model;
use crate::report::plot::{
    plot_xy, temperature_colors, AxisScale, Dash, MarkerShape, Rgb, XyAxes, XyGroup,
};

/// The files [`Diagrams::write`] writes (`larson_miller.png` only with a baseline).
pub const FILES: [&str; 3] = ["stress_rupture.png", "norton.png", "larson_miller.png"];

/// A condition asked of `predict` with the model's prediction there (drawn as a triangle).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Asked {
    pub temperature_c: f64,
    pub stress_mpa: f64,
    /// h; NaN without rupture.
    pub rupture_time_h: f64,
    /// 1/h.
    pub min_rate: f64,
}

/// What the diagrams show.
pub struct Diagrams<'a> {
    /// The configuration (its name titles the plots; its integrator and ω_f simulate).
    pub cfg: &'a RunConfig,
    /// The measured tests drawn (and whose stresses span the model's lines).
    pub data: &'a Dataset,
    pub model: &'a dyn Model,
    pub params: &'a [f64],
    /// The Larson–Miller baseline, if there is one.
    pub lmp: Option<&'a LarsonMiller>,
    /// Conditions asked of `predict`.
    pub asked: &'a [Asked],
    /// The temperature left out of the fit (`holdout`): its tests drawn as open circles.
    pub held_out_c: Option<f64>,
}

/// The model at one temperature on a stress grid: (stress MPa, rupture time h or NaN,
/// minimum creep rate 1/h).
#[derive(Debug, Clone, PartialEq)]
pub struct ModelLine {
    pub temperature_c: f64,
    pub points: Vec<(f64, f64, f64)>,
}

/// 40 stresses evenly in log stress over [lo / 1.1, hi × 1.1], MPa.
pub fn stress_grid(lo: f64, hi: f64) -> Vec<f64> {
    let (a, b) = ((lo / 1.1).ln(), (hi * 1.1).ln());
    (0..40)
        .map(|i| (a + (b - a) * i as f64 / 39.0).exp())
        .collect()
}

impl Diagrams<'_> {
    /// The tested and asked temperatures, ascending, °C.
    pub fn temperatures(&self) -> Vec<f64> {
        let mut t: Vec<f64> = self
            .data
            .curves
            .iter()
            .map(|c| c.temperature_c)
            .chain(self.asked.iter().map(|a| a.temperature_c))
            .collect();
        t.sort_by(f64::total_cmp);
        t.dedup();
        t
    }

    /// The model's line at each temperature (simulated).
    pub fn model_lines(&self) -> Vec<ModelLine> {
        let ode = self.cfg.solver.ode_options();
        self.temperatures()
            .into_iter()
            .map(|t| {
                let (lo, hi) = self
                    .data
                    .curves
                    .iter()
                    .filter(|c| c.temperature_c == t)
                    .map(|c| c.stress_mpa)
                    .chain(
                        self.asked
                            .iter()
                            .filter(|a| a.temperature_c == t)
                            .map(|a| a.stress_mpa),
                    )
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), s| {
                        (a.min(s), b.max(s))
                    });
                let points = stress_grid(lo, hi)
                    .into_iter()
                    .map(|s| {
                        let l = self.lmp.map_or(f64::NAN, |l| l.rupture_time(t, s));
                        let c = Condition {
                            temperature_c: t,
                            stress_mpa: s,
                        };
                        let r = simulate_at(
                            self.model,
                            self.params,
                            c,
                            self.cfg.objective.omega_f,
                            &ode,
                            horizon(self.data, l),
                        );
                        let tr = if r.ruptured() { r.t_end } else { f64::NAN };
                        (s, tr, r.min_rate)
                    })
                    .collect();
                ModelLine {
                    temperature_c: t,
                    points,
                }
            })
            .collect()
    }

    /// Writes the diagrams into `out`; returns the plots that failed (their errors).
    pub fn write(&self, out: &Path) -> Vec<String> {
        let lines = self.model_lines();
        let name = &self.cfg.name;
        let mut failures = Vec::new();
        let mut draw = |file: &str, title: String, axes: XyAxes<'_>, groups: Vec<XyGroup>| {
            if let Err(e) = plot_xy(&out.join(file), &title, axes, &groups) {
                failures.push(e.to_string());
            }
        };
        draw(
            FILES[0],
            format!("{name} — stress–rupture"),
            XyAxes {
                x_label: "rupture time (h)",
                y_label: "stress (MPa)",
                x_scale: AxisScale::Log,
                y_scale: AxisScale::Log,
            },
            self.stress_rupture(&lines),
        );
        draw(
            FILES[1],
            format!("{name} — minimum creep rate against stress (Norton plot)"),
            XyAxes {
                x_label: "stress (MPa)",
                y_label: "minimum creep rate (%/h)",
                x_scale: AxisScale::Log,
                y_scale: AxisScale::Log,
            },
            self.norton(&lines),
        );
        if let Some(l) = self.lmp {
            let x_label = format!(
                "Larson–Miller parameter T·(C + log10 t_r), K (C = {:.2})",
                l.c
            );
            draw(
                FILES[2],
                format!("{name} — Larson–Miller master curve"),
                XyAxes {
                    x_label: &x_label,
                    y_label: "stress (MPa)",
                    x_scale: AxisScale::Linear,
                    y_scale: AxisScale::Log,
                },
                self.larson_miller(l, &lines),
            );
        }
        failures
    }

    /// Per temperature its colour and legend label ("850 °C", "850 °C (held out)").
    fn keyed_temperatures(&self, lines: &[ModelLine]) -> Vec<(f64, Rgb, String)> {
        let temps: Vec<f64> = lines.iter().map(|l| l.temperature_c).collect();
        temperature_colors(&temps)
            .into_iter()
            .zip(&temps)
            .map(|(c, &t)| {
                let label = if self.held_out_c == Some(t) {
                    format!("{t} °C (held out)")
                } else {
                    format!("{t} °C")
                };
                (t, c, label)
            })
            .collect()
    }

    /// The marker of the measured tests at `t`: open circles for the held-out temperature.
    fn measured_shape(&self, t: f64) -> MarkerShape {
        if self.held_out_c == Some(t) {
            MarkerShape::OpenCircle
        } else {
            MarkerShape::Circle
        }
    }

    /// The legend's key to the styles (black): measured, held out, model, asked.
    fn style_keys(&self, measured: &str) -> Vec<XyGroup> {
        let mut keys = vec![XyGroup::key(
            measured,
            Rgb::BLACK,
            None,
            Some(MarkerShape::Circle),
        )];
        if let Some(t) = self.held_out_c {
            keys.push(XyGroup::key(
                format!("measured at {t} °C, held out of the fit"),
                Rgb::BLACK,
                None,
                Some(MarkerShape::OpenCircle),
            ));
        }
        keys.push(XyGroup::key(
            "creepfit (model)",
            Rgb::BLACK,
            Some(Dash::Solid),
            None,
        ));
        if !self.asked.is_empty() {
            keys.push(XyGroup::key(
                "asked condition (creepfit)",
                Rgb::BLACK,
                None,
                Some(MarkerShape::Triangle),
            ));
        }
        keys
    }

    /// Colour keys of the temperatures: line and marker in the temperature's colour.
    fn temperature_keys(keyed: &[(f64, Rgb, String)]) -> Vec<XyGroup> {
        keyed
            .iter()
            .map(|(_, c, label)| {
                XyGroup::key(
                    label.clone(),
                    *c,
                    Some(Dash::Solid),
                    Some(MarkerShape::Circle),
                )
            })
            .collect()
    }

    /// Stress (y) against rupture time (x): measured, model, Larson–Miller dashed, asked.
    pub fn stress_rupture(&self, lines: &[ModelLine]) -> Vec<XyGroup> {
        let keyed = self.keyed_temperatures(lines);
        let mut groups = Vec::new();
        for ((t, color, _), line) in keyed.iter().zip(lines) {
            let (t, color) = (*t, *color);
            groups.push(XyGroup::line(
                "",
                line.points.iter().map(|&(s, tr, _)| (tr, s)).collect(),
                color,
                Dash::Solid,
            ));
            if let Some(l) = self.lmp {
                groups.push(XyGroup::line(
                    "",
                    line.points
                        .iter()
                        .map(|&(s, _, _)| (l.rupture_time(t, s), s))
                        .collect(),
                    color,
                    Dash::Dashed,
                ));
            }
            groups.push(XyGroup::points(
                "",
                self.data
                    .curves
                    .iter()
                    .filter(|c| c.temperature_c == t)
                    .filter_map(|c| c.rupture_time_h.map(|r| (r, c.stress_mpa)))
                    .collect(),
                color,
                self.measured_shape(t),
            ));
            groups.push(self.asked_at(t, color, |a| (a.rupture_time_h, a.stress_mpa)));
        }
        groups.extend(Self::temperature_keys(&keyed));
        groups.extend(self.style_keys("measured"));
        if let Some(l) = self.lmp {
            groups.push(XyGroup::key(
                format!("Larson–Miller baseline (C = {:.2})", l.c),
                Rgb::BLACK,
                Some(Dash::Dashed),
                None,
            ));
        }
        groups
    }

    /// Minimum creep rate (%/h, y) against stress (x): measured, model, asked.
    pub fn norton(&self, lines: &[ModelLine]) -> Vec<XyGroup> {
        let keyed = self.keyed_temperatures(lines);
        let mut groups = Vec::new();
        for ((t, color, _), line) in keyed.iter().zip(lines) {
            let (t, color) = (*t, *color);
            groups.push(XyGroup::line(
                "",
                line.points
                    .iter()
                    .map(|&(s, _, rate)| (s, 100.0 * rate))
                    .collect(),
                color,
                Dash::Solid,
            ));
            groups.push(XyGroup::points(
                "",
                self.data
                    .curves
                    .iter()
                    .filter(|c| c.temperature_c == t)
                    .map(|c| (c.stress_mpa, 100.0 * c.min_rate()))
                    .collect(),
                color,
                self.measured_shape(t),
            ));
            groups.push(self.asked_at(t, color, |a| (a.stress_mpa, 100.0 * a.min_rate)));
        }
        let given = self
            .data
            .curves
            .iter()
            .filter(|c| c.min_rate_measured.is_some())
            .count();
        let measured = if given == self.data.curves.len() {
            "measured"
        } else if given == 0 {
            "measured (estimated from the curve)"
        } else {
            "measured (or estimated from the curve)"
        };
        groups.extend(Self::temperature_keys(&keyed));
        groups.extend(self.style_keys(measured));
        groups
    }

    /// Stress (y) against the Larson–Miller parameter (x) with the baseline's C: measured,
    /// model per temperature, the master curve dashed, asked.
    pub fn larson_miller(&self, l: &LarsonMiller, lines: &[ModelLine]) -> Vec<XyGroup> {
        let keyed = self.keyed_temperatures(lines);
        let p = |t: f64, tr: f64| lmp::parameter(t, tr, l.c);
        let mut groups = Vec::new();
        for ((t, color, _), line) in keyed.iter().zip(lines) {
            let (t, color) = (*t, *color);
            groups.push(XyGroup::line(
                "",
                line.points
                    .iter()
                    .map(|&(s, tr, _)| (p(t, tr), s))
                    .collect(),
                color,
                Dash::Solid,
            ));
            groups.push(XyGroup::points(
                "",
                self.data
                    .curves
                    .iter()
                    .filter(|c| c.temperature_c == t)
                    .filter_map(|c| c.rupture_time_h.map(|r| (p(t, r), c.stress_mpa)))
                    .collect(),
                color,
                self.measured_shape(t),
            ));
            groups.push(self.asked_at(t, color, |a| (p(t, a.rupture_time_h), a.stress_mpa)));
        }
        let (s0, s1) = l.stress_range_mpa;
        groups.push(XyGroup::line(
            "",
            stress_grid(s0, s1)
                .into_iter()
                .map(|s| (l.lmp(s), s))
                .collect(),
            Rgb::BLACK,
            Dash::Dashed,
        ));
        groups.extend(Self::temperature_keys(&keyed));
        groups.extend(self.style_keys("measured"));
        groups.push(XyGroup::key(
            format!("Larson–Miller master curve (C = {:.2})", l.c),
            Rgb::BLACK,
            Some(Dash::Dashed),
            None,
        ));
        groups
    }

    /// The asked conditions at `t` as triangles at `at(asked)`.
    fn asked_at(&self, t: f64, color: Rgb, at: impl Fn(&Asked) -> (f64, f64)) -> XyGroup {
        XyGroup::points(
            "",
            self.asked
                .iter()
                .filter(|a| a.temperature_c == t)
                .map(at)
                .collect(),
            color,
            MarkerShape::Triangle,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::Overrides;
    use crate::data::ZERO_CELSIUS_K;

    /// The joint seed configuration (560 and 590 °C, three curves each) at its start values.
    fn joint() -> (RunConfig, Dataset, Box<dyn Model>, Vec<f64>) {
        let (cfg, data) =
            RunConfig::resolve(Path::new("configs/cmv-joint.toml"), &Overrides::default()).unwrap();
        let model = cfg.build_model().unwrap();
        let params = cfg.starts_all_given().unwrap();
        (cfg, data, model, params)
    }

    fn keys(groups: &[XyGroup]) -> Vec<&str> {
        groups
            .iter()
            .filter(|g| !g.label.is_empty())
            .map(|g| g.label.as_str())
            .collect()
    }

    #[test]
    fn model_lines_span_the_stresses_and_fall_with_stress() {
        let (cfg, data, model, params) = joint();
        let asked = [Asked {
            temperature_c: 575.0,
            stress_mpa: 70.0,
            rupture_time_h: f64::NAN,
            min_rate: f64::NAN,
        }];
        let d = Diagrams {
            cfg: &cfg,
            data: &data,
            model: model.as_ref(),
            params: &params,
            lmp: None,
            asked: &asked,
            held_out_c: None,
        };
        assert_eq!(d.temperatures(), [560.0, 575.0, 590.0]);
        let lines = d.model_lines();
        assert_eq!(lines.len(), 3);
        for l in &lines {
            assert_eq!(l.points.len(), 40);
            let tested: Vec<f64> = data
                .curves
                .iter()
                .filter(|c| c.temperature_c == l.temperature_c)
                .map(|c| c.stress_mpa)
                .chain(
                    asked
                        .iter()
                        .filter(|a| a.temperature_c == l.temperature_c)
                        .map(|a| a.stress_mpa),
                )
                .collect();
            let lo = tested.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = tested.iter().copied().fold(0.0, f64::max);
            assert!((l.points[0].0 - lo / 1.1).abs() < 1e-9 * lo);
            assert!((l.points[39].0 - hi * 1.1).abs() < 1e-9 * hi);
            // Higher stress: shorter life, faster minimum rate (KHD at fixed temperature).
            for w in l.points.windows(2) {
                assert!(w[1].0 > w[0].0);
                assert!(w[1].1 < w[0].1, "{}: {:?}", l.temperature_c, w);
                assert!(w[1].2 > w[0].2, "{}: {:?}", l.temperature_c, w);
            }
        }
        // Hotter: shorter life at the same stress (measured: 51,900 h at 560 °C and 5,100 h at
        // 590 °C, 100 MPa).
        let at = |l: &ModelLine, s: f64| {
            l.points
                .windows(2)
                .find(|w| w[0].0 <= s && s <= w[1].0)
                .map(|w| w[0].1)
                .unwrap()
        };
        assert!(at(&lines[0], 105.0) > 3.0 * at(&lines[2], 105.0));
    }

    #[test]
    fn diagram_groups_name_every_temperature_and_style() {
        let (cfg, data, model, params) = joint();
        let lmp = LarsonMiller::fit_curves(&data.curves, 1).unwrap();
        let d = Diagrams {
            cfg: &cfg,
            data: &data,
            model: model.as_ref(),
            params: &params,
            lmp: Some(&lmp),
            asked: &[],
            held_out_c: Some(590.0),
        };
        let lines = d.model_lines();
        let sr = d.stress_rupture(&lines);
        let c = format!("{:.2}", lmp.c);
        assert_eq!(
            keys(&sr),
            [
                "560 °C",
                "590 °C (held out)",
                "measured",
                "measured at 590 °C, held out of the fit",
                "creepfit (model)",
                &format!("Larson–Miller baseline (C = {c})"),
            ]
        );
        let lm_key = sr.iter().find(|g| g.label.starts_with("Larson")).unwrap();
        assert_eq!(lm_key.stroke, Some(Dash::Dashed));
        // Measured tests at (rupture time, stress); the held-out ones as open circles.
        let measured: Vec<&XyGroup> = sr
            .iter()
            .filter(|g| {
                g.label.is_empty() && g.marker.is_some() && g.marker != Some(MarkerShape::Triangle)
            })
            .collect();
        assert_eq!(measured.len(), 2);
        assert_eq!(measured[0].marker, Some(MarkerShape::Circle));
        assert_eq!(measured[1].marker, Some(MarkerShape::OpenCircle));
        let mut pts: Vec<(f64, f64)> = measured.iter().flat_map(|g| g.points.clone()).collect();
        let mut want: Vec<(f64, f64)> = data
            .curves
            .iter()
            .map(|c| (c.rupture_time_h.unwrap(), c.stress_mpa))
            .collect();
        pts.sort_by(|a, b| a.0.total_cmp(&b.0));
        want.sort_by(|a, b| a.0.total_cmp(&b.0));
        assert_eq!(pts, want);
        // The dashed baseline lines: the baseline's rupture time at each grid stress.
        let dashed: Vec<&XyGroup> = sr
            .iter()
            .filter(|g| g.label.is_empty() && g.stroke == Some(Dash::Dashed))
            .collect();
        assert_eq!(dashed.len(), 2);
        for (g, t) in dashed.iter().zip([560.0, 590.0]) {
            for &(tr, s) in &g.line {
                assert!((tr / lmp.rupture_time(t, s) - 1.0).abs() < 1e-12);
            }
        }

        // Larson–Miller: T·(C + log10 t_r) in K for each measured test, and the master curve.
        let lm = d.larson_miller(&lmp, &lines);
        let measured: Vec<(f64, f64)> = lm
            .iter()
            .filter(|g| {
                g.label.is_empty() && g.marker.is_some() && g.marker != Some(MarkerShape::Triangle)
            })
            .flat_map(|g| g.points.clone())
            .collect();
        assert_eq!(measured.len(), data.curves.len());
        for c in &data.curves {
            let p =
                (c.temperature_c + ZERO_CELSIUS_K) * (lmp.c + c.rupture_time_h.unwrap().log10());
            assert!(
                measured
                    .iter()
                    .any(|m| (m.0 - p).abs() < 1e-9 * p && m.1 == c.stress_mpa),
                "{} °C, {} MPa: LMP {p}",
                c.temperature_c,
                c.stress_mpa
            );
        }
        let master = lm
            .iter()
            .find(|g| g.label.is_empty() && g.color == Rgb::BLACK)
            .unwrap();
        assert_eq!(master.stroke, Some(Dash::Dashed));
        assert!(master
            .line
            .iter()
            .all(|&(x, s)| (x - lmp.lmp(s)).abs() < 1e-9 * x));
        assert!(keys(&lm)
            .iter()
            .any(|k| k.starts_with("Larson–Miller master curve")));

        // Norton: every measured minimum rate, in %/h; the data give no measured rates.
        let n = d.norton(&lines);
        assert!(keys(&n).contains(&"measured (estimated from the curve)"));
        let rates: Vec<(f64, f64)> = n
            .iter()
            .filter(|g| {
                g.label.is_empty() && g.marker.is_some() && g.marker != Some(MarkerShape::Triangle)
            })
            .flat_map(|g| g.points.clone())
            .collect();
        for c in &data.curves {
            assert!(rates.contains(&(c.stress_mpa, 100.0 * c.min_rate())));
        }
        // Two temperatures: two colours, cool before hot.
        let colours: Vec<Rgb> = sr
            .iter()
            .filter(|g| g.label.contains("°C") && !g.label.starts_with("measured"))
            .map(|g| g.color)
            .collect();
        assert_eq!(colours, temperature_colors(&[560.0, 590.0]));
    }

    #[test]
    fn writes_the_three_diagrams() {
        let (cfg, data, model, params) = joint();
        let lmp = LarsonMiller::fit_curves(&data.curves, 1).unwrap();
        let dir = tempfile::TempDir::new().unwrap();
        let asked = [Asked {
            temperature_c: 575.0,
            stress_mpa: 100.0,
            rupture_time_h: 1.7e4,
            min_rate: 1.08e-6,
        }];
        let mut d = Diagrams {
            cfg: &cfg,
            data: &data,
            model: model.as_ref(),
            params: &params,
            lmp: Some(&lmp),
            asked: &asked,
            held_out_c: None,
        };
        assert!(d.write(dir.path()).is_empty());
        for f in FILES {
            let len = std::fs::metadata(dir.path().join(f)).unwrap().len();
            assert!(len > 5_000, "{f}: {len} bytes");
        }
        // Without a baseline: no Larson–Miller diagram.
        let bare = tempfile::TempDir::new().unwrap();
        d.lmp = None;
        assert!(d.write(bare.path()).is_empty());
        assert!(bare.path().join(FILES[0]).exists() && bare.path().join(FILES[1]).exists());
        assert!(!bare.path().join(FILES[2]).exists());
    }
}
