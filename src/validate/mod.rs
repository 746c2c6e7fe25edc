//! Statistical validation of the Monte Carlo against the model (`lidarsim validate`).
//!
//! N independent profiles are drawn exactly as `simulate` draws them (same samplers,
//! seed and profile indices: `simulate --seed S --profiles N` writes the very counts
//! validated here). Per bin, four statistics are compared with their model values,
//! each turned into a z-score from its sampling distribution:
//!
//! * **mean** of the accumulated counts against `κ1 = M(λ_sig+λ_bkg+λ_dc)`: exact
//!   Poisson test on the total `Σ_p c_p ~ Poisson(N·κ1)` when shots are identical
//!   (two-sided p converted to a z-score), normal otherwise;
//! * **variance** (unbiased sample variance s²) against `κ2` (= κ1 for Poisson), with
//!   `Var(s²) = μ4/N − κ2²(N−3)/(N(N−1))`;
//! * **S/N with the background known** (paper Eq. 4): `x = c − M(λ_bkg+λ_dc)`,
//!   `SNR̂ = x̄/s_x` against `M·λ_sig/sqrt(κ2)`, with the delta-method variance
//!   `Var(SNR̂) ≈ [1 + m²(μ4−μ2²)/(4μ2³) − m·μ3/μ2²]/N`;
//! * **S/N with the background estimated** from `n_b` signal-free bins drawn in the
//!   same profile (model.md §2): `y = c − b̂`, model `M·λ_sig/sqrt(κ2 + M(λ_bkg+λ_dc)/n_b)`,
//!   same delta method with the cumulants of `y`.
//!
//! The cumulants of the accumulated count are those of a (mixed) Poisson: with
//! pulse-energy jitter σ, `κ1 = M(s+r)`, `κ2 = M(s+r+σ²s²)`, `κ3 = M(s+r+3σ²s²)`,
//! `κ4 = M(s+r+7σ²s²)` (s signal, r background + dark per shot; Stirling numbers of
//! the second kind on the cumulants of the shot's mean).
//!
//! **Verdict.** A statistic is tested in the bins where its approximation holds
//! (mean: every bin with κ1 > 0 — bins with κ1 = 0 must hold only zeros; the others:
//! `N·κ1 ≥ 100` and, for S/N, a model S/N ≥ 0.1). For each statistic two
//! multiple-testing-aware checks at level α = 2.5·10⁻⁴ each: the number of bins outside
//! their 99 % interval against its Binomial(K, 0.01) law, and `Σ z²` against χ²(K).
//! Eight checks at 2.5·10⁻⁴ give an overall false-alarm rate below 2·10⁻³.
//!
//! Here: the realizations drawn and summed exactly, bin by bin, and compared with the
//! models; the models, the statistics and the report have their own files.

mod bins;
pub mod calibration;
pub mod exact;
pub mod file;
mod model;
pub mod partial;
mod report;
mod run;
pub mod scene;
mod statistics;

pub use bins::{
    BinSums, ChannelBins, MIN_REALIZATIONS, RealizationSource, SimulatorSource, validate_channels,
    validate_source,
};
pub use calibration::{BIN_INTERVAL, CHECK_LEVEL, Check, check};
pub use model::{
    BinModel, afterpulsed_bin_models, analog_bin_models, bin_models, recorded_bin_models,
    snr_standard_error,
};
pub use report::{BinReport, Report, Stat, write_table};
pub use run::{Sums, ValidateOptions, Validation, run, run_cancellable};
pub use statistics::{MIN_SNR, MIN_TOTAL_COUNTS};

#[cfg(test)]
mod tests;
