//! The beam path through the piecewise-constant atmosphere and its exact bin integral
//! (the algorithm is in the module docs of `signal`).

use std::sync::OnceLock;

use crate::atmosphere::Atmosphere;
use crate::config::PlatformKind;
use crate::error::{Error, Result};
use crate::geometry::{Geometry, Overlap};
use crate::surface::Surface;

use super::laying::{self, PathBytes, PathExtent, Segment, SegmentLobes};

/// Degree of the interpolant of `η/r²` on a piece, plus one.
const NODES: usize = 6;
/// Largest piece length relative to its start range.
const MAX_PIECE_FRACTION: f64 = 0.1;
/// Smallest piece next to an overlap kink, m.
const GRADED_MIN_PIECE_M: f64 = 1e-4;

/// The surface's echo on the beam: where it is and its integrated backscatter.
#[derive(Debug, Clone, Copy)]
pub struct SurfaceEcho {
    /// Range of the surface from the instrument, m.
    pub range_m: f64,
    /// `ρ·cos θ/π`, sr⁻¹ (`crate::surface`).
    pub integrated_backscatter_sr: f64,
}

/// The beam path from the instrument out to the last bin.
#[derive(Debug, Clone)]
pub struct BeamPath {
    /// In range order: from the instrument ([`PathExtent::Whole`]) or from the last
    /// segment before the window's first bin ([`PathExtent::Bins`]).
    pub(super) segments: Vec<Segment>,
    /// One per segment for [`PathExtent::Whole`], else empty.
    pub(super) lobes: Vec<SegmentLobes>,
    /// The memory the path took while it was laid and after ([`laying::laying_bytes`]).
    laid_bytes: PathBytes,
    overlap: Overlap,
    /// The surface echo, if the scene has a surface within the window.
    surface: Option<SurfaceEcho>,
    /// Range below which η ≡ 0 (0 when the receiver sees from r = 0).
    zero_overlap_until_m: f64,
    /// The overlap's kinks (`Overlap::breakpoints_m`), ascending: the bin integral splits
    /// there and grades its pieces towards them.
    kinks_m: Vec<f64>,
}

impl BeamPath {
    /// Lays the atmosphere's slabs along the beam of `geometry`, out to its last bin, as
    /// much of it as `extent` keeps; a space-borne beam stops at the `surface` (at sea
    /// level when there is none), whose echo is added to the bin that holds it.
    pub fn new(
        atmosphere: &Atmosphere,
        geometry: &Geometry,
        overlap: Overlap,
        surface: Option<Surface>,
        extent: PathExtent,
    ) -> Self {
        let r_max = geometry.max_range_m();
        let z_far = geometry.altitude_at_range(r_max);
        let span = Self::altitude_span(atmosphere, geometry, surface.as_ref());
        let laid_bytes = laying::laying_bytes(atmosphere, geometry, surface.as_ref(), extent);
        let surface = surface
            .filter(|s| geometry.kind == PlatformKind::Spaceborne && s.altitude_m >= z_far)
            .map(|s| SurfaceEcho {
                range_m: geometry.range_at_altitude(s.altitude_m),
                integrated_backscatter_sr: atmosphere.surface_echo_share()
                    * s.integrated_backscatter_sr(geometry.local_cos_at(s.altitude_m)),
            });
        let (segments, lobes) = laying::lay(atmosphere, geometry, span, extent);
        let zero_overlap_until_m = if overlap.sees_zero_range() {
            0.0
        } else {
            overlap
                .breakpoints_m()
                .into_iter()
                .fold(f64::INFINITY, f64::min)
                .min(r_max)
        };
        let mut kinks_m = overlap.breakpoints_m();
        kinks_m.sort_by(f64::total_cmp);
        BeamPath {
            segments,
            lobes,
            laid_bytes,
            overlap,
            surface,
            zero_overlap_until_m,
            kinks_m,
        }
    }

    /// The altitudes `(z_lo, z_hi)` the beam's path through the atmosphere spans
    /// ([`laying::altitude_span`]).
    pub fn altitude_span(
        atmosphere: &Atmosphere,
        geometry: &Geometry,
        surface: Option<&Surface>,
    ) -> (f64, f64) {
        laying::altitude_span(atmosphere, geometry, surface)
    }

