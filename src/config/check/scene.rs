//! The checks of `[surface]` and `[scene]`: the albedo and height, the segments (their
//! layers, aerosol and surface) and the curtain.

use crate::config::scenario::ScenarioConfig;
use crate::config::scene::{PlatformKind, SceneConfig, SegmentAerosol, SurfaceConfig};
use crate::error::Result;

use super::Checker;

impl ScenarioConfig {
    /// `[scene.model_fields]`: alone, over an orbit, with files, known roles and
    /// physical radii and efficiency (the files themselves are checked when read).
    fn validate_model_fields(
        &self,
        c: &Checker,
        scene: &SceneConfig,
        m: &crate::config::model_fields::ModelFieldsConfig,
    ) -> Result<()> {
        if scene.curtain.is_some() || !scene.segments.is_empty() {
            return Err(c.fail(
                "scene.model_fields",
                "gives the scene along the track: use it, scene.curtain or scene.segments, \
                 one of them",
            ));
        }
        let station = self.platform.latitude_deg.is_some() && self.platform.longitude_deg.is_some();
        match self.platform.kind {
            PlatformKind::Ground if !station => {
                return Err(c.fail(
                    "scene.model_fields",
                    "model fields over a ground lidar are sampled at its station: give \
                     platform.latitude_deg and platform.longitude_deg",
                ));
            }
            PlatformKind::Ground => {}
            _ if self.orbit.is_none() => {
                return Err(c.fail(
                    "scene.model_fields",
                    "model fields are sampled along an orbit: a space-borne platform needs \
                     [orbit]",
                ));
            }
            _ => {}
        }
        if m.files.is_empty() || m.files.len() > 16 {
            return Err(c.fail("scene.model_fields.files", "give 1 to 16 files"));
        }
        for role in m.variables.keys() {
            if !crate::config::model_fields::ROLES.contains(&role.as_str()) {
                return Err(c.fail(
                    &format!("scene.model_fields.variables.{role}"),
                    format!(
                        "is not a role; the roles are {}",
                        crate::config::model_fields::ROLES.join(", ")
                    ),
                ));
            }
        }
        let most = crate::limits::MAX_SUBCOLUMNS;
        if m.subcolumns == 0 || m.subcolumns > most {
            return Err(c.fail(
                "scene.model_fields.subcolumns",
                format!("must be from 1 to {most}, got {}", m.subcolumns),
            ));
        }
        c.range(
            "scene.model_fields.liquid_effective_radius_um",
            m.liquid_effective_radius_um,
            1.0,
            100.0,
        )?;
        c.range(
            "scene.model_fields.extinction_efficiency",
            m.extinction_efficiency,
            1.0,
            3.0,
        )?;
        let classes = m.aerosol_depolarization.keyed();
        let overrides = classes
            .iter()
            .map(|(k, v)| (format!("aerosol_depolarization.{k}"), *v))
            .chain([
                ("liquid_depolarization".to_string(), m.liquid_depolarization),
                ("ice_depolarization".to_string(), m.ice_depolarization),
            ]);
        if !m.aerosol_depolarization.is_empty() && m.aerosol_optics.is_none() {
            return Err(c.fail(
                "scene.model_fields.aerosol_depolarization",
                "needs scene.model_fields.aerosol_optics (without it no aerosol comes from \
                 the fields)",
            ));
        }
        for (key, delta) in overrides {
            if let Some(d) = delta {
                depolarization(c, &format!("scene.model_fields.{key}"), d)?;
            }
        }
        // (the names themselves: the species table's owner, `owners.aerosol_species`)
        if m.aerosol_species.is_some() && m.aerosol_optics.is_none() {
            return Err(c.fail(
                "scene.model_fields.aerosol_species",
                "needs scene.model_fields.aerosol_optics (the table that gives the species \
                 their optics)",
            ));
        }
        Ok(())
    }

