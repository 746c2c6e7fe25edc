//! What the detector records of the photons that reach it (architecture: sampler →
//! detector → output). Absent for an ideal linear detector: a scene without dead time
//! has no detector stage and keeps every exact fast path.

pub mod dead_time;

pub use dead_time::{DeadTime, DeadTimeModel};

/// Count rate above which a photon counter without a dead-time model is out of its
/// linear range (a non-paralyzable τ = 3.5 ns loses 15 % at 50 MHz; field notes: the
/// non-paralyzable correction is fitted below ~50 MHz).
pub const LINEAR_RANGE_HZ: f64 = 50e6;
