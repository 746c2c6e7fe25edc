//! Command-line values, validated like config values: one parser per kind of option,
//! each refusing what the run could not honour with a message that names the range.
//! clap calls them; its message is then `invalid value 'X' for '--opt': REASON`.

use crate::error::compact;
use crate::sampling::approx::MAX_TOLERANCE;

pub use crate::limits::{MAX_PROFILES, MAX_REALIZATIONS};
/// Largest `--threads`.
pub const MAX_THREADS: usize = 1024;

/// A whole number in `[lo, hi]`, written as an integer or in scientific notation
/// (`1e6`).
fn whole(s: &str, lo: u64, hi: u64) -> Result<u64, String> {
    let range = || format!("must be a whole number from {lo} to {}", compact(hi as f64));
    if let Ok(n) = s.trim().parse::<u64>() {
        return if (lo..=hi).contains(&n) {
            Ok(n)
        } else {
            Err(range())
        };
    }
    match s.trim().parse::<f64>() {
        Ok(x) if x.is_finite() && x.fract() == 0.0 && x >= lo as f64 && x <= hi as f64 => {
            Ok(x as u64)
        }
        _ => Err(range()),
    }
}

/// `--profiles`: 1 to [`MAX_PROFILES`].
pub fn profiles(s: &str) -> Result<usize, String> {
    whole(s, 1, MAX_PROFILES).map(|n| n as usize)
}

/// `--realizations`: 1 to [`MAX_REALIZATIONS`] (`validate` has its own minimum).
pub fn realizations(s: &str) -> Result<usize, String> {
    whole(s, 1, MAX_REALIZATIONS).map(|n| n as usize)
}

/// `--threads`: 1 to [`MAX_THREADS`].
pub fn threads(s: &str) -> Result<usize, String> {
    whole(s, 1, MAX_THREADS as u64).map(|n| n as usize)
}

/// `--seed`: any whole number from 0 to 2^64 − 1, as an integer.
pub fn seed(s: &str) -> Result<u64, String> {
    s.trim()
        .parse::<u64>()
        .map_err(|_| "must be a whole number from 0 to 18446744073709551615".to_string())
}

/// `--tolerance`: a KS distance in (0, [`MAX_TOLERANCE`]].
pub fn tolerance(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(t) if t > 0.0 && t <= MAX_TOLERANCE => Ok(t),
        _ => Err(format!(
            "must be a number in (0, {}] (the largest KS distance per bin; omit it for exact draws)",
            compact(MAX_TOLERANCE)
        )),
    }
}

/// `export-scc-calibration --pol-calib-range MIN,MAX`: two ranges in m, `0 ≤ MIN < MAX`
/// (the file's recorded range is checked against them when it is read).
pub fn pol_calib_range_m(s: &str) -> Result<(f64, f64), String> {
    let reason =
        || "must be MIN,MAX in m of range with 0 <= MIN < MAX (e.g. 1000,2500)".to_string();
    let (lo, hi) = s.split_once(',').ok_or_else(reason)?;
    let m = |t: &str| {
        t.trim()
            .parse::<f64>()
            .ok()
            .filter(|r| r.is_finite() && *r >= 0.0)
    };
    match (m(lo), m(hi)) {
        (Some(lo), Some(hi)) if lo < hi => Ok((lo, hi)),
        _ => Err(reason()),
    }
}

/// Most bits per downlinked count (`onboard --word-bits`): a 64-bit word.
pub const MAX_WORD_BITS: u32 = 64;

/// `onboard --word-bits`: 1 to [`MAX_WORD_BITS`].
pub fn word_bits(s: &str) -> Result<u32, String> {
    whole(s, 1, u64::from(MAX_WORD_BITS)).map(|n| n as u32)
}

/// `--shard`: `K/N` (0 ≤ K < N) or `auto` ([`crate::shard::ShardArg`]).
pub fn shard(s: &str) -> Result<crate::shard::ShardArg, String> {
    s.parse()
}

/// Largest altitude `quicklook --altitude-range` accepts, km (beyond any orbit a lidar
/// flies).
pub const MAX_ALTITUDE_KM: f64 = 1.0e5;

/// `quicklook --altitude-range LO,HI`: two altitudes in km, `LO < HI`, each within
/// ±[`MAX_ALTITUDE_KM`].
pub fn altitude_range_km(s: &str) -> Result<(f64, f64), String> {
    let reason = || {
        format!(
            "must be LO,HI in km with LO < HI (e.g. 0,15), each within ±{}",
            compact(MAX_ALTITUDE_KM)
        )
    };
    let (lo, hi) = s.split_once(',').ok_or_else(reason)?;
    let km = |t: &str| {
        t.trim()
            .parse::<f64>()
            .ok()
            .filter(|z| z.is_finite() && z.abs() <= MAX_ALTITUDE_KM)
    };
    match (km(lo), km(hi)) {
        (Some(lo), Some(hi)) if lo < hi => Ok((lo, hi)),
        _ => Err(reason()),
    }
}

/// Largest `quicklook --mask-snr`.
pub const MAX_MASK_SNR: f64 = 1.0e6;

/// `quicklook --mask-snr X`: a number from 0 to [`MAX_MASK_SNR`].
pub fn mask_snr(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(x) if (0.0..=MAX_MASK_SNR).contains(&x) => Ok(x),
        _ => Err(format!(
            "must be an S/N from 0 to {} (e.g. 3)",
            compact(MAX_MASK_SNR)
        )),
    }
}

/// `quicklook --x-axis AXIS`: one of [`crate::figures::quicklook::XAxis::NAMES`].
pub fn x_axis(s: &str) -> Result<crate::figures::quicklook::XAxis, String> {
    use crate::figures::quicklook::XAxis;
    XAxis::parse(s).ok_or_else(|| format!("must be one of {}", XAxis::NAMES.join(", ")))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_accept_integers_and_scientific_notation_in_range() {
        assert_eq!(profiles("1e6"), Ok(1_000_000));
        assert_eq!(profiles("20"), Ok(20));
        for bad in ["-1", "0", "1.5", "abc", "1e13", "nan", "inf", ""] {
            assert!(profiles(bad).is_err(), "{bad}");
        }
        assert!(threads("100000").is_err());
        for bad in ["0", "65", "-1", "1e3", "x"] {
            let e = word_bits(bad).unwrap_err();
            assert!(e.contains("from 1 to 64"), "{bad}: {e}");
        }
        assert_eq!(word_bits("64"), Ok(64));
        assert_eq!(word_bits("1"), Ok(1));
        assert_eq!(threads("2"), Ok(2));
    }

    #[test]
    fn tolerance_is_refused_outside_its_range() {
        for bad in ["NaN", "-1", "0", "inf", "2", "0.02"] {
            let e = tolerance(bad).unwrap_err();
            assert!(e.contains("0.01"), "{bad}: {e}");
        }
        assert_eq!(tolerance("1e-3"), Ok(1e-3));
    }

    #[test]
    fn seeds_are_whole_numbers() {
        assert!(seed("-1").is_err());
        assert!(seed("1000000000000000000000000000000").is_err());
        assert_eq!(seed("18446744073709551615"), Ok(u64::MAX));
    }
}
