//! The atmosphere's slabs laid along the beam (`BeamPath::new`'s segments), in range
//! order, keeping only what the model reads ([`PathExtent`]), and the memory that takes.

use crate::atmosphere::{Atmosphere, Slab};
use crate::config::PlatformKind;
use crate::geometry::Geometry;
use crate::surface::Surface;

/// One stretch of the beam with constant optical properties: what the bin integral
/// reads.
#[derive(Debug, Clone, Copy)]
pub struct Segment {
    /// Range at the segment's start (nearer the instrument), m.
    pub r_start: f64,
    /// Range at its end, m.
    pub r_end: f64,
    /// Attenuating extinction (η_ms applied), m⁻¹ of path.
    pub alpha: f64,
    /// Backscatter seen by the channel, m⁻¹ sr⁻¹.
    pub beta: f64,
    /// One-way attenuating optical depth from the instrument to `r_start`.
    pub tau_start: f64,
}

/// What the small-angle multiple-scattering models read of a segment besides
/// ([`PathExtent::Whole`] keeps one per segment, the `constant` model none).
#[derive(Debug, Clone, Copy)]
pub struct SegmentLobes {
    /// Particle (aerosol and cloud) extinction, m⁻¹.
    pub alpha_particle: f64,
    /// Extinction of the particles in the small-angle model, m⁻¹ (`multiple_scattering`).
    pub alpha_lobe: f64,
    /// `Σ α·Θ²` of their forward lobes, m⁻¹ rad².
    pub alpha_theta2: f64,
    /// `Σ α·g` of the same particles (their asymmetry factors), m⁻¹.
    pub alpha_lobe_g: f64,
    /// Absorption by gases (ozone), m⁻¹.
    pub alpha_absorbing: f64,
    /// Backscatter of every species in every polarization (the elastic return a
    /// channel's share is taken from), m⁻¹ sr⁻¹.
    pub beta_total: f64,
    /// Backscatter of the clouds in every polarization, m⁻¹ sr⁻¹ (a water cloud's
    /// depolarization, `multiple_scattering`).
    pub beta_cloud: f64,
}

/// The altitudes `(z_lo, z_hi)` the beam's path through the atmosphere spans (empty
/// when `z_hi <= z_lo`): a space-borne beam from the platform or the atmosphere's top
/// down to the window's end or the `surface` (sea level without one); a ground beam
/// from the station up to the window's end or the atmosphere's top.
pub fn altitude_span(
    atmosphere: &Atmosphere,
    geometry: &Geometry,
    surface: Option<&Surface>,
) -> (f64, f64) {
    let r_max = geometry.max_range_m();
    let z_far = geometry.altitude_at_range(r_max);
    let ground_m = surface.map_or(0.0, |s| s.altitude_m);
    match geometry.kind {
        // The beam stops at the surface.
        PlatformKind::Spaceborne => (
            z_far.max(ground_m),
            geometry.platform_altitude_m.min(atmosphere.top_m()),
        ),
        PlatformKind::Ground => (geometry.platform_altitude_m, z_far.min(atmosphere.top_m())),
    }
}

/// How much of the beam path a `BeamPath` keeps.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PathExtent {
    /// From the window's first bin on, with the bin integral's optics only: what the
    /// `constant` multiple-scattering model reads. The slabs between the instrument and
    /// the window (the atmosphere above a space-borne window, below a raised ground
    /// window) are summed into the optical depth and not kept, but for the last one.
    Bins,
    /// From the instrument, with every segment's forward-lobe optics: what the
    /// small-angle models read along the whole beam.
    Whole,
}

impl PathExtent {
    /// The extent the model of a config reads: [`Whole`](Self::Whole) with the
    /// small-angle multiple-scattering models, else [`Bins`](Self::Bins).
    pub fn for_model(model: crate::config::MultipleScatteringModel) -> Self {
        match model {
            crate::config::MultipleScatteringModel::Constant => PathExtent::Bins,
            _ => PathExtent::Whole,
        }
    }

    /// Heap bytes of one kept segment.
    pub fn bytes_per_segment(self) -> f64 {
        let lobes = match self {
            PathExtent::Bins => 0,
            PathExtent::Whole => std::mem::size_of::<SegmentLobes>(),
        };
        (std::mem::size_of::<Segment>() + lobes) as f64
    }
}

/// Slabs beyond the grid's over any altitude span: the splits at the molecular, ozone
/// and aerosol profiles' tops, the span's two ends and their partial grid cells, and
/// the held segment before the window (`lay_in_range_order`), with room to spare.
const EXTRA_SLABS: f64 = 8.0;

