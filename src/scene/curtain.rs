//! A tabulated curtain (`[scene] curtain = "FILE.h5"`): the aerosol and cloud of the
//! scene as an along-track × altitude grid, e.g. from a model or a retrieval. Each
//! along-track column becomes a segment of the track whose layers are the grid's cells
//! (`docs/scenes.md` has the layout; `configs/atmospheres/curtain_example.h5` is an
//! example made by `tools/make_curtain_example.py`).
//!
//! **Layout** (HDF5 or netCDF-4):
//!
//! | name | dims | meaning |
//! |---|---|---|
//! | `along_track_km` | (along_track) | start of each column along the track, km, strictly increasing from 0 |
//! | `altitude_km` | (altitude) | cell centres, km, strictly increasing, evenly spaced within 0.1 % ([`SPACING_TOLERANCE`]; cells span the midpoints) |
//! | `extinction_aerosol`, `extinction_cloud` | (along_track, altitude) | extinction, km⁻¹, ≥ 0 (either may be absent) |
//! | `lidar_ratio_aerosol`, `lidar_ratio_cloud` | (along_track, altitude) | lidar ratio, sr, in [1, 1e4] where the extinction is > 0 |
//! | `depolarization_aerosol`, `depolarization_cloud` | (along_track, altitude) | linear depolarization ratio in [0, 1] (absent = 0) |
//! | root attribute `wavelength_nm` | | the wavelength of the values |
//! | attribute `angstrom_exponent` of `extinction_aerosol` | | its Ångström exponent (absent = 0) |
//!
//! A column's last stretch runs to the next column's start; the last column's length is
//! the previous spacing. Cells with zero extinction are left out.

use std::path::Path;

use crate::config::{LayerConfig, LayerKind, SegmentConfig};
use crate::error::{Error, Result};

/// Most cells (columns × altitudes) a curtain may have.
pub const MAX_CELLS: usize = 2_000_000;

