//! The onboard summation: native shot-level counts in, integer sums per region out.

use super::RegionLayout;

/// Sums consecutive single-shot native profiles into each region's downlinked profiles.
#[derive(Debug, Clone)]
pub struct Averager {
    regions: Vec<RegionLayout>,
    /// Per region: its running sums and the shots in them.
    pending: Vec<(Vec<u64>, u32)>,
}

impl Averager {
    /// An averager for `regions` (from [`super::Scheme::layout`]).
    pub fn new(regions: Vec<RegionLayout>) -> Self {
        let pending = regions.iter().map(|r| (vec![0u64; r.bins], 0)).collect();
        Averager { regions, pending }
    }

    /// The regions.
    pub fn regions(&self) -> &[RegionLayout] {
        &self.regions
    }

    /// Adds one shot's native counts; `emit(region, sums)` receives every region profile
    /// completed by it (its shots summed and bins merged, integers only).
    pub fn add_shot(&mut self, native: &[u64], mut emit: impl FnMut(usize, &[u64])) {
        for (k, (r, (sums, shots))) in self.regions.iter().zip(&mut self.pending).enumerate() {
            let span = &native[r.first_bin..r.first_bin + r.merge * r.bins];
            for (s, chunk) in sums.iter_mut().zip(span.chunks_exact(r.merge)) {
                *s += chunk.iter().sum::<u64>();
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
