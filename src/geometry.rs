//! Viewing geometry (model.md §3): range ↔ altitude, the range-bin grid, the overlap
//! function η(r) and the ground-track speed.
//!
//! **Spherical Earth** (docs/model.md §3, default): from a platform at radius `P = R+H`, a
//! beam off nadir by φ reaches altitude z at range r with
//! `(R+z)² = P² + r² − 2rP·cos φ`, so `r(z) = P·cos φ − sqrt((R+z)² − P²·sin²φ)` (the
//! near intersection); it misses the Earth when `sin φ > R/P`. From a station at radius
//! `S = R+z0`, a beam at φ from zenith: `(R+z)² = S² + r² + 2rS·cos φ`. At φ = 0 both
//! reduce exactly to the flat formulas, which are used there (nadir and zenith results
//! do not change). **Flat Earth** (`platform.earth_curvature = false`, the paper's
//! model.md §3): space-borne `r = (H − z)/cos φ`, ground-based `r = (z − z0)/cos φ`.

use crate::config::{OverlapConfig, PlatformKind, ScenarioConfig};
use crate::constants::{EARTH_GM_M3_PER_S2, EARTH_RADIUS_M, SPEED_OF_LIGHT_M_PER_S};
use crate::error::{Error, Result};

/// Largest number of range bins a scenario may ask for.
pub const MAX_BINS: usize = 10_000_000;

/// Range width of a time bin, `ΔR = c·Δt/2` (300 m for 2 µs).
pub fn bin_range_m(bin_width_s: f64) -> f64 {
    SPEED_OF_LIGHT_M_PER_S * bin_width_s / 2.0
}

/// Ground-track speed of a circular orbit at `altitude_m`,
/// `v_g = R_E/(R_E+H) · sqrt(G·M_E/(R_E+H))` (model.md §3): ≈ 6.9 km/s at 600 km.
pub fn ground_track_speed_m_per_s(altitude_m: f64) -> f64 {
    let radius = EARTH_RADIUS_M + altitude_m;
    EARTH_RADIUS_M / radius * (EARTH_GM_M3_PER_S2 / radius).sqrt()
}

/// Maximum repetition rate with one pulse in flight at a time, `c/(2H)` (docs/model.md §3).
pub fn max_rep_rate_hz(range_m: f64) -> f64 {
    SPEED_OF_LIGHT_M_PER_S / (2.0 * range_m)
}

/// The largest repetition rate at which no pulse's returns reach another pulse's
/// recording window (docs/model.md §3, pulses in flight): returns come from ranges
/// `returns = (r_a, r_s)` (top of the atmosphere to the surface), the window records
/// `window = (r_n, r_f)`. Pulse `j−k` is seen in window `j` when `k·T ∈ [B, A]` with
/// `A = 2(r_s − r_n)/c`, `B = 2(r_a − r_f)/c`; with `B ≤ 0 < A` every window is clean
/// when `T > max(A, −B)`, whatever the number of pulses in flight. (A window wholly
/// above the atmosphere, `B > 0`, is clean at `T > A` too; lower rates that slip
/// between returns are not searched.)
pub fn clean_windows_max_rep_rate_hz(returns: (f64, f64), window: (f64, f64)) -> f64 {
    let a = 2.0 * (returns.1 - window.0) / SPEED_OF_LIGHT_M_PER_S;
    let b = 2.0 * (returns.0 - window.1) / SPEED_OF_LIGHT_M_PER_S;
    let t_min = a.max(-b);
    if t_min > 0.0 {
        1.0 / t_min
    } else {
        f64::INFINITY
    }
}

/// The beam's path and the range-bin grid.
#[derive(Debug, Clone)]
pub struct Geometry {
    /// Space-borne (looking down) or ground (looking up).
    pub kind: PlatformKind,
    /// Platform (space-borne) or station (ground) altitude, m.
    pub platform_altitude_m: f64,
    /// cos φ of the beam angle from nadir (space-borne) or zenith (ground).
    pub cos_angle: f64,
    /// sin φ; 0 for a nadir or zenith beam.
    pub sin_angle: f64,
    /// Whether the Earth is a sphere (else flat, the paper's geometry).
    pub spherical: bool,
    /// Range width of one bin, m.
    pub bin_range_m: f64,
    /// Range at the start of the window's first bin after the trigger, m (bin
    /// `pretrigger_bins`; bin 0 when there are none).
    pub window_start_range_m: f64,
    /// Number of bins, the pre-trigger bins included.
    pub n_bins: usize,
    /// Bins recorded before the pulse leaves (`acquisition.pretrigger_bins`): the first
    /// bins of the grid, at negative range, holding background and dark counts only.
    pub pretrigger_bins: usize,
}