/// The segments of the curtain file `path`.
pub fn segments(path: &Path) -> Result<Vec<SegmentConfig>> {
    let fail = |why: String| Error::output(path, why);
    crate::input_file::check("scene.curtain", path)?;
    let f = hdf5::File::open(path)
        .map_err(|_| fail("cannot open the curtain (not an HDF5 / netCDF-4 file)".into()))?;
    // sizes first, from the datasets' shapes: nothing sized by the file is read before
    // the cells are known to be at most MAX_CELLS and to fit in memory
    let length = |name: &str| -> Result<usize> {
        let d = f
            .dataset(name)
            .map_err(|_| fail(format!("curtain: no `{name}`")))?;
        match d.shape()[..] {
            [n] => Ok(n),
            ref other => Err(fail(format!(
                "curtain: `{name}` has {} dimensions, not 1",
                other.len()
            ))),
        }
    };
    let (nx, nz) = (length("along_track_km")?, length("altitude_km")?);
    let cells = nx.saturating_mul(nz);
    if cells > MAX_CELLS {
        return Err(fail(format!(
            "curtain: {nx} columns × {nz} altitudes is more than {MAX_CELLS} cells"
        )));
    }
    // six grids of f64, and a layer of each species in each cell at most
    crate::resources::require_memory(
        &format!("{}: the curtain", path.display()),
        cells as f64 * (6.0 * 8.0 + 2.0 * std::mem::size_of::<LayerConfig>() as f64),
    )?;
    let vector = |name: &str| -> Result<Vec<f64>> {
        f.dataset(name)
            .and_then(|d| d.read_raw::<f64>())
            .map_err(|_| fail(format!("curtain: `{name}` is not readable as numbers")))
    };
    let x = vector("along_track_km")?;
    let z = vector("altitude_km")?;
    check_axis(&x, "along_track_km").map_err(fail)?;
    check_axis(&z, "altitude_km").map_err(fail)?;
    check_even(&z, "altitude_km").map_err(fail)?;
    let wavelength_nm: f64 = f
        .attr("wavelength_nm")
        .and_then(|a| a.read_scalar())
        .map_err(|_| fail("curtain: no root attribute `wavelength_nm`".into()))?;
    if !(wavelength_nm.is_finite() && wavelength_nm > 0.0) {
        return Err(fail(format!(
            "curtain: root attribute `wavelength_nm` is {wavelength_nm}, not a positive number"
        )));
    }
    let grid = |name: &str, default: Option<f64>| -> Result<Option<Vec<f64>>> {
        match f.dataset(name) {
            Ok(d) => {
                if d.shape() != [x.len(), z.len()] {
                    return Err(fail(format!(
                        "curtain: `{name}` is {}, not (along_track, altitude) = {} × {}",
                        crate::error::shape_text(&d.shape()),
                        x.len(),
                        z.len()
                    )));
                }
                let v: Vec<f64> = d
                    .read_raw()
                    .map_err(|_| fail(format!("curtain: `{name}` is not readable as numbers")))?;
                Ok(Some(v))
            }
            Err(_) => Ok(default.map(|d| vec![d; x.len() * z.len()])),
        }
    };
    let mut species = Vec::new();
    for (kind, tag) in [(LayerKind::Aerosol, "aerosol"), (LayerKind::Cloud, "cloud")] {
        let Some(ext) = grid(&format!("extinction_{tag}"), None)? else {
            continue;
        };
        let ratio = grid(&format!("lidar_ratio_{tag}"), None)?.ok_or_else(|| {
            fail(format!(
                "curtain: `extinction_{tag}` without `lidar_ratio_{tag}`"
            ))
        })?;
        let depol = grid(&format!("depolarization_{tag}"), Some(0.0))?.unwrap_or_default();
        let angstrom = f
            .dataset(&format!("extinction_{tag}"))
            .and_then(|d| d.attr("angstrom_exponent"))
            .and_then(|a| a.read_scalar::<f64>())
            .ok();
        if let Some(a) = angstrom.filter(|a| !a.is_finite()) {
            return Err(fail(format!(
                "curtain: attribute `angstrom_exponent` of `extinction_{tag}` is {a}, not finite"
            )));
        }
        check_values(&ext, &ratio, &depol, tag).map_err(fail)?;
        species.push((kind, ext, ratio, depol, angstrom));
    }
    let dz = if z.len() > 1 { z[1] - z[0] } else { 1.0 };
    let spacing = if x.len() > 1 {
        x[x.len() - 1] - x[x.len() - 2]
    } else {
        1.0
    };
    Ok((0..x.len())
        .map(|i| {
            let length_km = if i + 1 < x.len() {
                x[i + 1] - x[i]
            } else {
                spacing
            };
            let mut layers = Vec::new();
            for (kind, ext, ratio, depol, angstrom) in &species {
                for (k, zc) in z.iter().enumerate() {
                    let c = i * z.len() + k;
                    if ext[c] > 0.0 {
                        layers.push(LayerConfig {
                            kind: *kind,
                            base_km: zc - dz / 2.0,
                            top_km: zc + dz / 2.0,
                            extinction_per_km: ext[c],
                            lidar_ratio_sr: ratio[c],
                            depolarization: depol[c],
                            multiple_scattering: 1.0,
                            phase: None,
                            effective_radius_um: None,
                            asymmetry_factor: None,
                            angstrom_exponent: *angstrom,
                            reference_wavelength_nm: Some(wavelength_nm),
                            lidar_ratio_sr_by_wavelength: Default::default(),
                            cloud_fraction: None,
                            cell_length_km: None,
                            species: None,
                        });
                    }
                }
            }
            SegmentConfig {
                length_km,
                layers: Some(layers),
                aerosol: None,
                surface: None,
                water_vapour: None,
                molecular: None,
            }
        })
        .collect())
}

