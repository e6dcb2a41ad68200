//! `report.md`: the diagnosis for a person.

use super::{Candidate, Diagnosis, Verdict};
use crate::config::DiagnoseSetup;
use crate::diagnose::gof::KNOTS;
use crate::diagnose::signature::STAGES;

fn f(v: f64, prec: usize) -> String {
    if v.is_finite() {
        format!("{v:.prec$}")
    } else {
        "–".into()
    }
}

fn opt(v: Option<f64>, prec: usize) -> String {
    v.map_or("–".into(), |x| f(x, prec))
}

fn list(v: &[f64], prec: usize) -> String {
    v.iter()
        .map(|x| {
            if x.is_finite() {
                format!("{x:+.prec$}")
            } else {
                "–".into()
            }
        })
        .collect::<Vec<_>>()
        .join(" / ")
}

/// A curve's row label: its stress (and specimen), preceded by its temperature when the
/// curves are at several (`several_t`).
fn curve_label(c: &super::CurveSignature, several_t: bool) -> String {
    let t = if several_t {
        format!("{} °C, ", c.temperature_c)
    } else {
        String::new()
    };
    match &c.specimen {
        Some(s) => format!("{t}{} ({s})", c.stress_mpa),
        None => format!("{t}{}", c.stress_mpa),
    }
}

