//! The raw lidar file: HDF5, readable as netCDF-4 (see `interface.md`, "Raw lidar file").
//!
//! [`RawFileWriter`] streams one profile at a time into a file laid out as
//!
//! | name | dims | type |
//! |---|---|---|
//! | `profile` | (profile) | i64 coordinate `0..n_profiles`, dimension scale |
//! | `bin` | (bin) | i64 coordinate `0..n_bins`, dimension scale |
//! | `counts` | (profile, bin) | u16 / u32 / u64 ([`CountWidth`]), chunked, shuffle + deflate |
//! | `signal_counts`, `background_counts`, `dark_counts` | (profile, bin) | as `counts`, only with [`RawFileSpec::components`] |
//! | `time` | (profile) | f64, s |
//! | `n_shots` | (profile) | u64 |
//! | one per [`BinVariable`] | (bin) | f64 |
//!
//! Every variable carries CF `long_name` and `units`, and every variable other than the
//! two scales has the `profile`/`bin` dimension scales attached, so netCDF-4 readers
//! (`ncdump`, xarray with h5netcdf or netCDF4) see named dimensions. String attributes
//! are fixed-length, NUL-terminated UTF-8 strings (netCDF `NC_CHAR`), which h5py,
//! h5netcdf/xarray and the netCDF-C library all read. The file uses the HDF5 1.8 file
//! format (`libver_bounds(V18, V18)`), readable by every HDF5 since 1.8 and so by any
//! netCDF-4 build.
//!
//! The file is complete or absent: it is written under a temporary name in the
//! destination directory (`.NAME.partial-PID-SEQ`) and renamed over the final path by
//! [`RawFileWriter::finish`] only once every profile has been written, flushed, closed
//! and synced. A writer dropped without `finish` (an error, a panic) deletes its
//! temporary file.
//!
//! HDF5 calls go through the `hdf5` crate, whose global lock serializes them; the
//! dimension-scale calls (`H5DS*`, from libhdf5_hl) are made under the same lock. The
//! writer is meant to be used from one thread.

use std::ffi::CString;
use std::fs;
use std::io;
use std::path::{Path, PathBuf};

use hdf5::plist::dataset_create::AttrCreationOrder;
use hdf5::plist::file_access::LibraryVersion;
use hdf5::plist::file_create::LinkCreationOrder;
use hdf5::{Dataset, File, H5Type, Location};

use crate::error::{Error, Result};

/// Declarations from the HDF5 high-level library (libhdf5_hl, built by the `hl`
/// feature of `hdf5-metno-sys`), which the `hdf5` crate does not bind.
mod ffi {
    use hdf5_sys::h5::herr_t;
    use hdf5_sys::h5i::hid_t;
    use std::ffi::{c_char, c_uint};

    unsafe extern "C" {
        /// Turns dataset `dsid` into a dimension scale named `dimname`.
        pub fn H5DSset_scale(dsid: hid_t, dimname: *const c_char) -> herr_t;
        /// Attaches scale `dsid` to dimension `idx` of dataset `did`.
        pub fn H5DSattach_scale(did: hid_t, dsid: hid_t, idx: c_uint) -> herr_t;
    }
}

/// Name of the profile dimension (and of its coordinate variable).
pub const PROFILE_DIM: &str = "profile";
/// Name of the range-bin dimension (and of its coordinate variable).
pub const BIN_DIM: &str = "bin";
/// Names of the per-component count variables, in the order of
/// [`ProfileRecord::components`]: signal, background, dark.
pub const COMPONENT_NAMES: [&str; 3] = ["signal_counts", "background_counts", "dark_counts"];
/// Variable names the writer itself defines; a [`BinVariable`] may not use them.
pub const RESERVED_NAMES: [&str; 8] = [
    PROFILE_DIM,
    BIN_DIM,
    "counts",
    "time",
    "n_shots",
    COMPONENT_NAMES[0],
    COMPONENT_NAMES[1],
    COMPONENT_NAMES[2],
];

/// Target size of one chunk of a (profile, bin) count variable, in bytes. Well below
/// HDF5's default 1 MiB per-dataset chunk cache, so the chunk being filled stays cached.
const TARGET_CHUNK_BYTES: usize = 256 * 1024;
/// Deflate level of the count variables (shuffle is applied first). Level 1 is about
/// twice as fast as 4 on simulated counts for ~4 % larger files.
const DEFLATE_LEVEL: u8 = 1;
/// Rows of the `profile` coordinate written per call at creation (bounds memory).
const COORD_BLOCK: usize = 64 * 1024;

/// Integer width of the stored counts, chosen by the caller from the largest count it
/// expects (see [`CountWidth::for_max_count`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum CountWidth {
    /// Unsigned 16-bit: counts up to 65 535.
    U16,
    /// Unsigned 32-bit: counts up to 4 294 967 295.
    U32,
    /// Unsigned 64-bit.
    U64,
}

impl CountWidth {
    /// The largest count this width stores.
    pub fn max_value(self) -> u64 {
        match self {
            CountWidth::U16 => u64::from(u16::MAX),
            CountWidth::U32 => u64::from(u32::MAX),
            CountWidth::U64 => u64::MAX,
        }
    }

    /// Bytes per stored count.
    pub fn bytes(self) -> usize {
        match self {
            CountWidth::U16 => 2,
            CountWidth::U32 => 4,
            CountWidth::U64 => 8,
        }
    }

    /// Lower-case type name, e.g. `"u16"`, for messages.
    pub fn name(self) -> &'static str {
        match self {
            CountWidth::U16 => "u16",
            CountWidth::U32 => "u32",
            CountWidth::U64 => "u64",
        }
    }

    /// The narrowest width that holds a Poisson count of mean `max_expected` (the largest
    /// expected count of any bin in any profile) with safe headroom:
    /// `mean + 20·sqrt(mean) + 64`. A Poisson draw exceeds that bound with probability
    /// below 1e-80, so a width chosen here never overflows in practice (and
    /// [`RawFileWriter::write_profile`] refuses, rather than wraps, if it does).
    ///
    /// Errors if `max_expected` is negative or not finite, or if even u64 cannot hold it.
    pub fn for_max_count(max_expected: f64) -> Result<CountWidth> {
        if !max_expected.is_finite() || max_expected < 0.0 {
            return Err(Error::Unsupported(format!(
                "cannot size the raw file's counts: the largest expected count per bin is \
                 {max_expected}, not a finite non-negative number"
            )));
        }
        let bound = max_expected + 20.0 * max_expected.sqrt() + 64.0;
        for width in [CountWidth::U16, CountWidth::U32, CountWidth::U64] {
            // `as f64` rounds u64::MAX up to 2^64, so compare strictly below it.
            if bound < width.max_value() as f64 {
                return Ok(width);
            }
        }
        Err(Error::Unsupported(format!(
            "the largest expected count per bin ({max_expected:e}) does not fit a 64-bit \
             counter; accumulate fewer shots per profile"
        )))
    }
}

