//! The deterministic model's product ([`ExpectedProfile`]): expected counts per shot per
//! bin and the atmosphere's truth at bin centres, and the memory it takes.

use crate::atmosphere::bin_mean::BinMean;
use crate::atmosphere::{MolecularState, Optics};
use crate::signal::{BinMultipleScattering, PathBytes};
use crate::snr;

/// Memory the deterministic model holds per range bin beyond its beam path
/// ([`crate::signal::laying_bytes`]), bytes: the expected profile and truth by species
/// (37 f64: 296 bytes while the model is computed, its pieces of 64 Ki bins besides),
/// the detector's means and, while `expect` writes it, the CSV's twelve columns (400
/// bytes then, the path let go). Peak RSS of `/usr/bin/time -v lidarsim expect
/// configs/paper/scenario1.toml --set instrument.bin_width_s=1e-10 --set
/// acquisition.top_altitude_km=40 --csv big.csv` (2.67e6 bins, 1.07e7 of the path's
/// 2.29e7 slabs kept): 1.13 GB, estimated 1.63 GB (3.17 GB before the path kept only
/// what the bins read, 5.27 GB before the bins were taken a piece at a time); at
/// `bin_width_s` 2e-9 (1.33e5 bins) 77 MB, estimated 81 MB. Rounded up from 400 for
/// the small-angle models' per-bin multiple scattering.
pub const MODEL_BYTES_PER_BIN: f64 = 450.0;

/// The model's memory for `bins` range bins along a beam path of `path`
/// ([`crate::signal::laying_bytes`]), bytes, at its peak: the kept segments with the
/// larger of what the path takes while it is laid and what the bins take after.
pub fn model_bytes(bins: f64, path: PathBytes) -> f64 {
    path.kept + path.laying.max(bins * MODEL_BYTES_PER_BIN)
}

/// One bin of [`Scenario::expected`]'s model, before multiple scattering and the
/// detector.
pub(super) struct ModelBin {
    pub(super) altitude_m: f64,
    pub(super) range_m: f64,
    pub(super) point: Optics,
    pub(super) bin_mean: BinMean,
    pub(super) state: MolecularState,
    pub(super) overlap: f64,
    pub(super) t2: f64,
    pub(super) signal: f64,
    pub(super) range_weight: f64,
    pub(super) attenuated_backscatter: f64,
}

/// Expected counts per shot per bin and the atmosphere's truth at bin centres.
#[derive(Debug, Clone, Default)]
pub struct ExpectedProfile {
    /// Bin-centre altitude, m.
    pub altitude_m: Vec<f64>,
    /// Bin-centre range, m.
    pub range_m: Vec<f64>,
    /// The atmosphere's optics at the bin centre, by species (the point truth).
    pub point: Vec<Optics>,
    /// The particles' optics averaged over the bin's range, by species (what the counts
    /// integrate; [`BinMean`]).
    pub bin_mean: Vec<BinMean>,
    /// The molecular state at the bin centre.
    pub state: Vec<MolecularState>,
    /// Overlap η(r) at the bin centre.
    pub overlap: Vec<f64>,
    /// Two-way transmission to the bin centre (multiple-scattering factors applied).
    pub t2: Vec<f64>,
    /// Expected signal counts per shot (exact bin integral of Eq. 2).
    pub signal: Vec<f64>,
    /// Range weight `∫_bin η(r)/r² dr`, m⁻¹.
    pub range_weight: Vec<f64>,
    /// Bin-averaged attenuated backscatter `∫η β T² r⁻² dr / ∫η r⁻² dr`, m⁻¹ sr⁻¹, so
    /// that `signal = C · attenuated_backscatter · range_weight`; 0 where the range
    /// weight is 0 (no overlap).
    pub attenuated_backscatter: Vec<f64>,
    /// Expected background counts per shot per bin (Eq. 3).
    pub background: f64,
    /// Expected dark counts per shot per bin.
    pub dark: f64,
    /// Expected recorded counts per shot per bin after the detector (dead time); the
    /// total `λ_i` for an ideal detector.
    pub recorded: Vec<f64>,
    /// Expected signal-induced counts per shot per bin (`src/detector/induced.rs`); empty
    /// when the detector has none.
    pub induced: Vec<f64>,
    /// Expected afterpulses per shot per bin (`src/detector/afterpulse.rs`), included in
    /// `recorded`; empty when the detector has none.
    pub afterpulse: Vec<f64>,
    /// The small-angle multiple scattering of each bin (`multiple_scattering.model =
    /// "small_angle"`), already in `signal` and `attenuated_backscatter`; empty in the
    /// `constant` model.
    pub multiple_scattering: Vec<BinMultipleScattering>,
    /// Signal-free bins used to estimate the background (0 = none available).
    pub background_bins: usize,
    /// Their indices: bins of the window lying wholly above the atmosphere, nearest the
    /// atmosphere first, at most `acquisition.background_bins` of them.
    pub background_bin_indices: Vec<usize>,
    /// The point truth's aerosol extinction by CAMS species, m⁻¹: `(species 0-based,
    /// α_s per bin)` for each species the column's layers carry, summing to
    /// `point[i].alpha_aer` (none but in a model-field scene with aerosol).
    pub alpha_aer_by_species: Vec<(usize, Vec<f64>)>,
}

