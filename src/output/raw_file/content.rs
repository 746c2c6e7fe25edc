//! What a simulation puts in its raw file besides the counts: the model's expectations,
//! the truth, the instrument's constants, CF time and the provenance attributes
//! (`docs/file-format.md` describes each).

use std::time::{Duration, SystemTime, UNIX_EPOCH};

use super::spec::{AttrValue, CONVENTIONS, Dims, FORMAT_VERSION, Variable, var};
use super::truth;
use crate::error::{Error, Result};
use crate::scenario::{ExpectedProfile, Lidar, Scenario};

/// The environment variable that fixes `date_created` and `history` (the
/// reproducible-builds convention): seconds since 1970-01-01 UTC.
pub const SOURCE_DATE_EPOCH: &str = "SOURCE_DATE_EPOCH";

/// How a run drew its counts, for the root attributes.
#[derive(Debug, Clone)]
pub struct RunInfo<'a> {
    /// Seed used.
    pub seed: u64,
    /// Method used (`shot`, `aggregate`, ...).
    pub method: &'a str,
    /// Further attributes of the method (e.g. the normal-approximation threshold).
    pub method_attributes: Vec<(String, AttrValue)>,
    /// The command line, recorded in `history`.
    pub command_line: &'a str,
    /// The resolved config with the run's values written in (`config`,
    /// `RunValues::stored_config` of the simulate module).
    pub config: String,
}

/// Options of `simulate` that do not change the file's content, left out of `history`
/// with their values: the output path, the shard and the thread count. So the whole run
/// and the merge of its shards (`lidarsim merge`) record the same history, and a
/// run gives the same bytes whatever its output name (docs/file-format.md).
pub const HISTORY_OMITS: [&str; 5] = ["-o", "--output", "--shard", "--threads", "--photons"];

/// Options of `onboard` left out of its product's `history` besides [`HISTORY_OMITS`]:
/// its other outputs and the partial of a shard, which do not change the product, so
/// that the whole run (with `--report`) and the merge of its shards (with `--partial`)
/// record the same history.
pub const PRODUCT_HISTORY_OMITS: [&str; 3] = ["--report", "--partial", "--raw"];

/// The root attribute that marks a file as an onboard product.
pub const PRODUCT_ATTRIBUTE: &str = "lidarsim_product";

/// The command line as `history` records it: the program as `lidarsim`, then every
/// argument but those of [`HISTORY_OMITS`] (as `-o X`, `--output=X` or `-oX`).
pub fn history_command(args: impl IntoIterator<Item = String>) -> String {
    history_command_omitting(args, &[])
}

/// [`history_command`] leaving out `extra` options with their values too (`onboard`'s
/// other outputs, which do not change its product: [`PRODUCT_HISTORY_OMITS`]).
pub fn history_command_omitting(args: impl IntoIterator<Item = String>, extra: &[&str]) -> String {
    let omitted = |o: &str| HISTORY_OMITS.contains(&o) || extra.contains(&o);
    let mut args = args.into_iter();
    let mut kept = vec![];
    if args.next().is_some() {
        kept.push("lidarsim".to_string());
    }
    while let Some(a) = args.next() {
        let option = a.split('=').next().unwrap_or(&a);
        if omitted(a.as_str()) {
            args.next(); // its value
        } else if !(omitted(option) && a.contains('=')
            || a.starts_with("-o") && !a.starts_with("--"))
        {
            kept.push(a);
        }
    }
    kept.join(" ")
}

/// CF units of `time`: `seconds since 2004-03-21 00:00:00` from an RFC 3339 start time
/// (validated with the config).
pub fn time_units(start_time: &str) -> Result<String> {
    let t = humantime::parse_rfc3339(start_time)
        .map_err(|e| Error::Unsupported(format!("acquisition.start_time {start_time:?}: {e}")))?;
    let iso = humantime::format_rfc3339_seconds(t).to_string();
    Ok(format!(
        "seconds since {}",
        iso.trim_end_matches('Z').replacen('T', " ", 1)
    ))
}

