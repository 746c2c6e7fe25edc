//! What a run is before any count is drawn: its options resolved against the config
//! ([`RunValues`], the config it stores) and everything but the counts ([`RunPlan`],
//! the raw file's layout).

use std::path::PathBuf;

use super::changing::unbuilt_scene;
use super::energy::{RunEnergy, run_energy};
use super::method::{ResolvedMethod, check_detector, fastest_within_totals, resolve_method};
use super::orbit::orbit_of;
use super::scene;
use crate::config::Method;
use crate::error::{Error, Result};
use crate::output::raw_file::content::{self, RunInfo};
use crate::output::raw_file::{AttrValue, CountWidth, RawFileSpec};
use crate::scenario::{ExpectedProfile, Lidar};

/// Options of one run; `None` takes the config's value.
#[derive(Debug, Clone, Default)]
pub struct RunOptions {
    /// Output raw file.
    pub output: PathBuf,
    /// Seed (`simulation.seed`).
    pub seed: Option<u64>,
    /// Profiles (`acquisition.profiles`).
    pub profiles: Option<usize>,
    /// Method (`simulation.method`).
    pub method: Option<Method>,
    /// Tolerance for `auto` (`simulation.tolerance`): largest KS distance per bin.
    pub tolerance: Option<f64>,
    /// Component-resolved counts (`simulation.components`).
    pub components: Option<bool>,
    /// How a changing scene's truth is stored (`simulation.truth`, `--truth`).
    pub truth: Option<crate::config::TruthForm>,
    /// Show a progress bar (on a terminal only).
    pub progress: bool,
    /// The command line, recorded in the file's `history`
    /// ([`content::history_command`] says which arguments it keeps).
    pub command_line: String,
    /// Write this shard of the run only (`--shard K/N`, [`crate::shard`]).
    pub shard: Option<crate::shard::Shard>,
    /// Stops the run when set (the Python module's Ctrl-C): `simulate::run` then returns
    /// [`Error::Interrupted`] before its next profile, its temporary file removed.
    pub cancel: Option<std::sync::Arc<std::sync::atomic::AtomicBool>>,
    /// Also write every recorded event to this photon file (`--photons`,
    /// docs/photons.md); shot-level runs of photon-counting channels only.
    pub photons: Option<PathBuf>,
}

/// What a run is before any count is drawn: the resolved seed, method, model and scene,
/// and the raw file of the whole run. `simulate` draws from it; `merge`
/// (`simulate::merge`) builds it again from a shard's stored config, so that both
/// write the same file.
pub struct RunPlan {
    /// Seed of the counts.
    pub seed: u64,
    /// Profiles of the whole run.
    pub profiles: usize,
    /// Component-resolved counts.
    pub components: bool,
    /// How a changing scene's truth is stored.
    pub truth: crate::config::TruthForm,
    /// The method used.
    pub method: ResolvedMethod,
    /// Every channel's per-shot expectations (the scene's first column).
    pub expected: Vec<ExpectedProfile>,
    /// The emitted energies.
    pub energy: RunEnergy,
    /// The scene model where the scene changes along the track.
    pub scene: Option<scene::SceneModel>,
    /// Per-shot means of every bin of every channel.
    pub totals: Vec<f64>,
    /// The raw file of the whole run.
    pub spec: RawFileSpec,
}

/// The values of a run that a command-line option may set in place of its config key
/// ([`RunOptions`] over the loaded config): what [`plan`] runs with.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunValues {
    /// `acquisition.profiles` (`--profiles`).
    pub profiles: usize,
    /// `simulation.seed` (`--seed`).
    pub seed: u64,
    /// `simulation.method` as asked (`--method`), before `auto` is resolved.
    pub method: Method,
    /// `simulation.components` (`--components`).
    pub components: bool,
    /// `simulation.tolerance` (`--tolerance`).
    pub tolerance: Option<f64>,
    /// `simulation.truth` (`--truth`).
    pub truth: crate::config::TruthForm,
}

impl RunValues {
    /// Each option of `opts` that is given, else its key in `cfg` (or that key's default).
    pub fn resolve(opts: &RunOptions, cfg: &crate::config::ScenarioConfig) -> Self {
        RunValues {
            profiles: opts.profiles.unwrap_or(cfg.acquisition.profiles),
            seed: opts.seed.unwrap_or(cfg.simulation.seed),
            method: opts.method.unwrap_or(cfg.simulation.method),
            components: opts.components.unwrap_or(cfg.simulation.components),
            tolerance: opts.tolerance.or(cfg.simulation.tolerance),
            truth: opts.truth.unwrap_or(cfg.simulation.truth),
        }
    }

