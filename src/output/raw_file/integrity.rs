//! What a file's values must mean before anything is drawn, validated, exported or
//! merged from it: ONE check of a file's integrity, beyond its shapes and types
//! ([`super::read::check`]), that every reader applies — `merge` (raw shards and
//! product shards), `validate --file` (and so Python's `validate_file`), `quicklook`,
//! `curtain` and `export-scc` (`docs/file-format.md`, "What a reader accepts").
//!
//! * the channels' names (`channel_name`, or `channel` before format 5) are not empty
//!   and each given once, the channel numbers (format 5) strictly increasing
//!   ([`channel_labels`]);
//! * the channel's strings are words of their vocabulary ([`CHANNEL_WORDS`]), and a
//!   `glue_partner` is another channel of the file or empty;
//! * the calibration is a number of its sign ([`CALIBRATION`]): `lidar_constant` and
//!   `range_weight` finite and ≥ 0, `nominal_pulse_energy` finite and > 0, and for an
//!   analog channel `analog_counts_per_photoelectron` and `adc_volts_per_count` finite
//!   and > 0 (a reader divides by each);
//! * every profile's `profile_column` and `profile_column_weight` are possible
//!   ([`check_profile_columns`]);
//! * every other per-profile variable of floats is finite, and where the file has the
//!   component counts, signal + background + dark is `counts` (what `merge` checks of
//!   every row it copies).
//!
//! Each refusal is one line naming the file, the variable and the reason; the values are
//! read [`ROWS`] profiles at a time (memory does not grow with the file).

use std::path::Path;

use hdf5::types::TypeDescriptor;
use hdf5::{Dataset, Group};
use ndarray::{Ix1, Ix2, Ix3, s};

use super::read::{RawHeader, is_float, read_text};
use super::spec::{CHANNEL_DIM, CHANNEL_NAME, COMPONENT_NAMES, PROFILE_COLUMN_NAMES};
use crate::error::describe_hdf5_error;
use crate::error::{Error, Result};

/// Profiles whose rows are checked at once (at most 2^20 values of a row variable).
pub const ROWS: usize = 65_536;
/// Values of a (profile, channel, bin) variable read at once.
const VALUES: usize = 1 << 20;
/// How far a profile's column weights may sum from 1 (rounding of the shares of its
/// shots; the writers' sums are within 1e-15).
pub const WEIGHT_SUM_TOLERANCE: f64 = 1e-9;

/// The words each string variable of the channel dimension may hold (the names of the
/// receiver's and detector's kinds, `src/receiver/channel.rs`, `src/config/`): a file
/// whose word no reader knows is refused, not read as a default.
pub const CHANNEL_WORDS: [(&str, &[&str]); 6] = [
    ("channel_kind", &["elastic", "hsrl_molecular", "raman"]),
    ("channel_species", &["", "N2", "H2O"]),
    ("polarization", &["total", "parallel", "perpendicular"]),
    ("detection_mode", &["photon_counting", "analog", "both"]),
    ("acquisition_mode", &["photon_counting", "analog"]),
    (
        "dead_time_model",
        &["none", "nonparalyzable", "paralyzable"],
    ),
];

/// What a calibration value must be: finite, finite and ≥ 0, or finite and > 0.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Sign {
    Finite,
    NonNegative,
    Positive,
}

/// The calibration a reader divides by (or, the analog offset, subtracts), and what
/// each must be; `true`: of analog channels only (NaN in the others). The last two are
/// an onboard product's (its regions' record of photoelectrons, every channel).
const CALIBRATION: [(&str, Sign, bool); 8] = [
    ("lidar_constant", Sign::NonNegative, false),
    ("nominal_pulse_energy", Sign::Positive, false),
    ("range_weight", Sign::NonNegative, false),
    ("analog_counts_per_photoelectron", Sign::Positive, true),
    ("adc_volts_per_count", Sign::Positive, true),
    ("analog_offset", Sign::Finite, true),
    ("counts_per_photoelectron", Sign::Positive, false),
    ("counts_offset", Sign::Finite, false),
];

