//! Reading the fields a run's profiles need: each variable found by its role
//! ([`super::names`]), its units checked, only the slab (time × levels × latitude ×
//! longitude box) around the track read, every value of it checked finite, and each
//! profile's column sampled by the stated rule ([`super::grid`]). Fields are laid out
//! `(time, level, latitude, longitude)` (the CF order of ERA5, MERRA-2, CAMS and ICON),
//! surface fields `(time, latitude, longitude)` or `(latitude, longitude)`.

use std::path::PathBuf;

use super::column::{FieldColumn, Level, STANDARD_GRAVITY, build};
use super::grid::{Axes, parse_time_units};
use super::names::{Quantity, candidates, factor, quantity};
use super::reader::{Fail, Files, Var};
use super::slab::{Boxed, MAX_SLAB_CELLS, Slab, Vertical, runs};
use crate::config::ModelFieldsConfig;

/// Where and when a profile samples the fields.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Unix time, s.
    pub time_s: f64,
    /// Latitude, degrees north.
    pub latitude_deg: f64,
    /// Longitude, degrees east.
    pub longitude_deg: f64,
}

/// The roles read per level, in this order.
const LEVEL_ROLES: [&str; 10] = [
    "temperature",
    "specific_humidity",
    "liquid",
    "ice",
    "cloud_fraction",
    "pressure",
    "height",
    "geopotential",
    "liquid_effective_radius",
    "ice_effective_radius",
];

/// Whether a per-level role must be in the files.
fn required(role: &str) -> bool {
    matches!(role, "temperature" | "specific_humidity" | "liquid" | "ice")
}

/// The files' variable of `role`: the config's name, else the mapping's first found.
fn find(files: &Files, cfg: &ModelFieldsConfig, role: &str) -> Result<Option<Var>, Fail> {
    if let Some(name) = cfg.variables.get(role) {
        return files.find(name).map(Some).ok_or_else(|| {
            (
                files.path(0).to_path_buf(),
                format!(
                    "`{name}` (scene.model_fields.variables.{role}): no such variable in the files"
                ),
            )
        });
    }
    Ok(candidates(cfg.model, role)
        .iter()
        .find_map(|n| files.find(n)))
}

/// The factor to SI of `v` playing `role`, from its `units` attribute.
fn units(files: &Files, v: &Var, role: &str) -> Result<f64, Fail> {
    let fail = |why: String| {
        (
            files.path(v.file).to_path_buf(),
            format!("`{}`: {why}", v.name),
        )
    };
    let q = quantity(role).ok_or_else(|| fail(format!("{role} has no units rule")))?;
    match files.text_attr(v, "units") {
        Some(u) => factor(q, &u).map_err(fail),
        None if q == Quantity::One => Ok(1.0),
        None => Err(fail(
            "has no `units` attribute (units are read, not guessed)".into(),
        )),
    }
}

/// A 1-D coordinate, finite.
fn axis(files: &Files, v: &Var) -> Result<Vec<f64>, Fail> {
    let fail = |why: &str| {
        (
            files.path(v.file).to_path_buf(),
            format!("`{}`: {why}", v.name),
        )
    };
    if v.shape.len() != 1 || v.shape[0] == 0 {
        return Err(fail("is not a non-empty 1-D coordinate"));
    }
    let x = files
        .read_all(v)
        .map_err(|e| (files.path(v.file).to_path_buf(), e))?;
    if x.iter().any(|x| !x.is_finite()) {
        return Err(fail("has a NaN or fill value"));
    }
    Ok(x)
}

/// Strictly monotonic (`rising`: strictly increasing).
fn monotonic(x: &[f64], rising_only: bool) -> bool {
    let up = x.windows(2).all(|w| w[1] > w[0]);
    up || (!rising_only && x.windows(2).all(|w| w[1] < w[0]))
}

/// The columns of `samples` from the files `paths` of `cfg`, the fields read in runs of
/// profiles of at most [`MAX_SLAB_CELLS`] cells each.
pub fn columns(
    cfg: &ModelFieldsConfig,
    paths: &[PathBuf],
    samples: &[Sample],
) -> Result<Vec<FieldColumn>, Fail> {
    columns_in_runs(cfg, paths, samples, MAX_SLAB_CELLS)
}

/// [`columns`] with the fields read in runs of profiles whose box has at most
/// `max_cells` cells (a profile's own box always read whole): the same columns
/// whatever the bound.
pub fn columns_in_runs(
    cfg: &ModelFieldsConfig,
    paths: &[PathBuf],
    samples: &[Sample],
    max_cells: usize,
) -> Result<Vec<FieldColumn>, Fail> {
    let mut out = Vec::with_capacity(samples.len());
    for_each_column(cfg, paths, samples, max_cells, |_, c| {
        out.push(c);
        Ok(())
    })?;
    Ok(out)
}