/// The slabs of `atmosphere` over an altitude span of `span_m`: at most this many (the
/// grid's, one split at each layer edge, [`EXTRA_SLABS`]).
fn slabs_over(atmosphere: &Atmosphere, span_m: f64) -> f64 {
    (span_m / atmosphere.grid_m).max(0.0).floor()
        + EXTRA_SLABS
        + 2.0 * atmosphere.layers.len() as f64
}

/// The range from which [`PathExtent::Bins`] keeps the path: the window's first bin after
/// the trigger (pre-trigger bins integrate nothing).
fn keep_from_m(geometry: &Geometry, extent: PathExtent) -> f64 {
    match extent {
        PathExtent::Bins => geometry.window_start_range_m,
        PathExtent::Whole => f64::NEG_INFINITY,
    }
}

/// The memory of a beam path, bytes ([`laying_bytes`]).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct PathBytes {
    /// Its kept segments (and lobes), held with the model.
    pub kept: f64,
    /// Every slab's altitude edge while the slabs are iterated
    /// (`Atmosphere::slabs_iter`), let go once the path is laid.
    pub laying: f64,
    /// The slabs it is laid from (for messages).
    pub slabs: f64,
}

/// The memory a beam path of `extent` needs while it is laid and after: at most
/// `kept_slabs_bound` segments and one edge per slab of the whole path.
pub fn laying_bytes(
    atmosphere: &Atmosphere,
    geometry: &Geometry,
    surface: Option<&Surface>,
    extent: PathExtent,
) -> PathBytes {
    let (z_lo, z_hi) = altitude_span(atmosphere, geometry, surface);
    let all = slabs_over(atmosphere, z_hi - z_lo);
    let kept = kept_slabs_bound(atmosphere, geometry, (z_lo, z_hi), extent).min(all);
    PathBytes {
        kept: kept * extent.bytes_per_segment(),
        laying: all * std::mem::size_of::<f64>() as f64,
        slabs: all,
    }
}

/// At most how many segments a path of `extent` over `(z_lo, z_hi)` keeps.
fn kept_slabs_bound(
    atmosphere: &Atmosphere,
    geometry: &Geometry,
    (z_lo, z_hi): (f64, f64),
    extent: PathExtent,
) -> f64 {
    if z_hi <= z_lo {
        return 0.0;
    }
    let keep_from = keep_from_m(geometry, extent);
    if keep_from == f64::NEG_INFINITY {
        return slabs_over(atmosphere, z_hi - z_lo);
    }
    let z_keep = geometry.altitude_at_range(keep_from).clamp(z_lo, z_hi);
    let span = if looks_down(geometry, (z_lo, z_hi)) {
        z_keep - z_lo
    } else {
        z_hi - z_keep
    };
    slabs_over(atmosphere, span)
}

/// Whether range grows as altitude falls over `(z_lo, z_hi)` (a beam looking down).
fn looks_down(geometry: &Geometry, (z_lo, z_hi): (f64, f64)) -> bool {
    geometry.range_at_altitude(z_hi) < geometry.range_at_altitude(z_lo)
}

/// The segments (and, for [`PathExtent::Whole`], their lobes) of the atmosphere's slabs
/// over `(z_lo, z_hi)` along the beam of `geometry`, in range order, each with its
/// optical depth from the instrument; for [`PathExtent::Bins`] without those ending
/// before the window but the last of them.
pub(super) fn lay(
    atmosphere: &Atmosphere,
    geometry: &Geometry,
    (z_lo, z_hi): (f64, f64),
    extent: PathExtent,
) -> (Vec<Segment>, Vec<SegmentLobes>) {
    if z_hi <= z_lo {
        return (vec![], vec![]);
    }
    let capacity = kept_slabs_bound(atmosphere, geometry, (z_lo, z_hi), extent);
    let mut laid = Laid::new(extent, keep_from_m(geometry, extent), capacity as usize);
    let slabs = atmosphere.slabs_iter(z_lo, z_hi);
    let in_order = if looks_down(geometry, (z_lo, z_hi)) {
        laid.take_all(slabs.rev(), geometry)
    } else {
        laid.take_all(slabs, geometry)
    };
    if in_order {
        return laid.finish();
    }
    drop(laid);
    lay_sorted(atmosphere, geometry, (z_lo, z_hi), extent)
}