/// The markdown report.
pub fn report_md(name: &str, setup: &DiagnoseSetup, d: &Diagnosis) -> String {
    let mut s = format!("# Diagnosis of {name}\n\n");
    s += &format!("**Verdict: {}**", d.verdict.as_str());
    match (&d.cause, &d.closest) {
        (Some(c), _) => s += &format!(" — cause: `{c}`"),
        (None, Some(c)) => {
            s += &format!(" — `{c}` improves the fit significantly but still misfits")
        }
        _ => {}
    }
    s += &format!(
        " (false-alarm level α = {}, {} bootstrap replicates{}).\n\n",
        d.alpha,
        d.bootstrap.replicates,
        if d.bootstrap.stopped_early {
            ", stopped early: no test could become significant"
        } else {
            ""
        }
    );
    if let Some(c) = &d.caution {
        s += &format!("**Caution:** {c}.\n\n");
    }
    if !d.indistinguishable.is_empty() {
        s += "The data cannot tell the cause apart from: ";
        s += &d
            .indistinguishable
            .iter()
            .map(|i| {
                format!(
                    "`{}` (AIC {:+.1} against a bootstrap spread of {:.1})",
                    i.name, i.delta_aic, i.spread95
                )
            })
            .collect::<Vec<_>>()
            .join(", ");
        s += ".\n\n";
    }
    if let Some(rho) = d.misfit_share {
        s += &format!(
            "Group means (`reduction = \"strain_means\"`): {:.0} % of a reading's error variance does not shrink with averaging (ρ = {rho:.3}, from the base fit; a mean of m readings is taken to have (1 − ρ)/m + ρ of a reading's variance{}).\n\n",
            100.0 * rho,
            if rho == 0.0 {
                ": white reading error, the √m weights"
            } else {
                ""
            }
        );
    }
    s += "## Decision\n\n";
    for w in &d.decision {
        s += &format!("- {w}\n");
    }
    s += "\n## What the calibrated base model gets wrong\n\n";
    s += "Sign convention: predicted − measured, in % of each curve's rupture strain \
          (positive: the model over-predicts the strain). Compared at the measured times only.\n\n";
    if d.evidence.is_empty() {
        s += "No stage bias or lifetime bias common to the curves reaches 2 standard errors \
              of the fitted reading error.\n\n";
    }
    for e in &d.evidence {
        s += &format!("- `{}`: {}\n", e.code, e.text);
    }
    s += "\n";
    for t in &d.gof {
        let g = &t.gof;
        s += &format!(
            "Misfit shape, {} (goodness-of-fit statistic G = {:.1} on {} columns, bootstrap p = {:.3}) \
             at life fractions {}: {} % of ε_f{}; log-lifetime bias {}.\n\n",
            super::shape_name(g.shape),
            g.statistic,
            g.dof,
            t.p_value,
            KNOTS.iter().map(|k| format!("{k}")).collect::<Vec<_>>().join(", "),
            list(&g.shape_pct, 2),
            match g.shape {
                super::gof::Shape::PerCurve => " (mean over the curves)",
                super::gof::Shape::TrendBeyondSpecimens => " (at the curves' mean ln σ and 1/T)",
                super::gof::Shape::Common | super::gof::Shape::CommonBeyondSpecimens => "",
            },
            f(g.lifetime_bias, 3)
        );
        if g.shape.beyond_specimens() {
            s += &format!(
                "Each specimen's own shape beside it: sd {:.2} % of ε_f at a knot (estimated).\n\n",
                g.specimen_shape_sd_pct
            );
        }
        if g.shape == super::gof::Shape::TrendBeyondSpecimens {
            for (what, v) in [
                ("ln σ", &g.stress_trend_pct),
                ("1/T", &g.temperature_trend_pct),
            ] {
                if v.iter().any(|x| x.is_finite()) {
                    s += &format!(
                        "Its change per standard deviation of {what} across the curves: {} % of ε_f.\n\n",
                        list(v, 2)
                    );
                }
            }
        }
        if !t.decides {
            s += &format!(
                "This {} test is reported, not part of the decision ({}).\n\n",
                super::shape_name(g.shape),
                if g.shape.beyond_specimens() {
                    "the model carries no specimen effects: every curve's own shape is tested as model error"
                } else {
                    "the model carries specimen effects: a shape of each specimen's own is the specimens' scatter, which the tests beyond specimen shapes look past"
                }
            );
        }
        s += &g_parts_md(g, d);
    }
    let several_t = d
        .base
        .curves
        .iter()
        .any(|c| c.temperature_c != d.base.curves[0].temperature_c);
    s += &format!(
        "| {}stress MPa | {} bias % (z) | first point % | last point: t/t_f, meas / pred strain % | lifetime error % | reading error sd %, φ |\n|---|---|---|---|---|---|\n",
        if several_t { "temperature °C, " } else { "" },
        STAGES.iter().map(|st| st.0).collect::<Vec<_>>().join(" / ")
    );
    for c in &d.base.curves {
        s += &format!(
            "| {} | {} | {:+.2} | {:.3}, {:.3} / {:.3} | {:+.2} | {:.4}, {:.2} |\n",
            curve_label(c, several_t),
            (0..3)
                .map(|k| format!("{} ({})", f(c.stage_bias_pct[k], 2), f(c.stage_z[k], 1)))
                .collect::<Vec<_>>()
                .join(" / "),
            c.first_point_pct,
            c.last_fraction,
            c.last_point_pct.0,
            c.last_point_pct.1,
            c.lifetime_err_pct,
            c.noise_sd_pct,
            c.noise_phi
        );
    }
    if !d.base.pinned.is_empty() {
        s += &format!(
            "\nBase constants on a bound: {}.\n",
            d.base
                .pinned
                .iter()
                .map(|(n, b)| format!("{n} ({b})"))
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    s += "\n## Candidates\n\n| model | −2 ln L | AIC | LR | LR needed (p ≤ α) | p | p (Holm) | ΔBIC (n_eff) | leave-one-stress-out RMSE | gain % | held-out lifetime error % | lifetime errors % | extra constants |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    let row = |c: &Candidate| -> String {
        let extra: Vec<String> = c
            .extra_constants
            .iter()
            .map(|n| {
                let v = c.constants.iter().find(|(m, _)| m == n).map(|p| p.1);
                format!("{n} = {}", v.map_or("–".into(), |v| format!("{v:.4e}")))
            })
            .collect();
        format!(
            "| {}{} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |\n",
            c.name,
            if c.significant { " *" } else { "" },
            f(c.objective, 2),
            f(c.aic, 2),
            f(c.lr, 2),
            opt(c.lr_critical, 2),
            opt(c.p_value, 3),
            opt(c.p_holm, 3),
            f(c.delta_bic, 1),
            f(c.loo_rmse, 4),
            f(c.gain_pct, 1),
            f(c.loo_lifetime_err_pct, 2),
            list(&c.lifetime_errs_pct, 2),
            if c.status == super::FitStatus::Failed {
                format!("fit failed from all {} starts", c.failed_starts)
            } else {
                extra.join(", ")
            }
        )
    };
    s += &row(&d.base);
    for c in &d.candidates {
        s += &row(c);
    }
    s += "\n`*`: rejects the base model at the family's level α. LR = −2 ln L(base) − (−2 ln L). \
          ΔBIC and the leave-one-stress-out errors are for orientation; the decision uses the \
          bootstrap p-values only. LR needed: the ratio the extension would have needed for \
          p ≤ α before Holm's adjustment (its null distribution's upper-α quantile); far above \
          the χ² value (3.84 for one added constant) the null refits disagree and only a large \
          effect can show.\n";
    for c in std::iter::once(&d.base).chain(&d.candidates) {
        if !c.loo_failed_folds.is_empty() {
            s += &format!(
                "\n{}: the leave-one-out fit failed from every start without the curves at {:?} MPa; no held-out error is reported.\n",
                c.name, c.loo_failed_folds
            );
        }
    }
    if let Some(n) = &d.base.noise {
        s += &format!(
            "\n## Error model of the base fit\n\nReading error per curve (marginal sd, % strain): {}; AR(1) correlation: {}; scatter of rupture times: {:.2} % (ln scale; floor {:.2} %).\n",
            n.strain_sd_pct.iter().map(|v| format!("{v:.4}")).collect::<Vec<_>>().join(" / "),
            n.phi.iter().map(|v| format!("{v:.2}")).collect::<Vec<_>>().join(" / "),
            n.lifetime_sd_pct,
            100.0 * d.settings.lifetime_sd_floor
        );
        s += &if n.reading_error_growth > 0.0 {
            format!(
                "The reading error grows with strain: at each curve's largest strain it is {:.2} times its value at zero (fitted to the residuals; the bootstrap's replicates draw it so).\n",
                1.0 + n.reading_error_growth
            )
        } else {
            "The reading error does not grow with strain (the likelihood's best growth is zero).\n"
                .to_string()
        };
    }
    s += &specimens_md(d, setup);
    if d.bootstrap.failed_base_refits > 0
        || d.bootstrap.failed_extension_refits.iter().any(|f| f.1 > 0)
    {
        s += &format!(
            "\nRefits that failed in the bootstrap (counted against rejection): base {}; {}.\n",
            d.bootstrap.failed_base_refits,
            d.bootstrap
                .failed_extension_refits
                .iter()
                .map(|(n, k)| format!("{n} {k}"))
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    s += &format!(
        "\n## Method\n\nEvery model is fitted by maximum likelihood under an error model with an AR(1) \
         reading error per curve and a log-normal scatter of rupture times; each extension is tested \
         against the base model by its likelihood ratio, and the base model's fit by two statistics for \
         a misfit shape beyond the error model ({}); the null \
         distributions come from {} parametric bootstrap \
         replicates under the fitted base model{}, every replicate refitted by every model (the base \
         from up to {} distinct optima found on the data; each extension from the replicate's base \
         optimum with the extension switched off, and slightly on where the likelihood is flat there, \
         and from its own optimum on the data; plus {} random start(s)){}{}. Holm's procedure keeps the chance of any false alarm at α = {}. A \
         significant extension is the cause only if it passes its own goodness-of-fit tests ({}).\n",
        if d.gof.iter().any(|g| g.decides && g.gof.shape.beyond_specimens()) {
            "with specimen effects: a shape common to the curves, and one changing linearly with \
             ln σ and 1/T, each beyond a random shape of each specimen's own"
        } else {
            "common to the curves, and per curve"
        },
        if d.bootstrap.stopped_early {
            format!(
                "at most {} ({} drawn: sampling stopped once no test could become \
                 significant any more)",
                d.bootstrap.max, d.bootstrap.replicates
            )
        } else if d.bootstrap.most > d.bootstrap.max {
            format!(
                "{} (up to {} for a test whose p-value after {} is at most α/2, where Holm's \
                 thresholds are a few replicates apart)",
                d.bootstrap.max, d.bootstrap.most, d.bootstrap.max
            )
        } else {
            d.bootstrap.max.to_string()
        },
        shapes_md(d),
        d.settings.replicate_basins,
        d.settings.replicate_starts,
        dropped_md(d),
        again_md(d),
        d.alpha,
        match d.verdict {
            Verdict::Extension | Verdict::Unexplained if !d.cause_gof.is_empty() => format!(
                "here p = {}",
                d.cause_gof
                    .iter()
                    .filter(|g| g.decides)
                    .map(|g| format!("{:.3}", g.p_value))
                    .collect::<Vec<_>>()
                    .join(" and ")
            ),
            _ => "not needed here".into(),
        }
    );
    s
}

/// What the null replicates' new specimens were given besides their factors: the data's
/// specimens' own shapes, resampled (empty without).
fn shapes_md(d: &Diagnosis) -> String {
    if d.bootstrap.specimen_shape_sd_pct > 0.0 {
        format!(
            " (each new specimen with factors drawn from the fitted scatter and a shape of its \
             own, one of the data's specimens' shapes beyond the shape they share, resampled: \
             {:.2} % of ε_f at a knot)",
            d.bootstrap.specimen_shape_sd_pct
        )
    } else {
        String::new()
    }
}

/// Where a goodness-of-fit statistic sits: its three largest parts by curve (and the
/// rupture times' part), each with its share of G; empty where G is 0.
fn g_parts_md(g: &super::gof::Gof, d: &Diagnosis) -> String {
    if !(g.statistic > 0.0) || g.curve_g.len() != d.base.curves.len() {
        return String::new();
    }
    let several_t = d
        .base
        .curves
        .iter()
        .any(|c| c.temperature_c != d.base.curves[0].temperature_c);
    let mut order: Vec<usize> = (0..g.curve_g.len()).collect();
    order.sort_by(|&a, &b| g.curve_g[b].total_cmp(&g.curve_g[a]));
    let total: f64 = g.curve_g.iter().sum::<f64>() + g.lifetime_g;
    let share = |v: f64| 100.0 * v / total;
    let top: Vec<String> = order
        .iter()
        .take(3)
        .map(|&i| {
            let c = &d.base.curves[i];
            let t = if several_t {
                format!("{} °C, ", c.temperature_c)
            } else {
                String::new()
            };
            let sp = c
                .specimen
                .as_ref()
                .map_or(String::new(), |s| format!(" ({s})"));
            format!(
                "{t}{} MPa{sp} {:.1} ({:.0} %)",
                c.stress_mpa,
                g.curve_g[i],
                share(g.curve_g[i])
            )
        })
        .collect();
    format!(
        "Where G sits (each curve's part, descriptive, not a test): {}; the rupture times {:.1} ({:.0} %).\n\n",
        top.join(", "),
        g.lifetime_g,
        share(g.lifetime_g)
    )
}

/// The Method paragraph's clause on the tests bootstrapped again with the start that found the
/// data's best fit (empty when none was).
fn again_md(d: &Diagnosis) -> String {
    let again: Vec<String> = d
        .candidates
        .iter()
        .filter(|c| c.null_again)
        .map(|c| match c.null_again_effect {
            Some(e) => format!(
                "{}: {} of {} replicates' ratios raised, {} → {} at or above the data's",
                c.name, e.raised, e.replicates, e.at_or_above[0], e.at_or_above[1]
            ),
            None => c.name.clone(),
        })
        .collect();
    if again.is_empty() {
        return String::new();
    }
    format!(
        "; the tests that rejected were bootstrapped again on the same replicates with the fresh \
         start that found the extension's best fit on the data added to every refit, and their \
         p-values are the second run's ({})",
        again.join("; ")
    )
}

/// The Method paragraph's clause on extensions decided early and not refitted after that
/// (empty when none was).
fn dropped_md(d: &Diagnosis) -> String {
    let dropped: Vec<String> = d
        .candidates
        .iter()
        .filter_map(|c| {
            c.null_replicates
                .filter(|&l| l < d.bootstrap.replicates)
                .map(|l| format!("{} after {l}", c.name))
        })
        .collect();
    if dropped.is_empty() {
        return String::new();
    }
    format!(
        "; an extension with {} null ratios at or above its own was decided not significant \
         (Besag and Clifford's sequential test) and not refitted after that ({} replicates)",
        crate::diagnose::bootstrap::STOP_EXCEEDANCES,
        dropped.join(", ")
    )
}

/// The report's section on the scatter between specimens: what the base fit estimated (and
/// each specimen's factors), or why it carries none.
fn specimens_md(d: &Diagnosis, setup: &DiagnoseSetup) -> String {
    use crate::likelihood::EffectKind;
    let mut s = String::from("\n## Specimens\n\n");
    let Some(sp) = &d.base.specimen else {
        let replicates = crate::specimen::shares_a_condition(
            d.base
                .curves
                .iter()
                .map(|c| (c.temperature_c, c.stress_mpa)),
        );
        let auto = setup.specimen_effects
            == crate::config::SpecimenEffects::Auto(crate::config::AutoWord::Auto);
        let why = if d.specimen_scatter_zero {
            "the base fit with specimen factors estimated their scatter beyond the stress trend at zero for every kind, so the diagnosis went on without them (every model at the base's zero scatter; the bootstrap draws identical specimens)".to_string()
        } else if auto && !replicates {
            "no two specimens share a temperature and stress, so specimen-to-specimen scatter cannot be told from the stress dependence of the constants ([objective] specimen_effects fits it anyway)".to_string()
        } else {
            "the base fit found no scatter between specimens, or none was asked for".to_string()
        };
        s += &format!("The base model treats every specimen as the population's: {why}.\n");
        return s;
    };
    for (j, k) in sp.kinds.iter().enumerate() {
        let what = k.describe();
        if crate::likelihood::scatter_at_bound(sp.scatter[j]) {
            s += &format!(
                "- The {what}'s scatter is at the estimate's bound (sd of the ln factor {:.1}): the data do not bound it, and the null bootstrap draws new specimens from it; read the tests with care.\n",
                sp.scatter[j]
            );
            continue;
        }
        s += &format!(
            "- The {what} varies {:.0} % between specimens (sd of the ln factor {:.3}, 95 % {:.3}–{:.3}{}).\n",
            crate::report::tables::lognormal_cv_pct(sp.scatter[j]),
            sp.scatter[j],
            sp.scatter_lo95[j],
            sp.scatter_hi95[j],
            crate::report::tables::scatter_dof_note(sp.scatter_dof.get(j).copied())
        );
    }
    if sp.scatter_method != crate::specimen::ScatterMethod::LinearMixedModel {
        s += &format!("- The scatter is {}.\n", sp.scatter_method.note());
    }
    for t in d
        .base
        .specimen_stress_trend
        .iter()
        .filter(|t| t.slope.is_finite())
    {
        s += &format!(
            "- The ln {} factors against ln stress within temperatures: slope {:+.2} ± {:.2} (t-test p {}, {} degrees of freedom; called at p < {}){}.\n",
            t.kind.name(),
            t.slope,
            t.se,
            crate::report::tables::p_text(t.p_value),
            t.df,
            crate::likelihood::STRESS_TREND_ALPHA,
            if t.follows_stress() {
                ": **they follow stress**, a stress dependence the base's constants miss and its factors take up, which the tests above cannot see (for the ductility: what `stress_ductility` would carry, ν ≈ −slope)"
            } else {
                ""
            }
        );
    }
    for t in &d.base.specimen_temperature_levels {
        s += &format!("- {}.\n", crate::report::tables::temperature_levels_text(t));
    }
    for c in &d.base.specimen_campaign_levels {
        s += &format!("- {}.\n", crate::report::tables::campaign_levels_text(c));
    }
    s += "\nEach specimen's factor (its value over the population's; the null bootstrap draws new specimens from this scatter):\n\n| stress MPa | specimen |";
    for k in &sp.kinds {
        s += match k {
            EffectKind::Rate => " creep-rate factor |",
            EffectKind::Ductility => " ductility factor |",
            EffectKind::Coarsening => " coarsening factor |",
        };
    }
    s += "\n|---|---|";
    s += &"---|".repeat(sp.kinds.len());
    s += "\n";
    for (i, c) in d.base.curves.iter().enumerate() {
        s += &format!(
            "| {} | {} |",
            c.stress_mpa,
            c.specimen.as_deref().unwrap_or("-")
        );
        for e in &sp.effects {
            s += &format!(" {:.3} |", e.get(i).copied().unwrap_or(f64::NAN).exp());
        }
        s += "\n";
    }
    s
}

/// The residual series of the base model and of the chosen (else the lowest-AIC) extension,
/// on the curves diagnose worked on (each binned to `max_points`): per curve, (t / t_f,
/// predicted − measured strain in % of the rupture strain), thinned to
/// [`crate::report::plot::PLOT_POINTS`]. With specimen effects every curve is predicted at its
/// own specimen's factors (as the tests see it). Returned as (candidate name, series), base first.
pub fn residual_series(
    setup: &DiagnoseSetup,
    data: &crate::data::Dataset,
    max_points: usize,
    d: &Diagnosis,
) -> crate::error::Result<Vec<(String, Vec<crate::report::plot::CurveSeries>)>> {
    use crate::report::plot::{CurveId, CurveSeries};
    let chosen = d
        .candidates
        .iter()
        .find(|c| Some(&c.name) == d.cause.as_ref())
        .or_else(|| {
            d.candidates
                .iter()
                .filter(|c| c.aic.is_finite())
                .min_by(|a, b| a.aic.total_cmp(&b.aic))
        });
    let curves: Vec<crate::data::Curve> = data
        .curves
        .iter()
        .map(|c| crate::data::binned(c, max_points))
        .collect();
    let settings = &setup.settings;
    let mut out = Vec::new();
    for c in std::iter::once(&d.base).chain(chosen) {
        let variant = setup
            .variants
            .iter()
            .find(|v| v.name == c.name)
            .ok_or_else(|| {
                crate::error::Error::Diagnose(format!("no model '{}' was compared", c.name))
            })?;
        let x: Vec<f64> = c.constants.iter().map(|p| p.1).collect();
        // With specimen effects, each curve at its own specimen's constants: the residuals the
        // tests and the report's table see, not the population's.
        let factors = c
            .specimen
            .as_ref()
            .and_then(|sp| sp.curve_factors(variant.model.as_ref()));
        let obj = crate::likelihood::raw_objective(variant.model.as_ref(), &curves, settings)
            .with_factors(factors);
        let ev = obj.evaluate(&x);
        let series: Vec<CurveSeries> = curves
            .iter()
            .zip(&ev.curves)
            .map(|(cu, p)| CurveSeries {
                id: CurveId::of(cu),
                points: crate::report::tables::thin(
                    (0..cu.times_h.len())
                        .map(|k| {
                            (
                                cu.times_h[k] / cu.life_h(),
                                100.0 * (p.strain[k] - cu.strains[k]) / cu.rupture_strain,
                            )
                        })
                        .collect(),
                    crate::report::plot::PLOT_POINTS,
                ),
            })
            .collect();
        out.push((c.name.clone(), series));
    }
    Ok(out)
}
