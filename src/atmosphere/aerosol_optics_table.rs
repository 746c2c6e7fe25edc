//! ECMWF's aerosol optics table, as ECMWF distributes it with ecRad
//! (`aerosol_ifs_rrtm_*.nc`, netCDF-3 classic; a netCDF-4 copy reads too): per
//! aerosol type, the monochromatic mass extinction coefficient and lidar ratio, the
//! hydrophilic types' per relative-humidity bin (docs/model.md §4l). lidarsim ships no
//! copy of it nor its numbers; `configs/fields/aerosol_optics_like_ifs.nc` is a made-up
//! table in its layout (`tools/make_aerosol_optics_table.py`).
//!
//! The layout, as ecRad reads it (`radiation/radiation_aerosol_optics_data.F90`,
//! `setup`, "Read the monochromatic scattering data at selected wavelengths"):
//! `wavelength_mono(wavelength_mono)` in m; `relative_humidity1(relative_humidity)`,
//! the bins' lower bounds (1 = saturation), and `relative_humidity2` their upper ones;
//! `mass_ext_mono_hydrophobic(hydrophobic, wavelength_mono)` (m² kg⁻¹),
//! `lidar_ratio_mono_hydrophobic(hydrophobic, wavelength_mono)` (sr),
//! `mass_ext_mono_hydrophilic(hydrophilic, relative_humidity, wavelength_mono)` and
//! `lidar_ratio_mono_hydrophilic(…)` likewise (netCDF's C order; ecRad's Fortran arrays
//! are the same dimensioned `(n_mono_wl, nrh, n_type)`), and the types' codes in
//! `code_hydrophilic` / `code_hydrophobic` (2 characters each: `SS`, `DD`, …).

use std::path::{Path, PathBuf};

use super::aerosol_species::{CamsSpecies, IfsType};
use crate::error::{Error, Result};
use crate::scene::fields::reader::{Files, Var};

/// The relative tolerance to which a requested wavelength must equal one of the table's
/// `wavelength_mono` (stored as float32, 6e-8 relative): an exact match, no interpolation.
pub const WAVELENGTH_MATCH_RELATIVE: f64 = 1e-6;

/// ECMWF's aerosol optics table, its monochromatic part.
#[derive(Debug, Clone)]
pub struct AerosolOpticsTable {
    /// The file read (named in every refusal).
    pub path: PathBuf,
    /// `wavelength_mono`, m.
    pub wavelength_m: Vec<f64>,
    /// `relative_humidity1`: the RH bins' lower bounds, 0–1.
    pub rh_lower: Vec<f64>,
    /// `relative_humidity2`: the RH bins' upper bounds, 0–1.
    pub rh_upper: Vec<f64>,
    /// `mass_ext_mono_hydrophobic`, row-major (type, wavelength), m² kg⁻¹.
    pub mass_ext_hydrophobic: Vec<f64>,
    /// `lidar_ratio_mono_hydrophobic`, row-major (type, wavelength), sr.
    pub lidar_ratio_hydrophobic: Vec<f64>,
    /// `mass_ext_mono_hydrophilic`, row-major (type, RH bin, wavelength), m² kg⁻¹.
    pub mass_ext_hydrophilic: Vec<f64>,
    /// `lidar_ratio_mono_hydrophilic`, row-major (type, RH bin, wavelength), sr.
    pub lidar_ratio_hydrophilic: Vec<f64>,
    /// Number of hydrophobic types.
    pub n_hydrophobic: usize,
    /// Number of hydrophilic types.
    pub n_hydrophilic: usize,
    /// `code_hydrophobic`, if the file has it readable.
    pub codes_hydrophobic: Option<Vec<String>>,
    /// `code_hydrophilic`, if the file has it readable.
    pub codes_hydrophilic: Option<Vec<String>>,
}

/// One line naming the file, the variable and the reason.
fn refuse(path: &Path, var: &str, reason: impl std::fmt::Display) -> Error {
    Error::Unsupported(format!("{}: variable `{var}`: {reason}", path.display()))
}

