//! The bin-averaged optics beside the point truth (docs/file-format.md "Bin-averaged
//! optics"): the particles' extinction and backscatter by species averaged over each
//! bin's range ([`crate::atmosphere::bin_mean::BinMean`]), what the counts integrate, each
//! (column, channel, bin), with `cell_methods = "bin: mean"`.

use crate::scenario::ExpectedProfile;

/// A bin mean of one bin of a column's channel (the same type as `truth::Truth`, named
/// here so that this table does not import the point truth's module, which imports it).
type BinTruth = fn(&ExpectedProfile, usize) -> f64;

/// The CF attribute that says a variable is the mean over its bin.
pub(crate) const CELL_METHODS: (&str, &str) = ("cell_methods", "bin: mean");

/// The bin means by species, each (column, channel, bin): name, long name, units, value.
/// The onboard product averages them over each region bin's native bins, which is the
/// mean over the region bin (the multiple-scattering factors weighted by extinction,
/// [`ms_weighted`]).
pub(crate) const BIN_MEAN_TRUTH: [(&str, &str, &str, BinTruth); 6] = [
    (
        "alpha_aer_bin_mean",
        "aerosol extinction coefficient averaged over the bin's range (what the counts integrate)",
        "m-1",
        |e, i| e.bin_mean[i].alpha_aer,
    ),
    (
        "alpha_cld_bin_mean",
        "cloud extinction coefficient averaged over the bin's range (what the counts integrate)",
        "m-1",
        |e, i| e.bin_mean[i].alpha_cld,
    ),
    (
        "beta_aer_bin_mean",
        "aerosol backscatter coefficient averaged over the bin's range (what the counts integrate)",
        "m-1 sr-1",
        |e, i| e.bin_mean[i].beta_aer,
    ),
    (
        "beta_cld_bin_mean",
        "cloud backscatter coefficient averaged over the bin's range (what the counts integrate)",
        "m-1 sr-1",
        |e, i| e.bin_mean[i].beta_cld,
    ),
    (
        "ms_factor_aer_bin_mean",
        "effective multiple-scattering factor of the bin's aerosol extinction: the bin mean of eta alpha_aer over alpha_aer_bin_mean (1 without aerosol)",
        "1",
        |e, i| e.bin_mean[i].ms_factor_aer(),
    ),
    (
        "ms_factor_cld_bin_mean",
        "effective multiple-scattering factor of the bin's cloud extinction: the bin mean of eta alpha_cld over alpha_cld_bin_mean (1 without cloud)",
        "1",
        |e, i| e.bin_mean[i].ms_factor_cld(),
    ),
];

/// The extinction a bin-mean multiple-scattering factor weights, by name (the onboard
/// product's region bin takes `Σ⟨ηα⟩/Σ⟨α⟩` over its native bins, not their factors'
/// mean).
pub(crate) fn ms_weighted(name: &str) -> Option<(BinTruth, BinTruth)> {
    match name {
        "ms_factor_aer_bin_mean" => Some((
            |e, i| e.bin_mean[i].ms_alpha_aer,
            |e, i| e.bin_mean[i].alpha_aer,
        )),
        "ms_factor_cld_bin_mean" => Some((
            |e, i| e.bin_mean[i].ms_alpha_cld,
            |e, i| e.bin_mean[i].alpha_cld,
        )),
        _ => None,
    }
}
