//! The surface below a space-borne lidar (docs/model.md §4e): a Lambertian reflector of albedo
//! ρ at the ground altitude, whose echo lands in the bin that holds it.
//!
//! **Echo.** A Lambertian surface lit at local incidence θ reflects the radiance
//! `L = ρ·E/π` with `E = P·cos θ/A_beam`; the receiver sees the spot's projected area
//! `A_beam`, so the received power is `P·T²·ρ·cos θ·A/(π r²)`: in the lidar equation
//! (Eq. 2) the surface is a backscatter that integrates to `ρ·cos θ/π` sr⁻¹ across it,
//! and it adds `C·η(r_s)·(ρ cos θ/π)·T²(r_s)/r_s²` counts per shot to the bin holding
//! the surface range r_s (nadir: cos θ = 1, the form of docs/model.md §4e). The beam stops at
//! the surface: nothing below it is seen. Specular glint (ocean at nadir) is not
//! modelled: the ocean's albedo here is its Lambertian equivalent.

use crate::config::{ScenarioConfig, SurfaceConfig, SurfaceKind};

/// A Lambertian surface.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Surface {
    /// Reflectance ρ at the laser wavelength.
    pub albedo: f64,
    /// Altitude of the surface above sea level, m.
    pub altitude_m: f64,
}

/// What reflects sunlight under a column (docs/model.md §4f).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reflector {
    /// Its albedo ρ.
    pub albedo: f64,
    /// Its altitude (the surface, or the thick cloud's top), m: the sunlight crosses
    /// the atmosphere above it (`crate::scene::sky::SkyColumn::above`).
    pub altitude_m: f64,
}

/// The reflector under a column: the top of the highest optically thick cloud (optical
/// depth ≥ 1) with `cloud_albedo`, else the surface (land at 0 m when the scene has
/// none).
pub fn reflector_below(cfg: &ScenarioConfig) -> Reflector {
    let thick_cloud_top_km = cfg
        .atmosphere
        .layers
        .iter()
        .filter(|l| {
            l.kind == crate::config::LayerKind::Cloud
                && l.extinction_per_km * (l.top_km - l.base_km) >= 1.0
        })
        .map(|l| l.top_km)
        .fold(None, |m: Option<f64>, t| Some(m.map_or(t, |m| m.max(t))));
    if let Some(top_km) = thick_cloud_top_km {
        return Reflector {
            albedo: cfg.background.cloud_albedo.unwrap_or(DEFAULT_CLOUD_ALBEDO),
            altitude_m: top_km * 1e3,
        };
    }
    cfg.surface.as_ref().map_or(
        Reflector {
            albedo: crate::config::SurfaceKind::Land.albedo(),
            altitude_m: 0.0,
        },
        |s| {
            let surface = Surface::from_config(s);
            Reflector {
                albedo: surface.albedo,
                altitude_m: surface.altitude_m,
            }
        },
    )
}

/// Albedo of an optically thick cloud top at visible wavelengths (liquid stratocumulus
/// of optical depth ~10–20: 0.6–0.8).
pub const DEFAULT_CLOUD_ALBEDO: f64 = 0.7;

impl SurfaceKind {
    /// A typical Lambertian albedo at 532 nm (documented in `docs/config.md`): open ocean
    /// 0.05 (its diffuse reflectance with foam and whitecaps, no glint), vegetated land
    /// 0.15, fresh snow 0.9.
    pub fn albedo(self) -> f64 {
        match self {
            SurfaceKind::Ocean => 0.05,
            SurfaceKind::Land => 0.15,
            SurfaceKind::Snow => 0.9,
        }
    }
}

impl Surface {
    /// The surface of a validated config: its albedo, or its kind's.
    pub fn from_config(s: &SurfaceConfig) -> Self {
        Surface {
            albedo: s.albedo.unwrap_or_else(|| s.kind.albedo()),
            altitude_m: s.altitude_km * 1e3,
        }
    }

    /// The surface's integrated backscatter `ρ·cos θ/π` (sr⁻¹) for a beam meeting it at
    /// local incidence cos θ = `local_cos`.
    pub fn integrated_backscatter_sr(&self, local_cos: f64) -> f64 {
        self.albedo * local_cos / std::f64::consts::PI
    }
}
