//! One shard of a run (`K/N`) and the rows of the run it draws.

use std::ops::Range;

use crate::error::{Error, Result};

/// One shard of a run: `index` of `count` (0 ≤ index < count).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// K, from 0.
    pub index: usize,
    /// N, at least 1.
    pub count: usize,
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

impl Shard {
    /// Shard `index` of `count`; refuses `count = 0` and `index ≥ count`.
    pub fn new(index: usize, count: usize) -> std::result::Result<Shard, String> {
        if count == 0 {
            return Err("the shard count N must be at least 1".into());
        }
        if index >= count {
            return Err(format!(
                "shard {index} of {count} does not exist: K runs from 0 to N-1 = {}",
                count - 1
            ));
        }
        Ok(Shard { index, count })
    }

    /// Its rows of `total`: `⌊K·total/N⌋ .. ⌊(K+1)·total/N⌋` (empty when N > total).
    pub fn rows(self, total: usize) -> Range<usize> {
        let at = |k: usize| (k as u128 * total as u128 / self.count as u128) as usize;
        at(self.index)..at(self.index + 1)
    }

    /// [`Shard::rows`], refusing a cut that leaves shards empty (N greater than the
    /// `total` of `what`, e.g. profiles): an empty shard could not be a valid raw file.
    pub fn rows_of(self, total: usize, what: &str) -> Result<Range<usize>> {
        if self.count > total {
            return Err(Error::Unsupported(format!(
                "--shard {self}: {} shards of {total} {what} would leave shards empty; \
                 use at most {total} shards",
                self.count
            )));
        }
        Ok(self.rows(total))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_cut_the_run_in_order_exactly_once() {
        for total in [1usize, 7, 10, 12, 1000] {
            for count in 1..=total.min(9) {
                let mut next = 0;
                for index in 0..count {
                    let r = Shard::new(index, count).unwrap().rows(total);
                    assert_eq!(r.start, next);
                    assert!(!r.is_empty(), "{index}/{count} of {total}");
                    next = r.end;
                }
                assert_eq!(next, total);
            }
        }
        assert_eq!(Shard::new(1, 3).unwrap().rows(10), 3..6);
    }
}
