//! The report of `lidarsim onboard --report` (docs/config.md columns): per scheme and
//! region the resolutions, the Eq. 4 and empirical S/N, the data rate and, for a scene
//! that changes along the track, the averaging bias.
//!
//! Its sums are exact, so they do not depend on the order of the profiles: integer sums
//! of the downlinked counts (each region's first channel) for the empirical S/N, and exact sums
//! ([`ExactSum`]) of the averaging biases. The single run and the combined partials of
//! its shards (`onboard::partial`) add the same terms and write the same report, byte for
//! byte.

use std::io::Write;

use serde::{Deserialize, Serialize};

use super::{RegionLayout, Scheme};
use crate::scenario::ExpectedProfile;
use crate::validate::exact::{ExactSum, decimal};

/// The sums of one downlinked bin (the region's first channel) over the region's profiles.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct BinSums {
    /// Downlinked profiles.
    pub n: u64,
    /// Σ c of the downlinked counts.
    #[serde(with = "decimal")]
    pub counts: u128,
    /// Σ c².
    #[serde(with = "decimal")]
    pub squares: u128,
    /// Σ of the profiles' finite averaging biases ([`averaging_bias`]).
    pub bias: ExactSum,
    /// How many there are.
    pub biased: u64,
}

impl BinSums {
    /// Adds a downlinked count.
    pub fn add_count(&mut self, c: u64) {
        let c = u128::from(c);
        self.n += 1;
        self.counts += c;
        self.squares += c * c;
    }

    /// Adds `other`'s terms.
    fn add(&mut self, other: &BinSums) {
        self.n += other.n;
        self.counts += other.counts;
        self.squares += other.squares;
        self.bias.merge(&other.bias);
        self.biased += other.biased;
    }

    /// The empirical S/N: the mean count above the expected background and dark counts
    /// `rest` of a downlinked bin, over the standard deviation of the counts.
    fn snr(&self, rest: f64) -> f64 {
        let (n, sum, sq) = (self.n as f64, self.counts as f64, self.squares as f64);
        let mean = sum / n;
        let var = (sq - n * mean * mean) / (n - 1.0);
        (mean - rest) / var.sqrt()
    }
}

/// The sums of one scheme: per region, per downlinked bin.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct SchemeSums {
    /// Per region, per bin.
    pub regions: Vec<Vec<BinSums>>,
}

impl SchemeSums {
    /// Empty sums for `regions`.
    pub fn new(regions: &[RegionLayout]) -> Self {
        SchemeSums {
            regions: regions
                .iter()
                .map(|r| vec![BinSums::default(); r.bins])
                .collect(),
        }
    }

    /// Adds `other` (of the same layout; else says why not).
    pub fn add(&mut self, other: &SchemeSums) -> std::result::Result<(), String> {
        let shape = |s: &SchemeSums| s.regions.iter().map(Vec::len).collect::<Vec<_>>();
        if shape(self) != shape(other) {
            return Err(format!(
                "its sums have regions of {:?} bins, not {:?}",
                shape(other),
                shape(self)
            ));
        }
        for (a, b) in self.regions.iter_mut().zip(&other.regions) {
            a.iter_mut().zip(b).for_each(|(x, y)| x.add(y));
        }
        Ok(())
    }
}

/// The averaging bias of one downlinked bin (docs/model.md): how far the log of the
/// averaged true signal lies above the average of the shots' logs,
/// `ln(Σs/N) − Σ ln s/N ≥ 0` (Jensen), what a retrieval working on the log of averaged
/// counts (extinction, optical depth) misses against the full-resolution truth; 0 over a
/// uniform scene, growing with the horizontal averaging over broken cloud. NaN where a
/// shot has no signal.
pub fn averaging_bias(sum: f64, sum_ln: f64, n: u32) -> f64 {
    let n = f64::from(n);
    (sum / n).ln() - sum_ln / n
}