/// A per-bin variable written beside the counts as a 1-D (bin) f64 dataset, e.g.
/// `altitude`, `range`, `expected_signal`, `snr_eq4`, `beta_mol`.
#[derive(Clone, Debug, PartialEq)]
pub struct BinVariable {
    /// Variable name in the file (must not be one of [`RESERVED_NAMES`]).
    pub name: String,
    /// CF `long_name`.
    pub long_name: String,
    /// CF `units` (UDUNITS string, `"1"` for dimensionless).
    pub units: String,
    /// One value per bin (`RawFileSpec::n_bins` values).
    pub data: Vec<f64>,
}

/// The value of a root (global) attribute.
#[derive(Clone, Debug, PartialEq)]
pub enum AttrValue {
    /// A text attribute (stored as a fixed-length UTF-8 string, netCDF `NC_CHAR`).
    Str(String),
    /// An unsigned integer attribute (netCDF `NC_UINT64`), e.g. the seed.
    U64(u64),
    /// A floating-point attribute (netCDF `NC_DOUBLE`).
    F64(f64),
}

/// Everything about a raw file that is known before the first profile.
#[derive(Clone, Debug)]
pub struct RawFileSpec {
    /// Range bins per profile (length of the `bin` dimension), at least 1.
    pub n_bins: usize,
    /// Profiles in the file (length of the `profile` dimension), at least 1. Every one
    /// must be written before [`RawFileWriter::finish`].
    pub n_profiles: usize,
    /// Integer width of `counts` (and of the component variables).
    pub count_width: CountWidth,
    /// Whether the file also holds `signal_counts`, `background_counts` and
    /// `dark_counts` (profile, bin); each [`ProfileRecord`] must then carry them.
    pub components: bool,
    /// Per-bin variables, written at creation, in this order.
    pub bin_variables: Vec<BinVariable>,
    /// Root attributes, in this order (`Conventions`, `title`, `source`, `history`,
    /// `config`, `seed`, `method`, ...).
    pub root_attributes: Vec<(String, AttrValue)>,
}

/// One profile, as handed to [`RawFileWriter::write_profile`].
#[derive(Clone, Copy, Debug)]
pub struct ProfileRecord<'a> {
    /// Row in the file, `0..n_profiles`; profiles may come in any order, each once.
    pub index: usize,
    /// Profile centre time since the run's start, s.
    pub time_s: f64,
    /// Shots accumulated in this profile.
    pub n_shots: u64,
    /// Accumulated raw counts, one per bin.
    pub counts: &'a [u64],
    /// Signal, background and dark counts, one per bin each; present exactly when the
    /// spec asked for components, and then summing to `counts` bin by bin.
    pub components: Option<[&'a [u64]; 3]>,
}

/// Open HDF5 handles of a file being written.
struct OpenFile {
    file: File,
    counts: Dataset,
    components: Option<[Dataset; 3]>,
    time: Dataset,
    n_shots: Dataset,
}

impl OpenFile {
    /// Closes every handle, the file last, reporting an error from the final flush.
    fn close(self) -> hdf5::Result<()> {
        let OpenFile {
            file,
            counts,
            components,
            time,
            n_shots,
        } = self;
        drop((counts, components, time, n_shots));
        file.close()
    }
}

/// Conversion buffer for one row of counts at the file's width (reused across rows).
enum RowBuf {
    U16(Vec<u16>),
    U32(Vec<u32>),
    /// No conversion needed: rows are written straight from the caller's slice.
    U64,
}

/// Streams a raw lidar file to disk, one profile at a time; see the module docs.
///
/// Memory use is one row of counts plus one bit per profile (to check that each is
/// written once), independent of the data volume.
pub struct RawFileWriter {
    final_path: PathBuf,
    temp_path: PathBuf,
    /// `None` once closed (by `finish`, or by `Drop`).
    open: Option<OpenFile>,
    /// Whether `temp_path` may exist on disk and is ours to delete.
    temp_exists: bool,
    n_bins: usize,
    n_profiles: usize,
    count_width: CountWidth,
    components: bool,
    /// One bit per profile: written yet?
    written: Vec<u64>,
    n_written: usize,
    buf: RowBuf,
}

/// A short, user-facing description of an I/O error ("permission denied", ...).
fn describe_io(err: &io::Error) -> String {
    match err.kind() {
        io::ErrorKind::PermissionDenied => "permission denied".into(),
        io::ErrorKind::NotFound => "no such directory".into(),
        io::ErrorKind::ReadOnlyFilesystem => "read-only file system".into(),
        io::ErrorKind::StorageFull => "no space left on device".into(),
        io::ErrorKind::NotADirectory => "a component of the path is not a directory".into(),
        _ => err.to_string(),
    }
}

/// Runs `f` under the `hdf5` crate's global lock.
fn locked<T>(f: impl FnOnce() -> T) -> T {
    hdf5::sync::sync(f)
}

