//! The recorded count of a non-paralyzable detector in one bin, drawn from its exact
//! counting distribution given the bin's true photons: O(1) per bin instead of an arrival
//! time per photon (docs/model.md §4b).
//!
//! # Method
//!
//! A bin of width Δt holds N true photons (drawn by the shot path), their arrival times
//! uniform in the bin (the rate is constant within a bin, as everywhere in the model);
//! the detector enters the bin dead for a residual `r ∈ [0, τ)` carried over from the
//! bin before (0 after an empty bin, since Δt ≥ τ) and leaves it dead for `r'`.
//!
//! * **Live-start law** (Müller 1973, NIM 112, 47: for a Poisson process of rate n on
//!   an interval L begun live, `N(L) ≥ k ⇔ (k−1)τ + Γ(k, n) ≤ L`). Given M photons
//!   uniform on L (the law no longer depends on n: the Poisson family is complete, so
//!   the conditional law given M is the unique one whose Poisson mixture is Müller's),
//!   the k-th recorded time is `(k−1)τ + L·U₍ₖ₎` in law, `U₍ₖ₎` the k-th of M sorted
//!   uniforms, jointly with the count and the dead time left at the end:
//!
//!   ```text
//!   P(R = k, ρ = 0 | M)     = P(Bin(M, 1 − kτ/L) = k)
//!   P(R = k, ρ ∈ dx | M)    = P(L·U₍ₖ₎ − (L − kτ) ∈ dx),   0 < x ≤ τ
//!   P(R ≥ k | M)            = P(Bin(M, 1 − (k−1)τ/L) ≥ k)
//!   ```
//!
//!   (each event's Poisson mixture over M ~ Poisson(nL) is Müller's; `tests/dead_time.rs`
//!   checks the law against the arrival-time sweep).
//! * **The bin as body and boundary.** The detector is live from `r` on (a non-paralyzable
//!   detector's dead photons do not extend it). The bin splits into the *body*
//!   `[r, r + Δt − τ)`, of fixed length L = Δt − τ begun live, and the *boundary* of
//!   total length τ: the head `[0, r)` (dead: its photons are lost) and the *extension*
//!   `[r + L, Δt)` of length `e = τ − r`. Given N, the boundary holds
//!   `B ~ Bin(N, τ/Δt)` photons uniform on it and the body `M = N − B` uniform on it.
//!   The body's (R, ρ) come from the live-start law of M on L, which depends on M only:
//!   one table per M, shared by every bin and rate of the run. The extension, shorter
//!   than τ, records at most one photon: the first of its photons at least ρ after its
//!   start; then `r' = y + r` (y that photon's offset in the extension), else
//!   `r' = max(0, ρ − e)`. Exact, dead time carried across bin edges included.
//!
//! # Sampling
//!
//! * B by inversion of 64-bit tail thresholds `⌊P(B ≥ j)·2^64⌋` per N (Devroye 1986,
//!   *Non-Uniform Random Variate Generation*, §X.3.3, as `sampling::table`): one `u64`.
//! * (R, ρ = 0 or ρ > 0) by an integer alias table per M over the pairs (Walker 1977;
//!   Vose 1991, `sampling::alias`): one `u64`.
//! * ρ, when positive and needed (r > 0 or boundary photons), from the density
//!   `∝ u^{k−1}(1−u)^{M−k}` on `(1 − kτ/L, 1 − (k−1)τ/L]` by rejection from the uniform
//!   (Devroye 1986, §II.3), squeezed by the density's least value on the cell (it is
//!   log-concave: the least is at an end): two `u64`, and logarithms only when the
//!   squeeze does not decide (a few % of draws; the density varies by a few % across
//!   the cell).
//! * The B boundary photons: a `u64` each (the mean of B is Nτ/Δt, 1 at 300 MHz).
//!
//! # Precision
//!
//! The binomial probabilities by Loader's saddle-point form (Loader 2000, "Fast and
//! accurate computation of binomial probabilities"; `stirlerr` and `bd0` as in R's
//! `dbinom`), relative error ~1e-14, tails summed from the smaller side; masses below
//! `2^-72` of the largest are dropped (as `sampling::pmf_alias`); the tables realise each
//! probability to a few `2^-64` absolute. The rejection step is exact to the 53 bits of
//! its uniforms.
//!
//! # Cost
//!
//! Measured by `benches/dead_time_rates.rs` (table in
//! `validation/reports/dead_time_cost.md`, one thread, 200 bins of 2 µs, τ = 3.5 ns): given
//! the photons, 3.3 ns a bin at 0.2 photons per bin (16 ns a photon, the shot path's
//! included: 6.7× the ideal detector, whose sparse path places a photon in ~2 ns); by
//! [`RateLaw`], 4.3–7 ns a bin from 0.6 to 20 photons (1.7–3.3×) and 11–22 ns from 60
//! to 600 (3.8–6.6×: the body's count, its residual ρ and the extension's photon are
//! three or four `u64` and a table load, where the ideal detector draws one). Per hit
//! bin with no carried dead time and no boundary photon one `u64` and, where M > 1, one
//! alias draw. [`Family`] tables are built on first use per M (per process, shared by
//! threads and runs: their content depends only on τ, Δt and M): ~10–100 µs and
//! 2–30 KiB each; a [`RateLaw`] per bin and run, ~0.1–0.5 ms and up to ~10 KiB. Bins of
//! more than [`MAX_PHOTONS`] photons go through the arrival-time sweep.

mod family;
mod probabilities;
mod rate_law;
mod support;
mod ziggurat;

pub use family::{Family, MAX_PHOTONS, family};
pub(crate) use probabilities::{pois_pmf, pois_tails};
pub use rate_law::{Drawn, RateLaw, is_dense, rate_law_bytes};
pub(crate) use ziggurat::{exp1_slow, ziggurat};