impl Geometry {
    /// Builds the bin grid of a validated config: bin 0 starts at the window's top
    /// (space-borne) or bottom (ground); bins cover the window, the last one may overhang it.
    /// A ground window with `acquisition.pretrigger_bins = N` starts N bins before the
    /// pulse leaves (range −N·Δr), as a transient recorder with a pre-trigger does.
    pub fn from_config(cfg: &ScenarioConfig, file: &str) -> Result<Self> {
        let p = &cfg.platform;
        let a = &cfg.acquisition;
        let angle = p.off_nadir_deg.to_radians();
        let sin_angle = if p.off_nadir_deg == 0.0 {
            0.0
        } else {
            angle.sin()
        };
        let mut g = Geometry {
            kind: p.kind,
            platform_altitude_m: p.altitude_km * 1e3,
            cos_angle: angle.cos(),
            sin_angle,
            spherical: p.earth_curvature,
            bin_range_m: bin_range_m(cfg.instrument.bin_width_s),
            window_start_range_m: 0.0,
            n_bins: 1,
            pretrigger_bins: 0,
        };
        let (top_m, bottom_m) = (a.top_altitude_km * 1e3, a.bottom_altitude_km * 1e3);
        g.check_reach(bottom_m, p.off_nadir_deg, file)?;
        let (near_m, far_m) = match p.kind {
            PlatformKind::Spaceborne => (g.range_at_altitude(top_m), g.range_at_altitude(bottom_m)),
            PlatformKind::Ground => (g.range_at_altitude(bottom_m), g.range_at_altitude(top_m)),
        };
        let n = ((far_m - near_m) / g.bin_range_m - 1e-9).ceil().max(1.0);
        let pretrigger = check_pretrigger(p.kind, near_m, a.pretrigger_bins, file)?;
        if n + pretrigger as f64 > MAX_BINS as f64 {
            let (key, what) = if pretrigger == 0 {
                (
                    "instrument.bin_width_s",
                    format!("the window needs {n} bins"),
                )
            } else {
                (
                    "acquisition.pretrigger_bins",
                    format!("the window's {n} bins and {pretrigger} pre-trigger bins make"),
                )
            };
            return Err(Error::config(
                file,
                key,
                format!("{what} more than the {MAX_BINS} allowed"),
            ));
        }
        g.window_start_range_m = near_m;
        g.n_bins = n as usize + pretrigger;
        g.pretrigger_bins = pretrigger;
        Ok(g)
    }

    /// Whether bin `i` is a pre-trigger bin (recorded before the pulse leaves).
    pub fn is_pretrigger(&self, i: usize) -> bool {
        i < self.pretrigger_bins
    }

    /// Range at the start of bin 0, m (negative with pre-trigger bins).
    pub fn first_bin_range_m(&self) -> f64 {
        self.bin_range_bounds(0).0
    }

    /// Refuses a space-borne beam that misses the Earth or never reaches the window's
    /// bottom `bottom_m` (docs/model.md §3: it misses when `sin φ > R/(R+H)`).
    fn check_reach(&self, bottom_m: f64, angle_deg: f64, file: &str) -> Result<()> {
        if !self.spherical || self.kind == PlatformKind::Ground || self.sin_angle == 0.0 {
            return Ok(());
        }
        let p = EARTH_RADIUS_M + self.platform_altitude_m;
        let limit_deg = (EARTH_RADIUS_M / p).asin().to_degrees();
        let tangent_m = p * self.sin_angle - EARTH_RADIUS_M;
        if angle_deg > limit_deg {
            return Err(Error::config(
                file,
                "platform.off_nadir_deg",
                format!(
                    "{angle_deg}° off nadir from {} km misses the Earth (it passes {:.0} km above \
                     the ground); the limit is {limit_deg:.2}°",
                    self.platform_altitude_m / 1e3,
                    tangent_m / 1e3
                ),
            ));
        }
        if tangent_m > bottom_m {
            return Err(Error::config(
                file,
                "acquisition.bottom_altitude_km",
                format!(
                    "the beam {angle_deg}° off nadir never descends below {:.3} km; raise the \
                     window's bottom",
                    tangent_m / 1e3
                ),
            ));
        }
        Ok(())
    }