/// Writes a scalar, fixed-length, NUL-terminated UTF-8 string attribute (netCDF
/// `NC_CHAR`, the classic text attribute type) on the object `loc`.
fn write_str_attr(loc: &Location, name: &str, value: &str) -> hdf5::Result<()> {
    use hdf5_sys::h5a::{H5Aclose, H5Acreate2, H5Awrite};
    use hdf5_sys::h5p::H5P_DEFAULT;
    use hdf5_sys::h5s::{H5S_class_t, H5Sclose, H5Screate};
    use hdf5_sys::h5t::{
        H5T_cset_t, H5T_str_t, H5Tclose, H5Tcopy, H5Tset_cset, H5Tset_size, H5Tset_strpad,
    };

    let c_name =
        CString::new(name).map_err(|_| hdf5::Error::from("attribute name contains NUL"))?;
    let bytes = value.as_bytes();
    if bytes.contains(&0) {
        return Err(hdf5::Error::from(format!(
            "attribute `{name}` contains a NUL character"
        )));
    }
    // A zero-size string type is invalid: an empty value is stored as one NUL byte.
    let mut buf = bytes.to_vec();
    if buf.is_empty() {
        buf.push(0);
    }
    locked(|| unsafe {
        let tid = hdf5::h5check(H5Tcopy(*hdf5::globals::H5T_C_S1))?;
        let sid = match hdf5::h5check(H5Screate(H5S_class_t::H5S_SCALAR)) {
            Ok(sid) => sid,
            Err(e) => {
                H5Tclose(tid);
                return Err(e);
            }
        };
        let result = (|| {
            hdf5::h5check(H5Tset_size(tid, buf.len()))?;
            hdf5::h5check(H5Tset_strpad(tid, H5T_str_t::H5T_STR_NULLTERM))?;
            hdf5::h5check(H5Tset_cset(tid, H5T_cset_t::H5T_CSET_UTF8))?;
            let aid = hdf5::h5check(H5Acreate2(
                loc.id(),
                c_name.as_ptr(),
                tid,
                sid,
                H5P_DEFAULT,
                H5P_DEFAULT,
            ))?;
            let written = hdf5::h5check(H5Awrite(aid, tid, buf.as_ptr().cast()));
            let closed = hdf5::h5check(H5Aclose(aid));
            written.and(closed).map(|_| ())
        })();
        H5Sclose(sid);
        H5Tclose(tid);
        result
    })
}

/// Writes a scalar numeric attribute.
fn write_num_attr<T: H5Type>(loc: &Location, name: &str, value: &T) -> hdf5::Result<()> {
    loc.new_attr::<T>()
        .shape(())
        .create(name)?
        .write_scalar(value)
}

/// Writes CF `long_name` and `units` on a variable.
fn write_cf_attrs(ds: &Dataset, long_name: &str, units: &str) -> hdf5::Result<()> {
    write_str_attr(ds, "long_name", long_name)?;
    write_str_attr(ds, "units", units)
}

/// Makes `ds` the dimension scale named `name`.
fn set_scale(ds: &Dataset, name: &str) -> hdf5::Result<()> {
    let c_name =
        CString::new(name).map_err(|_| hdf5::Error::from("dimension name contains NUL"))?;
    locked(|| hdf5::h5check(unsafe { ffi::H5DSset_scale(ds.id(), c_name.as_ptr()) }).map(|_| ()))
}

/// Attaches `scales[i]` to dimension `i` of `ds`.
fn attach_scales(ds: &Dataset, scales: &[&Dataset]) -> hdf5::Result<()> {
    locked(|| {
        for (idx, scale) in scales.iter().enumerate() {
            hdf5::h5check(unsafe { ffi::H5DSattach_scale(ds.id(), scale.id(), idx as u32) })?;
        }
        Ok(())
    })
}