/// Everything the report is made of.
pub struct ReportInput<'a> {
    /// Whether the scene changes along the track (the bias column is filled).
    pub scene_changes: bool,
    /// Every scheme, its layout and its sums.
    pub schemes: Vec<(&'a Scheme, &'a [RegionLayout], &'a SchemeSums)>,
    /// Every channel's expectations per shot (the first column of the scene); a
    /// region's row reports its first channel.
    pub expected: &'a [ExpectedProfile],
    /// Shots per second.
    pub rep_rate_hz: f64,
    /// Channels of the instrument.
    pub channels: usize,
    /// Bits per downlinked count.
    pub word_bits: u32,
}

/// The median of the finite values.
fn median(mut v: Vec<f64>) -> f64 {
    v.retain(|x| x.is_finite());
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// The median over a region's bins of their Eq. 4 S/N with `shots` shots.
fn eq4_median(g: &RegionLayout, e: &ExpectedProfile) -> f64 {
    let rest = (e.background + e.dark) * g.merge as f64;
    median(
        (0..g.bins)
            .map(|j| {
                let bins = g.first_bin + j * g.merge..g.first_bin + (j + 1) * g.merge;
                let s: f64 = e.signal[bins].iter().sum();
                crate::snr::eq4(s, rest, 0.0, f64::from(g.shots))
            })
            .collect(),
    )
}

/// The bias column: per bin the mean over the profiles; the median over the bins the
/// scene's changes reach (0 when none do); empty for a static scene.
fn bias_median(scene_changes: bool, sums: &[BinSums]) -> String {
    if !scene_changes {
        return String::new();
    }
    let affected: Vec<f64> = sums
        .iter()
        .map(|s| (s.bias.value(), s.biased))
        .filter(|&(sum, n)| n > 0 && sum > 1e-12)
        .map(|(sum, n)| sum / n as f64)
        .collect();
    format!("{:e}", median(affected).max(0.0))
}

/// The downlink of a layout, bit s⁻¹: every region's bins of each channel it holds,
/// `Σ_regions bins·channels·word_bits·f_L/shots`.
pub fn data_rate_bps(
    regions: &[RegionLayout],
    channels: usize,
    word_bits: u32,
    rep_rate_hz: f64,
) -> f64 {
    regions
        .iter()
        .map(|g| {
            (g.bins * g.channel_indices(channels).len()) as f64 * f64::from(word_bits) * rep_rate_hz
                / f64::from(g.shots)
        })
        .sum()
}

/// Writes the report: one row per scheme and region (docs/config.md columns); a region's
/// S/N columns are those of its first channel.
pub fn write_report(w: &mut dyn Write, r: &ReportInput) -> std::io::Result<()> {
    writeln!(
        w,
        "scheme,region,altitude_min_km,altitude_max_km,vertical_resolution_m,shots_averaged,bins,snr_eq4_median,snr_empirical_median,data_rate_bps,averaging_bias_median"
    )?;
    for &(scheme, regions, sums) in &r.schemes {
        let rate = data_rate_bps(regions, r.channels, r.word_bits, r.rep_rate_hz);
        for (k, (g, bins)) in regions.iter().zip(&sums.regions).enumerate() {
            let e = &r.expected[g.first_channel()];
            let rest = (e.background + e.dark) * g.merge as f64 * f64::from(g.shots);
            let empirical = median(bins.iter().map(|s| s.snr(rest)).collect());
            let (lo, hi, res) = match &g.region {
                Some(reg) => (reg.bottom_km, reg.top_km, reg.vertical_resolution_m),
                None => (f64::NAN, f64::NAN, f64::NAN),
            };
            writeln!(
                w,
                "{},{k},{lo},{hi},{res},{},{},{:e},{:e},{rate},{}",
                scheme.name,
                g.shots,
                g.bins,
                eq4_median(g, e),
                empirical,
                bias_median(r.scene_changes, bins)
            )?;
        }
    }
    Ok(())
}