    /// The config a run stores (the raw file's `config` attribute): `resolved_toml` (the
    /// loaded config after every `--set`) with these values written into their keys, so
    /// that simulating it again with no option reproduces the file. Every value is
    /// written, from an option, the file or a default alike, so that a stored config
    /// planned again (`merge`) stores the same text.
    pub fn stored_config(&self, resolved_toml: &str) -> Result<String> {
        let unwritable =
            |why: String| Error::Unsupported(format!("cannot store the run's config: {why}"));
        let mut table: toml::Table = resolved_toml
            .parse()
            .map_err(|e: toml::de::Error| unwritable(e.message().to_string()))?;
        let mut set = |section: &str, key: &str, value: toml::Value| {
            let slot = table
                .entry(section)
                .or_insert_with(|| toml::Value::Table(toml::Table::new()));
            match slot {
                toml::Value::Table(t) => {
                    t.insert(key.to_string(), value);
                    Ok(())
                }
                _ => Err(unwritable(format!("`{section}` is not a table"))),
            }
        };
        let profiles = i64::try_from(self.profiles).map_err(|e| unwritable(e.to_string()))?;
        set("acquisition", "profiles", toml::Value::Integer(profiles))?;
        set("simulation", "seed", crate::config::seed_value(self.seed))?;
        // as the config spells it (`auto`, `shot`, `aggregate`: Method's serde names)
        let method = toml::Value::try_from(self.method).map_err(|e| unwritable(e.to_string()))?;
        set("simulation", "method", method)?;
        set(
            "simulation",
            "components",
            toml::Value::Boolean(self.components),
        )?;
        if let Some(t) = self.tolerance {
            set("simulation", "tolerance", toml::Value::Float(t))?;
        }
        let truth = toml::Value::try_from(self.truth).map_err(|e| unwritable(e.to_string()))?;
        set("simulation", "truth", truth)?;
        toml::to_string(&table).map_err(|e| unwritable(e.to_string()))
    }
}

/// Resolves a run's options against its config and builds everything but the counts.
/// `resolved` is the method of a run already drawn (`merge`, from the shards' `method`);
/// `None` resolves `opts.method` (and `auto`'s tolerance) as `simulate` does.
pub fn plan(lidar: &Lidar, opts: &RunOptions, resolved: Option<ResolvedMethod>) -> Result<RunPlan> {
    let first = lidar.first();
    let values = RunValues::resolve(opts, &first.loaded.config);
    let RunValues {
        profiles,
        seed,
        method: requested,
        components,
        tolerance,
        truth,
    } = values;
    if profiles == 0 {
        return Err(Error::Unsupported("--profiles must be at least 1".into()));
    }
    check_detector(lidar, components)?;
    let mut method = match resolved {
        Some(m) => m,
        None => resolve_method(requested, lidar)?,
    };
    // what the plan holds from here on: the model's bins (its beam paths are laid and
    // counted in what the process holds) and the file's variables per bin, before the
    // run's own estimate (check_sizes)
    let bins = (lidar.channels.len() * first.geometry.n_bins) as f64;
    crate::resources::require_memory(
        &format!("planning a run of {bins} bins"),
        bins * (crate::scenario::MODEL_BYTES_PER_BIN + PLAN_BYTES_PER_BIN),
    )?;
    let expected = lidar.expected()?;
    let shots = first.shots_per_profile();
    let profile_time_s = shots as f64 / first.instrument.rep_rate_hz;
    let energy = run_energy(lidar, seed, profiles as f64 * profile_time_s)?;
    let totals: Vec<f64> = expected.iter().flat_map(|e| e.total_per_shot()).collect();
    if let (Some(t), None) = (tolerance, resolved) {
        if requested != Method::Auto {
            return Err(Error::Unsupported(format!(
                "--tolerance chooses among methods: use it with --method auto, not {}",
                method.name()
            )));
        }
        let approximable = method == ResolvedMethod::Aggregate && energy.law.is_constant();
        method = fastest_within_totals(t, &totals, shots, approximable);
    }
    let mut scene = unbuilt_scene(lidar, seed, profiles, &mut method, components, &energy)?;
    let spec = raw_file_spec(
        lidar,
        &expected,
        method,
        &values,
        energy,
        opts,
        scene.as_ref(),
    )?;
    if let Some(sc) = scene.as_mut() {
        sc.set_count_width(spec.count_width);
    }
    Ok(RunPlan {
        seed,
        profiles,
        components,
        truth,
        method,
        expected,
        energy,
        scene,
        totals,
        spec,
    })
}