/// The directory holding `path` (`.` for a bare file name).
fn parent_dir(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

impl RawFileWriter {
    /// Creates the file's temporary stand-in next to `final_path` and writes everything
    /// known up front: dimensions, per-bin variables, empty profile variables, and all
    /// attributes. `final_path` itself is not touched until [`finish`](Self::finish).
    ///
    /// Errors (as [`Error::Output`] naming `final_path`) if the spec is inconsistent
    /// (no bins or profiles, a bin variable of the wrong length or with a reserved or
    /// repeated name), if `final_path` is a directory, or if the file cannot be created
    /// (e.g. "cannot create a file in /dir: permission denied").
    pub fn create(final_path: &Path, spec: &RawFileSpec) -> Result<Self> {
        let fail = |reason: String| Error::output(final_path, reason);
        validate_spec(spec).map_err(fail)?;
        if final_path.is_dir() {
            return Err(fail("is a directory, not a file name".into()));
        }
        let temp_path =
            super::partial_path(final_path).ok_or_else(|| fail("not a file name".into()))?;
        let dir = parent_dir(final_path);

        // Create the temporary file with std first: a clear OS error beats HDF5's stack.
        fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&temp_path)
            .map_err(|e| {
                fail(format!(
                    "cannot create a file in {}: {}",
                    dir.display(),
                    describe_io(&e)
                ))
            })?;

        let mut writer = RawFileWriter {
            final_path: final_path.to_path_buf(),
            temp_path,
            open: None,
            temp_exists: true,
            n_bins: spec.n_bins,
            n_profiles: spec.n_profiles,
            count_width: spec.count_width,
            components: spec.components,
            written: vec![0; spec.n_profiles.div_ceil(64)],
            n_written: 0,
            buf: match spec.count_width {
                CountWidth::U16 => RowBuf::U16(Vec::with_capacity(spec.n_bins)),
                CountWidth::U32 => RowBuf::U32(Vec::with_capacity(spec.n_bins)),
                CountWidth::U64 => RowBuf::U64,
            },
        };
        // On error `writer` is dropped here, which closes and deletes the temporary file.
        let open = create_layout(&writer.temp_path, spec).map_err(|e| {
            fail(format!(
                "cannot write HDF5 file {}: {e}",
                writer.temp_path.display()
            ))
        })?;
        writer.open = Some(open);
        Ok(writer)
    }

    /// The final path given to [`create`](Self::create).
    pub fn final_path(&self) -> &Path {
        &self.final_path
    }

    /// The temporary path being written until [`finish`](Self::finish).
    pub fn temp_path(&self) -> &Path {
        &self.temp_path
    }

    /// Profiles written so far.
    pub fn profiles_written(&self) -> usize {
        self.n_written
    }

    /// Writes one profile row (`counts`, the components if any, `time`, `n_shots`).
    ///
    /// Everything is checked before anything is written, so a refused record leaves the
    /// file as it was: errors if `rec.index` is out of range or already written, if a
    /// slice's length is not `n_bins`, if components are missing or unexpected or do not
    /// sum to `counts`, if `time_s` is not finite, or if a count exceeds the file's
    /// [`CountWidth`] (never wrapped or clamped). An HDF5 failure leaves the profile
    /// unwritten; it may be retried.
    pub fn write_profile(&mut self, rec: &ProfileRecord) -> Result<()> {
        let fail = |reason: String| Error::output(&self.final_path, reason);
        self.validate_record(rec).map_err(fail)?;
        let open = self
            .open
            .as_ref()
            .ok_or_else(|| fail("the writer is already closed".into()))?;

        let row = rec.index;
        let result = (|| -> hdf5::Result<()> {
            write_row(&open.counts, &mut self.buf, rec.counts, row)?;
            if let (Some(datasets), Some(parts)) = (&open.components, &rec.components) {
                for (ds, part) in datasets.iter().zip(parts) {
                    write_row(ds, &mut self.buf, part, row)?;
                }
            }
            open.time.write_slice(&[rec.time_s][..], row..row + 1)?;
            open.n_shots.write_slice(&[rec.n_shots][..], row..row + 1)?;
            Ok(())
        })();
        result.map_err(|e| {
            Error::output(
                &self.final_path,
                format!(
                    "cannot write profile {row} to {}: {e}",
                    self.temp_path.display()
                ),
            )
        })?;
        self.written[row / 64] |= 1 << (row % 64);
        self.n_written += 1;
        Ok(())
    }

    /// Checks that every profile was written, closes the file (flushing it), syncs it to
    /// disk and renames it over the final path in one atomic step. On error the
    /// temporary file is deleted and the final path is left as it was.
    pub fn finish(mut self) -> Result<()> {
        if self.n_written != self.n_profiles {
            let missing =
                (0..self.n_profiles).find(|&i| self.written[i / 64] & (1 << (i % 64)) == 0);
            return Err(Error::output(
                &self.final_path,
                format!(
                    "incomplete: {} of {} profiles written (first missing: {})",
                    self.n_written,
                    self.n_profiles,
                    missing.map_or_else(|| "?".into(), |i| i.to_string())
                ),
            ));
        }
        let open = self
            .open
            .take()
            .ok_or_else(|| Error::output(&self.final_path, "the writer is already closed"))?;
        open.close().map_err(|e| {
            Error::output(
                &self.final_path,
                format!("cannot close HDF5 file {}: {e}", self.temp_path.display()),
            )
        })?;
        let io_fail = |what: &str, e: io::Error| {
            Error::output(
                &self.final_path,
                format!("{what} {}: {}", self.temp_path.display(), describe_io(&e)),
            )
        };
        fs::File::open(&self.temp_path)
            .and_then(|f| f.sync_all())
            .map_err(|e| io_fail("cannot sync", e))?;
        fs::rename(&self.temp_path, &self.final_path).map_err(|e| io_fail("cannot rename", e))?;
        self.temp_exists = false;
        // Make the rename durable; failure here does not undo a completed file.
        if let Ok(dir) = fs::File::open(parent_dir(&self.final_path)) {
            let _ = dir.sync_all();
        }
        Ok(())
    }

    /// All checks of `write_profile`, before anything is written.
    fn validate_record(&self, rec: &ProfileRecord) -> std::result::Result<(), String> {
        let i = rec.index;
        if i >= self.n_profiles {
            return Err(format!(
                "profile index {i} out of range (the file holds {} profiles)",
                self.n_profiles
            ));
        }
        if self.written[i / 64] & (1 << (i % 64)) != 0 {
            return Err(format!("profile {i} written twice"));
        }
        if !rec.time_s.is_finite() {
            return Err(format!("profile {i}: time {} s is not finite", rec.time_s));
        }
        let check_len = |what: &str, data: &[u64]| {
            if data.len() == self.n_bins {
                Ok(())
            } else {
                Err(format!(
                    "profile {i}: {what} has {} bins, the file has {}",
                    data.len(),
                    self.n_bins
                ))
            }
        };
        let max = self.count_width.max_value();
        let check_range = |what: &str, data: &[u64]| match data.iter().position(|&c| c > max) {
            None => Ok(()),
            Some(b) => Err(format!(
                "profile {i}, bin {b}: {what} {} exceeds the file's {} range (max {max})",
                data[b],
                self.count_width.name()
            )),
        };
        check_len("counts", rec.counts)?;
        check_range("count", rec.counts)?;
        match (self.components, &rec.components) {
            (false, None) => {}
            (true, None) => {
                return Err(format!(
                    "profile {i}: signal/background/dark counts missing"
                ));
            }
            (false, Some(_)) => {
                return Err(format!(
                    "profile {i}: component counts given but the file was created without them"
                ));
            }
            (true, Some(parts)) => {
                for (name, part) in COMPONENT_NAMES.iter().zip(parts) {
                    check_len(name, part)?;
                    check_range(name, part)?;
                }
                let [s, bg, d] = parts;
                for (b, &total) in rec.counts.iter().enumerate() {
                    let sum = s[b].checked_add(bg[b]).and_then(|x| x.checked_add(d[b]));
                    if sum != Some(total) {
                        return Err(format!(
                            "profile {i}, bin {b}: signal + background + dark = {} + {} + {} does not equal counts {total}",
                            s[b], bg[b], d[b]
                        ));
                    }
                }
            }
        }
        Ok(())
    }
}

impl Drop for RawFileWriter {
    /// An unfinished writer closes its file and deletes the temporary file, so nothing
    /// half-written is left behind.
    fn drop(&mut self) {
        if let Some(open) = self.open.take() {
            let _ = open.close();
        }
        if self.temp_exists {
            let _ = fs::remove_file(&self.temp_path);
            self.temp_exists = false;
        }
    }
}