    /// The platform's (space-borne) or station's (ground) distance from the Earth's centre, m.
    fn origin_radius_m(&self) -> f64 {
        EARTH_RADIUS_M + self.platform_altitude_m
    }

    /// Whether the spherical formulas apply (a sphere and a slanted beam); a nadir or
    /// zenith beam uses the flat formulas, which are then exact.
    fn curved(&self) -> bool {
        self.spherical && self.sin_angle != 0.0
    }

    /// Altitude of the beam at range `r_m`.
    pub fn altitude_at_range(&self, r_m: f64) -> f64 {
        let sign = match self.kind {
            PlatformKind::Spaceborne => -1.0,
            PlatformKind::Ground => 1.0,
        };
        if !self.curved() {
            return self.platform_altitude_m + sign * r_m * self.cos_angle;
        }
        let p = self.origin_radius_m();
        (p * p + r_m * r_m + sign * 2.0 * r_m * p * self.cos_angle).sqrt() - EARTH_RADIUS_M
    }

    /// Range at which the beam reaches altitude `z_m` (may be negative when the beam never
    /// does; a space-borne beam above its tangent altitude only).
    pub fn range_at_altitude(&self, z_m: f64) -> f64 {
        if !self.curved() {
            return match self.kind {
                PlatformKind::Spaceborne => (self.platform_altitude_m - z_m) / self.cos_angle,
                PlatformKind::Ground => (z_m - self.platform_altitude_m) / self.cos_angle,
            };
        }
        let p = self.origin_radius_m();
        let rz = EARTH_RADIUS_M + z_m;
        let reach = (rz * rz - p * p * self.sin_angle * self.sin_angle)
            .max(0.0)
            .sqrt();
        match self.kind {
            PlatformKind::Spaceborne => p * self.cos_angle - reach,
            PlatformKind::Ground => reach - p * self.cos_angle,
        }
    }

    /// cos of the angle between the beam and the local vertical at altitude `z_m`
    /// (`cos φ` on a flat Earth; on a sphere `sin θ_z = P·sin φ/(R+z)`).
    pub fn local_cos_at(&self, z_m: f64) -> f64 {
        if !self.curved() {
            return self.cos_angle;
        }
        let s = (self.origin_radius_m() * self.sin_angle / (EARTH_RADIUS_M + z_m)).min(1.0);
        (1.0 - s * s).sqrt()
    }

    /// Range interval `[start, end)` of bin `i`, m.
    pub fn bin_range_bounds(&self, i: usize) -> (f64, f64) {
        // from the window's start, so that pre-trigger bins leave the window's ranges
        // bit for bit as they are without them
        let start = self.window_start_range_m + self.bins_after_trigger(i) * self.bin_range_m;
        (start, start + self.bin_range_m)
    }

    /// Bin-centre range of bin `i`, m.
    pub fn bin_centre_range_m(&self, i: usize) -> f64 {
        self.window_start_range_m + (self.bins_after_trigger(i) + 0.5) * self.bin_range_m
    }

    /// `i − pretrigger_bins`, exactly (negative for a pre-trigger bin).
    fn bins_after_trigger(&self, i: usize) -> f64 {
        i as f64 - self.pretrigger_bins as f64
    }

    /// Bin-centre altitude of bin `i`, m.
    pub fn bin_centre_altitude_m(&self, i: usize) -> f64 {
        self.altitude_at_range(self.bin_centre_range_m(i))
    }

    /// Range from the instrument to the end of the last bin, m.
    pub fn max_range_m(&self) -> f64 {
        self.bin_range_bounds(self.n_bins - 1).1
    }
}

/// Checks `acquisition.pretrigger_bins` (`n`) against the platform: pre-trigger bins are
/// a ground recorder's (the bins before the pulse leaves, contiguous with the window, so
/// the window must start at the station, `near_m` = 0); a space-borne window starts
/// hundreds of km from the instrument and takes its background from the bins above the
/// atmosphere. Returns `n`.
fn check_pretrigger(kind: PlatformKind, near_m: f64, n: usize, file: &str) -> Result<usize> {
    let key = "acquisition.pretrigger_bins";
    if n == 0 {
        return Ok(0);
    }
    if kind == PlatformKind::Spaceborne {
        return Err(Error::config(
            file,
            key,
            "pre-trigger bins are a ground recorder's; a space-borne window takes its background \
             from the bins above the atmosphere (raise acquisition.top_altitude_km above 86 km)",
        ));
    }
    if near_m.abs() > 1e-6 {
        return Err(Error::config(
            file,
            key,
            format!(
                "pre-trigger bins come just before the pulse leaves, so the window must start at \
                 the station: the bottom is {:.0} m of range above it (set \
                 acquisition.bottom_altitude_km to platform.altitude_km)",
                near_m
            ),
        ));
    }
    Ok(n)
}

