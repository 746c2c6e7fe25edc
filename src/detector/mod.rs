//! What the detector records of the photons that reach it (architecture: sampler →
//! detector → output). Absent for an ideal linear detector: a scene without dead time
//! has no detector stage and keeps every exact fast path.

pub mod counting;
pub mod dead_time;
pub mod modulated;

pub use dead_time::{DeadTime, DeadTimeModel};
pub use modulated::DetectedShots;

use crate::config::{Checker, ScenarioConfig};
use crate::error::Result;

/// Longest dead time a photon counter may have, s.
pub const MAX_DEAD_TIME_S: f64 = 1e-6;

/// Checks `[instrument.detector]`: a dead time from 0 to [`MAX_DEAD_TIME_S`].
pub fn validate(config: &ScenarioConfig, c: &Checker) -> Result<()> {
    if let Some(d) = &config.instrument.detector {
        c.range(
            "instrument.detector.dead_time_s",
            d.dead_time_s,
            0.0,
            MAX_DEAD_TIME_S,
        )?;
    }
    Ok(())
}

/// Count rate above which a photon counter without a dead-time model is out of its
/// linear range (a non-paralyzable τ = 3.5 ns loses 15 % at 50 MHz; the
/// non-paralyzable correction is fitted below ~50 MHz).
pub const LINEAR_RANGE_HZ: f64 = 50e6;

/// The one-line warning for a scene without dead time whose brightest bin exceeds
/// [`LINEAR_RANGE_HZ`]: `lambda` are the expected counts per shot per bin, `altitude_m`
/// the bin centres. `None` when every bin is within the range.
pub fn linear_range_warning(
    lambda: &[f64],
    altitude_m: &[f64],
    bin_width_s: f64,
) -> Option<String> {
    let (bin, &peak) = lambda
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.total_cmp(b.1))?;
    let rate = peak / bin_width_s;
    (rate > LINEAR_RANGE_HZ).then(|| {
        format!(
            "lidarsim: warning: bin {bin} ({:.2} km) counts {:.0} MHz, beyond a photon counter's \
             linear range (~{:.0} MHz); set instrument.detector.dead_time_s to simulate its dead time",
            altitude_m[bin] / 1e3,
            rate / 1e6,
            LINEAR_RANGE_HZ / 1e6
        )
    })
}
