//! Poisson draws for a fixed large mean by rejection from a step envelope over the PMF:
//! about two `u64` and two small table loads per draw, with tables of `O(√μ)` bytes that
//! stay in the caches where a full alias table ([`super::pmf_alias`]) no longer does.
//!
//! # Method
//!
//! The PMF window of [`pmf_window`] (the PMF from the mode by its ratio recurrence,
//! truncated at `2^-72` of the mode on each side) is cut into cells of `w = 2^b` counts,
//! `w` about `σ/`[`CELLS_PER_SIGMA`]. The envelope is the step function equal on cell
//! `c` to the cell's largest weight `M_c`; a cell is chosen with probability
//! `w·M_c / Σ w·M` by an integer alias table ([`AliasTable`], Walker 1977; Vose 1991),
//! a count `k` of the cell uniformly by the low `b` bits of a second `u64`, and `k` is
//! accepted with probability `p_k/M_c` by the top 53 bits `v` of that `u64`; a rejected
//! pair is drawn again. This is the rejection method over a piecewise-constant ("table")
//! envelope (Devroye 1986, *Non-Uniform Random Variate Generation*, §II.3 and §VIII.2;
//! the cell-then-accept layout of Marsaglia, Tsang & Wang 2004, "Fast generation of
//! discrete random variables", J. Stat. Softw. 11(3), without their 5-table split), and
//! gives the PMF window exactly up to the rounding below.
//!
//! The acceptance test is squeezed by a byte per count, `q_k = ⌊256·p_k/M_c⌋`: with
//! `t = ⌊256·v⌋` (the top 8 bits of `v`), `t < q_k` accepts and `t > q_k` rejects
//! without arithmetic; only `t = q_k` (probability ≤ 1/256) computes `p_k/M_c` from
//! the cell's first weight by the same ratio recurrence (at most `w − 1` factors `μ/j`).
//! The envelope wastes about `|z|·w/(2σ)` of the proposals at `z` standard deviations:
//! 4–6 % of them in all at [`CELLS_PER_SIGMA`] (λ = 10³ to 10⁷), drawn again.
//!
//! # Precision
//!
//! That of [`super::pmf_alias`]: each weight carries the rounding of its recurrence,
//! at most `(|k − m| + w)·2^-53` relative; the cell choice is exact to `(n+1)·2^-64`
//! ([`AliasTable`]); the acceptance compares 53 uniform bits with the f64 ratio
//! `p_k/M_c`, exact to `2^-53` relative. The law is truncated where the window ends
//! (`< 2^-72` per side).
//!
//! # Cost
//!
//! Measured in `cost` (`sampling::shot`) (`cargo run --release --example sampler_costs`):
//! 6.0–8.3 ns per draw in the caches for λ = 30 … 10^6, 10.3 ns at 10^7 (Ahrens–Dieter:
//! 19–21 ns). Per bin an alias table of `≈ 20σ/w` (80–160) cells, 16 bytes per
//! power-of-two column, 16 bytes per cell for the exact test, and a byte per count of
//! the window (`≈ 20σ`, most of it): 7 KiB at `μ = 10^3`, 26 KiB at `10^6`, 66 KiB at
//! `10^7` ([`pmf_cells_bytes`]), where [`super::pmf_alias::PmfAlias`] needs 16 KiB,
//! 512 KiB and 2 MiB.

use rand::Rng;

use super::alias::AliasTable;
use super::pmf_alias::pmf_window;

/// Cells per standard deviation (at least; the cell width is the power of two at or
/// below `σ / CELLS_PER_SIGMA`): more cells waste fewer proposals and take more memory.
/// 4 measured faster than 16 on a whole scenario-1 aggregate run (tables that stay in
/// the caches matter more than 5 % more proposals).
pub const CELLS_PER_SIGMA: f64 = 4.0;

/// Widest cell, `2^MAX_CELL_BITS` counts: the low bits of the second `u64` that pick the
/// count within the cell must stay clear of the 53 bits of the acceptance uniform.
const MAX_CELL_BITS: u32 = 11;

