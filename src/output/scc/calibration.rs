//! The Δ90 depolarization calibration measurement as the SCC takes it: the two runs with
//! the receiver rotated by +45° and −45° (`simulate --calibration plus45|minus45`) in
//! **one** SCC file, each run's polarization channels a channel of their own (`_p45`
//! then `_m45`, as `atmospheric_lidar`'s `LicelCalibrationMeasurement` renames them),
//! on one time scale, with the per-channel `Pol_Calib_Range_Min/Max` (m) where the
//! calibration factor is taken. `docs/scc.md` "The ±45° calibration measurement".
//!
//! # Choices
//!
//! * **Channels**: the elastic channels (total, parallel, perpendicular; photon counting
//!   and analog) at the wavelengths that have a parallel or perpendicular channel: the
//!   channels the Δ90 method takes its ratio of. Raman, HSRL and elastic channels of
//!   other wavelengths are left out.
//! * **Time**: `atmospheric_lidar` requires runs of equal length and combines the two
//!   runs' time scales into one (`combine_scales`: the earlier run's starts, the later
//!   run's stops). Here profile `i` of the file is profile `i` of each run; its
//!   `Raw_Data_Start_Time` is the earlier start of the two and `Raw_Data_Stop_Time` the
//!   later stop, after the earlier run's start (floored to a second).
//! * **Variables**: every variable of the measurement export (the runs' own channel
//!   parameters are the truth of what was simulated), plus `Pol_Calib_Range_Min` and
//!   `Pol_Calib_Range_Max`; `channel_ID` from the options (`--channel-ids`, the `_p45`
//!   channels first), else 1, 2, ….

use std::path::Path;
use std::time::Duration;

use super::fields::{self, SccContent};
use super::options::SccOptions;
use super::read::{RawRun, bad, read_raw};
use crate::config::Channel as Polarization;
use crate::error::Result;
use crate::receiver::{ChannelConfig, ChannelKind};

/// The receiver rotation of each calibration run, degrees.
pub const CALIBRATION_ROTATIONS_DEG: [f64; 2] = [45.0, -45.0];

/// Options of the calibration export: the measurement export's, and the range (m) where
/// the SCC takes the calibration factor.
#[derive(Debug, Clone, PartialEq)]
pub struct SccCalibrationOptions {
    /// Measurement ID, station and the `channel_ID`s (`_p45` channels first, then `_m45`).
    pub scc: SccOptions,
    /// `Pol_Calib_Range_Min` and `Pol_Calib_Range_Max`, m of range.
    pub pol_calib_range_m: (f64, f64),
}

/// Reads the two calibration runs and derives the SCC content of their calibration
/// measurement; refuses, in one line naming the file, runs that are not the +45° and
/// −45° runs of one ground instrument with a polarization channel, of equal length and
/// binning, or a calibration range outside the recorded range.
pub fn calibration_content(
    plus45: &Path,
    minus45: &Path,
    opts: &SccCalibrationOptions,
) -> Result<SccContent> {
    let plus = read_raw(plus45)?;
    let minus = read_raw(minus45)?;
    check_rotation(plus45, &plus, CALIBRATION_ROTATIONS_DEG[0])?;
    check_rotation(minus45, &minus, CALIBRATION_ROTATIONS_DEG[1])?;
    check_alike(minus45, &plus, &minus)?;
    check_range(plus45, &plus, opts.pol_calib_range_m)?;
    let selected = calibration_channels(plus45, &plus)?;
    let config = plus.config.clone();
    let per_run = SccOptions {
        channel_ids: None,
        ..opts.scc.clone()
    };
    let p = fields::scc_content(plus45, plus, &per_run)?;
    let m = fields::scc_content(minus45, minus, &per_run)?;
    let mut c = combine(p, m, &selected);
    assign_ids(&mut c, plus45, opts.scc.channel_ids.as_deref())?;
    let stop = c.start + Duration::from_secs(c.stop_s.iter().copied().max().unwrap_or(0) as u64);
    c.text_attributes = fields::text_attributes(&config, &opts.scc, c.start, stop)?;
    c.pol_calib_range_m = Some(opts.pol_calib_range_m);
    Ok(c)
}

/// The run must have been drawn with the receiver rotated by `rotation_deg`
/// (`instrument.receiver_rotation_deg` of its `config` attribute).
fn check_rotation(path: &Path, raw: &RawRun, rotation_deg: f64) -> Result<()> {
    let rotation = raw
        .config
        .get("instrument")
        .and_then(|i| i.get("receiver_rotation_deg"))
        .and_then(|v| v.as_float().or_else(|| v.as_integer().map(|i| i as f64)))
        .unwrap_or(0.0);
    if rotation == rotation_deg {
        return Ok(());
    }
    let run = if rotation_deg > 0.0 {
        "plus45"
    } else {
        "minus45"
    };
    Err(bad(
        path,
        &format!(
            "not a {rotation_deg:+}° calibration run: its receiver is rotated by {rotation}° \
             (`instrument.receiver_rotation_deg`); make it with `lidarsim simulate CONFIG \
             --calibration {run}`"
        ),
    ))
}

