//! The onboard summation: native shot-level counts in, integer sums per region out.

use super::scheme::RegionLayout;

/// Sums consecutive single-shot native profiles into each region's downlinked profiles,
/// every channel (native profiles and sums channel-major).
#[derive(Debug, Clone)]
pub struct Averager {
    regions: Vec<RegionLayout>,
    /// Per region: its running sums (its channels × bins) and the shots in them.
    pending: Vec<(Vec<u64>, u32)>,
    /// Per region: the channels it holds.
    held: Vec<Vec<usize>>,
    n_bins: usize,
}

impl Averager {
    /// An averager for one channel of `n_bins` native bins (`regions` from
    /// [`super::scheme::Scheme::layout`]).
    pub fn new(regions: Vec<RegionLayout>, n_bins: usize) -> Self {
        Self::with_channels(regions, 1, n_bins)
    }

    /// An averager for `channels` channels of `n_bins` native bins each (a region holds
    /// the channels it lists, [`RegionLayout::channels`]).
    pub fn with_channels(regions: Vec<RegionLayout>, channels: usize, n_bins: usize) -> Self {
        let held: Vec<Vec<usize>> = regions
            .iter()
            .map(|r| r.channel_indices(channels))
            .collect();
        let pending = regions
            .iter()
            .zip(&held)
            .map(|(r, h)| (vec![0u64; r.bins * h.len()], 0))
            .collect();
        Averager {
            regions,
            pending,
            held,
            n_bins,
        }
    }

    /// The regions.
    pub fn regions(&self) -> &[RegionLayout] {
        &self.regions
    }

    /// Adds one shot's native counts; `emit(region, sums)` receives every region profile
    /// completed by it (its shots summed and bins merged, integers only; the region's
    /// channels, channel-major).
    pub fn add_shot(&mut self, native: &[u64], mut emit: impl FnMut(usize, &[u64])) {
        let regions = self.regions.iter().zip(&self.held);
        for (k, ((r, held), (sums, shots))) in regions.zip(&mut self.pending).enumerate() {
            for (&c, out) in held.iter().zip(sums.chunks_mut(r.bins)) {
                let start = c * self.n_bins + r.first_bin;
                let span = &native[start..start + r.merge * r.bins];
                for (s, chunk) in out.iter_mut().zip(span.chunks_exact(r.merge)) {
                    *s += chunk.iter().sum::<u64>();
                }
            }
            *shots += 1;
            if *shots == r.shots {
                emit(k, sums);
                sums.iter_mut().for_each(|s| *s = 0);
                *shots = 0;
            }
        }
    }
}