/// An exact Poisson(`μ`) sampler for one fixed large mean (see the module docs).
#[derive(Clone, Debug)]
pub struct PmfCells {
    /// The cell for the first `u64`.
    cells: AliasTable,
    /// `⌊256·p_k/M_c⌋` per count of the window's whole cells.
    squeeze: Box<[u8]>,
    /// Per cell: the weight of its first count and `1/M_c`, for the exact test.
    first_weight: Box<[(f64, f64)]>,
    /// The first count of the window.
    k0: u32,
    /// `log2` of the cell width.
    cell_bits: u32,
    mean: f64,
}

/// The `log2` of the cell width for `mean`.
fn cell_bits(mean: f64) -> u32 {
    let w = (mean.sqrt() / CELLS_PER_SIGMA).max(1.0);
    (w.log2().floor() as u32).min(MAX_CELL_BITS)
}

/// Bytes of the tables [`PmfCells::new`] builds for `mean` (for cost models and memory
/// bounds), without building them: the alias table's power-of-two columns of 16 bytes,
/// the squeeze bytes and 16 bytes per cell.
pub fn pmf_cells_bytes(mean: f64) -> usize {
    if mean <= 0.0 {
        return 0;
    }
    let entries = (20.0 * mean.sqrt() + 8.0).ceil() as usize;
    let cells = entries.div_ceil(1 << cell_bits(mean));
    16 * cells.next_power_of_two().max(2) + (cells << cell_bits(mean)) + 16 * cells
}

impl PmfCells {
    /// The sampler of Poisson(`mean`), `0 < mean < 4e9` (finite).
    pub fn new(mean: f64) -> PmfCells {
        let (k0, weights) = pmf_window(mean);
        assert!(
            !weights.is_empty(),
            "PmfCells needs a positive mean, got {mean}"
        );
        let cell_bits = cell_bits(mean);
        let w = 1usize << cell_bits;
        let n_cells = weights.len().div_ceil(w);
        let mut squeeze = vec![0u8; n_cells * w];
        let mut envelope = Vec::with_capacity(n_cells);
        let mut first_weight = Vec::with_capacity(n_cells);
        for (c, cell) in weights.chunks(w).enumerate() {
            // the exact test recomputes the cell's weights from its first one; the
            // envelope and the squeeze bytes come from the same recurrence and the same
            // `p·(1/M_c)`, so the three agree bit for bit
            // (the last cell's counts past the window keep their recurrence weights,
            // below 2^-72 of the mode: the law is truncated at the cell's end)
            let ratios = cell_ratios(cell[0], k0 + (c * w) as u32, mean, w);
            let max = ratios.iter().fold(0.0f64, |a, &b| a.max(b));
            let inv_max = 1.0 / max;
            for (q, r) in squeeze[c * w..].iter_mut().zip(&ratios) {
                *q = (r * inv_max * 256.0).floor().min(255.0) as u8;
            }
            envelope.push(max * w as f64);
            first_weight.push((cell[0], inv_max));
        }
        let ids: Vec<u32> = (0..n_cells as u32).collect();
        PmfCells {
            cells: AliasTable::new(&envelope, &ids),
            squeeze: squeeze.into_boxed_slice(),
            first_weight: first_weight.into_boxed_slice(),
            k0,
            cell_bits,
            mean,
        }
    }

    /// One draw.
    #[inline]
    pub fn sample<R: Rng + ?Sized>(&self, rng: &mut R) -> u32 {
        loop {
            let c = self.cells.bin_for(rng.next_u64());
            if let Some(k) = self.proposal(c, rng.next_u64()) {
                return k;
            }
        }
    }

    /// The count that the `u64` `y` proposes in cell `c` (its low bits), if its top 53
    /// bits accept it: the squeeze byte decides unless the top 8 bits equal it.
    #[inline(always)]
    fn proposal(&self, c: usize, y: u64) -> Option<u32> {
        let i = (y & ((1u64 << self.cell_bits) - 1)) as usize;
        let k = (c << self.cell_bits) + i;
        let q = self.squeeze[k];
        let t = (y >> 56) as u8;
        (t < q || (t == q && self.accepts(c, i, y >> 11))).then_some(self.k0 + k as u32)
    }