    /// The range where the beam's path through the atmosphere ends, m: a space-borne
    /// beam's surface (sea level without one), or the top of the atmosphere or the
    /// window's end looking up; infinite for an empty path.
    pub fn end_range_m(&self) -> f64 {
        self.segments.last().map_or(f64::INFINITY, |s| s.r_end)
    }

    /// The surface's echo, if any.
    pub fn surface(&self) -> Option<SurfaceEcho> {
        self.surface
    }

    /// The segments, ordered by range.
    pub fn segments(&self) -> &[Segment] {
        &self.segments
    }

    /// Lets the segments go once the model is computed, for a command that reads no more
    /// of the path (`expect`, whose CSV's columns then take their place): the path is
    /// empty after, as one through no atmosphere, and integrates no signal.
    pub fn release(&mut self) {
        self.segments = Vec::new();
        self.lobes = Vec::new();
    }

    /// The memory the path took while it was laid and after (its segments, and every
    /// slab's edge while they were iterated), bytes.
    pub fn laid_bytes(&self) -> PathBytes {
        self.laid_bytes
    }

    /// The overlap function η(r).
    pub fn overlap(&self) -> &Overlap {
        &self.overlap
    }

    /// One-way attenuating optical depth from the instrument to range `r_m`.
    pub fn optical_depth(&self, r_m: f64) -> f64 {
        let idx = self.segments.partition_point(|s| s.r_start <= r_m);
        if idx == 0 {
            return 0.0;
        }
        let s = &self.segments[idx - 1];
        s.tau_start + s.alpha * (r_m.min(s.r_end) - s.r_start)
    }

    /// Two-way transmission `T²(r) = exp(−2τ(r))`.
    pub fn two_way_transmission(&self, r_m: f64) -> f64 {
        (-2.0 * self.optical_depth(r_m)).exp()
    }

    /// `∫_{r_a}^{r_b} η(r)·β(r)·T²(r)/r² dr` (m⁻¹ sr⁻¹ m⁻¹·m = sr⁻¹ m⁻²·m), the
    /// atmospheric factor of a bin. Errors when the integral diverges (`r → 0` with η ≠ 0).
    pub fn bin_integral(&self, r_a: f64, r_b: f64) -> Result<f64> {
        let r_a = r_a.max(self.zero_overlap_until_m.min(r_b));
        if r_a <= 0.0 && r_b > 0.0 {
            return Err(Error::Unsupported(
                "a range bin starts at the instrument (r = 0) where the receiver sees the beam: the \
                 1/r² integral diverges; set instrument.overlap or raise acquisition.bottom_altitude_km"
                    .into(),
            ));
        }
        let first = self.segments.partition_point(|s| s.r_end <= r_a);
        let mut total = 0.0;
        for s in self.segments[first..]
            .iter()
            .take_while(|s| s.r_start < r_b)
        {
            let (a, b) = (s.r_start.max(r_a), s.r_end.min(r_b));
            if b <= a || s.beta == 0.0 {
                continue;
            }
            let t2_a = (-2.0 * (s.tau_start + s.alpha * (a - s.r_start))).exp();
            if t2_a == 0.0 {
                break; // beyond here T² underflows: nothing more reaches the receiver
            }
            total += s.beta * t2_a * self.attenuated_range_integral(a, b, 2.0 * s.alpha);
        }
        if let Some(echo) = self.surface.filter(|e| e.range_m >= r_a && e.range_m < r_b) {
            let r = echo.range_m;
            total +=
                self.overlap.eta(r) * echo.integrated_backscatter_sr * self.two_way_transmission(r)
                    / (r * r);
        }
        Ok(total)
    }

    /// The range weight of a bin, `∫_{r_a}^{r_b} η(r)/r² dr` (m⁻¹): the bin integral
    /// of a uniform, unattenuated unit backscatter, so that
    /// `bin_integral = attenuated backscatter (bin average) · range_weight`. Same
    /// quadrature as [`bin_integral`](Self::bin_integral); call it on bins whose
    /// integral converges.
    pub fn range_weight(&self, r_a: f64, r_b: f64) -> f64 {
        let r_a = r_a.max(self.zero_overlap_until_m.min(r_b));
        if r_b <= r_a || r_a <= 0.0 {
            return 0.0;
        }
        self.attenuated_range_integral(r_a, r_b, 0.0)
    }

