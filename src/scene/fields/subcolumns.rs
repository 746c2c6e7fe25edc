//! Subcolumns of a model column from its cloud fraction, by maximum-random overlap
//! (`scene.model_fields.subcolumns`; docs/model.md §4k).
//!
//! **Algorithm** (the generator of Räisänen, Barker, Khairoutdinov, Li & Randall 2004,
//! Q. J. R. Meteorol. Soc. 130, 2047, eq. 1–2 with the overlap parameter 1 between
//! adjacent cloudy levels: maximum-random overlap, the rule of SCOPS in COSP, Klein &
//! Jakob 1999, Webb et al. 2001). Levels from the top down; each subcolumn carries a
//! rank x, drawn U(0, 1) at the top level; at each level below, a subcolumn cloudy in
//! the level above keeps its rank (adjacent cloudy levels overlap maximally), any other
//! draws a new rank U(0, 1)·(1 − C_above), below the level above's cloudy ranks (cloud
//! separated by clear levels overlaps at random); the subcolumn is cloudy at level k
//! where x > 1 − C_k.
//!
//! **Properties.** x at every level is U(0, 1) (with probability C_above uniform on the
//! cloudy ranks, else uniform on the rest), so level k is cloudy in a fraction C_k of the
//! subcolumns in expectation; two adjacent levels cover max(C₁, C₂) together, two
//! separated by a clear level C₁ + C₂ − C₁C₂ (`tests/model_fields_subcolumns.rs` checks
//! both over 10⁴ columns).
//!
//! **Seed.** Profile p's subcolumns come from the run's seed and p alone
//! (`stream_rng(seed ^ SUBCOLUMN_STREAM, p, 0)`), so shards and the single run draw the
//! same ones. Cost: one uniform draw per subcolumn and level.

use rand::Rng;

use crate::sampling::stream_rng;

/// Stream of the subcolumn draws (xor-ed into the run's seed).
pub const SUBCOLUMN_STREAM: u64 = 0x5C0B_5C0B_0000_0001;

pub use crate::limits::MAX_SUBCOLUMNS;

/// The cloudy levels of `n` subcolumns of a column whose levels, **top first**, have
/// the cloud fractions `fraction_top_down` (each in [0, 1]): `mask[j][k]` is whether
/// subcolumn j is cloudy at level k (top first). Drawn from `rng` (uniforms of 53 bits,
/// as the broken layers' cells draw theirs).
pub fn max_random<R: Rng + ?Sized>(
    fraction_top_down: &[f64],
    n: usize,
    rng: &mut R,
) -> Vec<Vec<bool>> {
    let mut uniform = || (rng.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64);
    let mut rank: Vec<f64> = (0..n).map(|_| uniform()).collect();
    let mut mask = vec![vec![false; fraction_top_down.len()]; n];
    let mut above = 0.0f64;
    for (k, &c) in fraction_top_down.iter().enumerate() {
        for (j, x) in rank.iter_mut().enumerate() {
            if k > 0 && *x <= 1.0 - above {
                *x = uniform() * (1.0 - above);
            }
            mask[j][k] = *x > 1.0 - c;
        }
        above = c;
    }
    mask
}

/// The subcolumns of profile `profile` of a run of seed `seed`: [`max_random`] from that
/// profile's own stream.
pub fn of_profile(fraction_top_down: &[f64], n: usize, seed: u64, profile: u64) -> Vec<Vec<bool>> {
    max_random(
        fraction_top_down,
        n,
        &mut stream_rng(seed ^ SUBCOLUMN_STREAM, profile, 0),
    )
}

/// The shots of a profile of `shots` shots spread over `n` subcolumns as evenly as
/// they go: subcolumn j gets shots `⌊j·shots/n⌋ .. ⌊(j+1)·shots/n⌋` (every subcolumn at
/// least one where `n ≤ shots`).
pub fn shot_counts(shots: u64, n: usize) -> Vec<u64> {
    let n64 = n as u64;
    (0..n64)
        .map(|j| (j + 1) * shots / n64 - j * shots / n64)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn full_and_empty_levels_are_all_or_nothing() {
        let m = of_profile(&[0.0, 1.0, 0.0, 1.0], 50, 7, 3);
        for s in &m {
            assert_eq!(s, &vec![false, true, false, true]);
        }
    }

    #[test]
    fn shots_are_spread_evenly() {
        assert_eq!(shot_counts(15, 10), vec![1, 2, 1, 2, 1, 2, 1, 2, 1, 2]);
        assert_eq!(shot_counts(15, 10).iter().sum::<u64>(), 15);
        assert_eq!(shot_counts(3, 3), vec![1, 1, 1]);
    }

    #[test]
    fn the_same_profile_draws_the_same_subcolumns() {
        let f = [0.3, 0.5, 0.0, 0.7];
        assert_eq!(of_profile(&f, 10, 11, 4), of_profile(&f, 10, 11, 4));
        assert_ne!(of_profile(&f, 10, 11, 4), of_profile(&f, 10, 11, 5));
    }
}