/// The path laid as it was before it streamed: every slab collected, put in range order
/// (reversed, or a stable sort), the optical depths summed, then the segments before the
/// window dropped. What [`lay`] falls back to when the slabs do not come strictly in
/// range order (ranges of the same rounding at two edges; never seen), so that the
/// segments are the same bit for bit either way.
fn lay_sorted(
    atmosphere: &Atmosphere,
    geometry: &Geometry,
    span: (f64, f64),
    extent: PathExtent,
) -> (Vec<Segment>, Vec<SegmentLobes>) {
    let mut all: Vec<(Segment, SegmentLobes)> = atmosphere
        .slabs_iter(span.0, span.1)
        .map(|s| segment_of(&s, geometry))
        .collect();
    let by_range = |a: &Segment, b: &Segment| a.r_start.total_cmp(&b.r_start);
    if all.is_sorted_by(|a, b| by_range(&a.0, &b.0).is_gt()) {
        all.reverse();
    }
    if !all.is_sorted_by(|a, b| by_range(&a.0, &b.0).is_le()) {
        all.sort_by(|a, b| by_range(&a.0, &b.0));
    }
    let mut laid = Laid::new(extent, keep_from_m(geometry, extent), 0);
    let mut tau = 0.0;
    for (mut s, l) in all {
        s.tau_start = tau;
        tau += s.alpha * (s.r_end - s.r_start);
        laid.keep(s, l);
    }
    laid.finish()
}

/// The segment of one slab and its lobes, its optical depth still to be set.
fn segment_of(s: &Slab, geometry: &Geometry) -> (Segment, SegmentLobes) {
    let (ra, rb) = (
        geometry.range_at_altitude(s.z_lo),
        geometry.range_at_altitude(s.z_hi),
    );
    let o = &s.optics;
    let segment = Segment {
        r_start: ra.min(rb),
        r_end: ra.max(rb),
        alpha: o.alpha_effective,
        beta: o.beta_channel,
        tau_start: 0.0,
    };
    let lobes = SegmentLobes {
        alpha_particle: o.alpha_aer + o.alpha_cld,
        alpha_lobe: o.alpha_lobe,
        alpha_theta2: o.alpha_theta2,
        alpha_lobe_g: o.alpha_lobe_g,
        alpha_absorbing: o.alpha_o3,
        beta_total: o.beta_mol + o.beta_aer + o.beta_cld,
        beta_cloud: o.beta_cld,
    };
    (segment, lobes)
}

/// The segments being kept, in range order.
struct Laid {
    extent: PathExtent,
    keep_from_m: f64,
    segments: Vec<Segment>,
    lobes: Vec<SegmentLobes>,
    /// The last segment ending before the window, until one inside it comes.
    held: Option<(Segment, SegmentLobes)>,
    /// A segment reaching into the window has come: every later one is kept.
    keeping: bool,
}

impl Laid {
    fn new(extent: PathExtent, keep_from_m: f64, capacity: usize) -> Self {
        let lobes = match extent {
            PathExtent::Whole => Vec::with_capacity(capacity),
            PathExtent::Bins => vec![],
        };
        Laid {
            extent,
            keep_from_m,
            segments: Vec::with_capacity(capacity),
            lobes,
            held: None,
            keeping: false,
        }
    }

    /// Lays `slabs`, which should come in range order, summing the optical depth as
    /// they come; false (and the work abandoned) at the first that is not strictly
    /// farther than the one before.
    fn take_all(&mut self, slabs: impl Iterator<Item = Slab>, geometry: &Geometry) -> bool {
        let mut tau = 0.0;
        let mut last = f64::NEG_INFINITY;
        for slab in slabs {
            let (mut s, l) = segment_of(&slab, geometry);
            // strictly farther (a NaN range is not: the fallback sorts it as before)
            if s.r_start.partial_cmp(&last) != Some(std::cmp::Ordering::Greater) {
                return false;
            }
            last = s.r_start;
            s.tau_start = tau;
            tau += s.alpha * (s.r_end - s.r_start);
            self.keep(s, l);
        }
        true
    }

    /// Keeps segment `s` (in range order, its optical depth set), or holds it while it
    /// ends before the window.
    fn keep(&mut self, s: Segment, l: SegmentLobes) {
        if !self.keeping && s.r_end <= self.keep_from_m {
            self.held = Some((s, l));
            return;
        }
        self.keeping = true;
        if let Some((hs, hl)) = self.held.take() {
            self.push(hs, hl);
        }
        self.push(s, l);
    }

    fn push(&mut self, s: Segment, l: SegmentLobes) {
        self.segments.push(s);
        if self.extent == PathExtent::Whole {
            self.lobes.push(l);
        }
    }

    /// The kept segments and lobes (the held one too where none reached the window, so
    /// that the path still ends where it did).
    fn finish(mut self) -> (Vec<Segment>, Vec<SegmentLobes>) {
        if let Some((hs, hl)) = self.held.take() {
            self.push(hs, hl);
        }
        (self.segments, self.lobes)
    }
}