impl AerosolOpticsTable {
    /// Reads ECMWF's table at `path` (netCDF-3 classic as ECMWF distributes it, or a
    /// netCDF-4 copy), refusing in one line naming the file, the variable and the reason:
    /// a missing variable, a variable of the wrong rank or a dimension of the wrong size
    /// (the four optics variables' dimensions must be the types', `relative_humidity1`'s
    /// and `wavelength_mono`'s sizes), `wavelength_mono` not in m, a NaN or negative
    /// value (and a lidar ratio or wavelength of 0), RH bounds outside [0, 1] or not
    /// increasing.
    pub fn read(path: &Path) -> Result<Self> {
        let files = Files::open(&[path.to_path_buf()])
            .map_err(|(p, reason)| Error::Unsupported(format!("{}: {reason}", p.display())))?;
        let find = |name: &str| {
            files
                .find(name)
                .ok_or_else(|| refuse(path, name, "missing (not ECMWF's aerosol optics table with monochromatic optics, aerosol_ifs_rrtm_*.nc?)"))
        };
        let read = |v: &Var| files.read_all(v).map_err(|e| refuse(path, &v.name, e));

        let wl = find("wavelength_mono")?;
        rank(path, &wl, 1)?;
        if let Some(u) = files.text_attr(&wl, "units")
            && u.trim() != "m"
        {
            return Err(refuse(
                path,
                &wl.name,
                format!("units \"{u}\", expected \"m\""),
            ));
        }
        let wavelength_m = read(&wl)?;
        values(path, &wl.name, &wavelength_m, true)?;

        let rh1 = find("relative_humidity1")?;
        let rh2 = find("relative_humidity2")?;
        rank(path, &rh1, 1)?;
        rank(path, &rh2, 1)?;
        let rh_lower = read(&rh1)?;
        let rh_upper = read(&rh2)?;
        let nrh = rh_lower.len();
        if nrh == 0 {
            return Err(refuse(path, &rh1.name, "no relative-humidity bins"));
        }
        if rh_upper.len() != nrh {
            return Err(refuse(
                path,
                &rh2.name,
                format!("{} bounds, relative_humidity1 has {nrh}", rh_upper.len()),
            ));
        }
        for (name, v) in [(&rh1.name, &rh_lower), (&rh2.name, &rh_upper)] {
            values(path, name, v, false)?;
            if let Some(x) = v.iter().find(|x| **x > 1.0) {
                return Err(refuse(path, name, format!("{x} is above 1 (saturation)")));
            }
            if v.windows(2).any(|w| w[1] <= w[0]) {
                return Err(refuse(path, name, "bounds not increasing"));
            }
        }
        if let Some(k) = (0..nrh).find(|&k| rh_upper[k] < rh_lower[k]) {
            return Err(refuse(
                path,
                &rh2.name,
                format!("bin {}'s upper bound below its lower one", k + 1),
            ));
        }

        let nwl = wavelength_m.len();
        let ext_phobic = find("mass_ext_mono_hydrophobic")?;
        rank(path, &ext_phobic, 2)?;
        let n_hydrophobic = ext_phobic.shape[0];
        let ext_philic = find("mass_ext_mono_hydrophilic")?;
        rank(path, &ext_philic, 3)?;
        let n_hydrophilic = ext_philic.shape[0];
        let lr_phobic = find("lidar_ratio_mono_hydrophobic")?;
        let lr_philic = find("lidar_ratio_mono_hydrophilic")?;
        let phobic_shape = [n_hydrophobic, nwl];
        let philic_shape = [n_hydrophilic, nrh, nwl];
        shape(path, &ext_phobic, &phobic_shape)?;
        shape(path, &lr_phobic, &phobic_shape)?;
        shape(path, &ext_philic, &philic_shape)?;
        shape(path, &lr_philic, &philic_shape)?;
        let mass_ext_hydrophobic = read(&ext_phobic)?;
        let lidar_ratio_hydrophobic = read(&lr_phobic)?;
        let mass_ext_hydrophilic = read(&ext_philic)?;
        let lidar_ratio_hydrophilic = read(&lr_philic)?;
        values(path, &ext_phobic.name, &mass_ext_hydrophobic, false)?;
        values(path, &lr_phobic.name, &lidar_ratio_hydrophobic, true)?;
        values(path, &ext_philic.name, &mass_ext_hydrophilic, false)?;
        values(path, &lr_philic.name, &lidar_ratio_hydrophilic, true)?;

        let codes = |name: &str, n: usize| {
            let v = files.find(name)?;
            let bytes = files.read_all(&v).ok()?;
            if v.shape.len() != 2 || v.shape[0] != n || bytes.len() != n * v.shape[1] {
                return None;
            }
            Some(
                bytes
                    .chunks(v.shape[1])
                    .map(|c| {
                        c.iter()
                            .map(|b| *b as u8 as char)
                            .filter(|ch| *ch != '\0')
                            .collect::<String>()
                            .trim()
                            .to_string()
                    })
                    .collect(),
            )
        };
        Ok(AerosolOpticsTable {
            path: path.to_path_buf(),
            codes_hydrophobic: codes("code_hydrophobic", n_hydrophobic),
            codes_hydrophilic: codes("code_hydrophilic", n_hydrophilic),
            wavelength_m,
            rh_lower,
            rh_upper,
            mass_ext_hydrophobic,
            lidar_ratio_hydrophobic,
            mass_ext_hydrophilic,
            lidar_ratio_hydrophilic,
            n_hydrophobic,
            n_hydrophilic,
        })
    }

