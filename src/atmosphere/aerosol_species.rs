//! The aerosol species of CAMS (`aermr01` … `aermr18`, the mass mixing ratios in ERA5 /
//! CAMS files), the IFS optical type each is given in ECMWF's aerosol optics tables
//! (`src/atmosphere/aerosol_optics_table.rs`), the relative humidity that picks a hydrophilic
//! type's bin, and each species' particle linear depolarization ratio, a lidar default
//! the tables do not give (docs/model.md §4l).

/// A type of ECMWF's aerosol optics table, 1-based as in ecRad's `i_aerosol_type_map`
/// (where a negative number is a hydrophilic type and a positive one a hydrophobic type).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum IfsType {
    /// Hydrophilic type `k` (1-based): optics per relative-humidity bin.
    Hydrophilic(usize),
    /// Hydrophobic type `k` (1-based): optics independent of humidity.
    Hydrophobic(usize),
}

impl IfsType {
    /// The number ecRad's `i_aerosol_type_map` writes for it: `-k` hydrophilic, `k`
    /// hydrophobic.
    pub fn ecrad_index(self) -> i64 {
        match self {
            IfsType::Hydrophilic(k) => -(k as i64),
            IfsType::Hydrophobic(k) => k as i64,
        }
    }
}

/// The particle shape class of a species, for its default depolarization.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DepolarizationClass {
    /// Mineral dust (non-spherical, large).
    Dust,
    /// Sea salt (marine aerosol, near-spherical when wet).
    Marine,
    /// Organic matter and black carbon (smoke).
    Smoke,
    /// Sulphate, nitrate, ammonium: spherical solution droplets.
    Spherical,
}

/// One CAMS aerosol species (a mass mixing ratio `aermrNN`, kg kg⁻¹).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CamsSpecies {
    /// ECMWF's short name, `aermr01` … `aermr18`.
    pub short_name: &'static str,
    /// What it is.
    pub description: &'static str,
    /// Its type in ECMWF's aerosol optics table; None: no optics (a gas precursor or a
    /// type the IFS radiation does not map).
    pub ifs_type: Option<IfsType>,
    /// The two-letter codes ECMWF's tables give that type (`code_hydrophilic` /
    /// `code_hydrophobic`), checked against the table read: nitrate is `NI` in
    /// `aerosol_ifs_rrtm_49R1.nc` but `NF` (fine) and `NC` (coarse) in
    /// `aerosol_ifs_rrtm_46R1_with_NI_AM.nc`, the types the same.
    pub codes: &'static [&'static str],
    /// Its class for the default depolarization ([`particle_depolarization`]).
    pub depolarization_class: DepolarizationClass,
}

use DepolarizationClass as D;
use IfsType::{Hydrophilic as Philic, Hydrophobic as Phobic};

const fn species(
    short_name: &'static str,
    description: &'static str,
    ifs_type: Option<IfsType>,
    codes: &'static [&'static str],
    depolarization_class: DepolarizationClass,
) -> CamsSpecies {
    CamsSpecies {
        short_name,
        description,
        ifs_type,
        codes,
        depolarization_class,
    }
}