    /// `∫_a^b η(r)/r² · e^{−k(r−a)} dr`, splitting at the overlap's kinks.
    fn attenuated_range_integral(&self, a: f64, b: f64, k: f64) -> f64 {
        let is_kink = |r: f64| self.kinks_m.contains(&r);
        let mut total = 0.0;
        let mut start = a;
        let inside = self.kinks_m.iter().copied().filter(|r| *r > a && *r < b);
        for end in inside.chain(std::iter::once(b)) {
            let grade = (is_kink(start), is_kink(end));
            total += (-k * (start - a)).exp() * self.smooth_range_integral(start, end, k, grade);
            start = end;
        }
        total
    }

    /// `∫_a^b η(r)/r² · e^{−k(r−a)} dr` where η is smooth inside (a, b): pieces of length
    /// ≤ 10 % of their start range, product integration on each. Towards an end that is
    /// an overlap kink (`grade`: at a, at b), where η may have a non-polynomial kink
    /// (circles starting to touch: η ∝ (r − r₀)^{3/2}), the pieces also shrink
    /// geometrically, down to 0.1 mm.
    fn smooth_range_integral(&self, a: f64, b: f64, k: f64, grade: (bool, bool)) -> f64 {
        let mut total = 0.0;
        let mut s = a;
        while s < b {
            let mut w = (MAX_PIECE_FRACTION * s).min(b - s);
            let to_kink = match grade {
                (true, true) => (s - a).min(b - s),
                (true, false) => s - a,
                (false, true) => b - s,
                (false, false) => f64::INFINITY,
            };
            w = w.min(GRADED_MIN_PIECE_M.max(0.5 * to_kink)).min(b - s);
            let decay = (-k * (s - a)).exp();
            if decay == 0.0 {
                break;
            }
            let g: [f64; NODES] = std::array::from_fn(|m| {
                let r = s + w * chebyshev_nodes()[m];
                self.overlap.eta(r) / (r * r)
            });
            total += decay
                * w
                * product_weights(k * w)
                    .iter()
                    .zip(g)
                    .map(|(wt, gv)| wt * gv)
                    .sum::<f64>();
            s += w;
        }
        total
    }
}

/// Chebyshev nodes of the first kind mapped to [0, 1].
fn chebyshev_nodes() -> &'static [f64; NODES] {
    static NODES_01: OnceLock<[f64; NODES]> = OnceLock::new();
    NODES_01.get_or_init(|| {
        std::array::from_fn(|m| {
            0.5 * (1.0 - ((2 * m + 1) as f64 * std::f64::consts::PI / (2 * NODES) as f64).cos())
        })
    })
}

/// Inverse of the Vandermonde matrix of the nodes: row j gives the monomial coefficient
/// `c_j = Σ_m V⁻¹[j][m]·g(y_m)` of the interpolant.
fn inverse_vandermonde() -> &'static [[f64; NODES]; NODES] {
    static INV: OnceLock<[[f64; NODES]; NODES]> = OnceLock::new();
    INV.get_or_init(|| {
        let y = chebyshev_nodes();
        // Gauss–Jordan on [V | I]
        let mut m = [[0.0f64; 2 * NODES]; NODES];
        for (r, row) in m.iter_mut().enumerate() {
            for (c, v) in row.iter_mut().take(NODES).enumerate() {
                *v = y[r].powi(c as i32);
            }
            row[NODES + r] = 1.0;
        }
        for col in 0..NODES {
            let piv = (col..NODES)
                .max_by(|&i, &j| m[i][col].abs().total_cmp(&m[j][col].abs()))
                .unwrap_or(col);
            m.swap(col, piv);
            let p = m[col][col];
            m[col].iter_mut().for_each(|v| *v /= p);
            for r in 0..NODES {
                if r != col {
                    let f = m[r][col];
                    let pivot_row = m[col];
                    m[r].iter_mut()
                        .zip(pivot_row)
                        .for_each(|(v, pv)| *v -= f * pv);
                }
            }
        }
        // V⁻¹ maps node values to coefficients: c = V⁻¹ g
        std::array::from_fn(|j| std::array::from_fn(|mm| m[j][NODES + mm]))
    })
}

/// Weights `W_m(t) = Σ_j V⁻¹[j][m]·μ_j(t)`: `∫₀¹ p(y)·e^{−ty} dy = Σ_m W_m·p(y_m)` for the
/// interpolant p through the nodes.
fn product_weights(t: f64) -> [f64; NODES] {
    if t == 0.0 {
        // the plain interpolatory weights, which every range weight takes: once
        static NO_DECAY: OnceLock<[f64; NODES]> = OnceLock::new();
        return *NO_DECAY.get_or_init(|| weights_of_moments(exponential_moments(0.0)));
    }
    weights_of_moments(exponential_moments(t))
}