/// The time a file is created: `SOURCE_DATE_EPOCH` when set (a one-line error when it is
/// not a whole number of seconds), else now. ISO 8601 UTC, e.g. `2026-11-22T23:07:57Z`.
pub fn creation_time() -> Result<String> {
    let t = match std::env::var(SOURCE_DATE_EPOCH) {
        Ok(v) => {
            let secs: u64 = v.trim().parse().map_err(|_| {
                Error::Unsupported(format!(
                    "{SOURCE_DATE_EPOCH}={v:?} is not a whole number of seconds since 1970-01-01"
                ))
            })?;
            UNIX_EPOCH + Duration::from_secs(secs)
        }
        Err(_) => SystemTime::now(),
    };
    Ok(humantime::format_rfc3339_seconds(t).to_string())
}

/// The values of `f` for every channel, channel-major.
fn per_channel(expected: &[ExpectedProfile], f: impl Fn(&ExpectedProfile) -> Vec<f64>) -> Vec<f64> {
    expected.iter().flat_map(f).collect()
}

/// Where a run's expectations go in its file (docs/file-format.md, "The truth of each
/// profile"): one column's (channel, bin), or a changing scene's compact or per-profile
/// form.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TruthLayout {
    /// One column: every expectation (channel, bin).
    Static,
    /// A changing scene, each truth at the dimensions of what it depends on:
    /// `expected_signal` and `attenuated_backscatter` (column, channel, bin), and
    /// `expected_counts` too with a dead-time detector and no sun; `expected_background`
    /// (profile, channel); `expected_counts` (profile, channel, bin) with a dead-time
    /// detector under the sun (its rate follows the profile's sky); no `expected_counts`
    /// for ideal detectors (signal + background + dark) and no `snr_eq4` (Eq. 4 of
    /// those).
    Compact {
        /// Some channel has a dead time.
        dead_time: bool,
        /// The background is the sun's.
        solar: bool,
    },
    /// A changing scene with format 3's (profile, channel, bin) `expected_signal`,
    /// `expected_background`, `expected_counts`, `snr_eq4` and `attenuated_backscatter`
    /// (`--truth per-profile`), each exactly what [`super::per_profile`] rebuilds from the
    /// compact form.
    PerProfile,
}

impl TruthLayout {
    /// The layout of a run of `lidar`: `changing` whether its scene changes along the
    /// track (or with the sun), `form` what `simulation.truth` asks.
    pub fn of(lidar: &Lidar, changing: bool, form: crate::config::TruthForm) -> TruthLayout {
        match (changing, form) {
            (false, _) => TruthLayout::Static,
            (true, crate::config::TruthForm::PerProfile) => TruthLayout::PerProfile,
            (true, crate::config::TruthForm::Compact) => TruthLayout::Compact {
                dead_time: lidar
                    .channels
                    .iter()
                    .any(|c| c.instrument.dead_time.is_some()),
                solar: lidar.first().loaded.config.background.model
                    == crate::config::BackgroundModel::Solar,
            },
        }
    }
}

