//! Streaming the profiles of a raw file: one row of (channel, bin) counts at a time,
//! checked before it is written.
//!
//! Memory use is one row of counts plus one bit per profile (to check that each is
//! written once), independent of the data volume. The writer is meant to be used from
//! one thread (HDF5 calls are serialized anyway).

use std::path::{Path, PathBuf};

use hdf5::Dataset;

use super::layout::{self, OpenFile};
use super::{COMPONENT_NAMES, CountWidth, Dims, ProfileRecord, RawFileSpec};
use crate::error::{Error, Result};
use crate::output::safe_file::describe_hdf5_error;

/// Conversion buffer for one row of counts at the file's width (reused across rows).
enum RowBuf {
    U16(Vec<u16>),
    U32(Vec<u32>),
    /// No conversion needed: rows are written straight from the caller's slice.
    U64,
}

/// Streams a raw lidar file, one profile at a time.
pub struct RawFileWriter {
    /// The user-facing path, for messages.
    display: PathBuf,
    /// `None` once closed (by `finish`, or by `Drop`).
    open: Option<OpenFile>,
    n_per_profile: usize,
    n_channels: usize,
    n_profiles: usize,
    count_width: CountWidth,
    components: bool,
    /// Dimensions and values per profile of each per-profile variable, in the spec's order.
    per_profile_sizes: Vec<(Dims, usize)>,
    /// One bit per profile: written yet?
    written: Vec<u64>,
    n_written: usize,
    buf: RowBuf,
}

impl RawFileWriter {
    /// Creates the file at exactly `path` (a fresh temporary name from
    /// [`crate::output::safe_file`]) and writes everything known up front. `display` is
    /// the path the user asked for, used in messages only.
    ///
    /// Errors (as [`Error::Output`] naming `display`) if the spec is inconsistent or the
    /// file cannot be written, with HDF5 failures reduced to their OS reason.
    pub fn create(path: &Path, display: &Path, spec: &RawFileSpec) -> Result<Self> {
        let fail = |reason: String| Error::output(display, reason);
        layout::validate_spec(spec).map_err(fail)?;
        let written = crate::resources::try_vec(
            "the raw file's record of written profiles",
            spec.n_profiles.div_ceil(64),
            0u64,
        )?;
        let open = layout::create_layout(path, spec).map_err(|e| {
            fail(format!(
                "cannot write: {}",
                describe_hdf5_error(&e.to_string())
            ))
        })?;
        Ok(RawFileWriter {
            display: display.to_path_buf(),
            open: Some(open),
            n_per_profile: spec.counts_per_profile(),
            n_channels: spec.channels.len(),
            n_profiles: spec.n_profiles,
            count_width: spec.count_width,
            components: spec.components,
            per_profile_sizes: spec
                .variables
                .iter()
                .filter(|v| v.dims.per_profile())
                .map(|v| match v.dims {
                    Dims::Profile => (v.dims, 1),
                    _ => (v.dims, spec.counts_per_profile()),
                })
                .collect(),
            written,
            n_written: 0,
            buf: match spec.count_width {
                CountWidth::U16 => RowBuf::U16(Vec::new()),
                CountWidth::U32 => RowBuf::U32(Vec::new()),
                CountWidth::U64 => RowBuf::U64,
            },
        })
    }

    /// Profiles written so far.
    pub fn profiles_written(&self) -> usize {
        self.n_written
    }

    /// Writes one profile row (`counts`, the components if any, `time`, `n_shots`).
    ///
    /// Everything is checked before anything is written, so a refused record leaves the
    /// file as it was: errors if `rec.index` is out of range or already written, if a
    /// slice's length is not channels × bins, if components are missing or unexpected or
    /// do not sum to `counts`, if `time_s` is not finite, or if a count exceeds the
    /// file's [`CountWidth`] (never wrapped or clamped).
    pub fn write_profile(&mut self, rec: &ProfileRecord) -> Result<()> {
        self.validate_record(rec)
            .map_err(|r| Error::output(&self.display, r))?;
        let open = self
            .open
            .as_ref()
            .ok_or_else(|| Error::output(&self.display, "the writer is already closed"))?;
        let row = rec.index;
        let shape = (self.n_channels, self.n_per_profile / self.n_channels);
        let result = (|| -> hdf5::Result<()> {
            write_row(&open.counts, &mut self.buf, rec.counts, row, shape)?;
            if let (Some(datasets), Some(parts)) = (&open.components, &rec.components) {
                for (ds, part) in datasets.iter().zip(parts) {
                    write_row(ds, &mut self.buf, part, row, shape)?;
                }
            }
            open.time.write_slice(&[rec.time_s][..], row..row + 1)?;
            open.n_shots.write_slice(&[rec.n_shots][..], row..row + 1)?;
            open.pulse_energy
                .write_slice(&[rec.pulse_energy_j][..], row..row + 1)?;
            for ((ds, v), (dims, _)) in open
                .per_profile
                .iter()
                .zip(rec.values)
                .zip(&self.per_profile_sizes)
            {
                match dims {
                    Dims::Profile => ds.write_slice(&v[..], row..row + 1)?,
                    _ => ds.write_slice(ndarray_view(v, shape)?, (row, .., ..))?,
                }
            }
            Ok(())
        })();
        result.map_err(|e| {
            Error::output(
                &self.display,
                format!(
                    "cannot write profile {row}: {}",
                    describe_hdf5_error(&e.to_string())
                ),
            )
        })?;
        self.written[row / 64] |= 1 << (row % 64);
        self.n_written += 1;
        Ok(())
    }