/// The CAMS species and their IFS types.
///
/// `aermr01` … `aermr11` are the IFS's first eleven aerosol classes, mapped as ecRad's
/// IFS namelist for cycle 49R1 maps them: `test/ifs/configCY49R1.nam` line 90,
/// `i_aerosol_type_map = -1, -2, -3, 7, 8, 9, -4, 10, 11, 11, -5, 14` (the same in
/// `ifs/radiation_setup.F90`, lines ~290–302, of github.com/ecmwf-ifs/ecrad): sea salt bins
/// 1–3 → hydrophilic 1–3 (OPAC), dust bins 1–3 → hydrophobic 7–9 (Woodward 2001),
/// hydrophilic organic matter → hydrophilic 4, hydrophobic organic matter → hydrophobic
/// 10, both black carbons → hydrophobic 11 (OPAC), sulphate → hydrophilic 5 (GACP
/// ammonium sulphate). The map's 12th class (hydrophobic 14, stratospheric sulphate) is
/// marked "climatology only" there: CAMS's `aermr12` is the SO₂ precursor, a gas, given
/// no optics here; `aermr13` … `aermr15` are in no ecRad map either.
///
/// `aermr16` … `aermr18` (nitrate fine and coarse, ammonium) are in no ecRad namelist;
/// they take the types ECMWF's 46R1-and-later tables describe for them
/// (`description_hydrophilic` of `aerosol_ifs_rrtm_49R1.nc`: 8 "Fine mode Ammonium
/// sulfate (for ammonia)", 9 "Fine mode Nitrate", 10 "Coarse mode Nitrate"; the same
/// in `aerosol_ifs_rrtm_46R1_with_NI_AM.nc`, the IFS's default table in
/// `ifs/radiation_setup.F90`).
pub const CAMS_SPECIES: [CamsSpecies; 18] = [
    species(
        "aermr01",
        "sea salt, 0.03-0.5 um",
        Some(Philic(1)),
        &["SS"],
        D::Marine,
    ),
    species(
        "aermr02",
        "sea salt, 0.5-5 um",
        Some(Philic(2)),
        &["SS"],
        D::Marine,
    ),
    species(
        "aermr03",
        "sea salt, 5-20 um",
        Some(Philic(3)),
        &["SS"],
        D::Marine,
    ),
    species(
        "aermr04",
        "dust, 0.03-0.55 um",
        Some(Phobic(7)),
        &["DD"],
        D::Dust,
    ),
    species(
        "aermr05",
        "dust, 0.55-0.9 um",
        Some(Phobic(8)),
        &["DD"],
        D::Dust,
    ),
    species(
        "aermr06",
        "dust, 0.9-20 um",
        Some(Phobic(9)),
        &["DD"],
        D::Dust,
    ),
    species(
        "aermr07",
        "hydrophilic organic matter",
        Some(Philic(4)),
        &["OM"],
        D::Smoke,
    ),
    species(
        "aermr08",
        "hydrophobic organic matter",
        Some(Phobic(10)),
        &["OM"],
        D::Smoke,
    ),
    species(
        "aermr09",
        "hydrophilic black carbon",
        Some(Phobic(11)),
        &["BC"],
        D::Smoke,
    ),
    species(
        "aermr10",
        "hydrophobic black carbon",
        Some(Phobic(11)),
        &["BC"],
        D::Smoke,
    ),
    species(
        "aermr11",
        "sulphate",
        Some(Philic(5)),
        &["SU"],
        D::Spherical,
    ),
    species("aermr12", "SO2 precursor (a gas)", None, &[], D::Spherical),
    species(
        "aermr13",
        "aerosol type 13 (not mapped)",
        None,
        &[],
        D::Spherical,
    ),
    species(
        "aermr14",
        "aerosol type 14 (not mapped)",
        None,
        &[],
        D::Spherical,
    ),
    species(
        "aermr15",
        "aerosol type 15 (not mapped)",
        None,
        &[],
        D::Spherical,
    ),
    species(
        "aermr16",
        "nitrate, fine mode",
        Some(Philic(9)),
        &["NI", "NF"],
        D::Spherical,
    ),
    species(
        "aermr17",
        "nitrate, coarse mode",
        Some(Philic(10)),
        &["NI", "NC"],
        D::Spherical,
    ),
    species(
        "aermr18",
        "ammonium",
        Some(Philic(8)),
        &["AM"],
        D::Spherical,
    ),
];

impl CamsSpecies {
    /// The species of ECMWF short name `name` (`aermr01` … `aermr18`, case as ECMWF
    /// writes it).
    pub fn from_short_name(name: &str) -> Option<CamsSpecies> {
        CAMS_SPECIES.iter().copied().find(|s| s.short_name == name)
    }
}

/// Water vapour's molar mass over dry air's, `ε = M_w/M_d = R_dry/R_vap` (0.62198 from
/// the IFS's `R_dry` = 287.0597, `R_vap` = 461.5250 J kg⁻¹ K⁻¹), to three figures.
pub const EPSILON: f64 = 0.622;

/// Saturation vapour pressure over liquid water, Pa, by the Tetens formula as the IFS
/// uses it: `e_s = a₁ exp(a₃ (T − T₀)/(T − a₄))`, `a₁ = 611.21 Pa`, `a₃ = 17.502`,
/// `a₄ = 32.19 K`, `T₀ = 273.16 K` (IFS Documentation, Part IV: Physical processes,
/// chapter 7, Eq. 7.5 (Cy41r2; p. 116 of Cy45r1), after Buck 1981). Over water at every
/// temperature, as ecRad takes the humidity that picks the aerosols' bin
/// (`radiation/radiation_thermodynamics.F90`, `calc_saturation_wrt_liquid`, with its own
/// Tetens constants 611 Pa, 17.269, 35.86 K: within 0.04 % of these from 273 to 303 K).
pub fn saturation_vapour_pressure_over_water_pa(temperature_k: f64) -> f64 {
    611.21 * (17.502 * (temperature_k - 273.16) / (temperature_k - 32.19)).exp()
}

/// Relative humidity over liquid water, 0–1, from specific humidity `q` (kg kg⁻¹),
/// temperature (K) and pressure (Pa): the vapour pressure `e = q·p/(ε + (1 − ε)q)`
/// (from `q = ε e/(p − (1 − ε) e)`, ε = [`EPSILON`]) over
/// [`saturation_vapour_pressure_over_water_pa`], clipped to `[0, 1]` (a supersaturated or
/// negative value, as models' q can be, takes the last or first bin anyway: see
/// `AerosolOpticsTable::rh_bin` in `src/atmosphere/aerosol_optics_table.rs`). NaN if an input is not
/// finite.
pub fn relative_humidity_over_water(
    specific_humidity_kg_per_kg: f64,
    temperature_k: f64,
    pressure_pa: f64,
) -> f64 {
    let q = specific_humidity_kg_per_kg;
    if !(q.is_finite() && temperature_k.is_finite() && pressure_pa.is_finite()) {
        return f64::NAN;
    }
    let e = q * pressure_pa / (EPSILON + (1.0 - EPSILON) * q);
    (e / saturation_vapour_pressure_over_water_pa(temperature_k)).clamp(0.0, 1.0)
}