/// The variables of docs/file-format.md for every channel of `lidar`: coordinates, the
/// expectations, the instrument constants, and the truth of each of the scene's
/// `columns` ([`truth::column_variables`]).
/// In a changing scene ([`TruthLayout`]) the expectations are per column or per profile,
/// the rows of the per-profile ones written with each profile in the order they come
/// here (last); the other (channel, bin) variables are those of the first profile's
/// first column.
pub fn variables(
    lidar: &Lidar,
    expected: &[ExpectedProfile],
    columns: &[&[ExpectedProfile]],
    species: &[usize],
    shots: u64,
    layout: TruthLayout,
) -> Vec<Variable> {
    use Dims::{Bin, Channel, ChannelBin, ProfileChannel, ProfileChannelBin};
    let e0 = &expected[0];
    let channels = &lidar.channels;
    let instrument = |f: fn(&Scenario) -> f64| channels.iter().map(f).collect::<Vec<f64>>();
    let mut vars = vec![
        var(
            "altitude",
            Bin,
            "bin-centre altitude above sea level",
            "m",
            &[("standard_name", "altitude"), ("positive", "up")],
            e0.altitude_m.clone(),
        ),
        var(
            "range",
            Bin,
            "bin-centre range from the instrument",
            "m",
            &[],
            e0.range_m.clone(),
        ),
        var(
            "range_weight",
            Bin,
            "range weight of the bin: integral of overlap / range^2 over the bin",
            "m-1",
            &[],
            e0.range_weight.clone(),
        ),
        var(
            "lidar_constant",
            Channel,
            "lidar constant C = K E0 (lambda/hc) A TR TF Q: expected_signal = C attenuated_backscatter range_weight",
            "m2 sr",
            &[],
            instrument(|c| c.instrument.signal_constant),
        ),
        var(
            "wavelength",
            Channel,
            "detected wavelength of the channel",
            "nm",
            &[("standard_name", "radiation_wavelength")],
            instrument(|c| c.instrument.wavelength_nm),
        ),
        var(
            "nominal_pulse_energy",
            Channel,
            "nominal emitted pulse energy E0 of the channel's wavelength (expected_* and lidar_constant are at this energy)",
            "J",
            &[],
            instrument(|c| c.loaded.config.instrument.pulse_energy_j),
        ),
        var(
            "dead_time",
            Channel,
            "detector dead time (0 = ideal linear detector)",
            "s",
            &[],
            instrument(|c| c.instrument.dead_time.map_or(0.0, |d| d.tau_s)),
        ),
        var(
            "expected_signal",
            ChannelBin,
            "expected signal counts per shot at the nominal pulse energy (exact bin integral of Eq. 2)",
            "count",
            &[],
            per_channel(expected, |e| e.signal.clone()),
        ),
        var(
            "expected_background",
            ChannelBin,
            "expected sky-background counts per shot (Eq. 3)",
            "count",
            &[],
            per_channel(expected, |e| vec![e.background; e.n_bins()]),
        ),
        var(
            "expected_dark",
            ChannelBin,
            "expected dark counts per shot",
            "count",
            &[],
            per_channel(expected, |e| vec![e.dark; e.n_bins()]),
        ),
        var(
            "expected_counts",
            ChannelBin,
            "expected recorded counts per shot after the detector (dead time; ADC codes of an analog channel); signal + background + dark for an ideal photon counter",
            "count",
            &[],
            per_channel(expected, |e| e.recorded.clone()),
        ),
        var(
            "snr_eq4",
            ChannelBin,
            "Eq. 4 signal-to-noise ratio of one profile",
            "1",
            &[],
            per_channel(expected, |e| e.snr_eq4(shots as f64)),
        ),
        var(
            "attenuated_backscatter",
            ChannelBin,
            "bin-averaged attenuated backscatter seen by the channel",
            "m-1 sr-1",
            &[(
                "standard_name",
                "volume_attenuated_backwards_scattering_function_in_air",
            )],
            per_channel(expected, |e| e.attenuated_backscatter.clone()),
        ),
    ];
    vars.extend(truth::instrument_variables(lidar, e0));
    vars.extend(
        super::detection::detection_variables(lidar, expected)
            .into_iter()
            .map(|v| Variable {
                attributes: vec![("_FillValue".into(), AttrValue::F64(f64::NAN))],
                ..var(
                    v.name,
                    if v.per_bin { ChannelBin } else { Channel },
                    v.long_name,
                    v.units,
                    &[],
                    v.data,
                )
            }),
    );
    if channels
        .iter()
        .any(|c| c.instrument.dead_time.is_some_and(|d| d.pixels > 1))
    {
        vars.push(var(
            "detector_pixels",
            Channel,
            "pixels of the photon counter, sharing its photons evenly, each with the dead time \
             of its own (the counts are their sum); written when some channel has more than one",
            "1",
            &[],
            instrument(|c| c.instrument.dead_time.map_or(1.0, |d| f64::from(d.pixels))),
        ));
    }
    vars.extend(truth::column_variables(lidar, columns, species));
    match layout {
        TruthLayout::Static => {}
        TruthLayout::PerProfile => {
            // per profile, in the order the simulation gives their rows
            for name in super::per_profile::PER_PROFILE_NAMES {
                if let Some(i) = vars.iter().position(|v| v.name == name) {
                    let mut v = vars.remove(i);
                    v.dims = ProfileChannelBin;
                    v.data.clear();
                    v.long_name.push_str(" (average over the profile's shots)");
                    vars.push(v);
                }
            }
        }
        TruthLayout::Compact { dead_time, solar } => {
            let of_columns = |f: fn(&ExpectedProfile) -> &[f64]| -> Vec<f64> {
                columns
                    .iter()
                    .flat_map(|c| c.iter().flat_map(f))
                    .copied()
                    .collect()
            };
            let mut take = |name: &str| {
                let i = vars.iter().position(|v| v.name == name);
                i.map(|i| vars.remove(i))
            };
            let mut moved = vec![];
            for (name, data) in [
                ("expected_signal", of_columns(|e| &e.signal)),
                (
                    "attenuated_backscatter",
                    of_columns(|e| &e.attenuated_backscatter),
                ),
            ] {
                moved.extend(take(name).map(|v| per_column(v, data)));
            }
            let mut counts = take("expected_counts");
            if dead_time && !solar {
                let v = counts.take();
                moved.extend(v.map(|v| per_column(v, of_columns(|e| &e.recorded))));
            }
            take("snr_eq4");
            let mut pushed = vec![];
            if let Some(mut v) = take("expected_background") {
                v.dims = ProfileChannel;
                v.data.clear();
                v.long_name = "expected sky-background counts per shot and bin (Eq. 3), the \
                    same in every bin, averaged over the profile's shots"
                    .into();
                pushed.push(v);
            }
            if let (true, true, Some(mut v)) = (dead_time, solar, counts) {
                v.dims = ProfileChannelBin;
                v.data.clear();
                v.long_name.push_str(" (average over the profile's shots)");
                pushed.push(v);
            }
            // the column ones among the column truth, the per-profile ones last
            vars.extend(moved);
            vars.extend(pushed);
        }
    }
    vars
}

