//! Detector dead time (docs/model.md §4b): after a recorded count a photon counter is blind
//! for τ. Non-paralyzable: photons in the dead period are lost and do not extend it.
//! Paralyzable: every arriving photon, recorded or not, restarts it.
//!
//! **Sampler** ([`DeadTime::record_shot`], [`DeadTimedShots`]). The rate is taken
//! constant within a bin (as in the model below), dead time crosses bin edges, and the
//! detector is live at the start of the window. Six exact paths:
//!
//! * [`DeadTimedShots`] on bins at least 2τ wide, for a paralyzable detector at every
//!   rate and for a non-paralyzable one whose bins all hold fewer than
//!   [`LAW_FROM_PHOTONS`] photons per shot (or that draws every photon): the shot path's
//!   photons straight into the record, the *clusters* (adjacent bins hit in one shot, or
//!   a bin hit twice) recorded again exactly in time order and the record corrected
//!   (`clusters.rs`, issue 41): a photon's time is drawn only where an outcome depends on
//!   it;
//! * a non-paralyzable detector on bins at least 2τ wide ([`DeadTime::by_counts`]) draws
//!   each hit bin's recorded count from its counting distribution given the bin's photons
//!   (drawn by the shot path, exactly as without dead time), carrying the dead time
//!   left by a bin into the next ([`counting::Family`]): O(1) per hit bin, a lone photon
//!   without a draw;
//! * otherwise [`DeadTimedShots`] (fixed means, what `simulate`'s shot path runs) draws the bins
//!   of at least [`LAW_FROM_PHOTONS`] photons per shot from the counting law at their
//!   rate, without their photons ([`RateLaw`], tables built once per run), and the
//!   others as above;
//! * for profiles on bins at least 2τ wide, where its estimate is the lower (low rates,
//!   many shots a profile; [`DeadTimePath::Auto`]), the *column path* (`columns.rs`,
//!   issue 41): a block's shots drawn bin by bin as counts of shots, only those entering
//!   a bin dead or whose photons are not *plain* (every gap after the first, and the last
//!   to the end, at least τ: probability `(1 − kτ)^k`) given times; nothing per photon;
//! * where its cost estimate is the lower ([`DeadTimePath::Auto`]: the paralyzable
//!   detector from ~0.5 photons a bin, narrow bins) [`DeadTimedShots`] walks the
//!   shot's arrivals in time order as a Poisson process of the piecewise-constant rate
//!   (`walk.rs`: the time-change theorem, a ziggurat exponential per arrival, a guide
//!   table over the cumulative mean), the dead time applied as they come: O(arrivals)
//!   paralyzable, O(recorded counts) non-paralyzable, exact for any bin width, the shot
//!   path's photons not drawn;
//! * otherwise ([`DeadTime::record_shot`] for a paralyzable detector, narrow bins) each
//!   photon gets an arrival time uniform
//!   within its bin, the shot's arrivals are swept in time order, and a photon is
//!   recorded when the detector is live: O(photons · log photons) per shot.
//!
//! Nothing is drawn when τ = 0 (the scene then has no detector stage at all). Costs:
//! `benches/dead_time_rates.rs`, `validation/reports/dead_time_cost.md`.
//!
//! **Model** ([`DeadTime::recorded_means`]). With the rate n(t) piecewise constant per
//! bin, the mean recorded rate solves (Müller 1973, NIM 112, 47; docs/model.md §4b)
//!
//! ```text
//! non-paralyzable: m(t) = n(t)·(1 − ∫_{t−τ}^{t} m(s) ds)
//! paralyzable:     m(t) = n(t)·exp(−∫_{t−τ}^{t} n(s) ds)
//! ```
//!
//! solved on a grid of step h = min(τ, Δt)/64 by the midpoint rule (each step's rate at
//! its middle, the integral over the last τ a running sum of the earlier steps, the
//! oldest in part, plus half of the step itself, implicit in m), and integrated over each
//! bin. For a stationary rate it gives `n/(1+nτ)` and `n·e^{−nτ}` exactly, whatever τ/h;
//! at a step in the rate its error is O((h/τ)²) of the transient. A window whose grid
//! would exceed [`MAX_GRID_STEPS`] uses the stationary formulas per bin (error O(τ/Δt) at
//! the bin edges).
//!
//! **Variance** ([`DeadTime::recorded_mean_and_variance`]) of a bin's recorded count per
//! shot: non-paralyzable, exact given the dead time the solver carries into each bin
//! (`detector::dead_time_variance`); paralyzable, the renewal-theory form
//! `mΔt·(1 − 2nτ·e^{−nτ})` at the bin's rate ([`DeadTime::recorded_variance`], whose
//! non-paralyzable `nΔt/(1+nτ)³` is the asymptote for bins much longer than the count's
//! correlation time, ~(nτ)²·τ: 11× too low at nτ = 40 in bins of 40τ).
//!
//! [`counting::Family`]: super::counting::Family
//! [`RateLaw`]: super::counting::RateLaw

mod clusters;
mod columns;
mod model;
mod record;
mod shots;
mod walk;

pub use columns::{
    COLUMN_NS_PER_BIN, COLUMN_NS_PER_DRAWN_BIN, COLUMN_NS_PER_DRAWN_PHOTON, COLUMN_NS_PER_LEVEL,
    COLUMN_NS_PER_LEVEL_HIT,
};
pub use model::{DeadTime, DeadTimeModel, MAX_GRID_STEPS};
pub use record::{ARRIVAL_STREAM, Scratch};
pub use shots::{
    DeadTimePath, DeadTimedShots, LAW_BUDGET_BYTES, LAW_FROM_PHOTONS, NS_PER_DENSE_LAW_BIN,
    NS_PER_GIVEN_PHOTON, NS_PER_LAW_BIN, NS_PER_PHOTON,
};
pub use walk::{NS_PER_WALK_ARRIVAL, NS_PER_WALK_SHOT};

/// One profile through the dead time, every photon drawn
/// ([`super::recorder::recorded_profile`]; the detector's draws from the arrival stream
/// `seed ^ ARRIVAL_STREAM`).
pub use super::recorder::recorded_profile;