/// Checks the spec's own consistency.
fn validate_spec(spec: &RawFileSpec) -> std::result::Result<(), String> {
    if spec.n_bins == 0 || spec.n_profiles == 0 {
        return Err(format!(
            "a raw file needs at least one bin and one profile (got {} bins, {} profiles)",
            spec.n_bins, spec.n_profiles
        ));
    }
    let mut seen: Vec<&str> = Vec::new();
    for var in &spec.bin_variables {
        if var.name.is_empty() || var.name.contains(['/', '\0']) {
            return Err(format!("invalid variable name {:?}", var.name));
        }
        if RESERVED_NAMES.contains(&var.name.as_str()) {
            return Err(format!(
                "variable name `{}` is reserved by the raw file layout",
                var.name
            ));
        }
        if seen.contains(&var.name.as_str()) {
            return Err(format!("variable `{}` given twice", var.name));
        }
        seen.push(&var.name);
        if var.data.len() != spec.n_bins {
            return Err(format!(
                "variable `{}` has {} values, the file has {} bins",
                var.name,
                var.data.len(),
                spec.n_bins
            ));
        }
    }
    let mut seen_attrs: Vec<&str> = Vec::new();
    for (name, _) in &spec.root_attributes {
        if name.is_empty() || seen_attrs.contains(&name.as_str()) {
            return Err(format!("root attribute {name:?} is empty or given twice"));
        }
        seen_attrs.push(name);
    }
    Ok(())
}

/// Rows per chunk of a (profile, bin) count variable: about [`TARGET_CHUNK_BYTES`].
fn chunk_rows(n_bins: usize, n_profiles: usize, width: CountWidth) -> usize {
    let row_bytes = n_bins * width.bytes();
    (TARGET_CHUNK_BYTES / row_bytes.max(1)).clamp(1, n_profiles)
}

/// Creates an empty (profile, bin) count variable at the file's width.
fn create_count_var(file: &File, name: &str, spec: &RawFileSpec) -> hdf5::Result<Dataset> {
    let shape = (spec.n_profiles, spec.n_bins);
    let chunk = (
        chunk_rows(spec.n_bins, spec.n_profiles, spec.count_width),
        spec.n_bins,
    );
    let builder = file.new_dataset_builder();
    let builder = match spec.count_width {
        CountWidth::U16 => builder.empty::<u16>(),
        CountWidth::U32 => builder.empty::<u32>(),
        CountWidth::U64 => builder.empty::<u64>(),
    };
    builder
        .shape(shape)
        .chunk(chunk)
        .shuffle()
        .deflate(DEFLATE_LEVEL)
        .attr_creation_order(AttrCreationOrder::Indexed)
        .create(name)
}

/// Creates an empty contiguous 1-D variable of `n` elements.
fn create_1d<T: H5Type>(file: &File, name: &str, n: usize) -> hdf5::Result<Dataset> {
    file.new_dataset::<T>()
        .shape(n)
        .attr_creation_order(AttrCreationOrder::Indexed)
        .create(name)
}

/// Writes `0..n` into a 1-D i64 variable, in blocks.
fn write_index(ds: &Dataset, n: usize) -> hdf5::Result<()> {
    let mut block = Vec::with_capacity(n.min(COORD_BLOCK));
    for start in (0..n).step_by(COORD_BLOCK) {
        let end = (start + COORD_BLOCK).min(n);
        block.clear();
        block.extend((start..end).map(|i| i as i64));
        ds.write_slice(&block[..], start..end)?;
    }
    Ok(())
}

/// Creates the whole layout in a new HDF5 file at `path` (truncating it).
fn create_layout(path: &Path, spec: &RawFileSpec) -> hdf5::Result<OpenFile> {
    let file = File::with_options()
        // HDF5 1.8 format: readable by any HDF5 >= 1.8 (every netCDF-4), and with
        // dense attribute storage, so long attributes (the config) are fine.
        .with_fapl(|fapl| fapl.libver_bounds(LibraryVersion::V18, LibraryVersion::V18))
        .with_fcpl(|fcpl| {
            fcpl.link_creation_order(LinkCreationOrder::Indexed)
                .attr_creation_order(AttrCreationOrder::Indexed)
        })
        .create(path)?;

    for (name, value) in &spec.root_attributes {
        match value {
            AttrValue::Str(s) => write_str_attr(&file, name, s)?,
            AttrValue::U64(v) => write_num_attr(&file, name, v)?,
            AttrValue::F64(v) => write_num_attr(&file, name, v)?,
        }
    }

    // Dimensions: integer coordinate variables marked as dimension scales.
    let profile = create_1d::<i64>(&file, PROFILE_DIM, spec.n_profiles)?;
    write_index(&profile, spec.n_profiles)?;
    write_cf_attrs(&profile, "profile index", "1")?;
    set_scale(&profile, PROFILE_DIM)?;

    let bin = create_1d::<i64>(&file, BIN_DIM, spec.n_bins)?;
    write_index(&bin, spec.n_bins)?;
    write_cf_attrs(&bin, "range bin index", "1")?;
    set_scale(&bin, BIN_DIM)?;

    let counts = create_count_var(&file, "counts", spec)?;
    write_cf_attrs(
        &counts,
        "accumulated raw photon counts (signal + background + dark)",
        "count",
    )?;
    attach_scales(&counts, &[&profile, &bin])?;

    let components = if spec.components {
        let long_names = [
            "accumulated photon counts from the backscattered laser signal",
            "accumulated photon counts from the sky background",
            "accumulated detector dark counts",
        ];
        let mut made = Vec::with_capacity(3);
        for (name, long_name) in COMPONENT_NAMES.iter().zip(long_names) {
            let ds = create_count_var(&file, name, spec)?;
            write_cf_attrs(&ds, long_name, "count")?;
            attach_scales(&ds, &[&profile, &bin])?;
            made.push(ds);
        }
        let [s, b, d]: [Dataset; 3] = made
            .try_into()
            .map_err(|_| hdf5::Error::from("internal: 3 components"))?;
        Some([s, b, d])
    } else {
        None
    };

    let time = create_1d::<f64>(&file, "time", spec.n_profiles)?;
    write_cf_attrs(&time, "profile centre time since the start of the run", "s")?;
    attach_scales(&time, &[&profile])?;

    let n_shots = create_1d::<u64>(&file, "n_shots", spec.n_profiles)?;
    write_cf_attrs(&n_shots, "laser shots accumulated in the profile", "1")?;
    attach_scales(&n_shots, &[&profile])?;

    for var in &spec.bin_variables {
        let ds = create_1d::<f64>(&file, &var.name, spec.n_bins)?;
        ds.write(&var.data[..])?;
        write_cf_attrs(&ds, &var.long_name, &var.units)?;
        attach_scales(&ds, &[&bin])?;
    }

    Ok(OpenFile {
        file,
        counts,
        components,
        time,
        n_shots,
    })
}

