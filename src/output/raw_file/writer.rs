//! Streaming the profiles of a raw file, checked before they are buffered, written a
//! whole chunk at a time.
//!
//! Each (profile, channel, bin) variable (`counts`, the component counts, a changing
//! scene's truth) is filled chunk by chunk in memory, in the shuffled layout of HDF5's
//! shuffle filter ([`chunk::put_row`]). A chunk is complete when every one of its rows
//! has come (the last chunk holds fewer; its rows past the end stay 0, the fill value, as
//! HDF5 pads edge chunks); complete chunks wait in a queue, and when the queue holds
//! [`FLUSH_BYTES`] (and at [`RawFileWriter::finish`]) they are deflated in parallel on
//! rayon's pool (the run's `--threads`) and written in queue order by HDF5's direct chunk
//! write. The (profile) variables (`time`, `n_shots`, `pulse_energy`, geolocation) are
//! written [`COLUMN_BLOCK`] profiles per HDF5 call.
//!
//! Same bytes whatever the thread count: a chunk's bytes depend on its data only, the
//! queue's order and the moments it is written depend only on the order of the calls.
//! So the same spec and the same records in the same order give the same file: a writer
//! fed profiles 0, 1, 2, … (as `simulate` does) writes the same bytes whoever feeds it.
//!
//! Memory: one bit per profile (written yet?), plus, for a writer that sends profiles in
//! order, at most one chunk being filled per (profile, channel, bin) variable (about
//! [`layout::TARGET_CHUNK_BYTES`], or one profile's row if that is larger), one block of
//! the (profile) variables, the queue (under [`FLUSH_BYTES`] plus one chunk of raw bytes,
//! and while it is written, its compressed chunks), the written buffers kept for reuse
//! (at most [`FLUSH_BYTES`]) and one compressor per worker thread: [`buffer_bytes`], e.g.
//! about 60 MB for the orbit's six variables on two threads. Profiles may come in any
//! order; a chunk then stays in memory until all its rows have come.

use std::collections::BTreeMap;
use std::collections::btree_map::Entry;
use std::path::{Path, PathBuf};

use rayon::prelude::*;

use super::chunk;
use super::hdf5_ds::write_chunk;
use super::layout::{self, OpenFile};
use super::{COMPONENT_NAMES, CountWidth, Dims, ProfileRecord, RawFileSpec};
use crate::error::{Error, Result};
use crate::output::safe_file::describe_hdf5_error;

/// Raw (uncompressed) bytes of complete chunks that trigger their compression and
/// writing: a fixed size, not a function of the thread count, so that the sequence of
/// HDF5 calls (and so the file's layout) is the same on any machine. 16 MiB keeps 32
/// chunks of 512 KiB in a batch: work for many threads at once.
pub const FLUSH_BYTES: usize = 16 << 20;
/// Bytes of written chunk buffers kept for reuse.
const SPARE_BYTES: usize = FLUSH_BYTES;
/// Profiles per HDF5 call of the (profile) variables.
pub const COLUMN_BLOCK: usize = 4096;

/// The most memory the writer's buffers take for a writer that sends profiles in order:
/// one chunk being filled per (profile, channel, bin) variable (`variables` of them, rows
/// of at most `row_bytes`), the queue of complete chunks and the buffers kept for reuse
/// (each under [`FLUSH_BYTES`] plus a chunk), the compressed chunks of one batch (no
/// larger than their input plus 1/8), and each of `threads` workers' compressor (its
/// tables, ~300 kB, and room for a chunk and 1/8 plus 128 KiB).
pub fn buffer_bytes(row_bytes: usize, variables: usize, threads: usize) -> f64 {
    let chunk = layout::TARGET_CHUNK_BYTES.max(row_bytes) as f64;
    let flush = FLUSH_BYTES as f64 + chunk;
    variables as f64 * chunk
        + 2.0 * flush
        + 1.125 * flush
        + threads as f64 * (300e3 + 1.125 * chunk + 131_072.0)
}

/// A chunk being filled.
struct OpenChunk {
    /// Shuffled bytes, `chunk_rows × channels × bins` elements.
    data: Vec<u8>,
    /// Rows written into it so far.
    present: usize,
}

/// A complete chunk waiting to be deflated and written.
struct ReadyChunk {
    /// Index in [`OpenFile::rows`].
    var: usize,
    /// Chunk index along profiles.
    chunk: usize,
    data: Vec<u8>,
}

/// A chunk's stored bytes, or why it could not be compressed.
type Stored = std::result::Result<Vec<u8>, String>;

/// [`COLUMN_BLOCK`] profiles of the (profile) variables being filled.
struct ColumnBlock {
    time: Vec<f64>,
    n_shots: Vec<u64>,
    pulse_energy: Vec<f64>,
    /// The spec's (profile) variables, in its order.
    values: Vec<Vec<f64>>,
    present: usize,
}