    /// The exact acceptance of count `i` of cell `c` for the 53-bit uniform `v`:
    /// `v·2^-53 < p_k/M_c`.
    #[cold]
    fn accepts(&self, c: usize, i: usize, v: u64) -> bool {
        let (first, inv_max) = self.first_weight[c];
        let k_first = self.k0 + (c << self.cell_bits) as u32;
        let p = weight_after(first, k_first, self.mean, i);
        (v as f64) * (1.0 / (1u64 << 53) as f64) < p * inv_max
    }

    /// Realised probability of each count `0..len` (tests): each count's accepted mass
    /// (its cell's probability, `1/w`, and `p_k/M_c` as the exact test computes it) over
    /// the total accepted mass.
    #[cfg(test)]
    pub(crate) fn probabilities(&self, len: usize) -> Vec<f64> {
        let w = 1usize << self.cell_bits;
        let cell_p = self.cells.probabilities(self.first_weight.len());
        let mut p = vec![0.0; len];
        for (c, &pc) in cell_p.iter().enumerate() {
            let (first, inv_max) = self.first_weight[c];
            let k_first = self.k0 + (c << self.cell_bits) as u32;
            let ratios = cell_ratios(first, k_first, self.mean, w);
            for (i, r) in ratios.iter().enumerate() {
                if let Some(x) = p.get_mut(k_first as usize + i) {
                    *x += pc / w as f64 * (r * inv_max).min(1.0);
                }
            }
        }
        let total: f64 = p.iter().sum();
        p.iter().map(|x| x / total).collect()
    }
}

/// The weight of count `k_first + i` from the weight `first` of `k_first`, by the PMF's
/// ratio recurrence `p_{k+1} = p_k·μ/(k+1)`.
#[inline]
fn weight_after(first: f64, k_first: u32, mean: f64, i: usize) -> f64 {
    let mut p = first;
    for j in 1..=i as u32 {
        p *= mean / f64::from(k_first + j);
    }
    p
}

/// The weights of the `len` counts of a cell from its first weight, as [`weight_after`]
/// computes each (the same operations in the same order).
fn cell_ratios(first: f64, k_first: u32, mean: f64, len: usize) -> Vec<f64> {
    let mut out = Vec::with_capacity(len);
    let mut p = first;
    for i in 0..len as u32 {
        if i > 0 {
            p *= mean / f64::from(k_first + i);
        }
        out.push(p);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The squeeze bytes and the exact test are one acceptance: for every count of a
    /// few cells (single counts at λ = 30, 128 at 10^6) and every value of the top 8
    /// bits, [`PmfCells::proposal`] accepts exactly when the 53-bit uniform lies below
    /// `p_k/M_c`, at the edges of each squeeze step too. Deterministic.
    #[test]
    fn the_squeeze_decides_as_the_exact_test() {
        for mean in [30.0, 1e6] {
            let s = PmfCells::new(mean);
            let w = 1usize << s.cell_bits;
            let cells = s.first_weight.len();
            for c in [0, cells / 3, cells / 2, cells - 1] {
                let (first, inv_max) = s.first_weight[c];
                let k_first = s.k0 + (c * w) as u32;
                let ratios = cell_ratios(first, k_first, mean, w);
                for (i, r) in ratios.iter().enumerate() {
                    let r = r * inv_max;
                    for t in 0..=255u64 {
                        for low in [0, 1 << 20, (1u64 << 45) - 1] {
                            let v = (t << 45) | low;
                            let y = (v << 11) | i as u64;
                            let want = (v as f64) * (1.0 / (1u64 << 53) as f64) < r;
                            let got = s.proposal(c, y).is_some();
                            assert_eq!(got, want, "μ {mean}, cell {c}, count {i}, t {t}");
                        }
                    }
                }
            }
        }
    }

    /// [`pmf_cells_bytes`] (what the table budget counts) is at least what
    /// [`PmfCells::new`] allocates, from single-count cells to the widest.
    #[test]
    fn the_byte_estimate_bounds_the_tables() {
        for mean in [11.0, 30.0, 1e3, 4e4, 1e6, 1e8, 3e9] {
            let s = PmfCells::new(mean);
            let cells = s.first_weight.len();
            let built = 16 * cells.next_power_of_two().max(2) + s.squeeze.len() + 16 * cells;
            assert!(
                built <= pmf_cells_bytes(mean),
                "μ = {mean}: {built} > {}",
                pmf_cells_bytes(mean)
            );
        }
    }
}
