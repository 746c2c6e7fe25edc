//! The variable names of each model's files (the shipped mapping, overridable by
//! `[scene.model_fields.variables]`) and the units each role accepts, with the factor
//! to this module's SI units. Units are read from each variable's `units` attribute and
//! never guessed: a unit not listed here is refused.

use crate::config::FieldsModel;

/// Candidate names of `role` in `model`'s files, first match wins (none: not given).
pub fn candidates(model: FieldsModel, role: &str) -> &'static [&'static str] {
    use FieldsModel::{Cams, Era5, Icon, Merra2};
    match (model, role) {
        // IFS names (ERA5 and CAMS from the Climate / Atmosphere Data Store); the
        // hybrid coefficients as cdo writes them from GRIB (`hyam`, `hybm`, Pa and 1)
        (Era5 | Cams, "temperature") => &["t"],
        (Era5 | Cams, "specific_humidity") => &["q"],
        (Era5 | Cams, "liquid") => &["clwc"],
        (Era5 | Cams, "ice") => &["ciwc"],
        (Era5 | Cams, "cloud_fraction") => &["cc"],
        (Era5 | Cams, "surface_pressure") => &["sp"],
        (Era5 | Cams, "geopotential" | "surface_geopotential") => &["z"],
        (Era5 | Cams, "hybrid_a") => &["hyam", "a"],
        (Era5 | Cams, "hybrid_b") => &["hybm", "b"],
        // MERRA-2 (M2I3NVASM: T, QV, QL, QI, PS, PL, H, PHIS; M2T3NVRAD: CLOUD)
        (Merra2, "temperature") => &["T"],
        (Merra2, "specific_humidity") => &["QV"],
        (Merra2, "liquid") => &["QL"],
        (Merra2, "ice") => &["QI"],
        (Merra2, "cloud_fraction") => &["CLOUD"],
        (Merra2, "surface_pressure") => &["PS"],
        (Merra2, "pressure") => &["PL"],
        (Merra2, "height") => &["H"],
        (Merra2, "surface_geopotential") => &["PHIS"],
        // ICON regridded output (DWD names)
        (Icon, "temperature") => &["temp"],
        (Icon, "specific_humidity") => &["qv"],
        (Icon, "liquid") => &["qc"],
        (Icon, "ice") => &["qi"],
        (Icon, "cloud_fraction") => &["clc"],
        (Icon, "surface_pressure") => &["pres_sfc"],
        (Icon, "pressure") => &["pres"],
        (Icon, "height") => &["z_mc"],
        (_, "latitude") => &["latitude", "lat"],
        (_, "longitude") => &["longitude", "lon"],
        (_, "time") => &["time", "valid_time"],
        (_, "level") => &[
            "level",
            "model_level",
            "pressure_level",
            "lev",
            "plev",
            "height",
        ],
        _ => &[],
    }
}

/// What a role measures, which sets the units it accepts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Quantity {
    /// Kelvin.
    Temperature,
    /// Pa.
    Pressure,
    /// kg kg⁻¹.
    MixingRatio,
    /// 0–1.
    Fraction,
    /// m² s⁻² (geopotential).
    Geopotential,
    /// m.
    Length,
    /// µm (effective radii).
    Radius,
    /// Dimensionless (hybrid b).
    One,
    /// degrees north.
    Latitude,
    /// degrees east.
    Longitude,
}

/// The quantity of `role` (`level` and `time` are read by their own rules).
pub fn quantity(role: &str) -> Option<Quantity> {
    use Quantity as Q;
    Some(match role {
        "temperature" => Q::Temperature,
        "surface_pressure" | "pressure" | "hybrid_a" => Q::Pressure,
        "specific_humidity" | "liquid" | "ice" | "aerosol" => Q::MixingRatio,
        "cloud_fraction" => Q::Fraction,
        "geopotential" | "surface_geopotential" => Q::Geopotential,
        "height" => Q::Length,
        "liquid_effective_radius" | "ice_effective_radius" => Q::Radius,
        "hybrid_b" => Q::One,
        "latitude" => Q::Latitude,
        "longitude" => Q::Longitude,
        _ => return None,
    })
}

/// The factor from `units` to the quantity's unit (K, Pa, kg/kg, 1, m² s⁻², m, µm,
/// degrees), or why the units are refused.
pub fn factor(q: Quantity, units: &str) -> Result<f64, String> {
    let u: String = units.split_whitespace().collect::<Vec<_>>().join(" ");
    let f = match (q, u.as_str()) {
        (Quantity::Temperature, "K" | "kelvin" | "Kelvin" | "degK") => Some(1.0),
        (Quantity::Pressure, "Pa" | "pascal") => Some(1.0),
        (Quantity::Pressure, "hPa" | "mbar" | "millibars" | "millibar" | "mb") => Some(100.0),
        (Quantity::MixingRatio, "kg kg**-1" | "kg kg-1" | "kg/kg" | "kg kg^-1" | "1") => Some(1.0),
        (Quantity::MixingRatio, "g kg**-1" | "g kg-1" | "g/kg") => Some(1e-3),
        (Quantity::Fraction, "(0 - 1)" | "0-1" | "1" | "fraction") => Some(1.0),
        (Quantity::Fraction, "%" | "percent") => Some(0.01),
        (Quantity::Geopotential, "m**2 s**-2" | "m2 s-2" | "m^2 s^-2" | "m2/s2") => Some(1.0),
        (Quantity::Length, "m" | "metre" | "meter" | "metres" | "meters") => Some(1.0),
        (Quantity::Length, "km") => Some(1e3),
        (Quantity::Radius, "m") => Some(1e6),
        (Quantity::Radius, "um" | "µm" | "micron" | "microns" | "micrometer") => Some(1.0),
        (Quantity::One, "1" | "" | "dimensionless") => Some(1.0),
        (Quantity::Latitude, "degrees_north" | "degree_north" | "degrees_N" | "degree_N") => {
            Some(1.0)
        }
        (Quantity::Longitude, "degrees_east" | "degree_east" | "degrees_E" | "degree_E") => {
            Some(1.0)
        }
        _ => None,
    };
    f.ok_or_else(|| format!("units {units:?} are not units of {}", name(q)))
}

/// The quantity in words for messages.
fn name(q: Quantity) -> &'static str {
    match q {
        Quantity::Temperature => "temperature (K)",
        Quantity::Pressure => "pressure (Pa, hPa)",
        Quantity::MixingRatio => "a mass mixing ratio (kg kg**-1, g kg**-1)",
        Quantity::Fraction => "a fraction ((0 - 1), 1, %)",
        Quantity::Geopotential => "geopotential (m**2 s**-2)",
        Quantity::Length => "height (m, km)",
        Quantity::Radius => "an effective radius (m, um)",
        Quantity::One => "a dimensionless coefficient (1)",
        Quantity::Latitude => "latitude (degrees_north)",
        Quantity::Longitude => "longitude (degrees_east)",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn units_are_read_not_guessed() {
        assert_eq!(factor(Quantity::Pressure, "hPa"), Ok(100.0));
        assert_eq!(factor(Quantity::MixingRatio, "kg  kg**-1"), Ok(1.0));
        assert_eq!(factor(Quantity::Fraction, "%"), Ok(0.01));
        let e = factor(Quantity::Temperature, "degC").unwrap_err();
        assert!(e.contains("\"degC\" are not units of temperature"), "{e}");
        assert!(factor(Quantity::MixingRatio, "").is_err());
    }
}