/// Everything the raw file holds besides the profiles.
fn raw_file_spec(
    lidar: &Lidar,
    expected: &[ExpectedProfile],
    method: ResolvedMethod,
    values: &RunValues,
    energy: RunEnergy,
    opts: &RunOptions,
    scene: Option<&scene::SceneModel>,
) -> Result<RawFileSpec> {
    let RunValues {
        seed,
        profiles,
        components,
        tolerance,
        ..
    } = *values;
    let layout = content::TruthLayout::of(lidar, scene.is_some(), values.truth);
    let first = lidar.first();
    let shots = first.shots_per_profile();
    let mut method_attributes = vec![];
    if let ResolvedMethod::AggregateNormal { threshold } = method {
        method_attributes.push((
            "normal_approximation_threshold".into(),
            AttrValue::F64(threshold),
        ));
        method_attributes.push((
            "tolerance_ks".into(),
            AttrValue::F64(tolerance.unwrap_or(f64::NAN)),
        ));
    }
    let run_info = RunInfo {
        seed,
        method: method.name(),
        method_attributes,
        command_line: &opts.command_line,
        config: values.stored_config(&first.loaded.resolved_toml)?,
    };
    // the brightest bin at the brightest pulse of the run sizes the counters; a changing
    // scene's columns are built as its profiles need them, so its counters are at least
    // 32-bit and each column is checked against them when built
    // ([`scene::SceneModel::set_count_width`])
    let max_mean = expected
        .iter()
        .flat_map(|e| {
            e.signal
                .iter()
                .map(move |s| energy.envelope * s + e.background + e.dark)
        })
        .fold(0.0f64, f64::max)
        * shots as f64;
    // an analog record's codes reach at most the ADC's full scale every shot
    let analog_max = lidar
        .channels
        .iter()
        .filter_map(|c| c.instrument.analog.as_ref())
        .map(|a| a.full_scale_code() as f64 * shots as f64)
        .fold(0.0f64, f64::max);
    let max_mean = max_mean.max(analog_max);
    let mut count_width = CountWidth::for_max_count(max_mean)?;
    if scene.is_some() && count_width == CountWidth::U16 {
        count_width = CountWidth::U32;
    }
    // a changing scene's column truth comes column by column as the run builds them
    let static_columns = [expected];
    let column_models: &[&[ExpectedProfile]] = match scene {
        Some(_) => &[],
        None => &static_columns,
    };
    let species = match scene {
        Some(sc) => sc.aerosol_species.clone(),
        None => crate::output::raw_file::truth::aerosol_species_of(&static_columns),
    };
    Ok(RawFileSpec {
        n_bins: first.geometry.n_bins,
        n_profiles: profiles,
        first_profile: 0,
        channel_text: crate::output::raw_file::truth::channel_text(lidar),
        n_columns: scene.map_or(1, |sc| sc.n_columns()),
        streamed_columns: scene.is_some(),
        column_slots: scene.map_or(1, |sc| sc.column_slots),
        channels: lidar.channel_names(),
        count_width,
        components,
        time_units: content::time_units(&first.loaded.config.acquisition.start_time)?,
        variables: content::variables(lidar, expected, column_models, &species, shots, layout)
            .into_iter()
            .chain(
                orbit_of(lidar)?
                    .is_some()
                    .then(content::geolocation_variables)
                    .into_iter()
                    .flatten(),
            )
            .collect(),
        profile_coordinates: match orbit_of(lidar)? {
            Some(_) => content::GEOLOCATION.iter().map(|s| s.to_string()).collect(),
            None => vec![],
        },
        root_attributes: content::root_attributes(first, &run_info)?,
    })
}

/// Memory a run's plan holds per bin and channel beyond the model: the raw file's
/// per-bin variables (the truth, the expectations), bytes. Measured: peak RSS of
/// `simulate --profiles 2` over `expect --csv` of scenario 1's 40 km window at
/// `bin_width_s` 2e-9 and 1e-9 (1.33e5 and 2.67e5 bins): 111 and 167 MB more, 418 bytes a
/// bin (plus 55 MB of buffers the run's own estimate counts), rounded up.
const PLAN_BYTES_PER_BIN: f64 = 500.0;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_stored_config_planned_again_stores_the_same_text() {
        // what `merge` relies on: the stored config, loaded and resolved with the run's
        // values (or no option), gives those values and the same text
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("configs")
            .join("paper")
            .join("scenario1.toml");
        let loaded = crate::loaded::load(&path, &[]).unwrap();
        let values = RunValues {
            profiles: 400,
            seed: u64::MAX,
            method: Method::Auto,
            components: true,
            tolerance: Some(1e-3),
            truth: crate::config::TruthForm::PerProfile,
        };
        let stored = values.stored_config(&loaded.resolved_toml).unwrap();
        assert!(
            stored.contains("seed = \"18446744073709551615\""),
            "{stored}"
        );
        let again = crate::loaded::load_str(&stored, &path, &[]).unwrap();
        assert_eq!(
            RunValues::resolve(&RunOptions::default(), &again.config),
            values
        );
        assert_eq!(values.stored_config(&again.resolved_toml).unwrap(), stored);
        // the file's own values, written in when no option is given
        let own = RunValues::resolve(&RunOptions::default(), &loaded.config);
        let written = own.stored_config(&loaded.resolved_toml).unwrap();
        assert!(written.contains("profiles = 100"), "{written}");
    }
}
