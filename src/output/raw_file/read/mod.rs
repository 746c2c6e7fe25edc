//! What a reader of a lidarsim raw file accepts: ONE check of a file's header, used by
//! every command that reads raw files (`merge` of raw shards, `curtain`, `export-scc`,
//! `validate --file`),
//! so that they accept exactly the same files (`docs/file-format.md`, "What a reader
//! accepts").
//!
//! [`check`] looks at the file before anything sized by it is allocated:
//!
//! 1. the root attribute `lidarsim_format_version` is 2 to [`FORMAT_VERSION`] (whose
//!    files have the same counts and coordinates; `pulse_energy` is (profile) before
//!    format 4, [`energy_factors`] reads either);
//! 2. `counts` is (profile, channel, bin) of unsigned integers, no dimension empty;
//! 3. every dataset is stored with the filters lidarsim uses (shuffle, deflate,
//!    Fletcher-32) and holds the values it declares: its declared bytes are at most
//!    [`MAX_DEFLATE_RATIO`] times the bytes stored for it (plus [`STORAGE_SLACK_BYTES`]),
//!    so a file that declares 1e12 profiles it does not hold is refused at once;
//! 4. the variables of the layout have their dimensions and types (`time` (profile)
//!    float, `n_shots` (profile) unsigned, `altitude` (bin) float, the channel's strings,
//!    `profile_column` (profile, k) signed, ...), and every other dataset is (profile),
//!    (channel), (bin), (channel, bin), (profile, channel, bin), (column, bin) or
//!    (column, channel, bin) of floats;
//! 5. the coordinates `time`, `altitude`, `range`, `latitude`, `longitude` and
//!    `along_track_distance` are finite, `pulse_energy` finite and ≥ 0, and every
//!    `n_shots` ≥ 1, read [`SCAN_BLOCK`] values at a time (memory does not grow with
//!    the file).
//!
//! 6. then what its values mean ([`super::integrity`]: the channel's words, the
//!    calibration, every profile's columns, the per-profile floats, the components).
//!
//! Every refusal is one line naming the file and the variable or attribute.

use std::path::Path;

use hdf5::Dataset;
use hdf5::filters::Filter;
use hdf5::types::{TypeDescriptor, VarLenAscii, VarLenUnicode};
use ndarray::{Ix1, s};

use super::spec::{CHANNEL_DIM, COLUMN_DIM, FORMAT_VERSION, SLOT_DIM};
use crate::error::{Error, Result};

mod known;

pub use crate::error::shape_text;

use crate::resources::{human_bytes, require_memory};
use known::{Class, Dim, KNOWN, Known, OTHER_SHAPES, Values, dims_name, scan};

/// The largest compression ratio of deflate (zlib): a run of 258 bytes in a 1-bit literal
/// flag and a 1-bit distance at best, 1032:1 (RFC 1951; zlib's technical details). No
/// dataset stored with shuffle and deflate can hold more bytes than this times its
/// stored bytes.
pub const MAX_DEFLATE_RATIO: u64 = 1032;
/// Bytes a dataset may declare beyond [`MAX_DEFLATE_RATIO`] times its stored bytes
/// (headers and small variables stored compactly).
pub const STORAGE_SLACK_BYTES: u64 = 1 << 16;
pub use known::SCAN_BLOCK;

/// The header of a raw file that [`check`] accepted.
#[derive(Debug, Clone)]
pub struct RawHeader {
    /// Length of the `profile` dimension, at least 1.
    pub n_profiles: usize,
    /// Channel names (`channel_name`, or the `channel` coordinate before format 5), at
    /// least one.
    pub channels: Vec<String>,
    /// Length of the `bin` dimension, at least 1.
    pub n_bins: usize,
    /// Bytes per stored count (2, 4 or 8; 1 for a uint8 file).
    pub count_bytes: usize,
    /// Whether the file has `along_track_distance` (an orbit).
    pub along_track: bool,
    /// Its `lidarsim_format_version`, 2 to [`FORMAT_VERSION`].
    pub format_version: i64,
}

impl RawHeader {
    /// Counts per profile: channels × bins.
    pub fn counts_per_profile(&self) -> usize {
        self.channels.len() * self.n_bins
    }

    /// Refuses, naming the file, a reading of it that needs `bytes` of memory (`what`,
    /// e.g. "the curtain") where that much is not available.
    pub fn require_memory(&self, path: &Path, what: &str, bytes: f64) -> Result<()> {
        require_memory(&format!("{}: {what}", path.display()), bytes)
    }
}

