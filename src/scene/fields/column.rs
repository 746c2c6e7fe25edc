//! One profile's model column: the levels sampled at its time and place, each with its
//! pressure and height, and the layers the levels fill (bottom up).
//!
//! **Pressure** of each level: the file's 3-D pressure where it has one (MERRA-2 `PL`,
//! ICON `pres`), else `a + b·p_s` from the hybrid coefficients and the surface pressure
//! (model levels), else the level coordinate itself (pressure levels).
//! **Height**: the file's 3-D height (MERRA-2 `H`, ICON `z_mc`) or geopotential / g₀
//! (ERA5 pressure levels: `z`, g₀ = 9.80665 m s⁻²; geopotential height taken as
//! height), else the level coordinate (height levels), else the hypsometric equation
//! from the surface up: `z₀ = z_s + (R_d·T_v,0/g₀)·ln(p_s/p₀)`,
//! `z_{k+1} = z_k + (R_d·(T_v,k + T_v,k+1)/(2g₀))·ln(p_k/p_{k+1})`, with the surface
//! height `z_s` from the surface geopotential (0 without one).
//! **Layers**: level k fills the heights between the midpoints to its neighbours; the
//! lowest from the surface (or half a spacing below it without a surface height), the
//! highest to half a spacing above it. A level's optics are constant over its layer,
//! so the column's optical depth is `Σ α_k·Δz_k` exactly, and the range bins, which
//! average the layers over their span (`atmosphere::bin_mean`), keep it.

use crate::atmosphere::cloud_optics::{DRY_AIR_GAS_CONSTANT, VIRTUAL_FACTOR};

/// Standard gravity, m s⁻².
pub const STANDARD_GRAVITY: f64 = 9.80665;

/// One level of a profile's column, in SI units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Level {
    /// Pressure, Pa.
    pub p_pa: f64,
    /// Temperature, K.
    pub t_k: f64,
    /// Specific humidity, kg kg⁻¹.
    pub q: f64,
    /// Cloud liquid water mass mixing ratio, kg kg⁻¹.
    pub liquid: f64,
    /// Cloud ice mass mixing ratio, kg kg⁻¹.
    pub ice: f64,
    /// Cloud fraction, 0–1 (1 where the files give none).
    pub cloud_fraction: f64,
    /// Height above sea level, m (NaN until known).
    pub height_m: f64,
    /// The model's droplet effective radius, µm.
    pub liquid_radius_um: Option<f64>,
    /// The model's ice effective radius, µm.
    pub ice_radius_um: Option<f64>,
    /// The CAMS aerosol species' mass mixing ratios, kg kg⁻¹, by species
    /// (`aermr01` at 0 … `aermr18` at 17; 0 where not read).
    pub aerosol_mmr: [f64; 18],
}

/// A profile's column: levels bottom up and the heights of their layers' boundaries.
#[derive(Debug, Clone, PartialEq)]
pub struct FieldColumn {
    /// The levels, lowest first.
    pub levels: Vec<Level>,
    /// Layer boundaries, m, `levels.len() + 1` of them, increasing.
    pub interfaces_m: Vec<f64>,
    /// Surface pressure, Pa, where the files give one.
    pub surface_pressure_pa: Option<f64>,
    /// Surface height, m, where the files give one (surface geopotential / g₀).
    pub surface_height_m: Option<f64>,
}

/// Orders `levels` bottom up (by decreasing pressure), fills in the heights the
/// files did not give, and lays the layers; `Err` names what is out of order.
pub fn build(
    mut levels: Vec<Level>,
    surface_pressure_pa: Option<f64>,
    surface_height_m: Option<f64>,
) -> Result<FieldColumn, String> {
    if levels.first().map(|l| l.p_pa) < levels.last().map(|l| l.p_pa) {
        levels.reverse();
    }
    if levels
        .windows(2)
        .any(|w| w[1].p_pa >= w[0].p_pa || w[1].p_pa.is_nan())
    {
        return Err("levels out of order: the pressure is not strictly monotonic".into());
    }
    if levels.iter().any(|l| l.height_m.is_nan()) {
        let ps = surface_pressure_pa.ok_or(
            "heights from the hypsometric equation need the surface pressure: no \
             `surface_pressure`, `height` or `geopotential`",
        )?;
        let tv = |l: &Level| l.t_k * (1.0 + VIRTUAL_FACTOR * l.q);
        let scale = DRY_AIR_GAS_CONSTANT / STANDARD_GRAVITY;
        let z0 = surface_height_m.unwrap_or(0.0);
        if levels[0].p_pa > ps || ps.is_nan() {
            return Err(format!(
                "the lowest level's pressure {} Pa is above the surface pressure {ps} Pa",
                levels[0].p_pa
            ));
        }
        levels[0].height_m = z0 + scale * tv(&levels[0]) * (ps / levels[0].p_pa).ln();
        for k in 1..levels.len() {
            let (a, b) = (levels[k - 1], levels[k]);
            levels[k].height_m =
                a.height_m + scale * 0.5 * (tv(&a) + tv(&b)) * (a.p_pa / b.p_pa).ln();
        }
    }
    if levels
        .windows(2)
        .any(|w| w[1].height_m <= w[0].height_m || w[1].height_m.is_nan())
    {
        return Err(
            "levels out of order: the height does not increase as the pressure falls".into(),
        );
    }
    let n = levels.len();
    let z: Vec<f64> = levels.iter().map(|l| l.height_m).collect();
    let half = |a: usize, b: usize| 0.5 * (z[b] - z[a]);
    let mut interfaces = Vec::with_capacity(n + 1);
    interfaces.push(match surface_height_m {
        Some(zs) if zs < z[0] => zs,
        _ if n > 1 => z[0] - half(0, 1),
        _ => z[0] - 50.0,
    });
    interfaces.extend((1..n).map(|k| 0.5 * (z[k - 1] + z[k])));
    interfaces.push(if n > 1 {
        z[n - 1] + half(n - 2, n - 1)
    } else {
        z[0] + 50.0
    });
    Ok(FieldColumn {
        levels,
        interfaces_m: interfaces,
        surface_pressure_pa,
        surface_height_m,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn level(p: f64, t: f64) -> Level {
        Level {
            p_pa: p,
            t_k: t,
            q: 0.0,
            liquid: 0.0,
            ice: 0.0,
            cloud_fraction: 1.0,
            height_m: f64::NAN,
            liquid_radius_um: None,
            ice_radius_um: None,
            aerosol_mmr: [0.0; 18],
        }
    }

    #[test]
    fn an_isothermal_column_has_the_scale_height() {
        // dry, 250 K: z = H·ln(p_s/p), H = R_d·T/g₀
        let h = DRY_AIR_GAS_CONSTANT * 250.0 / STANDARD_GRAVITY;
        let c = build(
            vec![level(50_000.0, 250.0), level(90_000.0, 250.0)],
            Some(100_000.0),
            Some(0.0),
        )
        .unwrap();
        assert_eq!(c.levels[0].p_pa, 90_000.0);
        for l in &c.levels {
            let want = h * (100_000.0 / l.p_pa).ln();
            assert!((l.height_m - want).abs() < 1e-9 * want, "{l:?}");
        }
        assert_eq!(c.interfaces_m[0], 0.0);
        assert_eq!(c.interfaces_m.len(), 3);
        let e = build(
            vec![
                level(90_000.0, 250.0),
                level(50_000.0, 250.0),
                level(60_000.0, 250.0),
            ],
            Some(1e5),
            None,
        )
        .unwrap_err();
        assert!(e.contains("levels out of order"), "{e}");
    }
}