/// One column's rows of the (column, …) variables, in the order [`variables`] lists
/// them: what a run hands [`super::ProfileSink::write_column`] for column `column` (every
/// channel's model) of a scene whose columns are built as its profiles need them and
/// whose aerosol `species` are those of [`truth::aerosol_species_of`] over all of them.
pub fn column_rows(
    lidar: &Lidar,
    expected: &[ExpectedProfile],
    column: &[ExpectedProfile],
    species: &[usize],
    shots: u64,
    layout: TruthLayout,
) -> Vec<Vec<f64>> {
    variables(lidar, expected, &[column], species, shots, layout)
        .into_iter()
        .filter(|v| matches!(v.dims, Dims::ColumnBin | Dims::ColumnChannelBin))
        .map(|v| v.data)
        .collect()
}

/// `v` as a (column, channel, bin) variable of `data`: the column's value at the nominal
/// pulse energy.
fn per_column(mut v: Variable, data: Vec<f64>) -> Variable {
    v.dims = Dims::ColumnChannelBin;
    v.data = data;
    v.long_name.push_str(" of the column");
    v
}

/// The geolocation variables of a run with an orbit, in the order of their values.
pub const GEOLOCATION: [&str; 3] = ["latitude", "longitude", "along_track_distance"];

/// `latitude`, `longitude` and `along_track_distance` (profile): the ground-track
/// position of each profile's centre (`src/scene/orbit.rs`).
pub fn geolocation_variables() -> Vec<Variable> {
    let profile = |name: &str, long_name: &str, units: &str, attrs: &[(&str, &str)]| Variable {
        dims: Dims::Profile,
        ..var(name, Dims::Profile, long_name, units, attrs, Vec::new())
    };
    vec![
        profile(
            GEOLOCATION[0],
            "latitude of the profile centre's sub-satellite point (geocentric)",
            "degrees_north",
            &[("standard_name", "latitude")],
        ),
        profile(
            GEOLOCATION[1],
            "longitude of the profile centre's sub-satellite point",
            "degrees_east",
            &[("standard_name", "longitude")],
        ),
        profile(
            GEOLOCATION[2],
            "distance along the Earth-fixed ground track from the first shot to the profile centre",
            "m",
            &[],
        ),
    ]
}

