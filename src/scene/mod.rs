//! The world along the track: where the platform is at each shot (a circular orbit's
//! sub-satellite point) and where the sun is (solar zenith angle, daylight radiance).
//!
//! These modules are pure functions of time and place; they know nothing of configs.

pub mod orbit;
pub mod sun;
