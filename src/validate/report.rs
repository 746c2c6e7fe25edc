//! What a validation reports: each statistic per bin ([`Stat`], [`BinReport`]), the whole
//! [`Report`], and its table for a person.

use std::io::Write;

use serde::Serialize;

use super::calibration::{Check, Shape};

/// The result of one statistic in one bin.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Stat {
    /// Empirical value.
    pub empirical: f64,
    /// Model value.
    pub model: f64,
    /// z-score from the statistic's sampling distribution (None: not tested here).
    pub z: Option<f64>,
    /// The law of z under the model, where it departs from the normal.
    #[serde(skip)]
    pub shape: Option<Shape>,
}

impl Stat {
    /// A statistic this check does not compute (NaN values, shown as "-"; no z).
    pub fn untested() -> Stat {
        Stat {
            empirical: f64::NAN,
            model: f64::NAN,
            z: None,
            shape: None,
        }
    }
}

/// Everything measured in one bin.
#[derive(Debug, Clone, Serialize)]
pub struct BinReport {
    /// The receiver channel.
    pub channel: String,
    /// Bin index within the channel.
    pub bin: usize,
    /// Bin-centre altitude, m.
    pub altitude_m: f64,
    /// Mean accumulated count.
    pub mean: Stat,
    /// Variance of the accumulated count.
    pub variance: Stat,
    /// S/N with the background known (Eq. 4).
    pub snr_known_background: Stat,
    /// S/N with the background estimated from `n_b` bins.
    pub snr_estimated_background: Stat,
}

/// The whole validation.
#[derive(Debug, Clone, Serialize)]
pub struct Report {
    /// Scenario name.
    pub scenario: String,
    /// Method used.
    pub method: String,
    /// Seed.
    pub seed: u64,
    /// Realizations (profiles) drawn.
    pub realizations: usize,
    /// Shots per profile.
    pub shots_per_profile: u64,
    /// Signal-free bins used to estimate the background.
    pub background_bins: usize,
    /// The receiver channels validated.
    pub channels: Vec<String>,
    /// Per-bin results.
    pub bins: Vec<BinReport>,
    /// Verdicts per statistic.
    pub checks: Vec<Check>,
    /// Whether every check passed.
    pub consistent: bool,
    /// A warning about the scene (rates beyond a photon counter's range), if any.
    #[serde(skip)]
    pub warning: Option<String>,
}

/// A table for a person: the verdicts, then the bins that fell outside their interval.
pub fn write_table(w: &mut dyn Write, r: &Report) -> std::io::Result<()> {
    writeln!(
        w,
        "{} — {} realizations of {} shots, method {}, seed {}, {} background bins{}",
        r.scenario,
        r.realizations,
        r.shots_per_profile,
        r.method,
        r.seed,
        r.background_bins,
        if r.channels.len() > 1 {
            format!(", channels {}", r.channels.join(", "))
        } else {
            String::new()
        }
    )?;
    writeln!(w)?;
    write_body(w, r)?;
    writeln!(
        w,
        "{}",
        if r.consistent {
            "CONSISTENT: the simulated counts agree with the model (Poisson and Eq. 4; the \
             detector's law of docs/model.md §4b for dead time and analog records)."
        } else {
            "INCONSISTENT: at least one statistic departs from the model (false-alarm rate < 2e-3)."
        }
    )
}

/// The verdicts' table and a sample of the bins, then a blank line.
pub(super) fn write_body(w: &mut dyn Write, r: &Report) -> std::io::Result<()> {
    writeln!(
        w,
        "{:<26} {:>6} {:>8} {:>8} {:>12} {:>10}  verdict",
        "statistic", "bins", "outside", "allowed", "sum z^2", "p"
    )?;
    for c in &r.checks {
        writeln!(
            w,
            "{:<26} {:>6} {:>8} {:>8} {:>12.1} {:>10.3e}  {}",
            c.statistic,
            c.bins_tested,
            c.outside,
            c.outside_allowed,
            c.chi_square,
            c.chi_square_p,
            if c.pass { "ok" } else { "INCONSISTENT" }
        )?;
    }
    writeln!(w)?;
    let several = r.channels.len() > 1;
    let width = r.channels.iter().map(String::len).max().unwrap_or(0);
    let label = |c: &str| {
        if several {
            format!("{c:<width$} ")
        } else {
            String::new()
        }
    };
    writeln!(
        w,
        "{}{:>9} {:>12} {:>12} {:>8} {:>12} {:>8} {:>9} {:>9} {:>7}",
        label("channel"),
        "alt (km)",
        "mean",
        "model",
        "z",
        "variance",
        "z",
        "S/N",
        "Eq. 4",
        "z"
    )?;
    let z = |s: &Stat| {
        s.z.map(|z| format!("{z:8.2}"))
            .unwrap_or_else(|| format!("{:>8}", "-"))
    };
    // an S/N not computed (`validate --file`) shows as "-", never as NaN
    let snr = |x: f64| {
        if x.is_finite() {
            format!("{x:9.3}")
        } else {
            format!("{:>9}", "-")
        }
    };
    let step = (r.bins.len() / 40).max(1);
    for b in r.bins.iter().step_by(step) {
        writeln!(
            w,
            "{}{:9.3} {:12.5e} {:12.5e} {} {:12.5e} {} {} {} {}",
            label(&b.channel),
            b.altitude_m / 1e3,
            b.mean.empirical,
            b.mean.model,
            z(&b.mean),
            b.variance.empirical,
            z(&b.variance),
            snr(b.snr_known_background.empirical),
            snr(b.snr_known_background.model),
            z(&b.snr_known_background)
        )?;
    }
    if step > 1 {
        writeln!(w, "(every {step}th bin shown; --json has all)")?;
    }
    writeln!(w)
}