/// Streams a raw lidar file, one profile at a time.
pub struct RawFileWriter {
    /// The user-facing path, for messages.
    display: PathBuf,
    /// `None` once closed (by `finish`, or by `Drop`).
    open: Option<OpenFile>,
    n_per_profile: usize,
    n_profiles: usize,
    count_width: CountWidth,
    components: bool,
    /// Dimensions and values per profile of each per-profile variable, in the spec's order.
    per_profile_sizes: Vec<(Dims, usize)>,
    /// (bytes per element, profiles per chunk) of each of [`OpenFile::rows`].
    row_layout: Vec<(usize, usize)>,
    /// Chunks being filled, by chunk index, for each of [`OpenFile::rows`].
    filling: Vec<BTreeMap<usize, OpenChunk>>,
    /// Complete chunks, in the order they were completed.
    ready: Vec<ReadyChunk>,
    ready_bytes: usize,
    /// Blocks of the (profile) variables being filled, by block index.
    blocks: BTreeMap<usize, ColumnBlock>,
    /// Chunk buffers already written, for reuse (at most [`SPARE_BYTES`] in all).
    spare: Vec<Vec<u8>>,
    spare_bytes: usize,
    /// Why an earlier write failed: the file is then unusable.
    failed: Option<String>,
    /// One bit per profile: written yet?
    written: Vec<u64>,
    n_written: usize,
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
        let row_layout: Vec<(usize, usize)> = open
            .rows
            .iter()
            .map(|v| (v.elem_bytes, v.chunk_rows))
            .collect();
        Ok(RawFileWriter {
            display: display.to_path_buf(),
            n_per_profile: spec.counts_per_profile(),
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
            filling: row_layout.iter().map(|_| BTreeMap::new()).collect(),
            row_layout,
            open: Some(open),
            ready: Vec::new(),
            ready_bytes: 0,
            blocks: BTreeMap::new(),
            spare: Vec::new(),
            spare_bytes: 0,
            failed: None,
            written,
            n_written: 0,
        })
    }

    /// Profiles written so far (accepted: a profile may still wait in memory for the rest
    /// of its chunk; [`RawFileWriter::finish`] writes everything).
    pub fn profiles_written(&self) -> usize {
        self.n_written
    }

    /// Writes one profile row (`counts`, the components if any, `time`, `n_shots`,
    /// `pulse_energy`, the per-profile variables).
    ///
    /// Everything is checked before anything is buffered, so a refused record leaves the
    /// writer as it was: errors if `rec.index` is out of range or already written, if a
    /// slice's length is not channels × bins, if components are missing or unexpected or
    /// do not sum to `counts`, if `time_s` is not finite, or if a count exceeds the
    /// file's [`CountWidth`] (never wrapped or clamped). A failure to write (a full disk)
    /// leaves the writer unusable: every later call errors, and the caller drops the file.
    pub fn write_profile(&mut self, rec: &ProfileRecord) -> Result<()> {
        self.usable()?;
        self.validate_record(rec)
            .map_err(|r| Error::output(&self.display, r))?;
        if let Err(reason) = self.accept(rec) {
            self.failed = Some(reason.clone());
            return Err(Error::output(&self.display, reason));
        }
        let row = rec.index;
        self.written[row / 64] |= 1 << (row % 64);
        self.n_written += 1;
        Ok(())
    }

    /// Checks that every profile was written, writes what is still buffered and closes
    /// the file, flushing it. The caller syncs and renames it (through
    /// [`crate::output::safe_file`]).
    pub fn finish(mut self) -> Result<()> {
        self.usable()?;
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
        self.flush()
            .map_err(|reason| Error::output(&self.display, reason))?;
        if self.filling.iter().any(|f| !f.is_empty()) || !self.blocks.is_empty() {
            return Err(Error::output(
                &self.display,
                "internal: every profile was written but a chunk is incomplete",
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

    /// Errors if the writer is closed or an earlier write failed.
    fn usable(&self) -> Result<()> {
        if let Some(why) = &self.failed {
            return Err(Error::output(
                &self.display,
                format!("an earlier write failed ({why})"),
            ));
        }
        if self.open.is_none() {
            return Err(Error::output(&self.display, "the writer is already closed"));
        }
        Ok(())
    }

    /// Buffers a checked record; writes the blocks and chunks it completes.
    fn accept(&mut self, rec: &ProfileRecord) -> std::result::Result<(), String> {
        let row = rec.index;
        self.put_row(0, row, rec.counts, |c| c)?;
        let mut k = 1;
        if let Some(parts) = &rec.components {
            for part in parts {
                self.put_row(k, row, part, |c| c)?;
                k += 1;
            }
        }
        let mut column_values = Vec::new();
        for (i, v) in rec.values.iter().enumerate() {
            match self.per_profile_sizes[i].0 {
                Dims::Profile => column_values.push(v[0]),
                _ => {
                    self.put_row(k, row, v, f64::to_bits)?;
                    k += 1;
                }
            }
        }
        self.put_columns(rec, &column_values)?;
        if self.ready_bytes >= FLUSH_BYTES {
            self.flush()?;
        }
        Ok(())
    }

    /// Puts profile `row` of (profile, channel, bin) variable `var` into its chunk, and
    /// queues the chunk when it is complete.
    fn put_row<T: Copy>(
        &mut self,
        var: usize,
        row: usize,
        values: &[T],
        bits: impl Fn(T) -> u64,
    ) -> std::result::Result<(), String> {
        let (elem_bytes, chunk_rows) = self.row_layout[var];
        let (c, r) = (row / chunk_rows, row % chunk_rows);
        let elems = chunk_rows * self.n_per_profile;
        let rows_in_chunk = chunk_rows.min(self.n_profiles - c * chunk_rows);
        let open = match self.filling[var].entry(c) {
            Entry::Occupied(e) => e.into_mut(),
            Entry::Vacant(e) => {
                let size = elems * elem_bytes;
                let spare = self.spare.pop();
                self.spare_bytes -= spare.as_ref().map_or(0, Vec::len);
                let data = match spare {
                    // every byte of a full chunk is overwritten by its rows; an edge
                    // chunk's rows past the end hold the fill value, 0
                    Some(mut b) => {
                        b.resize(size, 0);
                        if rows_in_chunk < chunk_rows {
                            b.fill(0);
                        }
                        b
                    }
                    None => crate::resources::try_vec("a chunk of the raw file", size, 0u8)
                        .map_err(|e| e.to_string())?,
                };
                e.insert(OpenChunk { data, present: 0 })
            }
        };
        chunk::put_row(
            &mut open.data,
            elems,
            r * self.n_per_profile,
            elem_bytes,
            values,
            bits,
        );
        open.present += 1;
        if open.present == rows_in_chunk
            && let Some(done) = self.filling[var].remove(&c)
        {
            self.ready_bytes += done.data.len();
            self.ready.push(ReadyChunk {
                var,
                chunk: c,
                data: done.data,
            });
        }
        Ok(())
    }

    /// Puts the (profile) values of a record into their block, and writes the block when
    /// it is complete.
    fn put_columns(
        &mut self,
        rec: &ProfileRecord,
        values: &[f64],
    ) -> std::result::Result<(), String> {
        let (b, r) = (rec.index / COLUMN_BLOCK, rec.index % COLUMN_BLOCK);
        let start = b * COLUMN_BLOCK;
        let len = COLUMN_BLOCK.min(self.n_profiles - start);
        let block = self.blocks.entry(b).or_insert_with(|| ColumnBlock {
            time: vec![0.0; len],
            n_shots: vec![0; len],
            pulse_energy: vec![0.0; len],
            values: vec![vec![0.0; len]; values.len()],
            present: 0,
        });
        block.time[r] = rec.time_s;
        block.n_shots[r] = rec.n_shots;
        block.pulse_energy[r] = rec.pulse_energy_j;
        for (column, &v) in block.values.iter_mut().zip(values) {
            column[r] = v;
        }
        block.present += 1;
        if block.present < len {
            return Ok(());
        }
        let Some(block) = self.blocks.remove(&b) else {
            return Ok(());
        };
        let open = self.open.as_ref().ok_or("the writer is already closed")?;
        let range = start..start + len;
        (|| -> hdf5::Result<()> {
            open.time.write_slice(&block.time[..], range.clone())?;
            open.n_shots
                .write_slice(&block.n_shots[..], range.clone())?;
            open.pulse_energy
                .write_slice(&block.pulse_energy[..], range.clone())?;
            for (ds, column) in open.columns.iter().zip(&block.values) {
                ds.write_slice(&column[..], range.clone())?;
            }
            Ok(())
        })()
        .map_err(|e| {
            format!(
                "cannot write profiles {}–{}: {}",
                range.start,
                range.end - 1,
                describe_hdf5_error(&e.to_string())
            )
        })
    }

    /// Deflates the complete chunks in parallel and writes them in queue order.
    fn flush(&mut self) -> std::result::Result<(), String> {
        let ready = std::mem::take(&mut self.ready);
        self.ready_bytes = 0;
        if ready.is_empty() {
            return Ok(());
        }
        // compressed in parallel, in any order; `collect` keeps the queue's order
        let encoded: Vec<(ReadyChunk, Stored)> = ready
            .into_par_iter()
            .map(|c| {
                let stored = chunk::deflate(&c.data);
                (c, stored)
            })
            .collect();
        let open = self.open.as_ref().ok_or("the writer is already closed")?;
        for (c, stored) in encoded {
            let bytes = stored?;
            if self.spare_bytes + c.data.len() <= SPARE_BYTES {
                self.spare_bytes += c.data.len();
                self.spare.push(c.data);
            }
            let v = &open.rows[c.var];
            let first = c.chunk * v.chunk_rows;
            write_chunk(&v.ds, &[first as u64, 0, 0], &bytes).map_err(|e| {
                let last = (first + v.chunk_rows).min(self.n_profiles) - 1;
                format!(
                    "cannot write profiles {first}–{last} of `{}`: {}",
                    v.name,
                    describe_hdf5_error(&e.to_string())
                )
            })?;
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
            if v.len() != want || !v.iter().fold(true, |ok, x| ok & x.is_finite()) {
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
            // `max` is 2^k − 1, so every count fits when their bitwise OR does: one
            // vectorized pass; the position is searched only on failure
            if data.iter().fold(0, |acc, &c| acc | c) <= max {
                return Ok(());
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