    /// The RH bin (0-based) of relative humidity `rh` (0–1), as ecRad picks it
    /// (`radiation/radiation_aerosol_optics_data.F90`, `calc_rh_index`): the first bin
    /// while `rh ≤` the second bin's lower bound, else the last bin `k` with
    /// `rh >` its lower bound — bins `(lower_k, lower_{k+1}]`, the first closed below at
    /// −∞ and the last open above; no interpolation between bins (an RH exactly on an
    /// edge takes the lower bin). Only `relative_humidity1` is used, as by ecRad.
    pub fn rh_bin(&self, rh: f64) -> usize {
        let n = self.rh_lower.len();
        let mut k = 0;
        while k + 1 < n && rh > self.rh_lower[k + 1] {
            k += 1;
        }
        k
    }

    /// The index of `wavelength_m` in `wavelength_mono`: equal to within
    /// [`WAVELENGTH_MATCH_RELATIVE`] (ecRad's own `dry_aerosol_mass_extinction` takes the
    /// nearest mono wavelength within 2 %; lidarsim wants the laser's own); refused naming
    /// the table's wavelengths otherwise.
    pub fn wavelength_index(&self, wavelength_m: f64) -> Result<usize> {
        self.wavelength_m
            .iter()
            .position(|w| (w - wavelength_m).abs() <= WAVELENGTH_MATCH_RELATIVE * wavelength_m)
            .ok_or_else(|| {
                let nm: Vec<String> = self
                    .wavelength_m
                    .iter()
                    .map(|w| format!("{}", (w * 1e9 * 100.0).round() / 100.0))
                    .collect();
                refuse(
                    &self.path,
                    "wavelength_mono",
                    format!(
                        "no {} nm (the table has {} nm); lidarsim takes a mono wavelength exactly, it does not interpolate",
                        (wavelength_m * 1e9 * 1000.0).round() / 1000.0,
                        nm.join(", ")
                    ),
                )
            })
    }

    /// `(mass extinction m² kg⁻¹, lidar ratio sr)` of `species` at relative humidity
    /// `relative_humidity` (0–1; [`super::aerosol_species::relative_humidity_over_water`])
    /// and `wavelength_m`: a hydrophobic type's values at the wavelength
    /// ([`Self::wavelength_index`]), a hydrophilic type's in the RH bin ecRad picks
    /// ([`Self::rh_bin`]). Refused in one line: a species without optics, a type past the
    /// table's, a type whose code is not the species' (`code_hydrophilic` /
    /// `code_hydrophobic`), a NaN RH, a wavelength not in the table.
    pub fn optics(
        &self,
        species: &CamsSpecies,
        relative_humidity: f64,
        wavelength_m: f64,
    ) -> Result<(f64, f64)> {
        let w = self.wavelength_index(wavelength_m)?;
        self.optics_at_index(species, relative_humidity, w)
    }

    /// The two neighbouring `wavelength_mono` indices around `wavelength_m`, with its
    /// weight in `ln λ` between them (`(i, i, 0)` on a tabulated wavelength); refused
    /// outside the table's wavelengths.
    pub fn bracket(&self, wavelength_m: f64) -> Result<(usize, usize, f64)> {
        if let Ok(i) = self.wavelength_index(wavelength_m) {
            return Ok((i, i, 0.0));
        }
        let w = &self.wavelength_m;
        let mut best: Option<(usize, usize)> = None;
        for i in 0..w.len() {
            for j in 0..w.len() {
                let around = w[i] < wavelength_m && wavelength_m < w[j];
                let closer = best.is_none_or(|(a, b)| w[i] >= w[a] && w[j] <= w[b]);
                if around && closer {
                    best = Some((i, j));
                }
            }
        }
        let (i, j) = best.ok_or_else(|| {
            refuse(
                &self.path,
                "wavelength_mono",
                format!(
                    "{} nm is outside the table's wavelengths; lidarsim interpolates between \
                     them, it does not extrapolate",
                    (wavelength_m * 1e9 * 1000.0).round() / 1000.0
                ),
            )
        })?;
        let f = (wavelength_m / w[i]).ln() / (w[j] / w[i]).ln();
        Ok((i, j, f))
    }

