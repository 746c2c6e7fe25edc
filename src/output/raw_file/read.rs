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

use super::{
    BIN_DIM, CHANNEL_DIM, COLUMN_DIM, COMPONENT_NAMES, FORMAT_VERSION, PROFILE_COLUMN_NAMES,
    PROFILE_DIM, SLOT_DIM,
};
use crate::error::{Error, Result};
use crate::resources::{human_bytes, require_memory};

/// The largest compression ratio of deflate (zlib): a run of 258 bytes in a 1-bit literal
/// flag and a 1-bit distance at best, 1032:1 (RFC 1951; zlib's technical details). No
/// dataset stored with shuffle and deflate can hold more bytes than this times its
/// stored bytes.
pub const MAX_DEFLATE_RATIO: u64 = 1032;
/// Bytes a dataset may declare beyond [`MAX_DEFLATE_RATIO`] times its stored bytes
/// (headers and small variables stored compactly).
pub const STORAGE_SLACK_BYTES: u64 = 1 << 16;
/// Values of a per-profile variable read at once while checking them.
pub const SCAN_BLOCK: usize = 1 << 16;

/// The header of a raw file that [`check`] accepted.
#[derive(Debug, Clone)]
pub struct RawHeader {
    /// Length of the `profile` dimension, at least 1.
    pub n_profiles: usize,
    /// Channel names (the `channel` coordinate), at least one.
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

/// The type of a dataset's values, as far as the layout cares.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Class {
    Unsigned,
    Signed,
    Float,
    Text,
    Other,
}

impl Class {
    fn of(d: &Dataset) -> (Class, usize) {
        let Some(t) = d.dtype().ok().and_then(|t| t.to_descriptor().ok()) else {
            return (Class::Other, 0);
        };
        let size = t.size();
        let class = match t {
            TypeDescriptor::Unsigned(_) => Class::Unsigned,
            TypeDescriptor::Integer(_) => Class::Signed,
            TypeDescriptor::Float(_) => Class::Float,
            TypeDescriptor::VarLenUnicode
            | TypeDescriptor::VarLenAscii
            | TypeDescriptor::FixedAscii(_)
            | TypeDescriptor::FixedUnicode(_) => Class::Text,
            _ => Class::Other,
        };
        (class, size)
    }

    fn name(self) -> &'static str {
        match self {
            Class::Unsigned => "unsigned integers",
            Class::Signed => "signed integers",
            Class::Float => "floating-point numbers",
            Class::Text => "strings",
            Class::Other => "another type",
        }
    }
}

/// A dimension of the layout.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Dim {
    P,
    C,
    B,
    /// The scene's distinct columns (format 3), the length of `column`.
    Col,
    /// A profile's column slots (format 3), the length of `k`.
    K,
}

/// What [`check`] asks of a value of a variable.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Values {
    /// Nothing beyond its type.
    Any,
    /// Finite.
    Finite,
    /// Finite and ≥ 0.
    NonNegative,
    /// ≥ 1 (an unsigned count).
    AtLeastOne,
}

/// A variable of the layout: name, dimensions, type, whether every file has it, and
/// what its values must be.
struct Known {
    name: &'static str,
    dims: &'static [Dim],
    class: Class,
    required: bool,
    values: Values,
}

const fn known(
    name: &'static str,
    dims: &'static [Dim],
    class: Class,
    required: bool,
    values: Values,
) -> Known {
    Known {
        name,
        dims,
        class,
        required,
        values,
    }
}

/// A string variable of the channel dimension (format 3).
const fn channel_text(name: &'static str) -> Known {
    known(name, &[Dim::C], Class::Text, false, Values::Any)
}