/// The −45° run must be the +45° run's instrument and acquisition: the same channels,
/// bins and ranges, profiles and shots (the SCC pairs them profile by profile).
fn check_alike(minus45: &Path, plus: &RawRun, minus: &RawRun) -> Result<()> {
    let differs = |what: &str| {
        Err(bad(
            minus45,
            &format!(
                "its {what} differ from the +45° run's: the two calibration runs must be one instrument's"
            ),
        ))
    };
    if plus.channels != minus.channels {
        return differs("channels");
    }
    if plus.n_bins != minus.n_bins || plus.range_m != minus.range_m {
        return differs("bins (`range`)");
    }
    if plus.n_profiles != minus.n_profiles {
        return differs("numbers of profiles");
    }
    if plus.n_shots != minus.n_shots {
        return differs("shots per profile (`n_shots`)");
    }
    Ok(())
}

/// The calibration range must be increasing and within the recorded range after the
/// trigger.
fn check_range(path: &Path, raw: &RawRun, (lo, hi): (f64, f64)) -> Result<()> {
    let res = crate::constants::SPEED_OF_LIGHT_M_PER_S * raw.bin_width_s / 2.0;
    let first = raw.pretrigger_bins.min(raw.n_bins - 1);
    let (start, end) = (
        raw.range_m[first] - res / 2.0,
        raw.range_m[raw.n_bins - 1] + res / 2.0,
    );
    if lo.is_finite() && hi.is_finite() && start <= lo && lo < hi && hi <= end {
        return Ok(());
    }
    Err(bad(
        path,
        &format!(
            "--pol-calib-range {lo},{hi}: must be MIN,MAX in m of range with MIN < MAX, \
             within the recorded {start:.1}–{end:.1} m"
        ),
    ))
}

/// Indices of the file's channels the Δ90 calibration takes: the elastic channels at the
/// wavelengths of its parallel or perpendicular channels.
fn calibration_channels(path: &Path, raw: &RawRun) -> Result<Vec<usize>> {
    let receiver = fields::receiver_channels(path, raw)?;
    let config_of = |name: &String| receiver.iter().find(|r| &r.name == name);
    let polarized: Vec<f64> = receiver
        .iter()
        .filter(|r| is_elastic(r) && r.config.instrument.channel != Polarization::Total)
        .map(|r| r.config.instrument.wavelength_nm)
        .collect();
    let selected: Vec<usize> = raw
        .channels
        .iter()
        .enumerate()
        .filter(|(_, name)| {
            config_of(name).is_some_and(|r| {
                is_elastic(r) && polarized.contains(&r.config.instrument.wavelength_nm)
            })
        })
        .map(|(i, _)| i)
        .collect();
    if selected.is_empty() {
        return Err(bad(
            path,
            "no elastic channel is `parallel` or `perpendicular`: there is nothing to calibrate",
        ));
    }
    Ok(selected)
}

/// `channel_ID`: the given IDs, one per channel of the calibration file, else 1, 2, ….
fn assign_ids(c: &mut SccContent, path: &Path, ids: Option<&[i32]>) -> Result<()> {
    let n = c.channels.len();
    let ids: Vec<i32> = match ids {
        Some(ids) if ids.len() != n => {
            let names: Vec<&str> = c.channels.iter().map(|ch| ch.name.as_str()).collect();
            return Err(bad(
                path,
                &format!(
                    "{} SCC channel IDs given for the {n} channels of the calibration ({})",
                    ids.len(),
                    names.join(", ")
                ),
            ));
        }
        Some(ids) => ids.to_vec(),
        None => (1..=n as i32).collect(),
    };
    for (ch, id) in c.channels.iter_mut().zip(ids) {
        ch.id = id;
    }
    Ok(())
}

fn is_elastic(c: &ChannelConfig) -> bool {
    c.kind == ChannelKind::Elastic
}

/// One file of the two runs' `selected` channels: the +45° channels (`_p45`), then the
/// −45° channels (`_m45`), profile `i` of each run as profile `i`, on the time scale
/// from the earlier run's start.
fn combine(plus: SccContent, minus: SccContent, selected: &[usize]) -> SccContent {
    let t0 = plus.start.min(minus.start);
    let shift = |c: &SccContent| c.start.duration_since(t0).map_or(0, |d| d.as_secs() as i32);
    let (dp, dm) = (shift(&plus), shift(&minus));
    let start_s = (plus.start_s.iter().zip(&minus.start_s))
        .map(|(&a, &b)| (a + dp).min(b + dm))
        .collect();
    let stop_s = (plus.stop_s.iter().zip(&minus.stop_s))
        .map(|(&a, &b)| (a + dp).max(b + dm))
        .collect();
    let runs = [(&plus, "_p45"), (&minus, "_m45")];
    let channels = runs
        .iter()
        .flat_map(|(run, suffix)| {
            selected.iter().map(move |&k| {
                let mut ch = run.channels[k].clone();
                ch.name.push_str(suffix);
                ch
            })
        })
        .collect::<Vec<_>>();
    let (n_ch, n_bins) = (plus.channels.len(), plus.n_bins);
    let mut counts = Vec::with_capacity(plus.n_profiles * channels.len() * n_bins);
    let mut laser_shots = Vec::with_capacity(plus.n_profiles * channels.len());
    for p in 0..plus.n_profiles {
        for (run, _) in &runs {
            for &k in selected {
                let row = (p * n_ch + k) * n_bins;
                counts.extend_from_slice(&run.counts[row..row + n_bins]);
                laser_shots.push(run.laser_shots[p * n_ch + k]);
            }
        }
    }
    SccContent {
        channels,
        counts,
        laser_shots,
        start_s,
        stop_s,
        start: t0,
        ..plus
    }
}
