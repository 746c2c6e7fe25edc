//! A circular orbit around a spherical, rotating Earth, and its sub-satellite point.
//!
//! Algorithm (two-body Keplerian motion on a circle, spherical trigonometry; e.g.
//! Vallado, *Fundamentals of Astrodynamics and Applications*, 4th ed., §2.2 and §11.2;
//! Wertz, *Space Mission Engineering*, §8.1):
//!
//! * orbit radius `r = R_E + H`, mean motion `n = sqrt(G·M_E/r³)`, period `T = 2π/n`;
//! * argument of latitude (angle from the ascending node along the orbit)
//!   `u(t) = u0 + n·t`;
//! * geocentric latitude `φ = asin(sin i · sin u)`;
//! * longitude east of the ascending node in the inertial frame
//!   `Δλ = atan2(cos i · sin u, cos u)`; Earth-fixed longitude
//!   `λ(t) = λ_Ω + Δλ(u(t)) − ω_E·t`, with the node's Earth-fixed longitude at the start
//!   `λ_Ω = λ0 − Δλ(u0)`;
//! * start: `sin u0 = sin φ0 / sin i`, `u0 = asin(·)` on the ascending (northbound)
//!   half of the orbit, `π − asin(·)` on the descending half.
//!
//! Precision: exact for the model (a Keplerian circle over a sphere of radius
//! [`EARTH_RADIUS_M`]); the model ignores Earth's oblateness (J2 nodal regression,
//! ~1°/day for a sun-synchronous orbit, and the geodetic-vs-geocentric latitude
//! difference of up to 0.19°), drag and eccentricity. Over one orbit the sub-satellite
//! point of a real low orbit departs from it by a few km.
//!
//! **Along-track distance.** The length of the Earth-fixed ground track that the
//! latitudes and longitudes above describe, on the same sphere of radius
//! [`EARTH_RADIUS_M`]: the track of the sub-satellite point over the *rotating* Earth.
//! The sub-satellite point's Earth-fixed velocity is the inertial one minus `ω_E × r`;
//! with `p(u)` the unit vector of the inertial sub-satellite point,
//! `dp/du · (ẑ × p) = cos i`, so its speed is
//!
//! ```text
//! ds/dt = R_E · sqrt(n² − 2·n·ω_E·cos i + ω_E²·cos²φ),   cos²φ = 1 − sin²i·sin²u,
//! s(t)  = (R_E/n) · [F(u(t)) − F(u0)],   F(u) = ∫₀ᵘ sqrt(a² − b²·sin²x) dx,
//! a² = n² − 2·n·ω_E·cos i + ω_E²,   b² = ω_E²·sin²i
//! ```
//!
//! (`F` is `a` times the incomplete elliptic integral of the second kind `E(u | b²/a²)`).
//! `F` has period π in its integrand: `F(u) = m·F(π) + F(u − mπ)`, and `F` on [0, π)
//! is a table of 16 panels of π/16 plus one partial panel, each by 8-point
//! Gauss–Legendre quadrature. The integrand is analytic with `b²/a² ≈ 0.005` for a low
//! orbit, so the quadrature error is below 1e-12 relative (checked in the tests against
//! a 2·10⁶-step midpoint sum and against the summed great-circle lengths between
//! successive sub-satellite points). Over a non-rotating Earth (`ω_E = 0`) `s = v_g·t`
//! with `v_g = R_E·n` (model.md §3, [`ground_track_speed_m_per_s`]); the Earth's rotation
//! changes the ground speed by about `ω_E·R_E·|cos i|` (up to 0.46 km/s for an
//! equatorial orbit; for a sun-synchronous one, i = 98.2°, ~70 m/s: its track over the
//! rotating Earth is 1.2 % longer than `v_g·t` at the equator, 1.0 % at 60°).

use crate::config::{Checker, OrbitConfig, ScenarioConfig};
use crate::constants::{EARTH_GM_M3_PER_S2, EARTH_RADIUS_M, EARTH_ROTATION_RAD_PER_S};
use crate::geometry::ground_track_speed_m_per_s;
use std::f64::consts::PI;