/// The variables of the layout [`check`] knows by name (docs/file-format.md).
const KNOWN: [Known; 27] = [
    known(COLUMN_DIM, &[Dim::Col], Class::Signed, false, Values::Any),
    known(SLOT_DIM, &[Dim::K], Class::Signed, false, Values::Any),
    known(
        PROFILE_COLUMN_NAMES[0],
        &[Dim::P, Dim::K],
        Class::Signed,
        false,
        Values::Any,
    ),
    known(
        PROFILE_COLUMN_NAMES[1],
        &[Dim::P, Dim::K],
        Class::Float,
        false,
        Values::Any,
    ),
    channel_text("channel_kind"),
    channel_text("channel_species"),
    channel_text("polarization"),
    channel_text("detection_mode"),
    channel_text("acquisition_mode"),
    channel_text("glue_partner"),
    channel_text("dead_time_model"),
    channel_text("molecular_line"),
    known(
        "counts",
        &[Dim::P, Dim::C, Dim::B],
        Class::Unsigned,
        true,
        Values::Any,
    ),
    known(
        COMPONENT_NAMES[0],
        &[Dim::P, Dim::C, Dim::B],
        Class::Unsigned,
        false,
        Values::Any,
    ),
    known(
        COMPONENT_NAMES[1],
        &[Dim::P, Dim::C, Dim::B],
        Class::Unsigned,
        false,
        Values::Any,
    ),
    known(
        COMPONENT_NAMES[2],
        &[Dim::P, Dim::C, Dim::B],
        Class::Unsigned,
        false,
        Values::Any,
    ),
    known(CHANNEL_DIM, &[Dim::C], Class::Text, true, Values::Any),
    known(PROFILE_DIM, &[Dim::P], Class::Signed, false, Values::Any),
    known(BIN_DIM, &[Dim::B], Class::Signed, false, Values::Any),
    known("time", &[Dim::P], Class::Float, true, Values::Finite),
    known(
        "n_shots",
        &[Dim::P],
        Class::Unsigned,
        true,
        Values::AtLeastOne,
    ),
    known(
        "pulse_energy",
        &[Dim::P],
        Class::Float,
        true,
        Values::NonNegative,
    ),
    known("latitude", &[Dim::P], Class::Float, false, Values::Finite),
    known("longitude", &[Dim::P], Class::Float, false, Values::Finite),
    known(
        "along_track_distance",
        &[Dim::P],
        Class::Float,
        false,
        Values::Finite,
    ),
    known("altitude", &[Dim::B], Class::Float, true, Values::Finite),
    known("range", &[Dim::B], Class::Float, true, Values::Finite),
];

/// The shapes any other dataset of a raw file may have.
const OTHER_SHAPES: [&[Dim]; 7] = [
    &[Dim::P],
    &[Dim::C],
    &[Dim::B],
    &[Dim::C, Dim::B],
    &[Dim::P, Dim::C, Dim::B],
    &[Dim::Col, Dim::B],
    &[Dim::Col, Dim::C, Dim::B],
];

pub use crate::error::shape_text;

