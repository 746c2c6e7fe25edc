//! The method of a run: `auto` resolved by the scene and the cost of each method, and what
//! the scene's detector refuses.

use crate::config::Method;
use crate::error::{Error, Result};
use crate::sampling::ShotSampler;
use crate::sampling::approx;
use crate::scenario::{ExpectedProfile, Lidar};

/// The method actually used for a run (after `auto` is resolved).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ResolvedMethod {
    /// Every shot drawn.
    Shot,
    /// One exact Poisson(M·λ) draw per bin per profile.
    Aggregate,
    /// As `Aggregate`, but bins with `M·λ ≥ threshold` draw the normal approximation
    /// (`sampling::approx`), whose KS distance to the exact law is at most the tolerance
    /// that set the threshold. Only chosen by `auto` with a tolerance.
    AggregateNormal {
        /// Smallest mean drawn by the approximation, `approx::normal_threshold(tolerance)`.
        threshold: f64,
    },
}

impl ResolvedMethod {
    /// The name stored in the file's `method` attribute.
    pub fn name(self) -> &'static str {
        match self {
            ResolvedMethod::Shot => "shot",
            ResolvedMethod::Aggregate => "aggregate",
            ResolvedMethod::AggregateNormal { .. } => "aggregate-normal",
        }
    }

    /// The method a file's `method` attribute names (`threshold`: its
    /// `normal_approximation_threshold`, for `aggregate-normal`).
    pub fn from_name(name: &str, threshold: Option<f64>) -> Option<Self> {
        match (name, threshold) {
            ("shot", _) => Some(ResolvedMethod::Shot),
            ("aggregate", _) => Some(ResolvedMethod::Aggregate),
            ("aggregate-normal", Some(threshold)) => {
                Some(ResolvedMethod::AggregateNormal { threshold })
            }
            _ => None,
        }
    }
}

/// Approximate cost of one profile by each method, ns (constants measured in
/// `validation/reports/speed_vs_error.md`; the shot path's from its own cost model).
pub(super) mod cost {
    /// An exact aggregate draw with `M·λ < 12` (inversion).
    pub const AGGREGATE_SMALL_NS: f64 = 28.0;
    /// An exact aggregate draw with `M·λ ≥ 12` (Ahrens–Dieter).
    pub const AGGREGATE_LARGE_NS: f64 = 45.0;
    /// One normal-approximation draw.
    pub const NORMAL_NS: f64 = 14.0;
}

/// `auto` with a tolerance (KS distance per bin): the fastest of `shot`, `aggregate` and
/// `aggregate-normal` whose error is within it, by the cost constants above. `shot`
/// only where the scene needs it or where it is cheaper (sparse profiles of few shots).
pub fn fastest_within(
    tolerance: f64,
    e: &ExpectedProfile,
    shots: u64,
    aggregate_allowed: bool,
) -> ResolvedMethod {
    fastest_within_totals(tolerance, &e.total_per_shot(), shots, aggregate_allowed)
}

/// [`fastest_within`] for the per-shot totals of every bin of every channel.
pub fn fastest_within_totals(
    tolerance: f64,
    totals: &[f64],
    shots: u64,
    aggregate_allowed: bool,
) -> ResolvedMethod {
    if !aggregate_allowed {
        return ResolvedMethod::Shot;
    }
    let means: Vec<f64> = totals.iter().map(|l| l * shots as f64).collect();
    let exact = |m: f64| {
        if m < 12.0 {
            cost::AGGREGATE_SMALL_NS
        } else {
            cost::AGGREGATE_LARGE_NS
        }
    };
    let threshold = approx::normal_threshold(tolerance);
    let aggregate: f64 = means.iter().map(|&m| exact(m)).sum();
    let normal: f64 = means
        .iter()
        .map(|&m| {
            if m >= threshold {
                cost::NORMAL_NS
            } else {
                exact(m)
            }
        })
        .sum();
    let shot = ShotSampler::new(totals).strategy().est_ns_per_shot * shots as f64;
    let candidates = [
        (shot, ResolvedMethod::Shot),
        (aggregate, ResolvedMethod::Aggregate),
        (normal, ResolvedMethod::AggregateNormal { threshold }),
    ];
    // ties go to the exact method listed first
    candidates
        .into_iter()
        .fold((f64::INFINITY, ResolvedMethod::Aggregate), |best, c| {
            if c.0 < 0.8 * best.0 { c } else { best }
        })
        .1
}

/// What the scene needs drawn shot by shot; `None` when the profile's counts are
/// Poisson given the emitted energies (the detector is linear), so that `aggregate` is
/// exact: pulse-energy jitter and drift are drawn as the profile's summed energy.
pub fn per_shot_reason(lidar: &Lidar) -> Option<&'static str> {
    lidar
        .channels
        .iter()
        .any(|c| c.instrument.dead_time.is_some())
        .then_some("detector dead time makes the recorded counts non-Poisson")
}

/// Resolves `auto`, and refuses `aggregate` where it would not be exact.
pub fn resolve_method(requested: Method, lidar: &Lidar) -> Result<ResolvedMethod> {
    match (requested, per_shot_reason(lidar)) {
        (Method::Shot, _) | (Method::Auto, Some(_)) => Ok(ResolvedMethod::Shot),
        (Method::Aggregate | Method::Auto, None) => Ok(ResolvedMethod::Aggregate),
        (Method::Aggregate, Some(why)) => Err(Error::Unsupported(format!(
            "--method aggregate is not exact for this scene ({why}); use --method shot or auto"
        ))),
    }
}

/// What this version does not combine with dead time: component counts (a recorded
/// count is not a sum of parts).
pub fn check_detector(lidar: &Lidar, components: bool) -> Result<()> {
    let dead = lidar
        .channels
        .iter()
        .any(|c| c.instrument.dead_time.is_some());
    if dead && components {
        return Err(Error::Unsupported(
            "--components is not available with dead time: a recorded count is not a sum of \
             signal, background and dark counts"
                .into(),
        ));
    }
    if components
        && lidar
            .channels
            .iter()
            .any(|c| c.instrument.afterpulsing.is_some())
    {
        return Err(Error::Unsupported(
            "--components is not available with afterpulsing: an afterpulse is neither \
             signal, background nor dark"
                .into(),
        ));
    }
    if components && lidar.channels.iter().any(|c| c.instrument.analog.is_some()) {
        return Err(Error::Unsupported(
            "--components is not available with an analog detector: an ADC code is not a sum \
             of signal, background and dark counts"
                .into(),
        ));
    }
    Ok(())
}