/// Why a profile's columns and weights are impossible, if they are: every used slot a
/// column of `0..n_columns` seen once, of weight in (0, 1], the unused slots (−1) after
/// them with weight 0, the weights summing to 1 (within [`WEIGHT_SUM_TOLERANCE`]). One
/// rule for the writers (`check::RecordShape`) and every reader.
pub fn check_profile_columns(
    columns: &[i32],
    weights: &[f64],
    n_columns: usize,
) -> std::result::Result<(), String> {
    if columns.len() != weights.len() {
        return Err(format!(
            "{} columns and {} weights",
            columns.len(),
            weights.len()
        ));
    }
    let used = columns.iter().take_while(|&&c| c >= 0).count();
    if used == 0 {
        return Err("slot 0 is unused".into());
    }
    if let Some(j) = (used..columns.len()).find(|&j| columns[j] != -1) {
        return Err(format!(
            "slot {j} holds column {} after an unused slot (−1 marks an unused slot)",
            columns[j]
        ));
    }
    if let Some(j) = (0..used).find(|&j| columns[j] as usize >= n_columns) {
        return Err(format!(
            "slot {j}: column {} is not one of the {n_columns} columns",
            columns[j]
        ));
    }
    if let Some(j) = (1..used).find(|&j| columns[..j].contains(&columns[j])) {
        return Err(format!("slot {j} holds column {} twice", columns[j]));
    }
    if let Some(j) = (0..used).find(|&j| !(weights[j] > 0.0 && weights[j] <= 1.0)) {
        return Err(format!("slot {j}'s weight {} is not in (0, 1]", weights[j]));
    }
    if let Some(j) = (used..columns.len()).find(|&j| weights[j] != 0.0) {
        return Err(format!("slot {j} is unused but weighs {}", weights[j]));
    }
    let sum: f64 = weights.iter().sum();
    if (sum - 1.0).abs() > WEIGHT_SUM_TOLERANCE {
        return Err(format!("the weights sum to {sum}, not 1"));
    }
    Ok(())
}

/// A failure reading `name` of `path`, in one line.
fn unreadable<'a>(path: &'a Path, name: &'a str) -> impl Fn(hdf5::Error) -> Error + 'a {
    move |e| {
        Error::output(
            path,
            format!(
                "cannot read `{name}`: {}",
                describe_hdf5_error(&e.to_string())
            ),
        )
    }
}