    /// The surface: an albedo in [0, 1], within the window's reach, space-borne only.
    pub(super) fn validate_surface(&self, c: &Checker, s: &SurfaceConfig) -> Result<()> {
        if self.platform.kind == PlatformKind::Ground {
            return Err(c.fail(
                "surface",
                "a ground-based lidar looks up and sees no surface; remove [surface]",
            ));
        }
        if let Some(a) = s.albedo {
            c.range("surface.albedo", a, 0.0, 1.0)?;
        }
        c.range("surface.altitude_km", s.altitude_km, -0.5, 9.0)?;
        Ok(())
    }

    /// The scene's segments: positive lengths; their layers, aerosol and surface as the
    /// `[atmosphere]` and `[surface]` ones.
    pub(super) fn validate_scene(&self, c: &Checker, scene: &SceneConfig) -> Result<()> {
        match (self.platform.kind, scene.advection_speed_m_per_s) {
            (PlatformKind::Ground, Some(u)) => {
                c.range("scene.advection_speed_m_per_s", u, 0.1, 200.0)?
            }
            (PlatformKind::Ground, None) => {}
            (_, Some(_)) => {
                return Err(c.fail(
                    "scene.advection_speed_m_per_s",
                    "is a ground lidar's: a space-borne scene passes at the ground track's \
                     speed",
                ));
            }
            (_, None) => {}
        }
        if scene.curtain.is_some() && !scene.segments.is_empty() {
            return Err(c.fail(
                "scene.curtain",
                "gives the scene along the track: use it or scene.segments, not both",
            ));
        }
        if scene.curtain.is_some() && self.platform.kind == PlatformKind::Ground {
            return Err(c.fail("scene.curtain", "a curtain needs a space-borne platform"));
        }
        if let Some(m) = &scene.model_fields {
            self.validate_model_fields(c, scene, m)?;
        }
        if scene.segments.len() > 10_000 {
            return Err(c.fail("scene.segments", "at most 10,000 segments"));
        }
        for (i, seg) in scene.segments.iter().enumerate() {
            let key = |k: &str| format!("scene.segments[{i}].{k}");
            c.positive(&key("length_km"), seg.length_km, 1e6)?;
            for (n, l) in seg.layers.iter().flatten().enumerate() {
                let k = key(&format!("layers[{n}]."));
                if l.top_km <= l.base_km {
                    return Err(c.fail(&format!("{k}top_km"), "must be above base_km"));
                }
                c.range(
                    &format!("{k}extinction_per_km"),
                    l.extinction_per_km,
                    0.0,
                    1e4,
                )?;
                c.range(&format!("{k}lidar_ratio_sr"), l.lidar_ratio_sr, 1.0, 1e4)?;
                c.range(&format!("{k}depolarization"), l.depolarization, 0.0, 1.0)?;
                self.validate_broken(c, &k, l)?;
            }
            if seg
                .layers
                .iter()
                .flatten()
                .filter(|l| l.cloud_fraction.is_some())
                .count()
                > 3
            {
                return Err(c.fail(&key("layers"), "at most 3 broken layers per segment"));
            }
            if let Some(SegmentAerosol::Named(name)) = &seg.aerosol
                && name != "none"
            {
                return Err(c.fail(&key("aerosol"), "must be \"none\" or an aerosol table"));
            }
            if let Some(surface) = &seg.surface {
                if self.platform.kind == PlatformKind::Ground {
                    return Err(c.fail(
                        &key("surface"),
                        "a ground-based lidar looks up and sees no surface",
                    ));
                }
                self.validate_surface(c, surface)?;
            }
            if let Some(model) = &seg.molecular {
                super::atmosphere::check_molecular_model(model, &key("molecular"), c)?;
            }
        }
        Ok(())
    }
}

/// A linear depolarization ratio `δ = β⊥/β∥`: finite, `0 ≤ δ < 1` (δ = 1 would be
/// unpolarized backscatter, beyond any particle's single scattering).
fn depolarization(c: &Checker, key: &str, delta: f64) -> Result<()> {
    c.range(key, delta, 0.0, 1.0)?;
    if delta == 1.0 {
        return Err(c.fail(key, "must be below 1, got 1"));
    }
    Ok(())
}