    /// Checks that every profile was written and closes the file, flushing it. The
    /// caller syncs and renames it (through [`crate::output::safe_file`]).
    pub fn finish(mut self) -> Result<()> {
        if self.n_written != self.n_profiles {
            let missing =
                (0..self.n_profiles).find(|&i| self.written[i / 64] & (1 << (i % 64)) == 0);
            return Err(Error::output(
                &self.display,
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
            .ok_or_else(|| Error::output(&self.display, "the writer is already closed"))?;
        open.close().map_err(|e| {
            Error::output(
                &self.display,
                format!("cannot close: {}", describe_hdf5_error(&e.to_string())),
            )
        })
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
        if !rec.pulse_energy_j.is_finite() || rec.pulse_energy_j < 0.0 {
            return Err(format!(
                "profile {i}: pulse energy {} J is not a finite non-negative number",
                rec.pulse_energy_j
            ));
        }
        if rec.values.len() != self.per_profile_sizes.len() {
            return Err(format!(
                "profile {i}: {} per-profile variables given, the file has {}",
                rec.values.len(),
                self.per_profile_sizes.len()
            ));
        }
        for (k, (v, &(_, want))) in rec.values.iter().zip(&self.per_profile_sizes).enumerate() {
            if v.len() != want || v.iter().any(|x| !x.is_finite()) {
                return Err(format!(
                    "profile {i}: per-profile variable {k} has {} values (want {want}) or a non-finite one",
                    v.len()
                ));
            }
        }
        if !rec.time_s.is_finite() {
            return Err(format!("profile {i}: time {} s is not finite", rec.time_s));
        }
        let n = self.n_per_profile;
        let max = self.count_width.max_value();
        let check = |what: &str, data: &[u64]| {
            if data.len() != n {
                return Err(format!(
                    "profile {i}: {what} has {} values, the file has {n} per profile",
                    data.len()
                ));
            }
            match data.iter().position(|&c| c > max) {
                None => Ok(()),
                Some(b) => Err(format!(
                    "profile {i}, value {b}: {what} {} exceeds the file's {} range (max {max})",
                    data[b],
                    self.count_width.name()
                )),
            }
        };
        check("counts", rec.counts)?;
        match (self.components, &rec.components) {
            (false, None) => Ok(()),
            (true, None) => Err(format!(
                "profile {i}: signal/background/dark counts missing"
            )),
            (false, Some(_)) => Err(format!(
                "profile {i}: component counts given but the file was created without them"
            )),
            (true, Some(parts)) => {
                for (name, part) in COMPONENT_NAMES.iter().zip(parts) {
                    check(name, part)?;
                }
                let [s, bg, d] = parts;
                match (0..n).find(|&b| {
                    s[b].checked_add(bg[b]).and_then(|x| x.checked_add(d[b])) != Some(rec.counts[b])
                }) {
                    None => Ok(()),
                    Some(b) => Err(format!(
                        "profile {i}, value {b}: signal + background + dark = {} + {} + {} does not equal counts {}",
                        s[b], bg[b], d[b], rec.counts[b]
                    )),
                }
            }
        }
    }
}

impl Drop for RawFileWriter {
    /// An unfinished writer closes its file; [`crate::output::safe_file`] deletes it.
    fn drop(&mut self) {
        if let Some(open) = self.open.take() {
            let _ = open.close();
        }
    }
}

/// Writes row `row` of a (profile, channel, bin) count variable, converting to its width
/// (the range was checked by `validate_record`).
fn write_row(
    ds: &Dataset,
    buf: &mut RowBuf,
    data: &[u64],
    row: usize,
    (channels, bins): (usize, usize),
) -> hdf5::Result<()> {
    let sel = (row, .., ..);
    let shape = (channels, bins);
    match buf {
        RowBuf::U16(b) => {
            b.clear();
            b.extend(data.iter().map(|&c| c as u16));
            ds.write_slice(ndarray_view(b, shape)?, sel)
        }
        RowBuf::U32(b) => {
            b.clear();
            b.extend(data.iter().map(|&c| c as u32));
            ds.write_slice(ndarray_view(b, shape)?, sel)
        }
        RowBuf::U64 => ds.write_slice(ndarray_view(data, shape)?, sel),
    }
}

/// A (channels, bins) view of a channel-major row.
fn ndarray_view<T>(data: &[T], shape: (usize, usize)) -> hdf5::Result<ndarray::ArrayView2<'_, T>> {
    ndarray::ArrayView2::from_shape(shape, data).map_err(|e| hdf5::Error::from(e.to_string()))
}
