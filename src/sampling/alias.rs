//! Alias table over bins, in exact integer arithmetic.
//!
//! # Method
//!
//! Walker's alias method (Walker 1977, "An efficient method for generating
//! discrete random variables with general distributions", ACM TOMS 3(3),
//! 253–256) built by Vose's O(n) algorithm (Vose 1991, "A linear algorithm
//! for generating random numbers with a given distribution", IEEE Trans.
//! Softw. Eng. 17(9), 972–975).
//!
//! The weights are first rounded to integers `W_i` summing to exactly `2^64`
//! (`W_i = ⌊w_i / Σw · 2^64⌋`, the rounding remainder, at most a few units per
//! bin, given to the heaviest bin). The number of columns is padded to a power
//! of two `2^b ≥ 2` (padding columns have weight 0), each column holding
//! `C = 2^(64-b)` units, and Vose's construction runs on these integers, so it
//! has none of the floating-point leftovers of the textbook version. One draw
//! takes one `u64` `x`: its top `b` bits pick the column (exactly uniform), its
//! low `64-b` bits are compared with the column's integer threshold. The bin
//! is therefore returned with probability exactly `W_i / 2^64`: within
//! `(n+1)·2^-64` of `w_i/Σw` for every bin but the heaviest, which also takes the
//! rounding of `Σw` (summed with compensation: about `2^11` more units).

/// One column: `bins[0]` (its own bin) when the low bits are `< thr`, else
/// `bins[1]` (the alias); selected by index, without a branch.
#[derive(Clone, Copy, Debug)]
struct Column {
    thr: u64,
    bins: [u32; 2],
}

#[derive(Clone, Debug)]
pub(crate) struct AliasTable {
    cols: Box<[Column]>,
    shift: u32,
    mask: u64,
}

impl AliasTable {
    /// `weights[i] >= 0` (finite, not all zero) for the bin `ids[i]`.
    pub(crate) fn new(weights: &[f64], ids: &[u32]) -> Self {
        assert_eq!(weights.len(), ids.len());
        assert!(!weights.is_empty(), "alias table needs at least one bin");
        let n = weights.len();
        let b = (n.next_power_of_two().trailing_zeros()).max(1);
        let ncols = 1usize << b;
        let cap: u128 = 1u128 << (64 - b);
        // Neumaier's compensated sum (Neumaier 1974): the total to about one ulp whatever
        // the number of weights, so the rounding remainder given to the heaviest bin
        // below stays within about n + 2^11 units of 2^-64.
        let (mut total, mut carry) = (0.0f64, 0.0f64);
        for &x in weights {
            let t = total + x;
            carry += if total.abs() >= x.abs() {
                (total - t) + x
            } else {
                (x - t) + total
            };
            total = t;
        }
        let total = total + carry;
        assert!(
            total > 0.0 && total.is_finite(),
            "alias weights must have a positive finite sum"
        );

        // Integer weights summing to exactly 2^64.
        let scale = 18_446_744_073_709_551_616.0 / total;
        let mut w: Vec<u128> = weights.iter().map(|&x| (x * scale) as u128).collect();
        w.resize(ncols, 0);
        let sum: u128 = w.iter().sum();
        let target: u128 = 1u128 << 64;
        let heaviest = (0..n)
            .max_by(|&i, &j| weights[i].total_cmp(&weights[j]).then(j.cmp(&i)))
            .unwrap();
        if sum <= target {
            w[heaviest] += target - sum;
        } else {
            w[heaviest] -= sum - target;
        }

        let mut cols = vec![
            Column {
                thr: 0,
                bins: [0, 0],
            };
            ncols
        ];
        let id = |j: usize| if j < n { ids[j] } else { ids[heaviest] };
        let mut small: Vec<usize> = Vec::with_capacity(ncols);
        let mut large: Vec<usize> = Vec::with_capacity(ncols);
        for (j, &wj) in w.iter().enumerate().rev() {
            if wj < cap {
                small.push(j);
            } else {
                large.push(j);
            }
        }
        while let (Some(&s), Some(&l)) = (small.last(), large.last()) {
            small.pop();
            cols[s] = Column {
                thr: w[s] as u64,
                bins: [id(s), id(l)],
            };
            w[l] -= cap - w[s];
            if w[l] < cap {
                large.pop();
                small.push(l);
            }
        }
        // Exact arithmetic: what is left is exactly full (w == cap); `small`
        // can only be non-empty if that were violated.
        debug_assert!(small.is_empty());
        for j in large.into_iter().chain(small) {
            cols[j] = Column {
                thr: cap as u64,
                bins: [id(j), id(j)],
            };
        }
        AliasTable {
            cols: cols.into_boxed_slice(),
            shift: 64 - b,
            mask: (cap - 1) as u64,
        }
    }

    /// Number of columns (16 bytes each).
    pub(crate) fn columns(&self) -> usize {
        self.cols.len()
    }

    /// The bin for the uniform `u64` `x`.
    #[inline(always)]
    pub(crate) fn bin_for(&self, x: u64) -> usize {
        let c = &self.cols[(x >> self.shift) as usize];
        c.bins[usize::from((x & self.mask) >= c.thr)] as usize
    }

    /// The bin for the uniform `u64` `x` (as [`bin_for`](Self::bin_for)) and where `x`
    /// fell among the draws of its column half: `(bin, offset, width)`, `offset < width`.
    /// Given the half (and so given the bin), `offset` is uniform on `0..width`, so
    /// `(offset + V)/width` is uniform on `[0, 1)` for a `V` uniform on `[0, 1)`,
    /// independent of the bin and of every other draw: the photon's place within its
    /// bin, for free (issue 41). A half of width `w` holds `offset` to `1/w`.
    #[inline(always)]
    pub(crate) fn place(&self, x: u64) -> (usize, u64, u64) {
        let c = &self.cols[(x >> self.shift) as usize];
        let lo = x & self.mask;
        let side = lo >= c.thr;
        let (offset, width) = if side {
            (lo - c.thr, self.mask - c.thr + 1)
        } else {
            (lo, c.thr)
        };
        (c.bins[usize::from(side)] as usize, offset, width)
    }

    /// Realised probability of each column half, for tests: `(bin, P)` pairs, a bin
    /// possibly more than once (ids need not be small).
    #[cfg(test)]
    pub(crate) fn halves(&self) -> Vec<(u32, f64)> {
        let cap = (self.mask as f64) + 1.0;
        let ncols = self.cols.len() as f64;
        self.cols
            .iter()
            .flat_map(|c| {
                [
                    (c.bins[0], c.thr as f64 / cap / ncols),
                    (c.bins[1], (cap - c.thr as f64) / cap / ncols),
                ]
            })
            .collect()
    }

    /// Realised probability of each column entry, for tests: `(bin, P)` pairs summed by bin.
    #[cfg(test)]
    pub(crate) fn probabilities(&self, bins: usize) -> Vec<f64> {
        let cap = (self.mask as f64) + 1.0;
        let ncols = self.cols.len() as f64;
        let mut p = vec![0.0; bins];
        for c in self.cols.iter() {
            p[c.bins[0] as usize] += c.thr as f64 / cap / ncols;
            p[c.bins[1] as usize] += (cap - c.thr as f64) / cap / ncols;
        }
        p
    }
}