/// Refuses the profiles of `(columns, weights)` (datasets `profile_column` and
/// `profile_column_weight` of `rows` × slots, `prefix` the group's name and a `/`, or
/// empty) whose columns are impossible, naming the profile.
pub fn check_column_rows(
    path: &Path,
    prefix: &str,
    columns: &Dataset,
    weights: &Dataset,
    n_columns: usize,
) -> Result<()> {
    let rows = columns.shape().first().copied().unwrap_or(0);
    let [c_name, w_name] = PROFILE_COLUMN_NAMES.map(|n| format!("{prefix}{n}"));
    for start in (0..rows).step_by(ROWS) {
        let end = (start + ROWS).min(rows);
        let c = columns
            .read_slice::<i32, _, Ix2>(s![start..end, ..])
            .map_err(unreadable(path, &c_name))?;
        let w = weights
            .read_slice::<f64, _, Ix2>(s![start..end, ..])
            .map_err(unreadable(path, &w_name))?;
        for (i, (c, w)) in c.outer_iter().zip(w.outer_iter()).enumerate() {
            let (c, w) = (c.to_vec(), w.to_vec());
            if let Err(why) = check_profile_columns(&c, &w, n_columns) {
                return Err(Error::output(
                    path,
                    format!(
                        "profile row {}: `{c_name}` {c:?} with `{w_name}` {w:?}: {why}",
                        start + i
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// The channels' names of group `g` (a raw file's root, `prefix` empty, or a product's
/// region, `prefix` its name and a `/`) and their numbers: `channel` whole numbers ≥ 0,
/// strictly increasing, labelled by the strings of `channel_name` (format 5 raw files
/// and this version's products), or the strings of `channel` (earlier files: no
/// numbers). Refuses numbers without `channel_name`, a `channel_name` of another length
/// or not strings, and a name empty or given twice.
pub fn channel_labels(
    path: &Path,
    g: &Group,
    prefix: &str,
) -> Result<(Vec<String>, Option<Vec<i64>>)> {
    let bad = |why: String| Error::output(path, why);
    let d = g
        .dataset(CHANNEL_DIM)
        .map_err(|_| bad(format!("has no `{prefix}{CHANNEL_DIM}`")))?;
    let integer = d
        .dtype()
        .and_then(|t| t.to_descriptor())
        .is_ok_and(|t| matches!(t, TypeDescriptor::Integer(_) | TypeDescriptor::Unsigned(_)));
    let (label, names, numbers) = if integer {
        let full = format!("{prefix}{CHANNEL_DIM}");
        let numbers = d.read_raw::<i64>().map_err(unreadable(path, &full))?;
        let wrong =
            (0..numbers.len()).find(|&i| numbers[i] < 0 || i > 0 && numbers[i] <= numbers[i - 1]);
        if let Some(i) = wrong {
            return Err(bad(format!(
                "`{full}` value {i} is {}; the channel numbers are whole numbers ≥ 0, \
                 strictly increasing",
                numbers[i]
            )));
        }
        if !g.link_exists(CHANNEL_NAME) {
            return Err(bad(format!(
                "has no `{prefix}{CHANNEL_NAME}`: its numbered channels have no names"
            )));
        }
        let names = read_text(path, g, CHANNEL_NAME)?;
        if names.len() != numbers.len() {
            return Err(bad(format!(
                "`{prefix}{CHANNEL_NAME}` holds {} names for the {} channels of `{full}`",
                names.len(),
                numbers.len()
            )));
        }
        (CHANNEL_NAME, names, Some(numbers))
    } else {
        (CHANNEL_DIM, read_text(path, g, CHANNEL_DIM)?, None)
    };
    let mut seen = std::collections::HashSet::new();
    for (i, name) in names.iter().enumerate() {
        if name.is_empty() || !seen.insert(name) {
            let why = if name.is_empty() {
                "empty"
            } else {
                "given twice"
            };
            return Err(bad(format!(
                "`{prefix}{label}` value {i} ({name:?}) is {why}; each channel has a name of its own"
            )));
        }
    }
    Ok((names, numbers))
}

/// Refuses a channel string of `g` (raw file's root) outside [`CHANNEL_WORDS`], and a
/// `glue_partner` that is not another of `channels` (or empty).
pub fn check_channel_words(path: &Path, g: &Group, channels: &[String]) -> Result<()> {
    let bad = |name: &str, k: usize, word: &str, why: String| {
        Error::output(
            path,
            format!(
                "`{name}` of channel {} is {word:?}; {why}",
                channels.get(k).map_or("?", String::as_str)
            ),
        )
    };
    for (name, words) in CHANNEL_WORDS {
        if !g.link_exists(name) {
            continue;
        }
        for (k, word) in read_text(path, g, name)?.iter().enumerate() {
            if !words.contains(&word.as_str()) {
                let list: Vec<String> = words.iter().map(|w| format!("{w:?}")).collect();
                return Err(bad(name, k, word, format!("expected {}", list.join(", "))));
            }
        }
    }
    if g.link_exists("glue_partner") {
        for (k, partner) in read_text(path, g, "glue_partner")?.iter().enumerate() {
            let other = channels
                .iter()
                .enumerate()
                .any(|(j, c)| j != k && c == partner);
            if !(partner.is_empty() || other) {
                let why = "a glue partner is another channel of the file, or empty";
                return Err(bad("glue_partner", k, partner, why.into()));
            }
        }
    }
    Ok(())
}

/// Refuses a calibration value of group `g` (`prefix`: its name and a `/`, or empty)
/// that is not a number of its sign ([`CALIBRATION`]); `analog` says which channels
/// record analog codes (their chain's values must be given).
pub fn check_calibration(
    path: &Path,
    g: &Group,
    prefix: &str,
    channels: &[String],
    analog: &[bool],
) -> Result<()> {
    for (name, sign, analog_only) in CALIBRATION {
        let Ok(d) = g.dataset(name) else {
            continue;
        };
        let full = format!("{prefix}{name}");
        let v = d.read_raw::<f64>().map_err(unreadable(path, &full))?;
        let per_channel = name != "range_weight";
        for (i, &x) in v.iter().enumerate() {
            if analog_only && !analog.get(i).copied().unwrap_or(false) {
                continue;
            }
            let ok = x.is_finite()
                && match sign {
                    Sign::Finite => true,
                    Sign::NonNegative => x >= 0.0,
                    Sign::Positive => x > 0.0,
                };
            if !ok {
                let at = match per_channel {
                    true => format!("of channel {}", channels.get(i).map_or("?", String::as_str)),
                    false => format!("of bin {i}"),
                };
                let want = match sign {
                    Sign::Finite => "finite",
                    Sign::NonNegative => "finite and not negative",
                    Sign::Positive => "finite and positive",
                };
                return Err(Error::output(
                    path,
                    format!("`{full}` {at} is {x}; a reader calibrates with it: it must be {want}"),
                ));
            }
        }
    }
    Ok(())
}

/// Whether each channel of `g` records analog codes (`acquisition_mode`, checked).
pub fn analog_channels(path: &Path, g: &Group, n_channels: usize) -> Result<Vec<bool>> {
    if !g.link_exists("acquisition_mode") {
        return Ok(vec![false; n_channels]);
    }
    Ok(read_text(path, g, "acquisition_mode")?
        .iter()
        .map(|m| m == "analog")
        .collect())
}

/// The integrity of raw file `f` whose header [`super::read::check`] accepted (module
/// doc): its words, its calibration, its profiles' columns, its per-profile floats
/// finite and its components summing to its counts.
pub fn check_raw(path: &Path, f: &hdf5::File, h: &RawHeader) -> Result<()> {
    check_channel_words(path, f, &h.channels)?;
    let analog = analog_channels(path, f, h.channels.len())?;
    check_calibration(path, f, "", &h.channels, &analog)?;
    let n_columns = f
        .dataset(super::spec::COLUMN_DIM)
        .map(|d| d.shape().first().copied().unwrap_or(0))
        .unwrap_or(0);
    if let (Ok(c), Ok(w)) = (
        f.dataset(PROFILE_COLUMN_NAMES[0]),
        f.dataset(PROFILE_COLUMN_NAMES[1]),
    ) {
        check_column_rows(path, "", &c, &w, n_columns)?;
    }
    let datasets = f
        .datasets()
        .map_err(|_| Error::output(path, "cannot list its variables"))?;
    for d in datasets {
        if is_per_profile(&d, h.n_profiles, n_columns) && is_float(&d) {
            check_finite_rows(path, d.name().trim_start_matches('/'), &d)?;
        }
    }
    if COMPONENT_NAMES.iter().all(|n| f.link_exists(n)) {
        check_components(path, f, h)?;
    }
    Ok(())
}

/// Whether `d` is a (profile, …) variable of two or more dimensions: its first length is
/// the profiles' and not the columns' (where both are equal, its `coordinates` name
/// `time`, as lidarsim writes every (profile, …) variable's; a (column, …) one's may
/// hold NaN, the `_FillValue` of `pressure`). `profile_column_weight` is checked by
/// [`check_column_rows`].
fn is_per_profile(d: &Dataset, n_profiles: usize, n_columns: usize) -> bool {
    if d.ndim() < 2 || d.shape()[0] != n_profiles || d.name() == "/profile_column_weight" {
        return false;
    }
    n_profiles != n_columns
        || d.attr("coordinates")
            .and_then(|a| a.read_scalar::<hdf5::types::VarLenUnicode>())
            .is_ok_and(|c| c.as_str().split(' ').any(|w| w == "time"))
}

/// Refuses a (profile, …) variable of floats with a value that is not finite.
fn check_finite_rows(path: &Path, name: &str, d: &Dataset) -> Result<()> {
    let shape = d.shape();
    let row: usize = shape[1..].iter().product::<usize>().max(1);
    let step = (VALUES / row).max(1);
    for start in (0..shape[0]).step_by(step) {
        let end = (start + step).min(shape[0]);
        let bad = match shape.len() {
            2 => d
                .read_slice::<f64, _, Ix2>(s![start..end, ..])
                .map(|v| v.iter().position(|x| !x.is_finite())),
            _ => d
                .read_slice::<f64, _, Ix3>(s![start..end, .., ..])
                .map(|v| v.iter().position(|x| !x.is_finite())),
        }
        .map_err(unreadable(path, name))?;
        if let Some(i) = bad {
            return Err(Error::output(
                path,
                format!(
                    "`{name}` of profile {} is not finite; every per-profile value is a number",
                    start + i / row
                ),
            ));
        }
    }
    Ok(())
}

/// Refuses a file whose `signal_counts + background_counts + dark_counts` is not its
/// `counts` somewhere.
fn check_components(path: &Path, f: &hdf5::File, h: &RawHeader) -> Result<()> {
    let row = h.counts_per_profile().max(1);
    let step = (VALUES / row).max(1);
    let get = |name: &str| {
        f.dataset(name)
            .map_err(|_| Error::output(path, format!("has no `{name}`")))
    };
    let read = |d: &Dataset, name: &str, a: usize, b: usize| -> Result<Vec<u64>> {
        Ok(d.read_slice::<u64, _, Ix3>(s![a..b, .., ..])
            .map_err(unreadable(path, name))?
            .into_raw_vec())
    };
    let counts = get("counts")?;
    let parts = COMPONENT_NAMES.map(get);
    for start in (0..h.n_profiles).step_by(step) {
        let end = (start + step).min(h.n_profiles);
        let total = read(&counts, "counts", start, end)?;
        let mut sum = vec![0u64; total.len()];
        for (name, d) in COMPONENT_NAMES.iter().zip(&parts) {
            let d = d.as_ref().map_err(|e| Error::output(path, e.to_string()))?;
            for (s, v) in sum.iter_mut().zip(read(d, name, start, end)?) {
                *s = s.saturating_add(v);
            }
        }
        if let Some(i) = sum.iter().zip(&total).position(|(s, t)| s != t) {
            return Err(Error::output(
                path,
                format!(
                    "profile {}, channel {}, bin {}: signal + background + dark counts are {}, \
                     `counts` {}; the components sum to the counts",
                    start + i / row,
                    h.channels[i % row / h.n_bins],
                    i % h.n_bins,
                    sum[i],
                    total[i]
                ),
            ));
        }
    }
    Ok(())
}

/// A 1-D unsigned dataset's values are all ≥ 1 (`n_shots`), read [`ROWS`] at a time.
pub fn check_at_least_one(path: &Path, name: &str, d: &Dataset) -> Result<()> {
    let n = d.shape().first().copied().unwrap_or(0);
    for start in (0..n).step_by(ROWS) {
        let end = (start + ROWS).min(n);
        let v = d
            .read_slice::<u64, _, Ix1>(s![start..end])
            .map_err(unreadable(path, name))?;
        if let Some(i) = v.iter().position(|&x| x < 1) {
            return Err(Error::output(
                path,
                format!(
                    "`{name}` value {} is {}; every profile accumulates at least one shot",
                    start + i,
                    v[i]
                ),
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::check_profile_columns as check;

    #[test]
    fn impossible_profile_columns_are_told_apart() {
        assert!(check(&[1, 0, -1], &[0.25, 0.75, 0.0], 2).is_ok());
        assert!(check(&[0], &[1.0], 1).is_ok());
        let why = |c: &[i32], w: &[f64]| check(c, w, 2).unwrap_err();
        assert!(why(&[-1, 0], &[0.0, 1.0]).contains("slot 0 is unused"));
        assert!(why(&[0, -1, 1], &[0.5, 0.0, 0.5]).contains("slot 2 holds column 1 after"));
        assert!(why(&[0, 2], &[0.5, 0.5]).contains("slot 1: column 2 is not one of the 2"));
        assert!(why(&[1, 1], &[0.5, 0.5]).contains("slot 1 holds column 1 twice"));
        assert!(why(&[0, 1], &[0.0, 1.0]).contains("slot 0's weight 0 is not in (0, 1]"));
        assert!(why(&[0, -1], &[1.0, 0.5]).contains("slot 1 is unused but weighs 0.5"));
        assert!(why(&[0, 1], &[0.5, 0.6]).contains("sum to 1.1"));
        assert!(why(&[0, 1], &[0.5, f64::NAN]).contains("slot 1's weight NaN"));
        assert!(why(&[0], &[1.0, 0.0]).contains("1 columns and 2 weights"));
    }
}
