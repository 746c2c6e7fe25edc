//! What the counting tables share: the entries of a law kept around its median (the
//! cut-off), and a uniform from 64 random bits.

/// Masses below this, relative to the largest, are left out of a table (`2^-72`).
const CUTOFF: f64 = 1.0 / (1u128 << 72) as f64;

/// The entries of a law around its median `median` (R from `k_bottom` to `k_top`), each
/// side stopped once a mass (atom + cell) falls below [`CUTOFF`] of the median's: the
/// first R and the (atom, cell) masses.
pub(super) fn around(
    median: u32,
    k_bottom: u32,
    k_top: u32,
    masses: impl Fn(u32) -> (f64, f64),
) -> (u32, Vec<(f64, f64)>) {
    let total = |(a, c): (f64, f64)| a + c;
    let peak = total(masses(median));
    let mut below = Vec::new();
    let mut k = median;
    while k > k_bottom {
        k -= 1;
        let x = masses(k);
        if total(x) < CUTOFF * peak {
            break;
        }
        below.push(x);
    }
    let k0 = median - below.len() as u32;
    let mut entries: Vec<(f64, f64)> = below.into_iter().rev().collect();
    entries.push(masses(median));
    let mut k = median;
    while k < k_top {
        k += 1;
        let x = masses(k);
        if total(x) < CUTOFF * peak {
            break;
        }
        entries.push(x);
    }
    (k0, entries)
}

/// A uniform in [0, 1) from the top 53 bits of `x`.
#[inline(always)]
pub(super) fn unit_f64(x: u64) -> f64 {
    (x >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}