fn dims_name(dims: &[Dim]) -> String {
    let names: Vec<&str> = dims
        .iter()
        .map(|d| match d {
            Dim::P => PROFILE_DIM,
            Dim::C => CHANNEL_DIM,
            Dim::B => BIN_DIM,
            Dim::Col => COLUMN_DIM,
            Dim::K => SLOT_DIM,
        })
        .collect();
    format!("({})", names.join(", "))
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
    for d in &datasets {
        let name = d.name();
        let name = name.trim_start_matches('/');
        check_storage(path, name, d)?;
        let shape = d.shape();
        let (class, _) = Class::of(d);
        let want: Vec<&[Dim]> = match KNOWN.iter().find(|k| k.name == name) {
            Some(k) => {
                if class != k.class {
                    return Err(bad(format!(
                        "`{name}` holds {}, not {}",
                        class.name(),
                        k.class.name()
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

/// The `channel` coordinate's names.
fn read_channels(path: &Path, f: &hdf5::File) -> Result<Vec<String>> {
    read_text(path, f, CHANNEL_DIM)
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

/// Checks the values of variable `name` (dataset `d`), [`SCAN_BLOCK`] at a time.
fn scan(path: &Path, name: &str, values: Values, d: &Dataset) -> Result<()> {
    let n = d.shape().first().copied().unwrap_or(0);
    let unreadable = |e: hdf5::Error| {
        Error::output(
            path,
            format!(
                "cannot read `{}`: {}",
                name,
                crate::error::describe_hdf5_error(&e.to_string())
            ),
        )
    };
    for a in (0..n).step_by(SCAN_BLOCK) {
        let b = (a + SCAN_BLOCK).min(n);
        let bad_at = |i: usize, v: String, want: &str| {
            Error::output(path, format!("`{}` value {} is {v}; {want}", name, a + i))
        };
        match values {
            Values::Any => {}
            Values::AtLeastOne => {
                let v = d.read_slice::<u64, _, Ix1>(s![a..b]).map_err(unreadable)?;
                if let Some(i) = v.iter().position(|&x| x < 1) {
                    return Err(bad_at(
                        i,
                        v[i].to_string(),
                        "every profile accumulates at least one shot",
                    ));
                }
            }
            Values::Finite | Values::NonNegative if d.ndim() == 2 => {
                let v = d
                    .read_slice::<f64, _, ndarray::Ix2>(s![a..b, ..])
                    .map_err(unreadable)?;
                let ok = |x: f64| x.is_finite() && (values == Values::Finite || x >= 0.0);
                if let Some(((i, j), x)) = v.indexed_iter().find(|(_, x)| !ok(**x)) {
                    return Err(Error::output(
                        path,
                        format!(
                            "`{name}` value ({}, {j}) is {x}; it must be finite{}",
                            a + i,
                            if values == Values::Finite {
                                ""
                            } else {
                                " and not negative"
                            }
                        ),
                    ));
                }
            }
            Values::Finite | Values::NonNegative => {
                let v = d.read_slice::<f64, _, Ix1>(s![a..b]).map_err(unreadable)?;
                let ok = |x: f64| x.is_finite() && (values == Values::Finite || x >= 0.0);
                if let Some(i) = v.iter().position(|&x| !ok(x)) {
                    let want = match values {
                        Values::Finite => "it must be finite",
                        _ => "it must be finite and not negative",
                    };
                    return Err(bad_at(i, v[i].to_string(), want));
                }
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(tag: &str) -> std::path::PathBuf {
        let d =
            std::env::temp_dir().join(format!("lidarsim-raw-read-{tag}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    /// A minimal raw file: P profiles, 1 channel, B bins; `edit` changes it before closing.
    fn minimal(path: &Path, p: usize, b: usize, edit: impl FnOnce(&hdf5::File)) {
        let f = hdf5::File::create(path).unwrap();
        f.new_attr::<i32>()
            .create("lidarsim_format_version")
            .unwrap()
            .write_scalar(&FORMAT_VERSION)
            .unwrap();
        let u = |name: &str, shape: &[usize], v: &[u64]| {
            f.new_dataset::<u64>()
                .shape(shape)
                .create(name)
                .unwrap()
                .write_raw(v)
                .unwrap();
        };
        let x = |name: &str, v: &[f64]| {
            f.new_dataset::<f64>()
                .shape(v.len())
                .create(name)
                .unwrap()
                .write_raw(v)
                .unwrap();
        };
        u("counts", &[p, 1, b], &vec![3; p * b]);
        u("n_shots", &[p], &vec![10; p]);
        x("time", &(0..p).map(|i| i as f64).collect::<Vec<_>>());
        f.new_dataset::<f64>()
            .shape([p, 1])
            .create("pulse_energy")
            .unwrap()
            .write_raw(&vec![0.1; p])
            .unwrap();
        x(
            "altitude",
            &(0..b).map(|i| 30.0 * i as f64).collect::<Vec<_>>(),
        );
        x(
            "range",
            &(0..b).map(|i| 30.0 * i as f64).collect::<Vec<_>>(),
        );
        let names = [VarLenUnicode::from_str("532_total").unwrap()];
        f.new_dataset::<VarLenUnicode>()
            .shape(1)
            .create(CHANNEL_DIM)
            .unwrap()
            .write_raw(&names)
            .unwrap();
        edit(&f);
    }

    use std::str::FromStr;

    fn refusal(name: &str, edit: impl FnOnce(&hdf5::File)) -> String {
        let d = scratch(name);
        let path = d.join("raw.h5");
        minimal(&path, 4, 5, edit);
        let f = hdf5::File::open(&path).unwrap();
        let e = check(&path, &f)
            .map(|_| String::new())
            .unwrap_or_else(|e| e.to_string());
        drop(f);
        std::fs::remove_dir_all(&d).ok();
        assert!(!e.contains('\n'), "{e}");
        e
    }

    #[test]
    fn a_consistent_file_is_accepted_with_its_header() {
        let d = scratch("ok");
        let path = d.join("raw.h5");
        minimal(&path, 4, 5, |_| {});
        let f = hdf5::File::open(&path).unwrap();
        let h = check(&path, &f).unwrap();
        assert_eq!((h.n_profiles, h.n_bins, h.count_bytes), (4, 5, 8));
        assert_eq!(h.channels, vec!["532_total".to_string()]);
        assert!(!h.along_track);
        std::fs::remove_dir_all(&d).ok();
    }

    #[test]
    fn inconsistent_or_crafted_headers_are_refused_naming_the_variable() {
        let replace = |f: &hdf5::File, name: &str, v: &[f64]| {
            f.unlink(name).unwrap();
            f.new_dataset::<f64>()
                .shape(v.len())
                .create(name)
                .unwrap()
                .write_raw(v)
                .unwrap();
        };
        let e = refusal("short-time", |f| replace(f, "time", &[0.0, 1.0]));
        assert!(
            e.contains("`time` is 2,") && e.contains("(profile) = 4"),
            "{e}"
        );
        let e = refusal("nan-time", |f| {
            replace(f, "time", &[0.0, f64::NAN, 2.0, 3.0])
        });
        assert!(e.contains("`time` value 1 is NaN"), "{e}");
        let e = refusal("inf-alt", |f| {
            replace(f, "altitude", &[0.0, 1.0, f64::INFINITY, 3.0, 4.0])
        });
        assert!(e.contains("`altitude` value 2 is inf"), "{e}");
        let e = refusal("short-alt", |f| replace(f, "altitude", &[0.0, 1.0]));
        assert!(e.contains("`altitude` is 2,"), "{e}");
        let e = refusal("zero-shots", |f| {
            f.dataset("n_shots")
                .unwrap()
                .write_raw(&[10u64, 0, 10, 10])
                .unwrap()
        });
        assert!(e.contains("`n_shots` value 1 is 0"), "{e}");
        let e = refusal("version", |f| {
            f.attr("lidarsim_format_version")
                .unwrap()
                .write_scalar(&5)
                .unwrap()
        });
        assert!(e.contains("format version 5"), "{e}");
        let e = refusal("float-counts", |f| {
            f.unlink("counts").unwrap();
            f.new_dataset::<f64>()
                .shape([4, 1, 5])
                .create("counts")
                .unwrap()
                .write_raw(&[1.5; 20])
                .unwrap();
        });
        assert!(e.contains("`counts` holds floating-point"), "{e}");
        // 1e12 profiles declared, none stored (chunks never written)
        let e = refusal("huge", |f| {
            for name in ["counts", "n_shots", "time", "pulse_energy"] {
                f.unlink(name).unwrap();
            }
            let p = 1_000_000_000_000usize;
            f.new_dataset::<u16>()
                .chunk([1, 1, 5])
                .shape([p, 1, 5])
                .create("counts")
                .unwrap();
            f.new_dataset::<u64>()
                .chunk(1)
                .shape(p)
                .create("n_shots")
                .unwrap();
        });
        assert!(
            e.contains("`counts` declares") && e.contains("crafted"),
            "{e}"
        );
        let e = refusal("stray", |f| {
            f.new_dataset::<f64>()
                .shape([3, 5])
                .create("expected_signal")
                .unwrap();
        });
        assert!(e.contains("`expected_signal` is 3 × 5,"), "{e}");
    }
}