/// The overlap function η(r) of model.md §3: the fraction of the laser spot seen by the receiver.
#[derive(Debug, Clone)]
pub enum Overlap {
    /// η = 1 everywhere (default; always so for space-borne ranges).
    Full,
    /// η = 0 below `full_overlap_m`, 1 beyond.
    Step {
        /// Range of complete overlap, m.
        full_overlap_m: f64,
    },
    /// Biaxial geometric overlap.
    Geometric(BiaxialOverlap),
}

/// Biaxial geometric overlap: the fraction of a uniform laser spot (radius
/// `w0 + r·θL/2`) inside the field-of-view circle (radius `R_tel + r·θ/2`) whose centre
/// is `axis_offset_m` away (parallel axes), after Measures (1984), *Laser Remote
/// Sensing*, §7.5 (circle–circle intersection).
#[derive(Debug, Clone, Copy)]
pub struct BiaxialOverlap {
    /// Laser radius at the exit, m.
    pub beam_radius_m: f64,
    /// Laser half divergence, rad.
    pub beam_half_angle_rad: f64,
    /// Telescope radius, m.
    pub telescope_radius_m: f64,
    /// Receiver half field of view, rad.
    pub fov_half_angle_rad: f64,
    /// Axis separation, m.
    pub axis_offset_m: f64,
}

impl BiaxialOverlap {
    /// η(r): intersection area over the spot area.
    pub fn eta(&self, r_m: f64) -> f64 {
        let r = r_m.max(0.0);
        let r_laser = self.beam_radius_m + r * self.beam_half_angle_rad;
        let r_fov = self.telescope_radius_m + r * self.fov_half_angle_rad;
        circle_overlap_area(r_laser, r_fov, self.axis_offset_m)
            / (std::f64::consts::PI * r_laser * r_laser)
    }

    /// Ranges of the kinks, where the circles start to touch (`d = R_L + R_T`) and where
    /// one comes to lie inside the other (`d + R_L = R_T` or `d + R_T = R_L`): the radii
    /// grow linearly with range, so each is a closed form.
    pub fn breakpoints_m(&self) -> Vec<f64> {
        let grow = self.beam_half_angle_rad + self.fov_half_angle_rad;
        let gain = self.fov_half_angle_rad - self.beam_half_angle_rad;
        let (w0, rt, d) = (
            self.beam_radius_m,
            self.telescope_radius_m,
            self.axis_offset_m,
        );
        [
            (d - w0 - rt) / grow,
            (d + w0 - rt) / gain,
            (rt + d - w0) / -gain,
        ]
        .into_iter()
        .filter(|r| r.is_finite() && *r > 0.0)
        .collect()
    }
}

impl Overlap {
    /// From the instrument config (`telescope_area_m2` gives the telescope radius).
    pub fn from_config(cfg: &ScenarioConfig) -> Self {
        let i = &cfg.instrument;
        match &i.overlap {
            None | Some(OverlapConfig::None) => Overlap::Full,
            Some(OverlapConfig::FullRange { full_overlap_m }) => Overlap::Step {
                full_overlap_m: *full_overlap_m,
            },
            Some(OverlapConfig::Geometric {
                beam_radius_m,
                beam_divergence_rad,
                axis_offset_m,
            }) => Overlap::Geometric(BiaxialOverlap {
                beam_radius_m: *beam_radius_m,
                beam_half_angle_rad: beam_divergence_rad / 2.0,
                telescope_radius_m: (i.telescope_area_m2 / std::f64::consts::PI).sqrt(),
                fov_half_angle_rad: i.fov_rad / 2.0,
                axis_offset_m: *axis_offset_m,
            }),
        }
    }

    /// η(r) in [0, 1].
    pub fn eta(&self, r_m: f64) -> f64 {
        match self {
            Overlap::Full => 1.0,
            Overlap::Step { full_overlap_m } => f64::from(u8::from(r_m >= *full_overlap_m)),
            Overlap::Geometric(b) => b.eta(r_m),
        }
    }

