//! `lidarsim validate --file RAW.h5`: a raw file's counts against the expectation and
//! detector law the file itself carries, with `validate`'s calibrated statistics, so that
//! a merge, a copy or a file another tool has touched can be checked without its config.
//!
//! Per profile p, channel k and bin i the file gives the count `c`, the shots `M_p =
//! n_shots`, the energy factor `f_pk = pulse_energy[p, k] / nominal_pulse_energy[k]` (the
//! mean of exactly the shots' factors the counts were drawn with; every channel sees the
//! same pulses, each at its own laser line's energy; [`read::energy_factors`], which
//! reads the one energy per profile of formats 2 and 3 too) and the per-shot expectations at the nominal energy (`expected_*`, (channel,
//! bin) or, in a changing scene, (profile, channel, bin)). The law of `c`:
//!
//! * **ideal detector** (`dead_time` 0): given the shots' energies, a sum of independent
//!   Poisson counts, so `c ~ Poisson(μ)` exactly, with
//!   `μ = M_p·(expected_counts + (f_p − 1)·expected_signal)`;
//! * **dead time**: mean `M_p·expected_counts`, variance `M_p·v` with `v` the variance
//!   per shot ([`DeadTime::recorded_mean_and_variance`], the dead time carried from bin
//!   to bin) of the channel's arriving means
//!   `λ = expected_signal + expected_background + expected_dark`, the higher cumulants
//!   those of a Poisson law of that variance (as `validate` takes them).
//!
//! What the file cannot say is not judged, and the table says so: a dead-time channel in
//! a profile whose pulse energy is not the nominal one (the recorded mean is non-linear in
//! each shot's energy, which the file does not keep), and any channel in a profile that
//! mixes columns (`profile_column_weight`) with a varying energy (which shots saw which
//! column is not in the file).
//!
//! The statistics are those of [`super::scene`] with each count's own variance: per bin,
//! the total `Σc` against `Σμ` (exact Poisson tail for an ideal detector, normal
//! otherwise) and `V = Σ(c − μ)²` against `Σ var` with the cumulants of `(c − μ)²`
//! (Edgeworth-calibrated, tested where `Σμ ≥ 100`); per statistic the outside count and
//! `Σz²` at level 2.5·10⁻⁴ each ([`super::calibration`]), so a consistent file is called
//! INCONSISTENT with probability below 10⁻³ (four checks; the S/N is not tested).
//!
//! The file is opened through [`read::check`] and read [`BLOCK_VALUES`] counts at a time:
//! memory grows with channels × bins, not with the profiles.

use std::path::Path;

use super::scene;
use super::statistics::{MIN_TOTAL_COUNTS, mean_z};
use super::{BinModel, BinReport, Report, Stat};
use crate::detector::{DeadTime, DeadTimeModel};
use crate::error::{Error, Result};
use crate::output::raw_file::read::{self, RawHeader};

mod reader;
mod sums;
use reader::{Reader, read_all};
use sums::{Channels, Sums};

/// Counts read at once (with their expectations: 8 bytes each, five arrays at most).
pub const BLOCK_VALUES: usize = 1 << 20;
/// Memory held per bin: the sums and the report.
const BYTES_PER_BIN: f64 = 1200.0;