/// A circular orbit and where it starts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Orbit {
    /// Altitude above the spherical Earth, m.
    altitude_m: f64,
    /// Inclination i, rad.
    inclination_rad: f64,
    /// Argument of latitude at t = 0, rad.
    u0_rad: f64,
    /// Earth-fixed longitude of the ascending node at t = 0, rad.
    node_longitude_rad: f64,
    /// Mean motion n, rad s⁻¹.
    mean_motion_rad_per_s: f64,
    /// The Earth-fixed ground track's length per unit argument of latitude:
    /// `a² = n² − 2nω_E·cos i + ω_E²`, `b² = ω_E²·sin²i` (rad² s⁻²).
    speed_terms: (f64, f64),
    /// `F(kπ/16)`, k = 0…16 (the cumulative integral at the panel edges), rad s⁻¹.
    panel_edges: [f64; PANELS + 1],
}

/// Panels of `F` on [0, π].
const PANELS: usize = 16;

/// Nodes and weights of 8-point Gauss–Legendre quadrature on [−1, 1] (Abramowitz &
/// Stegun 1964, Table 25.4).
const GAUSS_LEGENDRE_8: [(f64, f64); 8] = [
    (-0.960_289_856_497_536_3, 0.101_228_536_290_376_26),
    (-0.796_666_477_413_626_7, 0.222_381_034_453_374_47),
    (-0.525_532_409_916_329, 0.313_706_645_877_887_3),
    (-0.183_434_642_495_649_8, 0.362_683_783_378_362),
    (0.183_434_642_495_649_8, 0.362_683_783_378_362),
    (0.525_532_409_916_329, 0.313_706_645_877_887_3),
    (0.796_666_477_413_626_7, 0.222_381_034_453_374_47),
    (0.960_289_856_497_536_3, 0.101_228_536_290_376_26),
];

/// The sub-satellite point at one time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GroundPoint {
    /// Geocentric latitude, degrees in [−90, 90].
    pub latitude_deg: f64,
    /// Longitude, degrees east in [−180, 180).
    pub longitude_deg: f64,
    /// Distance along the Earth-fixed ground track since the start (the length of the
    /// track these latitudes and longitudes describe; negative before the start), m.
    pub along_track_m: f64,
}

/// Checks `[orbit]`: an orbit [`Orbit::new`] accepts at the platform's altitude.
pub fn validate(config: &ScenarioConfig, c: &Checker) -> crate::error::Result<()> {
    if let Some(o) = &config.orbit {
        Orbit::from_config(o, config.platform.altitude_km * 1e3)
            .map_err(|reason| c.fail("orbit", reason))?;
    }
    Ok(())
}

impl Orbit {
    /// The orbit of `[orbit]` at `altitude_m` (the platform's altitude).
    pub fn from_config(o: &OrbitConfig, altitude_m: f64) -> Result<Self, String> {
        Orbit::new(
            altitude_m,
            o.inclination_deg,
            o.start_latitude_deg,
            o.start_longitude_deg,
            o.ascending,
        )
    }