/// `W_m = Σ_j V⁻¹[j][m]·μ_j` of the moments `mu`.
fn weights_of_moments(mu: [f64; NODES]) -> [f64; NODES] {
    let inv = inverse_vandermonde();
    std::array::from_fn(|m| (0..NODES).map(|j| inv[j][m] * mu[j]).sum())
}

/// `μ_j(t) = ∫₀¹ y^j e^{−ty} dy`, j = 0..NODES−1, for t ≥ 0: power series below t = 2,
/// upward recursion from `μ_0 = −expm1(−t)/t` above (stable there since j/t ≤ 2.5).
pub fn exponential_moments(t: f64) -> [f64; NODES] {
    if t < 2.0 {
        // the highest moment by its series Σ_n (−t)^n / (n! (j+n+1)), the others by the
        // downward recursion μ_{j−1} = (t·μ_j + e^{−t})/j, which damps errors by t/j
        let j = NODES - 1;
        let mut term = 1.0;
        let mut top = 1.0 / (j + 1) as f64;
        for n in 1..60 {
            term *= -t / n as f64;
            let add = term / (j + n + 1) as f64;
            top += add;
            if add.abs() < 1e-18 * top.abs() {
                break;
            }
        }
        let e = (-t).exp();
        let mut mu = [0.0; NODES];
        mu[j] = top;
        for i in (1..NODES).rev() {
            mu[i - 1] = (t * mu[i] + e) / i as f64;
        }
        mu
    } else {
        let e = (-t).exp();
        let mut mu = [0.0; NODES];
        mu[0] = -(-t).exp_m1() / t;
        for j in 1..NODES {
            mu[j] = (j as f64 * mu[j - 1] - e) / t;
        }
        mu
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The product-integration nodes are the zeros of the Chebyshev polynomial
    /// `T_N(2y − 1) = cos(N·acos(2y − 1))` on (0, 1), all of them (a node set outside the
    /// piece still integrates polynomials exactly, so only this catches it).
    #[test]
    fn nodes_are_the_chebyshev_zeros_inside_the_piece() {
        let nodes = chebyshev_nodes();
        for &y in nodes {
            assert!(y > 0.0 && y < 1.0, "{y}");
            let t_n = (NODES as f64 * (2.0 * y - 1.0).acos()).cos();
            assert!(t_n.abs() < 1e-12, "T_N({y}) = {t_n}");
        }
        let mut sorted = nodes.to_vec();
        sorted.sort_by(f64::total_cmp);
        sorted.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
        assert_eq!(sorted.len(), NODES, "distinct nodes");
    }

    fn brute_moment(j: usize, t: f64) -> f64 {
        let n = 200_000;
        (0..n)
            .map(|i| {
                let y = (i as f64 + 0.5) / n as f64;
                y.powi(j as i32) * (-t * y).exp()
            })
            .sum::<f64>()
            / n as f64
    }

    #[test]
    fn moments_match_quadrature_across_the_switch() {
        for t in [0.0, 1e-12, 0.3, 1.999_999, 2.0, 2.000_001, 7.0, 40.0] {
            let mu = exponential_moments(t);
            for (j, m) in mu.iter().enumerate() {
                let b = brute_moment(j, t);
                assert!(
                    (m - b).abs() <= 1e-8 * b.abs().max(1e-300),
                    "t={t} j={j}: {m} vs {b}"
                );
            }
        }
    }

    #[test]
    fn moments_for_huge_t_are_finite() {
        let mu = exponential_moments(1e6);
        assert!(mu.iter().all(|m| m.is_finite() && *m >= 0.0));
        assert!((mu[0] - 1e-6).abs() < 1e-15);
    }

    #[test]
    fn interpolation_weights_reproduce_polynomials() {
        // Σ W_m(0) y_m^p = 1/(p+1) for p ≤ 5
        let w = product_weights(0.0);
        for p in 0..NODES {
            let s: f64 = w
                .iter()
                .zip(chebyshev_nodes())
                .map(|(wi, y)| wi * y.powi(p as i32))
                .sum();
            assert!((s - 1.0 / (p + 1) as f64).abs() < 1e-12, "p={p}: {s}");
        }
    }
}
