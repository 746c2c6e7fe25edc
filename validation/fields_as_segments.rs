//! The segments a model-field scene becomes, written as a hand-written config (issue 39:
//! "the whole run no more than 1.5× the cost of the same run with a hand-written scene of
//! as many columns"). Reads a config with `[scene.model_fields]`, samples the fields as
//! `simulate` does for `--profiles P` (`scene::fields::with_model_fields`, the same
//! seed), and writes the resulting config — `[[scene.segments]]`, one per subcolumn
//! stretch, each with its layers and, with `molecules = "fields"`, its molecular and
//! water-vapour tables — as TOML, paths made absolute. `simulate` of the two configs
//! draws the same columns; `validation/fields_cost.sh` times them side by side.
//!
//!     cargo run --release --example fields_as_segments -- CONFIG PROFILES OUT.toml

use std::path::Path;

use lidarsim::scene::orbit::Orbit;
use lidarsim::scene::track::AlongTrack;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.len() != 4 {
        eprintln!("usage: fields_as_segments CONFIG PROFILES OUT.toml");
        std::process::exit(2);
    }
    if let Err(e) = run(Path::new(&args[1]), &args[2], Path::new(&args[3])) {
        eprintln!("fields_as_segments: {e}");
        std::process::exit(2);
    }
}

fn run(config: &Path, profiles: &str, out: &Path) -> Result<(), String> {
    let profiles: u64 = profiles.parse().map_err(|e| format!("PROFILES: {e}"))?;
    let sc = lidarsim::scenario::Scenario::load(config, &[]).map_err(|e| e.to_string())?;
    let cfg = sc.loaded.config.clone();
    let track = match &cfg.orbit {
        Some(o) => AlongTrack::Orbit(Orbit::from_config(o, cfg.platform.altitude_km * 1e3)?),
        None => AlongTrack::Speed(
            cfg.scene
                .as_ref()
                .and_then(|s| s.advection_speed_m_per_s)
                .unwrap_or(lidarsim::config::DEFAULT_ADVECTION_SPEED_M_PER_S),
        ),
    };
    let shots = sc.shots_per_profile();
    let seed = cfg.simulation.seed;
    let mut segments = lidarsim::scene::fields::with_model_fields(
        cfg,
        &sc.loaded,
        &track,
        (shots, profiles),
        seed,
    )
    .map_err(|e| e.to_string())?;
    segments.acquisition.profiles = profiles as usize;
    if let lidarsim::config::MolecularModel::File { file } =
        &mut segments.atmosphere.molecular.model
    {
        *file = sc.loaded.resolve_path(file);
    }
    let text = toml::to_string(&segments).map_err(|e| e.to_string())?;
    std::fs::write(out, text).map_err(|e| format!("{}: {e}", out.display()))?;
    let n = segments.scene.as_ref().map_or(0, |s| s.segments.len());
    println!(
        "wrote {}: {n} segments for {profiles} profiles",
        out.display()
    );
    Ok(())
}
