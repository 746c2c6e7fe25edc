//! The world along the track: where the platform is at each shot (a circular orbit's
//! sub-satellite point) and where the sun is (solar zenith angle, daylight radiance: the sunlight reflected below and the
//! air's scattered sunlight, `sky`).
//!
//! `orbit` and `sun` are pure functions of time and place; `track` lays the scene's
//! segments and broken cloud along the track.

pub mod curtain;
pub mod fields;
pub mod orbit;
pub mod sky;
pub mod sun;
pub mod track;