/// The file's check and its report; `Err` for a file that is not a raw file or carries
/// impossible expectations (exit 2), never an INCONSISTENT verdict for those.
pub fn check_file(path: &Path) -> Result<(Report, Vec<String>)> {
    crate::input_file::check("--file", path)?;
    let f = hdf5::File::open(path)
        .map_err(|_| Error::output(path, "not a lidarsim raw file (not HDF5)"))?;
    let header = read::check(path, &f)?;
    let bins = header.counts_per_profile() as f64;
    header.require_memory(
        path,
        "checking its counts",
        bins * BYTES_PER_BIN + 48.0 * BLOCK_VALUES as f64,
    )?;
    let channels = channels(path, &f, &header)?;
    let mut reader = Reader::new(path, &f, &header)?;
    let mut sums = vec![Sums::default(); header.counts_per_profile()];
    let mut judged = vec![0usize; channels.names.len()];
    let rows = (BLOCK_VALUES / header.counts_per_profile()).max(1);
    for first in (0..header.n_profiles).step_by(rows) {
        let end = (first + rows).min(header.n_profiles);
        let block = reader.block(first..end, &channels.nominal_energy)?;
        block.validate(path, &header)?;
        block.accumulate(path, &channels, header.n_bins, &mut sums, &mut judged)?;
    }
    let names = &channels.names;
    let n_bins = header.n_bins;
    let altitude = reader.altitude()?;
    let bins: Vec<BinReport> = sums
        .iter()
        .enumerate()
        .map(|(j, s)| {
            let (k, i) = (j / n_bins, j % n_bins);
            bin_report(
                s,
                judged[k],
                &names[k],
                i,
                altitude[i],
                channels.dead[k].is_some(),
            )
        })
        .collect();
    let checks = super::statistics::verdicts(&bins);
    let notes = not_judged(&channels, &judged, header.n_profiles);
    if judged.iter().all(|&n| n == 0) {
        return Err(Error::output(
            path,
            format!(
                "no profile can be judged from the file alone: {}",
                notes.join("; ")
            ),
        ));
    }
    let report = Report {
        scenario: path.display().to_string(),
        method: reader.text_attr("method").unwrap_or_else(|| "?".into()),
        seed: f
            .attr("seed")
            .and_then(|a| a.read_scalar::<u64>())
            .unwrap_or(0),
        realizations: judged.iter().copied().max().unwrap_or(0),
        shots_per_profile: reader.first_shots,
        background_bins: 0,
        channels: names.clone(),
        consistent: checks.iter().all(|c| c.pass),
        bins,
        checks,
        warning: None,
    };
    Ok((report, notes))
}

/// One line per channel with profiles left out, and why.
fn not_judged(channels: &Channels, judged: &[usize], n: usize) -> Vec<String> {
    channels
        .names
        .iter()
        .zip(judged)
        .zip(&channels.dead)
        .filter(|&((_, &j), _)| j < n)
        .map(|((name, &j), dead)| {
            let why = if dead.is_some() {
                "a dead-time detector with a pulse energy other than the nominal one, or \
                 mixed columns"
            } else {
                "mixed columns with a varying pulse energy"
            };
            format!(
                "channel {name}: {} of {n} profiles not judged from the file alone ({why})",
                n - j
            )
        })
        .collect()
}

/// Refuses a file whose counts follow a law this check does not rebuild from the file:
/// analog codes (`acquisition_mode`), afterpulses (`expected_afterpulse`); their laws are
/// checked by `lidarsim validate CONFIG`.
fn refuse_other_laws(path: &Path, f: &hdf5::File, h: &RawHeader) -> Result<()> {
    let refuse = |channel: &str, what: &str| {
        Err(Error::Unsupported(format!(
            "{}: channel {channel} {what}, whose law validate --file does not rebuild from a \
             file (this version): validate the run's config instead (lidarsim validate \
             CONFIG; the file's `config` attribute holds it)",
            path.display()
        )))
    };
    if f.link_exists("acquisition_mode") {
        let modes = crate::output::raw_file::read::read_text(path, f, "acquisition_mode")?;
        if let Some(k) = modes.iter().position(|m| m == "analog") {
            return refuse(&h.channels[k], "records analog ADC codes");
        }
    }
    if f.link_exists("expected_afterpulse") {
        let ap = read_all(path, f, "expected_afterpulse")?;
        let n = ap.len() / h.channels.len().max(1);
        if let Some(i) = ap.iter().position(|&x| x != 0.0) {
            return refuse(&h.channels[i / n.max(1)], "afterpulses");
        }
    }
    Ok(())
}