/// An axis: at least one finite value, strictly increasing (along-track from 0).
fn check_axis(v: &[f64], name: &str) -> std::result::Result<(), String> {
    if v.is_empty() || v.iter().any(|x| !x.is_finite()) {
        return Err(format!("curtain: `{name}` is empty or not finite"));
    }
    if v.windows(2).any(|w| w[1] <= w[0]) {
        return Err(format!("curtain: `{name}` is not strictly increasing"));
    }
    if name == "along_track_km" && v[0] != 0.0 {
        return Err(format!("curtain: `{name}` must start at 0"));
    }
    Ok(())
}

/// Relative tolerance of the altitude spacing: every spacing within 0.1 % of the first.
/// The cells span the midpoints of their centres with the first spacing, so uneven
/// centres would make cells overlap or leave gaps; 0.1 % admits a grid rounded to
/// float32 (about 2 mm at 40 km, under 0.01 % of a 30 m spacing).
pub const SPACING_TOLERANCE: f64 = 1e-3;

/// An axis evenly spaced within [`SPACING_TOLERANCE`] (it has been checked increasing).
fn check_even(v: &[f64], name: &str) -> std::result::Result<(), String> {
    let Some(first) = v.windows(2).map(|w| w[1] - w[0]).next() else {
        return Ok(());
    };
    for (k, w) in v.windows(2).enumerate() {
        let step = w[1] - w[0];
        if (step - first).abs() > SPACING_TOLERANCE * first {
            return Err(format!(
                "curtain: `{name}` is not evenly spaced: values {k} and {} ({} and {}) are \
                 {:.4} apart, the first two {:.4}; spacings must agree within {} %",
                k + 1,
                w[0],
                w[1],
                step,
                first,
                SPACING_TOLERANCE * 100.0
            ));
        }
    }
    Ok(())
}

/// A species' values: extinction ≥ 0, lidar ratio in [1, 1e4] and depolarization in
/// [0, 1] wherever there is extinction, everything finite.
fn check_values(
    ext: &[f64],
    ratio: &[f64],
    depol: &[f64],
    tag: &str,
) -> std::result::Result<(), String> {
    for c in 0..ext.len() {
        if !(ext[c].is_finite() && (0.0..=1e4).contains(&ext[c])) {
            return Err(format!(
                "curtain: `extinction_{tag}` cell {c} is {} (want 0 to 1e4 km-1)",
                ext[c]
            ));
        }
        if ext[c] > 0.0 && !(1.0..=1e4).contains(&ratio[c]) {
            return Err(format!(
                "curtain: `lidar_ratio_{tag}` cell {c} is {} (want 1 to 1e4 sr)",
                ratio[c]
            ));
        }
        if ext[c] > 0.0 && !(0.0..=1.0).contains(&depol[c]) {
            return Err(format!(
                "curtain: `depolarization_{tag}` cell {c} is {} (want 0 to 1)",
                depol[c]
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn altitudes_must_be_evenly_spaced_within_the_tolerance() {
        // 30 m cells to 40 km, and the same rounded to float32 (about 2 mm at 40 km)
        let z: Vec<f64> = (0..1334).map(|k| 0.015 + 0.03 * k as f64).collect();
        assert_eq!(check_even(&z, "altitude_km"), Ok(()));
        let z32: Vec<f64> = z.iter().map(|&x| f64::from(x as f32)).collect();
        assert_eq!(check_even(&z32, "altitude_km"), Ok(()));
        // one centre moved by 0.2 % of the spacing (60 mm): refused, naming the values
        let mut bad = z.clone();
        bad[500] += 0.002 * 0.03;
        let e = check_even(&bad, "altitude_km").unwrap_err();
        assert!(
            e.contains("`altitude_km` is not evenly spaced: values 499 and 500"),
            "{e}"
        );
        // 0.05 % passes: within the stated 0.1 %
        let mut near = z;
        near[500] += 0.0005 * 0.03;
        assert_eq!(check_even(&near, "altitude_km"), Ok(()));
        assert_eq!(check_even(&[1.0], "altitude_km"), Ok(()));
    }
}