/// Checks the raw file `f` (opened from `path`) as every reader of raw files accepts it
/// (module doc), before anything sized by it is allocated; its header, or one line
/// naming the file and what is wrong.
pub fn check(path: &Path, f: &hdf5::File) -> Result<RawHeader> {
    let bad = |why: String| Error::output(path, why);
    let version = check_version(path, f)?;
    let counts = f
        .dataset("counts")
        .map_err(|_| bad("has no `counts`: not a lidarsim raw file".into()))?;
    let shape = counts.shape();
    let [n_profiles, n_channels, n_bins] = shape[..] else {
        return Err(bad(format!(
            "`counts` has {} dimensions, not 3 (profile, channel, bin)",
            shape.len()
        )));
    };
    let (class, count_bytes) = Class::of(&counts);
    if class != Class::Unsigned {
        return Err(bad(format!(
            "`counts` holds {}; counts are unsigned integers (uint16, uint32 or uint64)",
            class.name()
        )));
    }
    if n_profiles == 0 || n_channels == 0 || n_bins == 0 {
        return Err(bad(format!(
            "`counts` is empty ({n_profiles} profiles × {n_channels} channels × {n_bins} bins)"
        )));
    }
    // the format-3 dimensions: the lengths of their 1-D coordinates (none without them)
    let coordinate_len = |name: &str| match f.dataset(name).map(|d| d.shape()) {
        Ok(shape) if shape.len() == 1 => shape[0],
        _ => usize::MAX,
    };
    let (n_columns, n_slots) = (coordinate_len(COLUMN_DIM), coordinate_len(SLOT_DIM));
    let len = |d: Dim| match d {
        Dim::P => n_profiles,
        Dim::C => n_channels,
        Dim::B => n_bins,
        Dim::Col => n_columns,
        Dim::K => n_slots,
    };
    let datasets = f
        .datasets()
        .map_err(|_| bad("cannot list its variables".into()))?;
    // every variable holds what it declares before any is compared with another, so
    // that a crafted length is named where it is (a huge `column`, not the first
    // variable on that dimension)
    for d in &datasets {
        check_storage(path, d.name().trim_start_matches('/'), d)?;
    }
    for d in &datasets {
        let name = d.name();
        let name = name.trim_start_matches('/');
        let shape = d.shape();
        let (class, _) = Class::of(d);
        let want: Vec<&[Dim]> = match KNOWN.iter().find(|k| k.name == name) {
            Some(k) => {
                let want = match k.name == CHANNEL_DIM && version >= 5 {
                    true => Class::Signed, // format 5 numbers the channels
                    false => k.class,
                };
                if class != want {
                    return Err(bad(format!(
                        "`{name}` holds {}, not {}",
                        class.name(),
                        want.name()
                    )));
                }
                vec![dims_in(k, version)]
            }
            None => {
                if class != Class::Float {
                    return Err(bad(format!(
                        "`{name}` holds {}, not floating-point numbers",
                        class.name()
                    )));
                }
                OTHER_SHAPES.to_vec()
            }
        };
        let fits = |dims: &&[Dim]| {
            dims.len() == shape.len() && dims.iter().zip(&shape).all(|(&d, &n)| len(d) == n)
        };
        if !want.iter().any(fits) {
            if let Some(why) = coordinate_disagrees(name, &shape, &want, len) {
                return Err(bad(why));
            }
            let expected: Vec<String> = want
                .iter()
                .filter(|dims| dims.iter().all(|&d| len(d) != usize::MAX))
                .map(|dims| {
                    let lens: Vec<String> = dims.iter().map(|&d| len(d).to_string()).collect();
                    format!("{} = {}", dims_name(dims), lens.join(" × "))
                })
                .collect();
            return Err(bad(format!(
                "`{name}` is {}, but `counts` (profile, channel, bin) = \
                 {n_profiles} × {n_channels} × {n_bins} makes it {}",
                shape_text(&shape),
                expected.join(" or ")
            )));
        }
    }
    for k in KNOWN.iter().filter(|k| k.required) {
        if f.dataset(k.name).is_err() {
            return Err(bad(format!(
                "has no `{}`: not a lidarsim raw file of format {FORMAT_VERSION}",
                k.name
            )));
        }
    }
    // the channel names: a few bytes each, bounded by what the file stores
    require_memory(
        &format!("{}: reading its channel names", path.display()),
        n_channels as f64 * 256.0,
    )?;
    let channels = read_channels(path, f)?;
    for k in KNOWN.iter().filter(|k| k.values != Values::Any) {
        if let Ok(d) = f.dataset(k.name) {
            scan(path, k.name, k.values, &d)?;
        }
    }
    let header = RawHeader {
        n_profiles,
        channels,
        n_bins,
        count_bytes,
        along_track: f.dataset("along_track_distance").is_ok(),
        format_version: version,
    };
    super::integrity::check_raw(path, f, &header)?;
    Ok(header)
}

