//! The lidar signal (model.md §1, paper Eq. 2): the beam path through the
//! piecewise-constant atmosphere, two-way transmission T², and the exact bin integral
//!
//! ```text
//! λ_sig,i = C · ∫_{r_i}^{r_i+ΔR} η(r) · β(r) · T²(r) / r² dr
//! ```
//!
//! **Algorithm.** Along the beam the atmosphere is a list of segments of constant α and
//! β. On a segment starting at `a`, `T²(a+x) = T²(a)·e^{−kx}` with `k = 2α`, so the
//! integral is `β·T²(a)·∫₀^w g(a+x)·e^{−kx} dx` with `g = η/r²` smooth. The segment is cut
//! into pieces no longer than 10 % of their start range; on each piece `g` is replaced by
//! its degree-5 interpolant at Chebyshev nodes (relative error < 2e-9 for `1/r²`), and
//! the exponential is integrated exactly against each power through the moments
//! `μ_j(t) = ∫₀¹ y^j e^{−ty} dy` (product integration). The moments use, for `t < 2`, a
//! power series for the highest and the downward recursion `μ_{j−1} = (t·μ_j + e^{−t})/j`
//! (stable: it damps errors by t/j) for the others, and above the stable upward recursion
//! `μ_j = (j·μ_{j−1} − e^{−t})/t` (with `μ_0 = −expm1(−t)/t`), so α → 0 and optical
//! depths in the hundreds are both accurate; `T²` underflows to 0, never to NaN. Pieces
//! shrink geometrically only towards the overlap's kinks, where η is not smooth.

mod beam_path;
mod laying;
mod multiple_scattering;

pub use beam_path::{BeamPath, SurfaceEcho, exponential_moments};
pub use laying::{PathBytes, PathExtent, Segment, SegmentLobes, laying_bytes};
pub use multiple_scattering::BinMultipleScattering;