impl ExpectedProfile {
    /// Room for `n` bins in each per-bin vector the model fills, exactly (no vector
    /// grows past the window by doubling).
    pub(super) fn reserve_exact(&mut self, n: usize) {
        self.altitude_m.reserve_exact(n);
        self.range_m.reserve_exact(n);
        self.point.reserve_exact(n);
        self.bin_mean.reserve_exact(n);
        self.state.reserve_exact(n);
        self.overlap.reserve_exact(n);
        self.t2.reserve_exact(n);
        self.signal.reserve_exact(n);
        self.range_weight.reserve_exact(n);
        self.attenuated_backscatter.reserve_exact(n);
    }

    /// Takes bin `b` of the model as the next bin.
    pub(super) fn push_bin(&mut self, b: ModelBin) {
        self.altitude_m.push(b.altitude_m);
        self.range_m.push(b.range_m);
        self.point.push(b.point);
        self.bin_mean.push(b.bin_mean);
        self.state.push(b.state);
        self.overlap.push(b.overlap);
        self.t2.push(b.t2);
        self.signal.push(b.signal);
        self.range_weight.push(b.range_weight);
        self.attenuated_backscatter.push(b.attenuated_backscatter);
    }

    /// Number of bins.
    pub fn n_bins(&self) -> usize {
        self.signal.len()
    }

    /// Bin `i`'s small-angle multiple scattering (ratio 1 in the `constant` model).
    pub fn multiple_scattering_at(&self, i: usize) -> BinMultipleScattering {
        self.multiple_scattering
            .get(i)
            .copied()
            .unwrap_or(BinMultipleScattering::NONE)
    }

    /// Expected total counts per shot in each bin, `λ_i = λ_sig,i + λ_bkg + λ_dc` (Eq. 1).
    pub fn total_per_shot(&self) -> Vec<f64> {
        self.photon_signal()
            .iter()
            .map(|s| s + self.background + self.dark)
            .collect()
    }

    /// What of the photons per shot scales with the pulse energy: the backscattered
    /// signal, plus the signal-induced counts where the detector has them
    /// ([`induced`](Self::induced)). The samplers draw this as the signal.
    pub fn photon_signal(&self) -> std::borrow::Cow<'_, [f64]> {
        if self.induced.is_empty() {
            return std::borrow::Cow::Borrowed(&self.signal);
        }
        std::borrow::Cow::Owned(
            self.signal
                .iter()
                .zip(&self.induced)
                .map(|(s, i)| s + i)
                .collect(),
        )
    }

    /// Eq. 4 S/N of each bin after `shots` shots.
    pub fn snr_eq4(&self, shots: f64) -> Vec<f64> {
        self.signal
            .iter()
            .map(|&s| snr::eq4(s, self.background, self.dark, shots))
            .collect()
    }

    /// S/N with the background estimated from `background_bins` bins; `None` when there are none.
    pub fn snr_estimated_background(&self, shots: f64) -> Option<Vec<f64>> {
        (self.background_bins > 0).then(|| {
            self.signal
                .iter()
                .map(|&s| {
                    snr::with_estimated_background(
                        s,
                        self.background,
                        self.dark,
                        shots,
                        self.background_bins,
                    )
                })
                .collect()
        })
    }
}