/// When variable `name` of `shape` fits one of its dimension lists `want` but for the
/// length of one `column` or `k` that the file has, the sentence that names that
/// coordinate: the variable and the coordinate disagree, and the coordinate is what
/// defines the dimension. (A file without the coordinate is refused as before.)
fn coordinate_disagrees(
    name: &str,
    shape: &[usize],
    want: &[&[Dim]],
    len: impl Fn(Dim) -> usize,
) -> Option<String> {
    let differs = |dims: &[Dim]| -> Vec<(Dim, usize)> {
        dims.iter()
            .zip(shape)
            .filter(|&(&d, &n)| len(d) != n)
            .map(|(&d, &n)| (d, n))
            .collect()
    };
    want.iter()
        .filter(|dims| dims.len() == shape.len())
        .find_map(|dims| match differs(dims)[..] {
            [(d @ (Dim::Col | Dim::K), n)] if len(d) != usize::MAX => {
                let coordinate = if d == Dim::Col { COLUMN_DIM } else { SLOT_DIM };
                Some(format!(
                    "`{name}` is {} {}: its {n} along `{coordinate}` disagree with the \
                     coordinate `{coordinate}`, which has {}",
                    shape_text(shape),
                    dims_name(dims),
                    len(d)
                ))
            }
            _ => None,
        })
}

/// The dimensions of known variable `k` in a file of format `version`: `pulse_energy` is
/// (profile, channel) from format 4 on, one energy per channel's laser line; (profile),
/// the first channel's, before.
fn dims_in(k: &Known, version: i64) -> &'static [Dim] {
    if k.name == "pulse_energy" && version >= 4 {
        &[Dim::P, Dim::C]
    } else {
        k.dims
    }
}

/// The energy factors `E/E₀` of profiles `rows` of raw file `f` (accepted by [`check`],
/// header `h`), (profile, channel) row-major: from format 4, `pulse_energy[p, c] /
/// nominal_pulse_energy[c]`; formats 2 and 3 kept one energy per profile, at the first
/// channel's nominal energy, and every channel shares its factor (the shots of one
/// laser), `pulse_energy[p] / nominal_pulse_energy[0]`. `nominal` is the file's
/// `nominal_pulse_energy`; a nominal energy of 0 gives the factor 1 (no pulse, no
/// signal to scale).
pub fn energy_factors(
    path: &Path,
    f: &hdf5::Group,
    h: &RawHeader,
    rows: std::ops::Range<usize>,
    nominal: &[f64],
) -> Result<Vec<f64>> {
    let channels = h.channels.len();
    let d = f
        .dataset("pulse_energy")
        .map_err(|_| Error::output(path, "has no `pulse_energy`"))?;
    let unreadable = |e: hdf5::Error| {
        Error::output(
            path,
            format!(
                "cannot read `pulse_energy`: {}",
                crate::error::describe_hdf5_error(&e.to_string())
            ),
        )
    };
    let ratio = |e: f64, e0: f64| if e0 > 0.0 { e / e0 } else { 1.0 };
    if nominal.len() != channels {
        return Err(Error::output(
            path,
            format!(
                "`nominal_pulse_energy` has {} values for {channels} channels",
                nominal.len()
            ),
        ));
    }
    if h.format_version >= 4 {
        let e = d
            .read_slice::<f64, _, ndarray::Ix2>(s![rows, ..])
            .map_err(unreadable)?;
        Ok(e.outer_iter()
            .flat_map(|row| {
                row.iter()
                    .zip(nominal)
                    .map(|(&e, &e0)| ratio(e, e0))
                    .collect::<Vec<_>>()
            })
            .collect())
    } else {
        let e = d.read_slice::<f64, _, Ix1>(s![rows]).map_err(unreadable)?;
        Ok(e.iter()
            .flat_map(|&e| std::iter::repeat_n(ratio(e, nominal[0]), channels))
            .collect())
    }
}

/// The root attribute `lidarsim_format_version` must be 2 to [`FORMAT_VERSION`]; the
/// version.
fn check_version(path: &Path, f: &hdf5::File) -> Result<i64> {
    let bad = |why: String| Error::output(path, why);
    let attr = f.attr("lidarsim_format_version").map_err(|_| {
        bad("not a lidarsim raw file (no `lidarsim_format_version` attribute)".into())
    })?;
    let integer = attr
        .dtype()
        .ok()
        .and_then(|t| t.to_descriptor().ok())
        .is_some_and(|t| matches!(t, TypeDescriptor::Integer(_) | TypeDescriptor::Unsigned(_)));
    let v = match attr.read_scalar::<i64>() {
        Ok(v) if integer => v,
        _ => {
            return Err(bad(
                "`lidarsim_format_version` is not an integer scalar: not a lidarsim raw file"
                    .into(),
            ));
        }
    };
    if !(2..=i64::from(FORMAT_VERSION)).contains(&v) {
        return Err(bad(format!(
            "lidarsim raw file format version {v}; this lidarsim reads format versions 2 \
             to {FORMAT_VERSION} (re-run `lidarsim simulate` with this version)"
        )));
    }
    Ok(v)
}