    /// Ranges where η(r) has a kink or a step; the bin integral splits there.
    pub fn breakpoints_m(&self) -> Vec<f64> {
        match self {
            Overlap::Full => vec![],
            Overlap::Step { full_overlap_m } => vec![*full_overlap_m],
            Overlap::Geometric(b) => b.breakpoints_m(),
        }
    }

    /// The range from which η(r) = 1, m: 0 for full overlap everywhere, the step's range,
    /// or for two circles the range where the beam comes to lie inside the field of view
    /// (`d + R_L = R_T`); infinite where it never does (a field of view narrower than the
    /// beam's divergence).
    pub fn full_overlap_range_m(&self) -> f64 {
        match self {
            Overlap::Full => 0.0,
            Overlap::Step { full_overlap_m } => *full_overlap_m,
            Overlap::Geometric(b) => {
                let gain = b.fov_half_angle_rad - b.beam_half_angle_rad;
                let inside = b.axis_offset_m + b.beam_radius_m - b.telescope_radius_m;
                match (inside <= 0.0, gain > 0.0) {
                    (true, _) => 0.0,
                    (false, true) => inside / gain,
                    (false, false) => f64::INFINITY,
                }
            }
        }
    }

    /// True when η(r) > 0 for r → 0⁺ (the 1/r² divergence is then not removed).
    pub fn sees_zero_range(&self) -> bool {
        self.eta(0.0) > 0.0 || self.eta(1e-9) > 0.0
    }
}

/// Area of the intersection of two circles of radii `a`, `b` whose centres are `d` apart.
pub fn circle_overlap_area(a: f64, b: f64, d: f64) -> f64 {
    use std::f64::consts::PI;
    if d >= a + b {
        return 0.0;
    }
    if d <= (a - b).abs() {
        let m = a.min(b);
        return PI * m * m;
    }
    let alpha = ((d * d + a * a - b * b) / (2.0 * d * a))
        .clamp(-1.0, 1.0)
        .acos();
    let beta = ((d * d + b * b - a * a) / (2.0 * d * b))
        .clamp(-1.0, 1.0)
        .acos();
    let kite = 0.5
        * ((-d + a + b) * (d + a - b) * (d - a + b) * (d + a + b))
            .max(0.0)
            .sqrt();
    a * a * alpha + b * b * beta - kite
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bin_width_2us_is_300m() {
        assert!((bin_range_m(2e-6) - 299.792458).abs() < 1e-9);
    }

    #[test]
    fn ground_track_speed_at_600km_is_about_6_9_km_s() {
        let v = ground_track_speed_m_per_s(600e3);
        assert!((v - 6.9e3).abs() < 0.1e3, "{v}");
    }

    #[test]
    fn max_rep_rate_at_600km_is_250hz() {
        assert!((max_rep_rate_hz(600e3) - 249.8).abs() < 0.1);
    }

    #[test]
    fn circle_overlap_limits() {
        use std::f64::consts::PI;
        assert_eq!(circle_overlap_area(1.0, 1.0, 2.5), 0.0);
        assert!((circle_overlap_area(1.0, 3.0, 0.5) - PI).abs() < 1e-12);
        // two unit circles one radius apart: 2π/3 − √3/2
        let lens = circle_overlap_area(1.0, 1.0, 1.0);
        assert!((lens - (2.0 * PI / 3.0 - 3f64.sqrt() / 2.0)).abs() < 1e-12);
    }

    #[test]
    fn geometric_overlap_rises_from_zero_to_one() {
        let o = Overlap::Geometric(BiaxialOverlap {
            beam_radius_m: 0.01,
            beam_half_angle_rad: 0.1e-3,
            telescope_radius_m: 0.1,
            fov_half_angle_rad: 0.5e-3,
            axis_offset_m: 0.3,
        });
        assert_eq!(o.eta(1.0), 0.0);
        assert!(!o.sees_zero_range());
        let bp = o.breakpoints_m();
        assert_eq!(bp.len(), 2);
        assert!((o.eta(bp[1] + 1.0) - 1.0).abs() < 1e-12);
        let mut last = 0.0;
        for k in 0..2000 {
            let e = o.eta(k as f64);
            assert!(e >= last - 1e-12 && e <= 1.0 + 1e-12);
            last = e;
        }
    }
}
