//! Physical constants (CODATA 2018 exact SI values where defined) and Earth figures.
//! One source of truth: every module takes its constants from here.

/// Speed of light in vacuum, m s⁻¹ (exact, SI).
pub const SPEED_OF_LIGHT_M_PER_S: f64 = 299_792_458.0;
/// Planck constant, J s (exact, SI).
pub const PLANCK_J_S: f64 = 6.626_070_15e-34;
/// Boltzmann constant, J K⁻¹ (exact, SI).
pub const BOLTZMANN_J_PER_K: f64 = 1.380_649e-23;
/// Avogadro constant, mol⁻¹ (exact, SI).
pub const AVOGADRO_PER_MOL: f64 = 6.022_140_76e23;
/// Vacuum electric permittivity ε₀, F m⁻¹ (CODATA 2018).
pub const VACUUM_PERMITTIVITY_F_PER_M: f64 = 8.854_187_812_8e-12;
/// Mean Earth radius, m (IUGG mean radius R1).
pub const EARTH_RADIUS_M: f64 = 6_371_008.8;
/// Geocentric gravitational constant G·M_E, m³ s⁻² (WGS 84).
pub const EARTH_GM_M3_PER_S2: f64 = 3.986_004_418e14;
/// Earth's sidereal rotation rate ω_E, rad s⁻¹: 2π per sidereal day of 86 164.0905 s
/// (7.29211586e-5), rounded to the customary 8 digits.
pub const EARTH_ROTATION_RAD_PER_S: f64 = 7.292_115_9e-5;
/// One Dobson unit as a column number density, m⁻² (0.01 mm of pure ozone at
/// 273.15 K and 101 325 Pa: 2.6868e20 molecules per m²).
pub const DOBSON_UNIT_PER_M2: f64 = 2.6868e20;
