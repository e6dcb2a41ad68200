//! The misfit share ρ (`errmodel::misfit_share_of`) of generated null sets' `strain_means`
//! group means, from the residuals at the **true** constants and specimen factors: what
//! `diagnose`'s estimate would be if its base fit reached the truth. Prints, per seed, the
//! set's sampling and reading-error φ, and ρ from the truth's residuals.
//! Usage: `cargo run --release --example misfit_share_truth -- DIR SEED...`
use creepfit::data::{reduce, Reduction};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let dir = std::path::PathBuf::from(&args[1]);
    println!("seed sampling noise_phi growth rho_truth rho_fit_without_factors rho_fit_with_factors factors");
    for s in &args[2..] {
        let seed: u64 = s.parse().expect("seed");
        let name = format!("set-{seed}");
        let set = creepfit::synth::generate_in(
            &name,
            "none",
            None,
            seed,
            creepfit::synth::World::Specimens,
        )
        .expect("set");
        let folder = dir.join(&name);
        creepfit::synth::write_set(&set, &folder).expect("write");
        let t = &set.truth;
        let sp = t.specimens.as_ref().expect("specimens world");
        let cfg = creepfit::config::RunConfig::load(&folder.join("config.toml")).expect("config");
        let data = cfg.load_data().expect("data");
        let idx: Vec<usize> = data
            .curves
            .iter()
            .map(|c| {
                sp.labels
                    .iter()
                    .position(|l| Some(l.as_str()) == c.specimen.as_deref())
                    .expect("a generated specimen")
            })
            .collect();
        let model = creepfit::model::build(&cfg.model, &[]).expect("model");
        let role = |r: creepfit::model::Role| {
            model
                .constants()
                .iter()
                .position(|c| c.role == r)
                .expect("rate and ductility constants")
        };
        let factors = creepfit::model::objective::CurveFactors {
            index: vec![
                role(creepfit::model::Role::Rate),
                role(creepfit::model::Role::InverseDuctility),
            ],
            factors: idx
                .iter()
                .map(|&i| vec![sp.rate_effects[i].exp(), (-sp.ductility_effects[i]).exp()])
                .collect(),
        };
        let reduced: Vec<_> = data
            .curves
            .iter()
            .map(|c| reduce(c, cfg.diagnose.max_points, Reduction::StrainMeans))
            .collect();
        let settings = creepfit::model::objective::FitSettings::from_config(&cfg);
        let obj = creepfit::likelihood::raw_objective(model.as_ref(), &reduced, &settings)
            .with_factors(Some(factors));
        let mut r = vec![0.0; obj.n_residuals()];
        let rho = match obj.residuals(&t.constants, &mut r) {
            Ok(()) => {
                let res = creepfit::likelihood::split_residuals(&reduced, &r);
                creepfit::errmodel::misfit_share_of(&reduced, &res)
            }
            Err(_) => f64::NAN,
        };
        // The base model fitted from the truth: without specimen factors (as `diagnose`'s
        // fresh starts before their polish) and then with them (the polish).
        let setup = cfg.diagnose_setup().expect("setup");
        let ml = creepfit::likelihood::MlOptions {
            lifetime_sd_floor: cfg.diagnose.lifetime_sd_floor,
            white_first: false,
            specimen: setup
                .specimen_effects
                .resolve(&reduced, setup.specimen_scatter)
                .0
                .with_scatter(setup.specimen_scatter),
            hold_scatter: None,
        };
        let plain_opts = creepfit::likelihood::MlOptions {
            specimen: creepfit::likelihood::SpecimenOptions::NONE,
            ..ml
        };
        let v = &setup.variants[0];
        let plain = creepfit::likelihood::ml_fit(
            v.model.as_ref(),
            &reduced,
            &v.space,
            &t.constants,
            &setup.settings,
            &plain_opts,
        );
        let rho_of = |f: &creepfit::likelihood::MlFit| {
            f.residuals.as_ref().map_or(f64::NAN, |r| {
                creepfit::errmodel::misfit_share_of(&reduced, r)
            })
        };
        let rho_plain = rho_of(&plain);
        let with = creepfit::likelihood::with_specimens(
            plain,
            v.model.as_ref(),
            &reduced,
            &v.space,
            &setup.settings,
            &ml,
        );
        let rho_with = rho_of(&with);
        println!(
            "{seed} {:?} {:.2} {:.2} {rho:.3} {rho_plain:.3} {rho_with:.3} {}",
            t.sampling,
            t.noise_phi,
            sp.error_growth,
            with.specimen.is_some()
        );
    }
}