/// Whether dataset `d` holds unsigned integers.
pub fn is_unsigned(d: &Dataset) -> bool {
    Class::of(d).0 == Class::Unsigned
}

/// Whether dataset `d` holds floating-point numbers.
pub fn is_float(d: &Dataset) -> bool {
    Class::of(d).0 == Class::Float
}

/// Refuses, naming the file and `name`, a 1-D dataset of floats with a value that is not
/// finite (read [`SCAN_BLOCK`] values at a time).
pub fn check_finite(path: &Path, name: &str, d: &Dataset) -> Result<()> {
    scan(path, name, Values::Finite, d)
}

/// A dataset is stored with lidarsim's filters and holds the bytes it declares.
pub fn check_storage(path: &Path, name: &str, d: &Dataset) -> Result<()> {
    let bad = |why: String| Error::output(path, why);
    if let Some(other) = d
        .filters()
        .into_iter()
        .find(|x| !matches!(x, Filter::Deflate(_) | Filter::Shuffle | Filter::Fletcher32))
    {
        let filter = match other {
            Filter::SZip(..) => "szip",
            Filter::NBit => "n-bit",
            Filter::ScaleOffset(_) => "scale-offset",
            _ => "an unknown",
        };
        return Err(bad(format!(
            "`{name}` is stored with the {filter} filter; lidarsim raw files use only \
             shuffle and deflate"
        )));
    }
    let (_, size) = Class::of(d);
    let declared = d
        .shape()
        .iter()
        .try_fold(size.max(1) as u64, |acc, &n| acc.checked_mul(n as u64));
    let stored = d.storage_size();
    let bound = stored
        .saturating_mul(MAX_DEFLATE_RATIO)
        .saturating_add(STORAGE_SLACK_BYTES);
    match declared {
        Some(bytes) if bytes <= bound => Ok(()),
        _ => Err(bad(format!(
            "`{name}` declares {} values ({}) but the file stores only {} of them, which \
             cannot hold that many: a truncated or crafted file",
            shape_text(&d.shape()),
            declared.map_or("more than 2^64 bytes".into(), |b| human_bytes(b as f64)),
            human_bytes(stored as f64)
        ))),
    }
}

/// The one-line error of variable `name` of the file at `path` that HDF5 could not read.
pub fn unreadable(path: &Path, name: &str, e: hdf5::Error) -> Error {
    Error::output(
        path,
        format!(
            "cannot read `{name}`: {}",
            crate::error::describe_hdf5_error(&e.to_string())
        ),
    )
}

/// The channels' names: `channel_name` beside the numbers `channel` = 0, 1, … (format
/// 5), or the strings of `channel` (formats 2 to 4); checked by
/// [`super::integrity::channel_labels`].
fn read_channels(path: &Path, f: &hdf5::File) -> Result<Vec<String>> {
    let (names, numbers) = super::integrity::channel_labels(path, f, "")?;
    if let Some(n) = numbers
        && let Some(i) = (0..n.len()).find(|&i| n[i] != i as i64)
    {
        return Err(Error::output(
            path,
            format!(
                "`{CHANNEL_DIM}` value {i} is {}, not {i}: a raw file numbers its channels 0, 1, …",
                n[i]
            ),
        ));
    }
    Ok(names)
}

/// A variable of variable-length strings (UTF-8, or ASCII as older tools write them),
/// e.g. `channel` or `dead_time_model`; anything else is refused naming the file and
/// the variable.
pub fn read_text(path: &Path, f: &hdf5::Group, name: &str) -> Result<Vec<String>> {
    let d = f
        .dataset(name)
        .map_err(|_| Error::output(path, format!("has no `{name}`")))?;
    let unreadable = || {
        Error::output(
            path,
            format!("`{name}` is not readable as variable-length strings"),
        )
    };
    if !matches!(Class::of(&d).0, Class::Text) {
        return Err(unreadable());
    }
    if let Ok(v) = d.read_raw::<VarLenUnicode>() {
        return Ok(v.iter().map(|s| s.as_str().to_string()).collect());
    }
    let v = d.read_raw::<VarLenAscii>().map_err(|_| unreadable())?;
    Ok(v.iter().map(|s| s.as_str().to_string()).collect())
}

#[cfg(test)]
mod tests;