    /// The orbit at `altitude_m` with inclination `inclination_deg` (0–180; above 90 is
    /// retrograde) whose sub-satellite point at t = 0 is (`start_latitude_deg`,
    /// `start_longitude_deg`), moving north (`ascending`) or south.
    ///
    /// Refuses a non-finite input, an altitude ≤ −R_E, an inclination outside [0, 180],
    /// and a start latitude the orbit never reaches: `|φ0| > i` (prograde) or
    /// `|φ0| > 180 − i` (retrograde). An equatorial orbit (i = 0 or 180) starts at φ0 = 0
    /// and ignores `ascending`.
    pub fn new(
        altitude_m: f64,
        inclination_deg: f64,
        start_latitude_deg: f64,
        start_longitude_deg: f64,
        ascending: bool,
    ) -> Result<Self, String> {
        let inputs = [
            altitude_m,
            inclination_deg,
            start_latitude_deg,
            start_longitude_deg,
        ];
        if inputs.iter().any(|x| !x.is_finite()) {
            return Err("orbit: altitude, inclination and start point must be finite".into());
        }
        if altitude_m <= -EARTH_RADIUS_M {
            return Err(format!(
                "orbit: altitude {altitude_m} m is inside the Earth's centre"
            ));
        }
        if !(0.0..=180.0).contains(&inclination_deg) {
            return Err(format!(
                "orbit: inclination {inclination_deg}° is outside [0°, 180°]"
            ));
        }
        let max_latitude_deg = inclination_deg.min(180.0 - inclination_deg);
        if start_latitude_deg.abs() > max_latitude_deg + 1e-12 {
            return Err(format!(
                "orbit: start latitude {start_latitude_deg}° is out of reach of an orbit \
                 inclined {inclination_deg}°: |latitude| must be at most {max_latitude_deg}°"
            ));
        }
        let inclination_rad = inclination_deg.to_radians();
        let u0_rad =
            start_argument_of_latitude(inclination_rad, start_latitude_deg.to_radians(), ascending);
        let radius_m = EARTH_RADIUS_M + altitude_m;
        let n = (EARTH_GM_M3_PER_S2 / radius_m.powi(3)).sqrt();
        let w = EARTH_ROTATION_RAD_PER_S;
        let speed_terms = (
            n * n - 2.0 * n * w * inclination_rad.cos() + w * w,
            (w * inclination_rad.sin()).powi(2),
        );
        let mut panel_edges = [0.0; PANELS + 1];
        let h = PI / PANELS as f64;
        for k in 0..PANELS {
            panel_edges[k + 1] =
                panel_edges[k] + speed_integral(speed_terms, k as f64 * h, (k + 1) as f64 * h);
        }
        Ok(Orbit {
            altitude_m,
            inclination_rad,
            u0_rad,
            node_longitude_rad: start_longitude_deg.to_radians()
                - longitude_from_node(inclination_rad, u0_rad),
            mean_motion_rad_per_s: n,
            speed_terms,
            panel_edges,
        })
    }

    /// `F(u) = ∫₀ᵘ sqrt(a² − b²·sin²x) dx` (module docs), rad s⁻¹.
    fn track_integral(&self, u_rad: f64) -> f64 {
        let periods = (u_rad / PI).floor();
        let rest = u_rad - periods * PI;
        let h = PI / PANELS as f64;
        let k = ((rest / h) as usize).min(PANELS - 1);
        let start = k as f64 * h;
        periods * self.panel_edges[PANELS]
            + self.panel_edges[k]
            + speed_integral(self.speed_terms, start, rest)
    }

    /// Distance along the Earth-fixed ground track from the start to `t_s`, m (module
    /// docs): the length of the track the sub-satellite points describe.
    pub fn along_track_m(&self, t_s: f64) -> f64 {
        let n = self.mean_motion_rad_per_s;
        let u = self.u0_rad + n * t_s;
        EARTH_RADIUS_M / n * (self.track_integral(u) - self.track_integral(self.u0_rad))
    }

    /// Orbital period `T = 2π·sqrt((R_E+H)³/(G·M_E))`, s (≈ 5792 s = 96.5 min at 600 km).
    pub fn period_s(&self) -> f64 {
        2.0 * PI / self.mean_motion_rad_per_s
    }

    /// Ground-track speed `v_g = R_E/(R_E+H)·sqrt(G·M_E/(R_E+H)) = R_E·n`, m s⁻¹
    /// (model.md §3; ≈ 6.9 km/s at 600 km), the speed of the sub-satellite point over a
    /// non-rotating Earth. The same formula as [`ground_track_speed_m_per_s`].
    pub fn ground_speed_m_per_s(&self) -> f64 {
        ground_track_speed_m_per_s(self.altitude_m)
    }

    /// Sub-satellite point `t_s` seconds after the start (negative `t_s` runs backwards).
    pub fn position(&self, t_s: f64) -> GroundPoint {
        let u = self.u0_rad + self.mean_motion_rad_per_s * t_s;
        let latitude = (self.inclination_rad.sin() * u.sin())
            .clamp(-1.0, 1.0)
            .asin();
        let longitude = self.node_longitude_rad + longitude_from_node(self.inclination_rad, u)
            - EARTH_ROTATION_RAD_PER_S * t_s;
        GroundPoint {
            latitude_deg: latitude.to_degrees(),
            longitude_deg: wrap_longitude_deg(longitude.to_degrees()),
            along_track_m: self.along_track_m(t_s),
        }
    }
}