/// Writes row `row` of a (profile, bin) count variable, converting to its width (the
/// range was checked by `validate_record`).
fn write_row(ds: &Dataset, buf: &mut RowBuf, data: &[u64], row: usize) -> hdf5::Result<()> {
    match buf {
        RowBuf::U16(b) => {
            b.clear();
            b.extend(data.iter().map(|&c| c as u16));
            ds.write_slice(&b[..], (row, ..))
        }
        RowBuf::U32(b) => {
            b.clear();
            b.extend(data.iter().map(|&c| c as u32));
            ds.write_slice(&b[..], (row, ..))
        }
        RowBuf::U64 => ds.write_slice(data, (row, ..)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use hdf5::types::TypeDescriptor;

    /// A fresh empty directory for one test, removed (with its contents) on drop.
    struct TestDir(PathBuf);

    impl TestDir {
        fn path(&self) -> &Path {
            &self.0
        }
    }

    impl Drop for TestDir {
        fn drop(&mut self) {
            let _ = fs::remove_dir_all(&self.0);
        }
    }

    fn scratch_dir() -> TestDir {
        use std::sync::atomic::{AtomicU64, Ordering};
        static N: AtomicU64 = AtomicU64::new(0);
        let n = N.fetch_add(1, Ordering::Relaxed);
        let dir =
            std::env::temp_dir().join(format!("lidarsim-raw-file-test-{}-{n}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).expect("test dir");
        TestDir(dir)
    }

    /// Names of the entries of `dir`.
    fn entries(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    /// Reads a fixed-length string attribute, whatever its length.
    fn read_str_attr(loc: &Location, name: &str) -> String {
        use hdf5_sys::h5a::{H5Aget_type, H5Aread};
        use hdf5_sys::h5t::{H5Tclose, H5Tget_size};
        let attr = loc
            .attr(name)
            .unwrap_or_else(|e| panic!("attribute {name}: {e}"));
        match attr.dtype().unwrap().to_descriptor().unwrap() {
            TypeDescriptor::FixedUnicode(_) | TypeDescriptor::FixedAscii(_) => {}
            other => panic!("attribute {name} has type {other:?}"),
        }
        locked(|| unsafe {
            let tid = H5Aget_type(attr.id());
            let size = H5Tget_size(tid);
            let mut buf = vec![0u8; size];
            assert!(H5Aread(attr.id(), tid, buf.as_mut_ptr().cast()) >= 0);
            H5Tclose(tid);
            let end = buf.iter().position(|&b| b == 0).unwrap_or(buf.len());
            String::from_utf8(buf[..end].to_vec()).unwrap()
        })
    }

    /// The spec of the small test file; `config` is a long multi-line string.
    fn small_spec(width: CountWidth, components: bool, config: &str) -> RawFileSpec {
        let n_bins = 7;
        RawFileSpec {
            n_bins,
            n_profiles: 5,
            count_width: width,
            components,
            bin_variables: vec![
                BinVariable {
                    name: "altitude".into(),
                    long_name: "bin-centre altitude".into(),
                    units: "m".into(),
                    data: (0..n_bins).map(|b| 1000.0 * b as f64).collect(),
                },
                BinVariable {
                    name: "snr_eq4".into(),
                    long_name: "Eq. 4 signal-to-noise ratio of one profile".into(),
                    units: "1".into(),
                    data: (0..n_bins).map(|b| 0.5 + b as f64).collect(),
                },
            ],
            root_attributes: vec![
                ("Conventions".into(), AttrValue::Str("CF-1.8".into())),
                ("title".into(), AttrValue::Str("test – µ".into())),
                ("history".into(), AttrValue::Str(String::new())),
                ("config".into(), AttrValue::Str(config.into())),
                ("seed".into(), AttrValue::U64(u64::MAX - 1)),
                ("accumulation_time_s".into(), AttrValue::F64(0.25)),
            ],
        }
    }

    /// Counts of profile `p`, bin `b` for the components (signal, background, dark).
    fn parts(p: usize, b: usize) -> [u64; 3] {
        [(10 * p + b) as u64, (p * b) as u64, 1 + b as u64]
    }

    /// Writes profile `p` of the small file.
    fn write_small_profile(w: &mut RawFileWriter, p: usize, components: bool) -> Result<()> {
        let comps: [Vec<u64>; 3] =
            std::array::from_fn(|k| (0..7).map(|b| parts(p, b)[k]).collect());
        let counts: Vec<u64> = (0..7).map(|b| parts(p, b).iter().sum()).collect();
        w.write_profile(&ProfileRecord {
            index: p,
            time_s: 0.5 + p as f64,
            n_shots: 100 + p as u64,
            counts: &counts,
            components: components.then(|| [&comps[0][..], &comps[1][..], &comps[2][..]]),
        })
    }

    #[test]
    fn round_trip_shapes_values_attributes() {
        let dir = scratch_dir();
        let path = dir.path().join("out.h5");
        // Longer than HDF5's 64 KiB compact-attribute limit, with newlines.
        let config: String = (0..5000).map(|i| format!("key_{i} = {i}\n")).collect();
        assert!(config.len() > 70_000);
        let spec = small_spec(CountWidth::U16, true, &config);
        let mut w = RawFileWriter::create(&path, &spec).unwrap();
        assert!(
            !path.exists(),
            "final name must stay untouched while writing"
        );
        assert!(w.temp_path().exists());
        for p in [3, 0, 4, 1, 2] {
            write_small_profile(&mut w, p, true).unwrap();
        }
        w.finish().unwrap();
        assert_eq!(entries(dir.path()), vec!["out.h5".to_string()]);

        let f = File::open(&path).unwrap();
        let counts = f.dataset("counts").unwrap();
        assert_eq!(counts.shape(), vec![5, 7]);
        assert_eq!(
            counts.dtype().unwrap().to_descriptor().unwrap(),
            TypeDescriptor::Unsigned(hdf5::types::IntSize::U2)
        );
        assert!(counts.is_chunked());
        let c = counts.read_2d::<u64>().unwrap();
        let signal = f
            .dataset("signal_counts")
            .unwrap()
            .read_2d::<u64>()
            .unwrap();
        let dark = f.dataset("dark_counts").unwrap().read_2d::<u64>().unwrap();
        for p in 0..5 {
            for b in 0..7 {
                assert_eq!(c[[p, b]], parts(p, b).iter().sum::<u64>());
                assert_eq!(signal[[p, b]], parts(p, b)[0]);
                assert_eq!(dark[[p, b]], parts(p, b)[2]);
            }
        }
        assert_eq!(f.dataset("background_counts").unwrap().shape(), vec![5, 7]);
        let time = f.dataset("time").unwrap().read_1d::<f64>().unwrap();
        assert_eq!(time.to_vec(), vec![0.5, 1.5, 2.5, 3.5, 4.5]);
        let shots = f.dataset("n_shots").unwrap().read_1d::<u64>().unwrap();
        assert_eq!(shots.to_vec(), vec![100, 101, 102, 103, 104]);
        assert_eq!(
            f.dataset("profile")
                .unwrap()
                .read_1d::<i64>()
                .unwrap()
                .to_vec(),
            (0..5).collect::<Vec<i64>>()
        );
        assert_eq!(
            f.dataset("bin").unwrap().read_1d::<i64>().unwrap().to_vec(),
            (0..7).collect::<Vec<i64>>()
        );
        let alt = f.dataset("altitude").unwrap();
        assert_eq!(alt.shape(), vec![7]);
        assert_eq!(alt.read_1d::<f64>().unwrap()[3], 3000.0);

        // CF attributes on every variable.
        for name in [
            "profile",
            "bin",
            "counts",
            "signal_counts",
            "background_counts",
            "dark_counts",
            "time",
            "n_shots",
            "altitude",
            "snr_eq4",
        ] {
            let ds = f.dataset(name).unwrap();
            assert!(
                !read_str_attr(&ds, "long_name").is_empty(),
                "{name} long_name"
            );
            assert!(!read_str_attr(&ds, "units").is_empty(), "{name} units");
        }
        assert_eq!(read_str_attr(&f.dataset("time").unwrap(), "units"), "s");
        assert_eq!(
            read_str_attr(&f.dataset("counts").unwrap(), "units"),
            "count"
        );
        assert_eq!(read_str_attr(&alt, "units"), "m");

        // Dimension scales attached: DIMENSION_LIST on data, CLASS/NAME on scales.
        for name in ["counts", "time", "n_shots", "altitude", "dark_counts"] {
            assert!(
                f.dataset(name).unwrap().attr("DIMENSION_LIST").is_ok(),
                "{name} has no scales"
            );
        }
        assert_eq!(
            read_str_attr(&f.dataset("profile").unwrap(), "NAME"),
            "profile"
        );
        assert_eq!(
            read_str_attr(&f.dataset("bin").unwrap(), "CLASS"),
            "DIMENSION_SCALE"
        );

        // Root attributes as given.
        assert_eq!(read_str_attr(&f, "Conventions"), "CF-1.8");
        assert_eq!(read_str_attr(&f, "title"), "test – µ");
        assert_eq!(read_str_attr(&f, "history"), "");
        assert_eq!(read_str_attr(&f, "config"), config);
        assert_eq!(
            f.attr("seed").unwrap().read_scalar::<u64>().unwrap(),
            u64::MAX - 1
        );
        assert_eq!(
            f.attr("accumulation_time_s")
                .unwrap()
                .read_scalar::<f64>()
                .unwrap(),
            0.25
        );
    }

    #[test]
    fn wide_counts_round_trip() {
        for (width, big) in [
            (CountWidth::U32, u64::from(u32::MAX)),
            (CountWidth::U64, u64::MAX),
        ] {
            let dir = scratch_dir();
            let path = dir.path().join("wide.h5");
            let mut spec = small_spec(width, false, "x");
            spec.n_profiles = 1;
            let mut w = RawFileWriter::create(&path, &spec).unwrap();
            let counts = [big, 0, 1, 2, 3, 4, big];
            w.write_profile(&ProfileRecord {
                index: 0,
                time_s: 0.0,
                n_shots: 1,
                counts: &counts,
                components: None,
            })
            .unwrap();
            w.finish().unwrap();
            let f = File::open(&path).unwrap();
            let ds = f.dataset("counts").unwrap();
            assert_eq!(ds.dtype().unwrap().size(), width.bytes());
            assert_eq!(
                ds.read_2d::<u64>().unwrap().row(0).to_vec(),
                counts.to_vec()
            );
            assert!(f.dataset("signal_counts").is_err());
        }
    }

    #[test]
    fn dropped_writer_leaves_nothing() {
        let dir = scratch_dir();
        let path = dir.path().join("out.h5");
        let spec = small_spec(CountWidth::U16, true, "x");
        let mut w = RawFileWriter::create(&path, &spec).unwrap();
        write_small_profile(&mut w, 0, true).unwrap();
        write_small_profile(&mut w, 1, true).unwrap();
        drop(w);
        assert!(
            entries(dir.path()).is_empty(),
            "left behind: {:?}",
            entries(dir.path())
        );

        // finish() with profiles missing is an error and also leaves nothing.
        let mut w = RawFileWriter::create(&path, &spec).unwrap();
        write_small_profile(&mut w, 0, true).unwrap();
        let err = w.finish().unwrap_err().to_string();
        assert!(
            err.contains("1 of 5 profiles written") && err.contains("first missing: 1"),
            "{err}"
        );
        assert!(
            entries(dir.path()).is_empty(),
            "left behind: {:?}",
            entries(dir.path())
        );
    }

    #[test]
    fn an_existing_file_survives_a_failed_run() {
        let dir = scratch_dir();
        let path = dir.path().join("out.h5");
        fs::write(&path, b"previous run").unwrap();
        let spec = small_spec(CountWidth::U16, false, "x");
        drop(RawFileWriter::create(&path, &spec).unwrap());
        assert_eq!(fs::read(&path).unwrap(), b"previous run");
        assert_eq!(entries(dir.path()), vec!["out.h5".to_string()]);
    }

    #[test]
    fn count_above_width_is_an_error_not_a_wrap() {
        let dir = scratch_dir();
        let path = dir.path().join("out.h5");
        let mut spec = small_spec(CountWidth::U16, false, "x");
        spec.n_profiles = 1;
        let mut w = RawFileWriter::create(&path, &spec).unwrap();
        let mut counts = [1u64, 2, 3, 65_536, 5, 6, 7];
        let err = w
            .write_profile(&ProfileRecord {
                index: 0,
                time_s: 0.0,
                n_shots: 1,
                counts: &counts,
                components: None,
            })
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("bin 3") && err.contains("65536") && err.contains("u16"),
            "{err}"
        );
        // The refused profile was not written, so finishing now fails...
        assert_eq!(w.profiles_written(), 0);
        // ...and the largest u16 is stored exactly.
        counts[3] = 65_535;
        w.write_profile(&ProfileRecord {
            index: 0,
            time_s: 0.0,
            n_shots: 1,
            counts: &counts,
            components: None,
        })
        .unwrap();
        w.finish().unwrap();
        let stored = File::open(&path)
            .unwrap()
            .dataset("counts")
            .unwrap()
            .read_2d::<u64>()
            .unwrap();
        assert_eq!(stored.row(0).to_vec(), counts.to_vec());
    }

    #[test]
    fn component_overflow_and_bad_records_are_refused() {
        let dir = scratch_dir();
        let path = dir.path().join("out.h5");
        let spec = small_spec(CountWidth::U16, true, "x");
        let mut w = RawFileWriter::create(&path, &spec).unwrap();
        let zeros = [0u64; 7];
        let counts = [1u64; 7];
        let rec = |index, counts, components| ProfileRecord {
            index,
            time_s: 1.0,
            n_shots: 1,
            counts,
            components,
        };
        let msg = |r: Result<()>| r.unwrap_err().to_string();
        assert!(msg(w.write_profile(&rec(0, &counts, None))).contains("missing"));
        assert!(
            msg(w.write_profile(&rec(0, &counts, Some([&zeros, &zeros, &zeros]))))
                .contains("does not equal")
        );
        assert!(
            msg(w.write_profile(&rec(5, &counts, Some([&counts, &zeros, &zeros]))))
                .contains("out of range")
        );
        assert!(
            msg(w.write_profile(&rec(0, &counts[..6], Some([&counts, &zeros, &zeros]))))
                .contains("6 bins")
        );
        let mut nan = rec(0, &counts, Some([&counts, &zeros, &zeros]));
        nan.time_s = f64::NAN;
        assert!(msg(w.write_profile(&nan)).contains("not finite"));
        w.write_profile(&rec(0, &counts, Some([&counts, &zeros, &zeros])))
            .unwrap();
        assert!(
            msg(w.write_profile(&rec(0, &counts, Some([&counts, &zeros, &zeros]))))
                .contains("twice")
        );
    }

    #[test]
    fn bad_specs_are_refused() {
        let dir = scratch_dir();
        let path = dir.path().join("out.h5");
        let mut spec = small_spec(CountWidth::U16, false, "x");
        spec.bin_variables[0].data.pop();
        let err = RawFileWriter::create(&path, &spec)
            .err()
            .unwrap()
            .to_string();
        assert!(err.contains("`altitude` has 6 values"), "{err}");
        let mut spec = small_spec(CountWidth::U16, false, "x");
        spec.bin_variables[1].name = "counts".into();
        assert!(
            RawFileWriter::create(&path, &spec)
                .err()
                .unwrap()
                .to_string()
                .contains("reserved")
        );
        let mut spec = small_spec(CountWidth::U16, false, "x");
        spec.n_profiles = 0;
        assert!(RawFileWriter::create(&path, &spec).is_err());
        assert!(entries(dir.path()).is_empty());
    }

    #[test]
    fn unwritable_destination_gives_a_clear_error() {
        let dir = scratch_dir();
        let spec = small_spec(CountWidth::U16, false, "x");

        // A directory that does not exist.
        let path = dir.path().join("missing").join("out.h5");
        let err = RawFileWriter::create(&path, &spec)
            .err()
            .unwrap()
            .to_string();
        assert!(err.starts_with(&path.display().to_string()), "{err}");
        assert!(
            err.contains("cannot create a file in") && err.contains("no such directory"),
            "{err}"
        );

        // A destination that is a directory.
        let err = RawFileWriter::create(dir.path(), &spec)
            .err()
            .unwrap()
            .to_string();
        assert!(err.contains("is a directory"), "{err}");

        // A read-only directory (meaningless for root, who may write anyway).
        use std::os::unix::fs::PermissionsExt;
        let ro = dir.path().join("ro");
        fs::create_dir(&ro).unwrap();
        fs::set_permissions(&ro, fs::Permissions::from_mode(0o555)).unwrap();
        let probe = ro.join("probe");
        let root_like = fs::write(&probe, b"").is_ok();
        let _ = fs::remove_file(&probe);
        if !root_like {
            let path = ro.join("out.h5");
            let err = RawFileWriter::create(&path, &spec)
                .err()
                .unwrap()
                .to_string();
            assert_eq!(
                err,
                format!(
                    "{}: cannot create a file in {}: permission denied",
                    path.display(),
                    ro.display()
                )
            );
        }
        fs::set_permissions(&ro, fs::Permissions::from_mode(0o755)).unwrap();
    }

    #[test]
    fn count_width_has_headroom() {
        assert_eq!(CountWidth::for_max_count(0.0).unwrap(), CountWidth::U16);
        assert_eq!(CountWidth::for_max_count(1000.0).unwrap(), CountWidth::U16);
        assert_eq!(
            CountWidth::for_max_count(62_000.0).unwrap(),
            CountWidth::U32
        );
        assert_eq!(
            CountWidth::for_max_count(65_535.0).unwrap(),
            CountWidth::U32
        );
        assert_eq!(CountWidth::for_max_count(4.0e9).unwrap(), CountWidth::U32);
        assert_eq!(CountWidth::for_max_count(4.294e9).unwrap(), CountWidth::U64);
        assert_eq!(CountWidth::for_max_count(1.0e18).unwrap(), CountWidth::U64);
        assert!(CountWidth::for_max_count(1.0e20).is_err());
        assert!(CountWidth::for_max_count(f64::NAN).is_err());
        assert!(CountWidth::for_max_count(f64::INFINITY).is_err());
        assert!(CountWidth::for_max_count(-1.0).is_err());
    }
}
