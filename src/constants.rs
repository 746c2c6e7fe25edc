//! Physical constants (CODATA 2018 exact SI values where defined) and Earth figures.
//! One source of truth: every module takes its constants from here.

/// Speed of light in vacuum, m s⁻¹ (exact, SI).
pub const SPEED_OF_LIGHT_M_PER_S: f64 = 299_792_458.0;
/// Planck constant, J s (exact, SI).
pub const PLANCK_J_S: f64 = 6.626_070_15e-34;
/// Boltzmann constant, J K⁻¹ (exact, SI).
pub const BOLTZMANN_J_PER_K: f64 = 1.380_649e-23;
/// Mean Earth radius, m (IUGG mean radius R1).
pub const EARTH_RADIUS_M: f64 = 6_371_008.8;
/// Geocentric gravitational constant G·M_E, m³ s⁻² (WGS 84).
pub const EARTH_GM_M3_PER_S2: f64 = 3.986_004_418e14;
