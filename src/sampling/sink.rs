//! Where a sampler's counts go: `(bin, count)` events into an accumulator or a
//! shot's own buffer.

/// Receiver of one shot's counts as `(bin, count)` events, `count ≥ 1`. A bin
/// may be reported more than once per shot (the sparse path reports one count
/// at a time); the shot's count in a bin is the sum of its events.
pub trait CountSink {
    fn add(&mut self, bin: usize, count: u32);

    /// One count in `bin` from the sparse path's placement by the uniform `draw`, with
    /// where the draw fell among the draws of that bin: `offset < width`, uniform on
    /// `0..width` given the bin, so that `(offset + V)/width`, for any `V` uniform on
    /// `[0, 1)` and independent, is uniform on `[0, 1)` and independent of the bin and of
    /// every other count: with the rate constant within a bin, the photon's time within
    /// it as a fraction of the bin, drawn at no cost (issue 41; `AliasTable::place`;
    /// `ShotSampler::placement` gives `(offset, width)` again from `draw`). A sink that
    /// needs no times takes it as `add(bin, 1)`.
    #[inline(always)]
    fn add_placed(&mut self, bin: usize, draw: u64, offset: u64, width: u64) {
        let _ = (draw, offset, width);
        self.add(bin, 1);
    }

    /// A count that may be 0 (reported only when it is not, unless the sink can take a
    /// zero for free: an accumulator adds it without a branch that the draws of a bin
    /// with `P(K = 0)` near ½ would mispredict).
    #[inline(always)]
    fn add_any(&mut self, bin: usize, count: u32) {
        if count > 0 {
            self.add(bin, count);
        }
    }
}

/// Accumulator: adds every event into `acc[bin]`.
impl CountSink for [u64] {
    #[inline(always)]
    fn add(&mut self, bin: usize, count: u32) {
        self[bin] += u64::from(count);
    }

    #[inline(always)]
    fn add_any(&mut self, bin: usize, count: u32) {
        self[bin] += u64::from(count);
    }
}

/// One shot's counts: a dense `u32` per bin plus the list of bins hit, cleared
/// in O(bins hit). Capacity is reserved up front: no allocation per shot.
#[derive(Clone, Debug)]
pub struct ShotCounts {
    counts: Vec<u32>,
    hit: Vec<u32>,
}

impl ShotCounts {
    pub fn new(bins: usize) -> Self {
        ShotCounts {
            counts: vec![0; bins],
            hit: Vec::with_capacity(bins),
        }
    }

    /// Counts of every bin in this shot.
    pub fn counts(&self) -> &[u32] {
        &self.counts
    }

    /// Bins with a non-zero count, in first-hit order.
    pub fn hit_bins(&self) -> &[u32] {
        &self.hit
    }

    /// `(bin, count)` of the bins with a non-zero count, in first-hit order.
    pub fn nonzero(&self) -> impl Iterator<Item = (usize, u32)> + '_ {
        self.hit
            .iter()
            .map(|&b| (b as usize, self.counts[b as usize]))
    }

    /// Total number of counts in this shot.
    pub fn total(&self) -> u64 {
        self.nonzero().map(|(_, c)| u64::from(c)).sum()
    }

    /// Reset to zero counts (O(bins hit)).
    pub fn clear(&mut self) {
        for &b in &self.hit {
            self.counts[b as usize] = 0;
        }
        self.hit.clear();
    }
}

impl CountSink for ShotCounts {
    #[inline(always)]
    fn add(&mut self, bin: usize, count: u32) {
        let c = &mut self.counts[bin];
        if *c == 0 {
            self.hit.push(bin as u32);
        }
        *c += count;
    }
}