/// `∫_{x0}^{x1} sqrt(a² − b²·sin²x) dx` by 8-point Gauss–Legendre quadrature (one panel
/// of at most π/16).
fn speed_integral((a2, b2): (f64, f64), x0: f64, x1: f64) -> f64 {
    let (mid, half) = (0.5 * (x0 + x1), 0.5 * (x1 - x0));
    half * GAUSS_LEGENDRE_8
        .iter()
        .map(|&(x, w)| {
            let s = (mid + half * x).sin();
            w * (a2 - b2 * s * s).sqrt()
        })
        .sum::<f64>()
}

/// `u0` from `sin u0 = sin φ0 / sin i`: `asin` going north, `π − asin` going south
/// (`0` for an equatorial orbit).
fn start_argument_of_latitude(inclination_rad: f64, latitude_rad: f64, ascending: bool) -> f64 {
    let sin_i = inclination_rad.sin();
    if sin_i.abs() < 1e-15 {
        return 0.0;
    }
    let u = (latitude_rad.sin() / sin_i).clamp(-1.0, 1.0).asin();
    if ascending { u } else { PI - u }
}

/// Inertial longitude east of the ascending node at argument of latitude `u`:
/// `atan2(cos i · sin u, cos u)`, rad.
fn longitude_from_node(inclination_rad: f64, u_rad: f64) -> f64 {
    (inclination_rad.cos() * u_rad.sin()).atan2(u_rad.cos())
}