/// The wavelengths at which [`particle_depolarization`] has defaults, m.
pub const DEPOLARIZATION_WAVELENGTHS_M: [f64; 3] = [355e-9, 532e-9, 1064e-9];

/// The default particle linear depolarization ratio `δ_p = β_⊥/β_∥` of a species at 355,
/// 532 or 1064 nm (within 0.5 nm); None at another wavelength. Defaults, not part of
/// ECMWF's tables (which assume spheres or give no polarization), to be overridden by
/// whoever knows better:
///
/// * dust 0.25, 0.31, 0.27: Freudenthaler et al. (2009, Tellus B 61, 165–179), pure
///   Saharan dust over Ouarzazate during SAMUM-1: mean 0.31 at 532 nm (range 0.27–0.35),
///   falling to 0.27 ± 0.04 at 1064 nm (abstract, p. 165); 0.25 at 355 nm, the lower UV
///   value the paper's lidars gave (its Sect. 5; the exact table was not re-checked);
/// * marine (sea salt) 0.02 at all three: Groß et al. (2011, Tellus B 63, 706–724),
///   SAMUM-2 marine boundary layer over Cape Verde, `δ_p = 0.02 ± 0.02` at 355 and 532 nm
///   (abstract, p. 706); carried to 1064 nm unmeasured;
/// * smoke (organic matter, black carbon) 0.05: aged biomass-burning smoke, Burton et al.
///   (2012, Atmos. Meas. Tech. 5, 73–98: smoke's mean `δ_532` of about 0.05 among their
///   aerosol types; the table was not re-checked), also at 355 and 1064 nm;
/// * sulphate, nitrate, ammonium 0.0: spherical solution droplets depolarize nothing
///   (Lorenz–Mie).
pub fn particle_depolarization(species: &CamsSpecies, wavelength_m: f64) -> Option<f64> {
    let k = DEPOLARIZATION_WAVELENGTHS_M
        .iter()
        .position(|w| (w - wavelength_m).abs() <= 0.5e-9)?;
    let by_wavelength = match species.depolarization_class {
        D::Dust => [0.25, 0.31, 0.27],
        D::Marine => [0.02, 0.02, 0.02],
        D::Smoke => [0.05, 0.05, 0.05],
        D::Spherical => [0.0, 0.0, 0.0],
    };
    Some(by_wavelength[k])
}

/// The particle linear depolarization ratio of `species` at `wavelength_m`: the
/// config's override for its class (`scene.model_fields.aerosol_depolarization`, at every
/// wavelength) where given, else [`particle_depolarization`]'s default; None where
/// neither gives one.
pub fn particle_depolarization_or(
    species: &CamsSpecies,
    wavelength_m: f64,
    overrides: &crate::config::AerosolDepolarization,
) -> Option<f64> {
    let given = match species.depolarization_class {
        D::Dust => overrides.dust,
        D::Marine => overrides.marine,
        D::Smoke => overrides.smoke,
        D::Spherical => overrides.sulphate,
    };
    given.or_else(|| particle_depolarization(species, wavelength_m))
}

/// Checks `scene.model_fields.aerosol_species`: each name a CAMS species with optics (the
/// config's owner check, `src/loaded.rs`).
pub fn validate(
    config: &crate::config::ScenarioConfig,
    c: &crate::config::Checker,
) -> crate::error::Result<()> {
    let names = config
        .scene
        .as_ref()
        .and_then(|s| s.model_fields.as_ref())
        .and_then(|m| m.aerosol_species.as_ref());
    for n in names.into_iter().flatten() {
        let known = CamsSpecies::from_short_name(n);
        if known.is_none_or(|s| s.ifs_type.is_none()) {
            return Err(c.fail(
                "scene.model_fields.aerosol_species",
                format!(
                    "`{n}` is not a CAMS species with optics (aermr01 … aermr11, \
                     aermr16 … aermr18 as ECMWF's tables map them)"
                ),
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn short_names_run_in_order_and_types_are_in_the_49r1_map() {
        for (k, s) in CAMS_SPECIES.iter().enumerate() {
            assert_eq!(s.short_name, format!("aermr{:02}", k + 1));
        }
        let map: Vec<i64> = CAMS_SPECIES[..11]
            .iter()
            .map(|s| s.ifs_type.unwrap().ecrad_index())
            .collect();
        assert_eq!(map, [-1, -2, -3, 7, 8, 9, -4, 10, 11, 11, -5]);
    }

    #[test]
    fn saturation_at_the_triple_point_is_a1() {
        assert_eq!(saturation_vapour_pressure_over_water_pa(273.16), 611.21);
    }
}