/// The channels' names, reference energy and detectors, refused where impossible.
fn channels(path: &Path, f: &hdf5::File, h: &RawHeader) -> Result<Channels> {
    let bad = |why: String| Error::output(path, why);
    let energy = read_all(path, f, "nominal_pulse_energy")?;
    let tau = read_all(path, f, "dead_time")?;
    for (name, v) in [("nominal_pulse_energy", &energy), ("dead_time", &tau)] {
        if v.len() != h.channels.len() {
            return Err(bad(format!("`{name}` is not (channel)")));
        }
        if let Some(k) = v.iter().position(|x| !(x.is_finite() && *x >= 0.0)) {
            return Err(bad(format!(
                "`{name}` of channel {} is {}; it must be finite and not negative",
                h.channels[k], v[k]
            )));
        }
    }
    if energy[0] == 0.0 {
        return Err(bad(
            "`nominal_pulse_energy` of the first channel is 0".into()
        ));
    }
    refuse_other_laws(path, f, h)?;
    let pixels = match f.dataset("detector_pixels") {
        Ok(_) => {
            let p = read_all(path, f, "detector_pixels")?;
            let bad_pixel = |x: f64| {
                !(x >= 1.0 && x <= f64::from(crate::detector::MAX_PIXELS) && x.fract() == 0.0)
            };
            if p.len() != h.channels.len() {
                return Err(bad("`detector_pixels` is not (channel)".into()));
            }
            if let Some(k) = p.iter().position(|&x| bad_pixel(x)) {
                return Err(bad(format!(
                    "`detector_pixels` of channel {} is {}; it must be a whole number from 1 to {}",
                    h.channels[k],
                    p[k],
                    crate::detector::MAX_PIXELS
                )));
            }
            p.iter().map(|&x| x as u32).collect()
        }
        Err(_) => vec![1u32; tau.len()],
    };
    let dead = if tau.iter().any(|&t| t > 0.0) {
        let models = crate::output::raw_file::read::read_text(path, f, "dead_time_model")?;
        if models.len() != tau.len() {
            return Err(bad("`dead_time_model` is not (channel)".into()));
        }
        let width = f
            .attr("bin_width_s")
            .and_then(|a| a.read_scalar::<f64>())
            .ok()
            .filter(|w| w.is_finite() && *w > 0.0)
            .ok_or_else(|| bad("has no positive root attribute `bin_width_s`".into()))?;
        tau.iter()
            .zip(&models)
            .zip(&pixels)
            .map(|((&t, m), &pixels)| {
                let model = match m.as_str() {
                    "paralyzable" => DeadTimeModel::Paralyzable,
                    _ => DeadTimeModel::Nonparalyzable,
                };
                (t > 0.0).then_some(DeadTime {
                    tau_s: t,
                    model,
                    bin_width_s: width,
                    pixels,
                })
            })
            .collect()
    } else {
        vec![None; tau.len()]
    };
    Ok(Channels {
        names: h.channels.clone(),
        nominal_energy: energy,
        dead,
    })
}

/// One bin's statistics from its sums over `n` judged profiles (as [`super::scene`]).
fn bin_report(
    s: &Sums,
    n: usize,
    channel: &str,
    bin: usize,
    altitude_m: f64,
    dead: bool,
) -> BinReport {
    let nf = (n as f64).max(1.0);
    let (mu, var, v, var_y) = (s.mu.value(), s.var.value(), s.v.value(), s.var_y.value());
    let model = if dead {
        BinModel::recorded(0.0, 0.0, mu, var, 1.0)
    } else {
        BinModel::new(0.0, mu, 1.0, 0.0)
    };
    let (z, shape) = if n == 0 {
        (None, None)
    } else {
        mean_z(s.total, 1.0, &model)
    };
    let mean = Stat {
        empirical: s.total as f64 / nf,
        model: mu / nf,
        z,
        shape,
    };
    let enough = n > 0 && mu >= MIN_TOTAL_COUNTS && var_y > 0.0;
    let cumulants = [var_y, s.k3.value(), s.k4.value()];
    let variance = scene::variance_stat(v, var, cumulants, enough, nf);
    scene::mean_and_variance(channel, bin, altitude_m, mean, variance)
}

/// The checks' table, the channels not judged, and the verdict.
pub fn write_file_table(
    w: &mut dyn std::io::Write,
    r: &Report,
    notes: &[String],
) -> std::io::Result<()> {
    writeln!(
        w,
        "{} — counts against the file's own expectation: {} profiles judged (first of {} \
         shots), method {}, seed {}, channels {}",
        r.scenario,
        r.realizations,
        r.shots_per_profile,
        r.method,
        r.seed,
        r.channels.join(", ")
    )?;
    writeln!(w)?;
    super::report::write_body(w, r)?;
    for n in notes {
        writeln!(w, "{n}")?;
    }
    writeln!(
        w,
        "{}",
        if r.consistent {
            "CONSISTENT: the file's counts agree with the expectation and detector law it \
             carries (false-alarm rate < 1e-3)."
        } else {
            "INCONSISTENT: the file's counts depart from the expectation and detector law it \
             carries (false-alarm rate < 1e-3)."
        }
    )
}
