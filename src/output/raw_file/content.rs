//! What a simulation puts in its raw file besides the counts: the model's expectations,
//! the truth, the instrument's constants, CF time and the provenance attributes
//! (`docs/file-format.md` describes each).

use std::time::{Duration, SystemTime, UNIX_EPOCH};

use super::{AttrValue, CONVENTIONS, Dims, FORMAT_VERSION, Variable};
use crate::config::Channel;
use crate::error::{Error, Result};
use crate::scenario::{ExpectedProfile, Scenario};

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
}

/// The channel's name: wavelength and polarization, e.g. `532_total`.
pub fn channel_name(wavelength_nm: f64, channel: Channel) -> String {
    let pol = match channel {
        Channel::Total => "total",
        Channel::Parallel => "parallel",
        Channel::Perpendicular => "perpendicular",
    };
    format!("{wavelength_nm}_{pol}")
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

fn var(
    name: &str,
    dims: Dims,
    long_name: &str,
    units: &str,
    attributes: &[(&str, &str)],
    data: Vec<f64>,
) -> Variable {
    Variable {
        name: name.into(),
        dims,
        long_name: long_name.into(),
        units: units.into(),
        attributes: attributes
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect(),
        data,
    }
}

/// The variables of interface.md (format version 2) for one channel: coordinates, the
/// expectations, the instrument constant and the atmosphere's truth.
pub fn variables(sc: &Scenario, e: &ExpectedProfile, shots: u64) -> Vec<Variable> {
    use Dims::{Bin, Channel, ChannelBin};
    let n = e.n_bins();
    let expected_counts: Vec<f64> = e.recorded.clone();
    vec![
        var(
            "altitude",
            Bin,
            "bin-centre altitude above sea level",
            "m",
            &[("standard_name", "altitude"), ("positive", "up")],
            e.altitude_m.clone(),
        ),
        var(
            "range",
            Bin,
            "bin-centre range from the instrument",
            "m",
            &[],
            e.range_m.clone(),
        ),
        var(
            "range_weight",
            Bin,
            "range weight of the bin: integral of overlap / range^2 over the bin",
            "m-1",
            &[],
            e.range_weight.clone(),
        ),
        var(
            "lidar_constant",
            Channel,
            "lidar constant C = K E0 (lambda/hc) A TR TF Q: expected_signal = C attenuated_backscatter range_weight",
            "m2 sr",
            &[],
            vec![sc.instrument.signal_constant],
        ),
        var(
            "expected_signal",
            ChannelBin,
            "expected signal counts per shot (exact bin integral of Eq. 2)",
            "count",
            &[],
            e.signal.clone(),
        ),
        var(
            "expected_background",
            ChannelBin,
            "expected sky-background counts per shot (Eq. 3)",
            "count",
            &[],
            vec![e.background; n],
        ),
        var(
            "expected_dark",
            ChannelBin,
            "expected dark counts per shot",
            "count",
            &[],
            vec![e.dark; n],
        ),
        var(
            "expected_counts",
            ChannelBin,
            "expected recorded counts per shot after the detector (dead time); signal + background + dark for an ideal detector",
            "count",
            &[],
            expected_counts,
        ),
        var(
            "snr_eq4",
            ChannelBin,
            "Eq. 4 signal-to-noise ratio of one profile",
            "1",
            &[],
            e.snr_eq4(shots as f64),
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
            e.attenuated_backscatter.clone(),
        ),
        var(
            "beta_mol",
            Bin,
            "molecular backscatter coefficient at the bin centre",
            "m-1 sr-1",
            &[],
            e.beta_mol.clone(),
        ),
        var(
            "beta_aer",
            Bin,
            "aerosol backscatter coefficient at the bin centre",
            "m-1 sr-1",
            &[],
            e.beta_aer.clone(),
        ),
        var(
            "beta_cld",
            Bin,
            "cloud backscatter coefficient at the bin centre",
            "m-1 sr-1",
            &[],
            e.beta_cld.clone(),
        ),
        var(
            "alpha_total",
            Bin,
            "total extinction coefficient at the bin centre",
            "m-1",
            &[],
            e.alpha_total.clone(),
        ),
        var(
            "t2",
            Bin,
            "two-way transmission to the bin centre (multiple-scattering factors applied)",
            "1",
            &[],
            e.t2.clone(),
        ),
    ]
}

/// The root attributes of interface.md: conventions, provenance, the resolved config,
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
        s("config", sc.loaded.resolved_toml.clone()),
        ("seed".into(), AttrValue::U64(run.seed)),
        s("method", run.method.into()),
        s("config_file", sc.loaded.path.display().to_string()),
        s("start_time", cfg.acquisition.start_time.clone()),
        f("wavelength_nm", sc.instrument.wavelength_nm),
        f("rep_rate_hz", sc.instrument.rep_rate_hz),
        f("bin_width_s", sc.instrument.bin_width_s),
        f("accumulation_time_s", sc.accumulation_time_s()),
    ];
    attrs.extend(run.method_attributes.iter().cloned());
    Ok(attrs)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn time_units_are_udunits() {
        assert_eq!(
            time_units("2004-03-21T06:30:00Z").unwrap(),
            "seconds since 2004-03-21 06:30:00"
        );
        assert!(time_units("yesterday").is_err());
    }

    #[test]
    fn channel_names_read_like_the_field() {
        assert_eq!(channel_name(532.0, Channel::Total), "532_total");
        assert_eq!(
            channel_name(1064.0, Channel::Perpendicular),
            "1064_perpendicular"
        );
        assert_eq!(channel_name(354.7, Channel::Parallel), "354.7_parallel");
    }
}