/// Each column of `samples` in order, handed to `each` with its profile index as soon as
/// it is sampled (so that a caller keeping less than the column holds less than every
/// column), the fields read in runs of at most `max_cells` cells.
pub fn for_each_column(
    cfg: &ModelFieldsConfig,
    paths: &[PathBuf],
    samples: &[Sample],
    max_cells: usize,
    mut each: impl FnMut(usize, FieldColumn) -> Result<(), Fail>,
) -> Result<(), Fail> {
    let files = Files::open(paths)?;
    let first = || files.path(0).to_path_buf();
    let need = |role: &str| -> Result<Var, Fail> {
        find(&files, cfg, role)?.ok_or_else(|| {
            (
                first(),
                format!(
                    "no {role} variable in the files (looked for {}; name it in \
                     scene.model_fields.variables.{role})",
                    candidates(cfg.model, role)
                        .iter()
                        .map(|n| format!("`{n}`"))
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            )
        })
    };
    let t_var = need("temperature")?;
    let at = |v: &Var| files.path(v.file).to_path_buf();
    // the axes
    let (lat_v, lon_v, time_v, lev_v) = (
        need("latitude")?,
        need("longitude")?,
        need("time")?,
        need("level")?,
    );
    let lat = axis(&files, &lat_v)?;
    let lon = axis(&files, &lon_v)?;
    let lev = axis(&files, &lev_v)?;
    let raw_t = axis(&files, &time_v)?;
    units(&files, &lat_v, "latitude")?;
    units(&files, &lon_v, "longitude")?;
    for (v, x, rising) in [
        (&lat_v, &lat, false),
        (&lon_v, &lon, true),
        (&lev_v, &lev, false),
    ] {
        if !monotonic(x, rising) {
            let how = if rising { "increasing" } else { "monotonic" };
            return Err((
                at(v),
                format!("`{}`: out of order (not strictly {how})", v.name),
            ));
        }
    }
    let tu = files.text_attr(&time_v, "units").ok_or_else(|| {
        (
            at(&time_v),
            format!("`{}`: has no `units` attribute", time_v.name),
        )
    })?;
    let (per, origin) =
        parse_time_units(&tu).map_err(|e| (at(&time_v), format!("`{}`: {e}", time_v.name)))?;
    let time_s: Vec<f64> = raw_t.iter().map(|t| origin + per * t).collect();
    if !monotonic(&time_s, true) {
        return Err((
            at(&time_v),
            format!("`{}`: out of order (not strictly increasing)", time_v.name),
        ));
    }
    let axes = Axes { lat, lon, time_s };
    let (nt, nl, ny, nx) = (axes.time_s.len(), lev.len(), axes.lat.len(), axes.lon.len());
    // each sample's weights; the slab they span
    let mut weights = Vec::with_capacity(samples.len());
    for (p, s) in samples.iter().enumerate() {
        let w = axes
            .weights(cfg.interpolation, s.time_s, s.latitude_deg, s.longitude_deg)
            .map_err(|axis| {
                (
                    at(&t_var),
                    format!(
                        "`{}`: the track is outside the fields' {axis}: profile {p} at \
                         {:.3}°N {:.3}°E, {} (the file spans {} to {})",
                        t_var.name,
                        s.latitude_deg,
                        s.longitude_deg,
                        iso(s.time_s),
                        iso(axes.time_s[0]),
                        iso(axes.time_s[nt - 1]),
                    ),
                )
            })?;
        weights.push(w);
    }
    // read a role's box: per level (t, level, y, x) or surface (t, y, x) / (y, x)
    let read = |v: &Var, role: &str, per_level: bool, b: &Slab| -> Result<Vec<f64>, Fail> {
        let f = units(&files, v, role)?;
        let fail = |why: String| (at(v), format!("`{}`: {why}", v.name));
        let (t0, ct, y0, cy, x0, cx) = (b.t0, b.ct, b.y0, b.cy, b.x0, b.cx);
        let (start, count) = match (per_level, &v.shape[..]) {
            (true, [a, b, c, d]) if [*a, *b, *c, *d] == [nt, nl, ny, nx] => {
                (vec![t0, 0, y0, x0], vec![ct, nl, cy, cx])
            }
            (false, [a, 1, c, d]) if [*a, *c, *d] == [nt, ny, nx] => {
                (vec![t0, 0, y0, x0], vec![ct, 1, cy, cx])
            }
            (false, [a, c, d]) if [*a, *c, *d] == [nt, ny, nx] => {
                (vec![t0, y0, x0], vec![ct, cy, cx])
            }
            (false, [c, d]) if [*c, *d] == [ny, nx] => (vec![y0, x0], vec![cy, cx]),
            (_, s) => {
                return Err(fail(format!(
                    "is {}, not {} as (time, {}latitude, longitude) = {}",
                    crate::error::shape_text(s),
                    role,
                    if per_level { "level, " } else { "" },
                    if per_level {
                        format!("{nt} × {nl} × {ny} × {nx}")
                    } else {
                        format!("{nt} × {ny} × {nx}")
                    }
                )));
            }
        };
        let mut x = files.read(v, &start, &count).map_err(fail)?;
        if let Some(i) = x.iter().position(|x| !x.is_finite()) {
            return Err(fail(format!(
                "a NaN or fill value in the slab the track needs (value {i})"
            )));
        }
        x.iter_mut().for_each(|x| *x *= f);
        Ok(if count.len() == 2 { x.repeat(ct) } else { x })
    };
    let mut per_level = Vec::new();
    for role in LEVEL_ROLES {
        let v = if required(role) {
            Some(need(role)?)
        } else {
            find(&files, cfg, role)?
        };
        // ERA5's `z` is geopotential on pressure levels, the surface's on model levels
        let v = v
            .filter(|v| role != "geopotential" || v.shape.len() == 4 && v.shape[1] == nl && nl > 1);
        per_level.push(v);
    }
    // the CAMS aerosol species (with an optics table): the requested, else all found
    let mut species = Vec::new();
    if cfg.aerosol_optics.is_some() {
        let names: Vec<String> = match &cfg.aerosol_species {
            Some(n) => n.clone(),
            None => crate::atmosphere::aerosol_species::CAMS_SPECIES
                .iter()
                .filter(|s| s.ifs_type.is_some() && files.find(s.short_name).is_some())
                .map(|s| s.short_name.to_string())
                .collect(),
        };
        for name in names {
            let index = crate::atmosphere::aerosol_species::CAMS_SPECIES
                .iter()
                .position(|s| s.short_name == name)
                .ok_or_else(|| {
                    (
                        first(),
                        format!(
                            "`{name}` (scene.model_fields.aerosol_species): not a CAMS species"
                        ),
                    )
                })?;
            let v = files.find(&name).ok_or_else(|| {
                (
                    first(),
                    format!(
                        "`{name}` (scene.model_fields.aerosol_species): no such variable in the \
                         files ({})",
                        (0..paths.len())
                            .map(|i| files.path(i).display().to_string())
                            .collect::<Vec<_>>()
                            .join(", ")
                    ),
                )
            })?;
            species.push((index, v));
        }
    }
    let surface =
        |role: &str| -> Result<Option<Var>, Fail> {
            Ok(find(&files, cfg, role)?
                .filter(|v| !(v.shape.len() == 4 && v.shape[1] == nl && nl > 1)))
        };
    let (ps_v, zs_v) = (
        surface("surface_pressure")?,
        surface("surface_geopotential")?,
    );
    // the level coordinate's own meaning: pressure or height, if its units say so
    let lev_units = files.text_attr(&lev_v, "units").unwrap_or_default();
    let lev_p = factor(Quantity::Pressure, &lev_units)
        .ok()
        .map(|f| lev.iter().map(|x| x * f).collect::<Vec<_>>());
    let lev_z = factor(Quantity::Length, &lev_units)
        .ok()
        .map(|f| lev.iter().map(|x| x * f).collect::<Vec<_>>());
    let hybrid = match (
        find(&files, cfg, "hybrid_a")?,
        find(&files, cfg, "hybrid_b")?,
    ) {
        (Some(a), Some(b)) => {
            let fa = units(&files, &a, "hybrid_a")?;
            let fb = units(&files, &b, "hybrid_b")?;
            let (va, vb) = (axis(&files, &a)?, axis(&files, &b)?);
            if va.len() != nl || vb.len() != nl {
                return Err((
                    at(&a),
                    format!(
                        "`{}`, `{}`: not one coefficient per level ({nl})",
                        a.name, b.name
                    ),
                ));
            }
            Some((
                va.iter().map(|x| x * fa).collect::<Vec<_>>(),
                vb.iter().map(|x| x * fb).collect::<Vec<_>>(),
            ))
        }
        _ => None,
    };
    let has = |i: usize| per_level[i].is_some();
    if !has(5) && hybrid.is_none() && lev_p.is_none() {
        return Err((
            at(&lev_v),
            format!(
                "`{}`: no pressure per level: neither a `pressure` variable, hybrid coefficients \
             (`hybrid_a`, `hybrid_b`) nor pressure units ({lev_units:?}) on the level coordinate",
                lev_v.name
            ),
        ));
    }
    if hybrid.is_some() && !has(5) && ps_v.is_none() {
        return Err((
            first(),
            "hybrid levels need the surface pressure: no surface_pressure variable".into(),
        ));
    }
    // sample each profile, the fields read by the box of a run of profiles at a time
    for run in runs(&weights, nl, max_cells) {
        let Some(b) = Slab::spanning(weights[run.clone()].iter().flatten()) else {
            continue;
        };
        crate::resources::require_memory(
            &format!("{}: the model fields' slab", first().display()),
            (b.cells(nl) * 8 * (LEVEL_ROLES.len() + 4 + species.len())) as f64,
        )
        .map_err(|e| (first(), e.to_string()))?;
        let mut fields = Vec::with_capacity(per_level.len());
        for (v, role) in per_level.iter().zip(LEVEL_ROLES) {
            fields.push(match v {
                Some(v) => Some(read(v, role, true, &b)?),
                None => None,
            });
        }
        let mut mmr = Vec::with_capacity(species.len());
        for (i, v) in &species {
            mmr.push((*i, read(v, "aerosol", true, &b)?));
        }
        let ps = match &ps_v {
            Some(v) => Some(read(v, "surface_pressure", false, &b)?),
            None => None,
        };
        let zs = match &zs_v {
            Some(v) => Some(read(v, "surface_geopotential", false, &b)?),
            None => None,
        };
        let boxed = Boxed {
            b,
            levels: nl,
            fields: &fields,
            species: &mmr,
        };
        let vertical = Vertical {
            hybrid: hybrid.as_ref(),
            lev_p: lev_p.as_deref(),
            lev_z: lev_z.as_deref(),
        };
        for p in run {
            let sp = ps.as_deref().map(|f| boxed.mix_surface(f, &weights[p]));
            let zsurf = zs
                .as_deref()
                .map(|z| boxed.mix_surface(z, &weights[p]) / STANDARD_GRAVITY);
            let mut levels = Vec::with_capacity(nl);
            for k in 0..nl {
                let level = vertical.level(&boxed, &weights[p], k, sp);
                check_level(&level).map_err(|(i, why)| {
                    let v = per_level[i].as_ref().unwrap_or(&t_var);
                    (
                        at(v),
                        format!("`{}`: {why} at level {k} of profile {p}", v.name),
                    )
                })?;
                levels.push(level);
            }
            each(
                p,
                build(levels, sp, zsurf)
                    .map_err(|e| (at(&lev_v), format!("`{}`: {e} (profile {p})", lev_v.name)))?,
            )?;
        }
    }
    Ok(())
}

/// A sampled level's values within physics: `Err((role index, why))`.
fn check_level(l: &Level) -> Result<(), (usize, String)> {
    if !(l.t_k > 100.0 && l.t_k < 400.0) {
        return Err((0, format!("temperature {} K is outside 100–400 K", l.t_k)));
    }
    if !(l.p_pa > 0.0 && l.p_pa < 1.2e5) {
        return Err((5, format!("pressure {} Pa is outside 0–1200 hPa", l.p_pa)));
    }
    if !(-1e-6..=1.0 + 1e-6).contains(&l.cloud_fraction) {
        return Err((
            4,
            format!("cloud fraction {} is outside 0–1", l.cloud_fraction),
        ));
    }
    for (i, r) in [(8, l.liquid_radius_um), (9, l.ice_radius_um)] {
        if let Some(r) = r.filter(|r| !(0.1..=1e4).contains(r)) {
            return Err((i, format!("effective radius {r} µm is outside 0.1–10^4 µm")));
        }
    }
    Ok(())
}

/// Unix seconds as an ISO 8601 UTC time for messages.
fn iso(t_s: f64) -> String {
    let days = (t_s / 86400.0).floor() as i64;
    let secs = (t_s - days as f64 * 86400.0).round() as i64;
    // the civil date of a day number (the inverse of grid::days_from_civil)
    let z = days + 719_468;
    let era = if z >= 0 { z } else { z - 146_096 } / 146_097;
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!(
        "{y:04}-{m:02}-{d:02}T{:02}:{:02}:{:02}Z",
        secs / 3600,
        secs % 3600 / 60,
        secs % 60
    )
}

#[cfg(test)]
mod tests {
    #[test]
    fn iso_inverts_the_civil_days() {
        assert_eq!(super::iso(0.0), "1970-01-01T00:00:00Z");
        assert_eq!(super::iso(1_709_274_600.0), "2024-03-01T06:30:00Z");
        assert_eq!(super::iso(-25_567.0 * 86400.0), "1900-01-01T00:00:00Z");
    }
}
