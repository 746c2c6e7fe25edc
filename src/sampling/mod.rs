//! Photon-count samplers (issue 3; docs/simulation.md).
//!
//! Per laser shot and range bin `i` the detected count is Poisson with mean
//! `λ_i = λ_sig,i + λ_bkg + λ_dc`, independent across bins and shots; a
//! profile accumulates `M` shots.
//!
//! * [`ShotSampler`]: exact draw of one shot, built once per set of means
//!   and reused for every shot. It mixes four exact paths per bin (dense
//!   table inversion, dense alias table over the PMF ([`PmfAlias`]), dense
//!   rejection from a step envelope over the PMF ([`PmfCells`]), dense
//!   Ahrens–Dieter, and the sparse "Poisson total + alias placement" path) by
//!   a measured cost model: see its docs and [`cost`].
//! * [`AggregateSampler`]: one Poisson(`M·λ_i`) draw per bin for fixed means,
//!   every bin's sampler built once (a [`ShotSampler`] over `M·λ_i`); exact
//!   when nothing varies from shot to shot and the detector is linear.
//! * [`add_aggregate`]: the same draw for means that change from profile to
//!   profile, computed on the fly (inversion or Ahrens–Dieter).
//! * [`stream_rng`], [`shot_profile`], [`aggregate_profile`]: reproducible
//!   streams. A profile's shots are cut into blocks of [`SHOT_BLOCK`] shots,
//!   block `b` of profile `p` drawn from `stream_rng(seed, p, b)`, and the
//!   integer block sums added: the result depends on the seed only, never on
//!   the rayon thread count or the schedule, and any profile, or any block of
//!   shots, can be regenerated alone.
//!
//! All counts are consumed through [`CountSink`] (`(bin, count)` events), so
//! the same sampler feeds accumulators (`[u64]`), per-shot buffers
//! ([`ShotCounts`]) or, later, a detector model.
//!
//! # Extension points
//!
//! Built since (see [`jitter`], and `src/detector/`, `src/onboard/` which use this
//! module, never the other way): per-shot varying means by thinning, the dead-time
//! detector wrapping a sampler, component colouring by separate streams, onboard sums
//! through [`ShotSampler::for_each_shot`].
//! The notes as first written:
//!
//! * **Per-shot varying means.** Pulse-energy jitter scales the signal part by
//!   `e_s` per shot: keep a sampler for the signal and one for background +
//!   dark (their sum has the same law). The sparse path's alias table depends
//!   only on the *shape* `λ_i/Σλ`, so a scaled shot only needs its total
//!   `N ~ Poisson(e_s·Λ)` redrawn ([`poisson_u64`]) and the same placement.
//!   Alternatively, exact thinning: build at the envelope `e_max·λ` and keep
//!   each count with probability `e_s/e_max` (per-shot binomial thinning of a
//!   Poisson is Poisson). A scene that changes along the track rebuilds the
//!   sampler per segment (O(n log n)) or thins against an envelope.
//! * **Detector stage (dead time, pile-up).** A sink receives each shot's
//!   `(bin, count)` events; given `k` counts in a bin, their arrival times are
//!   `k` i.i.d. draws from the within-bin rate profile (uniform for a
//!   constant rate), so a detector sink can draw times and apply dead time
//!   without any change here.
//! * **Component-resolved output.** Colour each count by its component with
//!   probabilities `λ_sig/λ`, `λ_bkg/λ`, `λ_dc/λ` (exact Poisson colouring),
//!   or run one sampler per component.
//! * **Onboard processing.** [`ShotSampler::for_each_shot`] hands every shot
//!   as a [`ShotCounts`] (dense counts plus the list of bins hit) to a
//!   closure, without allocating per shot.

mod aggregate;
pub(crate) mod alias;
pub mod approx;
pub mod jitter;
mod pmf_alias;
mod pmf_cells;
mod poisson;
mod profile;
mod shot;
mod sink;
mod streams;
mod table;
#[cfg(test)]
mod tests;

pub use aggregate::{AGGREGATE_PREBUILT_MAX, AggregateSampler, add_aggregate};
pub(crate) use alias::AliasTable;
pub use pmf_alias::{PmfAlias, pmf_alias_columns};
pub use pmf_cells::{CELLS_PER_SIGMA, PmfCells, pmf_cells_bytes};
pub use poisson::{AGGREGATE_CHUNK, AGGREGATE_INVERSION_MAX, poisson_u64};
pub use profile::{aggregate_profile, aggregate_profile_fixed, shot_profile};
pub use shot::{
    ALIAS_BUDGET_BYTES, DENSE_ALIAS_MAX, DENSE_TABLE_MAX, DenseMethod, PathChoice, ShotSampler,
    ShotStrategy, StrategyKind, TOTAL_TABLE_MAX, cost, table_bytes_bound,
};
pub use sink::{CountSink, ShotCounts};
pub use streams::{AGGREGATE_STREAM, SHOT_BLOCK, add_block_sums, stream_rng};
pub(crate) use table::count_above;