/// Longitude in degrees wrapped to [−180, 180).
fn wrap_longitude_deg(longitude_deg: f64) -> f64 {
    let wrapped = (longitude_deg + 180.0).rem_euclid(360.0) - 180.0;
    // rem_euclid may round up to exactly 360 for tiny negative inputs
    if wrapped >= 180.0 {
        wrapped - 360.0
    } else {
        wrapped
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Signed difference of two longitudes, degrees in [−180, 180).
    fn dlon(a: f64, b: f64) -> f64 {
        wrap_longitude_deg(a - b)
    }

    #[test]
    fn ground_speed_matches_model_md() {
        let o600 = Orbit::new(600e3, 98.0, 0.0, 0.0, true).unwrap();
        assert!((o600.ground_speed_m_per_s() - 6.9e3).abs() < 0.05e3);
        let o705 = Orbit::new(705e3, 98.2, 0.0, 0.0, true).unwrap();
        let v = o705.ground_speed_m_per_s();
        assert!((v - 6.77e3).abs() < 0.02e3, "{v}");
        assert_eq!(v, ground_track_speed_m_per_s(705e3));
    }

    #[test]
    fn period_of_a_low_orbit() {
        // Kepler over R_E = 6371.0088 km: 600 km → 96.54 min, 705 km → 98.73 min
        // (CALIPSO's published period is 98.8 min)
        let t600 = Orbit::new(600e3, 98.0, 0.0, 0.0, true).unwrap().period_s();
        assert!((t600 / 60.0 - 96.54).abs() < 0.01, "{}", t600 / 60.0);
        let t705 = Orbit::new(705e3, 98.2, 0.0, 0.0, true).unwrap().period_s();
        assert!((t705 / 60.0 - 98.8).abs() < 0.1, "{}", t705 / 60.0);
    }

    #[test]
    fn starts_where_asked() {
        for (lat, lon, asc) in [
            (0.0, 0.0, true),
            (45.0, -120.0, false),
            (-60.0, 179.9, true),
        ] {
            let o = Orbit::new(705e3, 98.2, lat, lon, asc).unwrap();
            let p = o.position(0.0);
            assert!((p.latitude_deg - lat).abs() < 1e-9);
            assert!(dlon(p.longitude_deg, lon).abs() < 1e-9);
            assert_eq!(p.along_track_m, 0.0);
            // ascending moves north, descending south
            let later = o.position(1.0);
            assert_eq!(later.latitude_deg > lat, asc, "{lat} {asc}");
        }
    }

    #[test]
    fn latitude_stays_within_inclination() {
        for (i, asc) in [(51.6, true), (98.2, false), (30.0, true)] {
            let o = Orbit::new(600e3, i, 10.0, 20.0, asc).unwrap();
            let limit = f64::min(i, 180.0 - i);
            let mut max_seen = 0.0f64;
            let end = 5.0 * o.period_s();
            let mut t = 0.0;
            while t < end {
                let lat = o.position(t).latitude_deg;
                assert!(lat.abs() <= limit + 1e-9, "i={i}: {lat}");
                max_seen = max_seen.max(lat.abs());
                t += 10.0;
            }
            assert!(max_seen > limit - 0.01, "i={i}: max {max_seen}");
        }
    }

    #[test]
    fn one_period_later_same_latitude_longitude_west_by_earth_rotation() {
        let o = Orbit::new(705e3, 98.2, 33.0, 12.0, false).unwrap();
        let period = o.period_s();
        let (p0, p1) = (o.position(0.0), o.position(period));
        assert!((p1.latitude_deg - p0.latitude_deg).abs() < 1e-9);
        let shift = dlon(p1.longitude_deg, p0.longitude_deg);
        let expected = -(EARTH_ROTATION_RAD_PER_S * period).to_degrees();
        assert!((shift - expected).abs() < 1e-9, "{shift} vs {expected}");
        // a 98.7-min orbit moves ~24.75° west per revolution
        assert!((expected + 24.75).abs() < 0.01, "{expected}");
    }

    /// Haversine great-circle distance between two points on the sphere of radius R_E, m.
    fn haversine_m(a: &GroundPoint, b: &GroundPoint) -> f64 {
        let (la, lb) = (a.latitude_deg.to_radians(), b.latitude_deg.to_radians());
        let dl = (b.longitude_deg - a.longitude_deg).to_radians();
        let h = ((lb - la) / 2.0).sin().powi(2) + la.cos() * lb.cos() * (dl / 2.0).sin().powi(2);
        2.0 * EARTH_RADIUS_M * h.sqrt().min(1.0).asin()
    }

    #[test]
    fn along_track_distance_is_the_length_of_the_track_the_points_describe() {
        // the summed great-circle lengths between sub-satellite points 0.1 s apart
        // (chord error ~ (v·dt)²/(24 R²) relative: 1e-17) over two orbits and back
        for (i, lat, asc) in [(98.2, 10.0, true), (51.6, -30.0, false), (0.0, 0.0, true)] {
            let o = Orbit::new(705e3, i, lat, 12.0, asc).unwrap();
            let (dt, steps) = (0.1, 2 * (o.period_s() / 0.1) as usize);
            let mut sum = 0.0;
            let mut prev = o.position(0.0);
            for k in 1..=steps {
                let p = o.position(k as f64 * dt);
                sum += haversine_m(&prev, &p);
                prev = p;
                if k % 5000 == 0 || k == steps {
                    let s = p.along_track_m;
                    assert!((s - sum).abs() < 1e-6 * sum, "i={i} k={k}: {s} vs {sum}");
                }
            }
            // backwards in time the distance is negative and as long
            let back = o.position(-1000.0).along_track_m;
            assert!(back < 0.0);
            assert!((back + o.position(1000.0).along_track_m).abs() < 0.05 * -back);
        }
    }

    #[test]
    fn along_track_quadrature_matches_a_midpoint_sum() {
        // ds/dt = R_E·sqrt(n² − 2nω cos i + ω² cos²φ), summed by 2e6 midpoints over 1.3 orbits
        let o = Orbit::new(600e3, 97.8, -40.0, 0.0, false).unwrap();
        let t_end = 1.3 * o.period_s();
        let steps = 2_000_000;
        let h = t_end / steps as f64;
        let n = 2.0 * PI / o.period_s();
        let w = EARTH_ROTATION_RAD_PER_S;
        let cos_i = 97.8f64.to_radians().cos();
        let sum: f64 = (0..steps)
            .map(|k| {
                let phi = o.position((k as f64 + 0.5) * h).latitude_deg.to_radians();
                EARTH_RADIUS_M
                    * (n * n - 2.0 * n * w * cos_i + w * w * phi.cos().powi(2)).sqrt()
                    * h
            })
            .sum();
        let s = o.along_track_m(t_end);
        assert!((s / sum - 1.0).abs() < 1e-9, "{s} vs {sum}");
    }

    #[test]
    fn earth_rotation_lengthens_a_retrograde_track_at_the_equator() {
        // at the equator of a 98.2° orbit the Earth-fixed speed is
        // R_E·sqrt(n² − 2nω cos i + ω²): 1.2 % above v_g = R_E·n
        let o = Orbit::new(705e3, 98.2, 0.0, 0.0, true).unwrap();
        let n = 2.0 * PI / o.period_s();
        let w = EARTH_ROTATION_RAD_PER_S;
        let expected = (1.0 - 2.0 * (w / n) * 98.2f64.to_radians().cos() + (w / n).powi(2)).sqrt();
        let ratio = o.along_track_m(1.0) / o.ground_speed_m_per_s();
        assert!((ratio - expected).abs() < 1e-6, "{ratio} vs {expected}");
        assert!((ratio - 1.012).abs() < 0.0005, "{ratio}");
    }

    #[test]
    fn inertial_arc_between_points_is_v_g_t() {
        // Great-circle distance between two sub-satellite points, corrected for the
        // Earth's rotation, equals v_g·Δt for Δt short of half an orbit.
        let o = Orbit::new(600e3, 51.6, -20.0, 40.0, true).unwrap();
        let dt = 600.0;
        let (a, b) = (o.position(0.0), o.position(dt));
        let lon_b = (b.longitude_deg + (EARTH_ROTATION_RAD_PER_S * dt).to_degrees()).to_radians();
        let (la, lb) = (a.latitude_deg.to_radians(), b.latitude_deg.to_radians());
        let c = la.sin() * lb.sin()
            + la.cos() * lb.cos() * (lon_b - a.longitude_deg.to_radians()).cos();
        let arc_m = EARTH_RADIUS_M * c.clamp(-1.0, 1.0).acos();
        let vt = o.ground_speed_m_per_s() * dt;
        assert!((arc_m - vt).abs() < 1e-3, "{arc_m} vs {vt}");
    }

    #[test]
    fn polar_orbit_reaches_the_pole_at_a_quarter_period() {
        let o = Orbit::new(600e3, 90.0, 0.0, 0.0, true).unwrap();
        let p = o.position(o.period_s() / 4.0);
        assert!((p.latitude_deg - 90.0).abs() < 1e-6, "{}", p.latitude_deg);
        let half = o.position(o.period_s() / 2.0);
        assert!(half.latitude_deg.abs() < 1e-9);
    }

    #[test]
    fn retrograde_orbit_moves_west_in_inertial_longitude() {
        let o = Orbit::new(705e3, 98.2, 0.0, 0.0, true).unwrap();
        // 100 s after the node the inertial longitude has decreased (cos i < 0)
        let t = 100.0;
        let p = o.position(t);
        let inertial = p.longitude_deg + (EARTH_ROTATION_RAD_PER_S * t).to_degrees();
        assert!(inertial < 0.0, "{inertial}");
    }

    #[test]
    fn refuses_unreachable_start_latitude() {
        let e = Orbit::new(600e3, 51.6, 60.0, 0.0, true).unwrap_err();
        assert!(e.contains("51.6"), "{e}");
        let e = Orbit::new(705e3, 98.2, -85.0, 0.0, true).unwrap_err();
        assert!(e.contains("81.8"), "{e}");
        assert!(Orbit::new(705e3, 98.2, -81.8, 0.0, true).is_ok());
        assert!(Orbit::new(600e3, 0.0, 0.0, 0.0, true).is_ok());
        assert!(Orbit::new(600e3, 0.0, 0.1, 0.0, true).is_err());
        assert!(Orbit::new(600e3, 190.0, 0.0, 0.0, true).is_err());
        assert!(Orbit::new(f64::NAN, 98.0, 0.0, 0.0, true).is_err());
    }

    #[test]
    fn equatorial_orbit_stays_on_the_equator() {
        let o = Orbit::new(600e3, 0.0, 0.0, 10.0, false).unwrap();
        for k in 0..20 {
            assert!(o.position(k as f64 * 500.0).latitude_deg.abs() < 1e-12);
        }
    }

    #[test]
    fn longitude_wraps_to_half_open_interval() {
        assert_eq!(wrap_longitude_deg(180.0), -180.0);
        assert_eq!(wrap_longitude_deg(-180.0), -180.0);
        assert!((wrap_longitude_deg(540.5) - 180.5 + 360.0).abs() < 1e-12);
        assert!((wrap_longitude_deg(-190.0) - 170.0).abs() < 1e-12);
        assert!(wrap_longitude_deg(-1e-17) < 180.0);
    }
}