    /// The mass extinction (m² kg⁻¹) of `species` at relative humidity
    /// `relative_humidity` and any `wavelength_m` within the table's: at a tabulated
    /// wavelength its value ([`Self::optics`]); between the neighbouring tabulated
    /// wavelengths `λ_a < λ < λ_b` log-log, an Ångström law between them:
    /// `ln k = ln k_a + f·(ln k_b − ln k_a)`, `f = ln(λ/λ_a)/ln(λ_b/λ_a)` (linear in
    /// `ln λ` where `k_a` or `k_b` is 0); refused outside them ([`Self::bracket`]).
    pub fn mass_extinction_at(
        &self,
        species: &CamsSpecies,
        relative_humidity: f64,
        wavelength_m: f64,
    ) -> Result<f64> {
        let (i, j, f) = self.bracket(wavelength_m)?;
        let a = self.optics_at_index(species, relative_humidity, i)?.0;
        if i == j {
            return Ok(a);
        }
        let b = self.optics_at_index(species, relative_humidity, j)?.0;
        Ok(if a > 0.0 && b > 0.0 {
            (a.ln() + f * (b.ln() - a.ln())).exp()
        } else {
            a + f * (b - a)
        })
    }

    /// [`Self::optics`] at `wavelength_mono` index `w`.
    fn optics_at_index(
        &self,
        species: &CamsSpecies,
        relative_humidity: f64,
        w: usize,
    ) -> Result<(f64, f64)> {
        let Some(t) = species.ifs_type else {
            return Err(Error::Unsupported(format!(
                "{}: {} ({}) has no optical type in ECMWF's table",
                self.path.display(),
                species.short_name,
                species.description
            )));
        };
        let nwl = self.wavelength_m.len();
        let (k, n, codes, var) = match t {
            IfsType::Hydrophobic(k) => (
                k,
                self.n_hydrophobic,
                &self.codes_hydrophobic,
                "mass_ext_mono_hydrophobic",
            ),
            IfsType::Hydrophilic(k) => (
                k,
                self.n_hydrophilic,
                &self.codes_hydrophilic,
                "mass_ext_mono_hydrophilic",
            ),
        };
        if k == 0 || k > n {
            return Err(refuse(
                &self.path,
                var,
                format!(
                    "{} needs type {} but the table has {n}",
                    species.short_name,
                    t.ecrad_index()
                ),
            ));
        }
        if let Some(c) = codes.as_ref().map(|c| &c[k - 1])
            && !species.codes.contains(&c.as_str())
        {
            let code_var = var.replace("mass_ext_mono", "code");
            return Err(refuse(
                &self.path,
                &code_var,
                format!(
                    "type {} is `{c}`, {} ({}) needs `{}`",
                    t.ecrad_index(),
                    species.short_name,
                    species.description,
                    species.codes.join("` or `")
                ),
            ));
        }
        Ok(match t {
            IfsType::Hydrophobic(_) => {
                let i = (k - 1) * nwl + w;
                (
                    self.mass_ext_hydrophobic[i],
                    self.lidar_ratio_hydrophobic[i],
                )
            }
            IfsType::Hydrophilic(_) => {
                if relative_humidity.is_nan() {
                    return Err(refuse(
                        &self.path,
                        "relative_humidity1",
                        format!("{}: relative humidity is NaN", species.short_name),
                    ));
                }
                let r = self.rh_bin(relative_humidity);
                let i = ((k - 1) * self.rh_lower.len() + r) * nwl + w;
                (
                    self.mass_ext_hydrophilic[i],
                    self.lidar_ratio_hydrophilic[i],
                )
            }
        })
    }
}

/// Refuses a variable not of rank `n`.
fn rank(path: &Path, v: &Var, n: usize) -> Result<()> {
    if v.shape.len() == n {
        Ok(())
    } else {
        Err(refuse(
            path,
            &v.name,
            format!(
                "{} dimensions ({}), expected {n}",
                v.shape.len(),
                crate::error::shape_text(&v.shape)
            ),
        ))
    }
}

/// Refuses a variable not of shape `want` (types × RH bins × wavelengths).
fn shape(path: &Path, v: &Var, want: &[usize]) -> Result<()> {
    if v.shape == want {
        Ok(())
    } else {
        Err(refuse(
            path,
            &v.name,
            format!(
                "shape {}, expected {} (types{} × wavelength_mono)",
                crate::error::shape_text(&v.shape),
                crate::error::shape_text(want),
                if want.len() == 3 {
                    " × relative_humidity1"
                } else {
                    ""
                }
            ),
        ))
    }
}

/// Refuses a NaN (a fill value reads as NaN), an infinite or a negative value, and 0 if
/// `positive`.
fn values(path: &Path, name: &str, v: &[f64], positive: bool) -> Result<()> {
    match v
        .iter()
        .enumerate()
        .find(|(_, x)| !x.is_finite() || **x < 0.0 || (positive && **x == 0.0))
    {
        None => Ok(()),
        Some((i, x)) => Err(refuse(
            path,
            name,
            format!(
                "value {x} at flat index {i} (expected finite and {})",
                if positive { "> 0" } else { "≥ 0" }
            ),
        )),
    }
}
