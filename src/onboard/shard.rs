//! `lidarsim onboard --shard K/N`: the onboard run cut at whole frames (docs/scale.md).
//!
//! The run draws T native shots, one per native profile, whose counts depend on the seed
//! and the shot only. A frame is L shots, the least common multiple of `shots_averaged`
//! over every region of every scheme given, so that no averaging group of any scheme
//! straddles two shards. With F = ⌊T/L⌋ whole frames, shard K of N holds frames
//! `⌊K·F/N⌋ … ⌊(K+1)·F/N⌋ − 1` ([`crate::shard::Shard::rows`]), and the last shard also
//! the `T − F·L` shots after the last whole frame: the shards' shots are the run's, each
//! once, and every region's downlinked profiles the run's, in order (the shots that do
//! not fill a last group of a region are summed nowhere, as in the whole run).

use std::ops::Range;

use super::RegionLayout;
use crate::error::{Error, Result};
use crate::shard::Shard;

/// Root attribute of a product shard: the shots of a frame (L), after the shard
/// attributes of [`crate::shard::SHARD_ATTRIBUTES`].
pub const FRAME_ATTRIBUTE: &str = "frame_shots";

/// Shots of a frame: the least common multiple of every region's shots (None when it
/// does not fit 64 bits).
pub fn frame_shots<'a>(regions: impl IntoIterator<Item = &'a RegionLayout>) -> Option<u64> {
    fn gcd(a: u64, b: u64) -> u64 {
        if b == 0 { a } else { gcd(b, a % b) }
    }
    regions.into_iter().try_fold(1u64, |l, r| {
        let s = u64::from(r.shots.max(1));
        (l / gcd(l, s)).checked_mul(s)
    })
}

/// The shots of shard `shard` of a run of `total` shots in frames of `frame` shots (no
/// check: empty when the shard has no frame).
pub fn shard_shots(shard: Shard, total: u64, frame: u64) -> Range<u64> {
    let frames = total / frame.max(1);
    let f = shard.rows(frames as usize);
    let start = f.start as u64 * frame;
    let end = match shard.index + 1 == shard.count {
        true => total,
        false => f.end as u64 * frame,
    };
    start..end
}

/// [`shard_shots`], refusing a cut that leaves shards without a whole frame (one line:
/// the shards, frames and the frame's shots).
pub fn shard_shots_of(shard: Shard, total: u64, frame: Option<u64>) -> Result<Range<u64>> {
    let Some(frame) = frame.filter(|&l| l <= total) else {
        return Err(Error::Unsupported(format!(
            "--shard {shard}: the run's {total} shots do not fill one frame (the least common \
             multiple of every region's shots_averaged, over every --scheme); run it whole"
        )));
    };
    let frames = usize::try_from(total / frame).unwrap_or(usize::MAX);
    shard.rows_of(frames, &format!("frames of {frame} shots"))?;
    Ok(shard_shots(shard, total, frame))
}

/// The profiles of `region` (of `shots` shots each) within `shots`, a range starting at a
/// whole frame: `first .. first + n` in the run's numbering.
pub fn region_profiles(region: &RegionLayout, shots: &Range<u64>) -> Range<usize> {
    profiles_within(region.shots, shots)
}

/// The profiles of `shots_averaged` shots each within `shots` (a range starting at a
/// whole frame), in the run's numbering.
pub fn profiles_within(shots_averaged: u32, shots: &Range<u64>) -> Range<usize> {
    let s = u64::from(shots_averaged.max(1));
    (shots.start / s) as usize..(shots.end / s) as usize
}

#[cfg(test)]
mod tests {
    use super::*;

    fn layout(shots: u32) -> RegionLayout {
        RegionLayout {
            first_bin: 0,
            merge: 1,
            bins: 1,
            shots,
            region: None,
            channels: None,
        }
    }

    #[test]
    fn frames_cover_the_run_once_with_the_leftover_last() {
        let l = frame_shots(&[layout(15), layout(5), layout(3), layout(1)]).unwrap();
        assert_eq!(l, 15);
        assert_eq!(frame_shots(&[layout(7), layout(3)]), Some(21));
        let (total, frame) = (90, 21);
        let cuts: Vec<Range<u64>> = (0..4)
            .map(|k| shard_shots_of(Shard::new(k, 4).unwrap(), total, Some(frame)).unwrap())
            .collect();
        assert_eq!(cuts, vec![0..21, 21..42, 42..63, 63..90]);
        // uniform:3 in the last shard: profiles 21..30, two of them in the leftover
        assert_eq!(region_profiles(&layout(3), &cuts[3]), 21..30);
        let five = shard_shots_of(Shard::new(0, 5).unwrap(), total, Some(frame));
        assert!(
            five.unwrap_err()
                .to_string()
                .contains("5 shards of 4 frames of 21 shots")
        );
        assert!(shard_shots_of(Shard::new(0, 1).unwrap(), 20, Some(21)).is_err());
        assert!(frame_shots(&[layout(1 << 31), layout((1 << 31) - 1), layout(999_983)]).is_none());
    }
}