/// The root attributes of docs/file-format.md: conventions, provenance, the resolved config,
/// the seed and method, the format version.
pub fn root_attributes(sc: &Scenario, run: &RunInfo) -> Result<Vec<(String, AttrValue)>> {
    let cfg = &sc.loaded.config;
    let created = creation_time()?;
    let s = |k: &str, v: String| (k.to_string(), AttrValue::Str(v));
    let f = |k: &str, v: f64| (k.to_string(), AttrValue::F64(v));
    let mut attrs = vec![
        s("Conventions", CONVENTIONS.into()),
        s(
            "title",
            format!("lidarsim synthetic raw lidar data: {}", cfg.name),
        ),
        s("institution", "synthetic data (lidarsim simulation)".into()),
        s("source", format!("lidarsim {}", env!("CARGO_PKG_VERSION"))),
        s("history", format!("{created} {}", run.command_line)),
        s("date_created", created),
        s(
            "references",
            "Fochesatto et al. (2004), Adv. Space Res. 34, 2227-2231".into(),
        ),
        s("comment", cfg.description.clone()),
        (
            "lidarsim_format_version".into(),
            AttrValue::I32(FORMAT_VERSION),
        ),
        s("config", run.config.clone()),
        ("seed".into(), AttrValue::U64(run.seed)),
        s("method", run.method.into()),
        s("config_file", sc.loaded.path.display().to_string()),
        s("start_time", cfg.acquisition.start_time.clone()),
        f("wavelength_nm", sc.instrument.wavelength_nm),
        f("rep_rate_hz", sc.instrument.rep_rate_hz),
        f("bin_width_s", sc.instrument.bin_width_s),
        f("accumulation_time_s", sc.accumulation_time_s()),
        f(
            "full_overlap_range_m",
            sc.path.overlap().full_overlap_range_m(),
        ),
        (
            "pretrigger_bins".into(),
            AttrValue::I32(i32::try_from(sc.geometry.pretrigger_bins).unwrap_or(i32::MAX)),
        ),
    ];
    attrs.extend(run.method_attributes.iter().cloned());
    Ok(attrs)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn history_leaves_out_what_does_not_change_the_content() {
        let args = |s: &str| s.split(' ').map(String::from).collect::<Vec<_>>();
        assert_eq!(
            history_command(args(
                "/x/target/release/lidarsim simulate c.toml -o a.h5 --profiles 10 --shard 1/3 \
                 --threads=2 --seed 7 -ob.h5 --output=c.h5 --set a.b=1"
            )),
            "lidarsim simulate c.toml --profiles 10 --seed 7 --set a.b=1"
        );
        assert_eq!(
            history_command(args("lidarsim simulate c.toml --threads 1 --output o.h5")),
            "lidarsim simulate c.toml"
        );
    }

    #[test]
    fn time_units_are_udunits() {
        assert_eq!(
            time_units("2004-03-21T06:30:00Z").unwrap(),
            "seconds since 2004-03-21 06:30:00"
        );
        assert!(time_units("yesterday").is_err());
    }
}
