//! Streaming the profiles of a raw file, checked before they are buffered, written a
//! whole chunk at a time.
//!
//! Each (profile, channel, bin) variable (`counts`, the component counts, a changing
//! scene's truth) is filled chunk by chunk in memory, in the shuffled layout of HDF5's
//! shuffle filter ([`chunk::put_row`]). A chunk is complete when every one of its rows
//! has come (the last chunk holds fewer; its rows past the end stay 0, the fill value, as
//! HDF5 pads edge chunks); complete chunks wait in a queue, and when the queue holds
//! [`FLUSH_BYTES`] (and at [`RawFileWriter::finish`]) they are deflated in parallel on
//! rayon's pool (the run's `--threads`; the count variables' chunks by byte planes, their
//! noise planes stored, [`planes`]) and written in queue order by HDF5's direct chunk
//! write. The (profile) variables (`time`, `n_shots`, `pulse_energy`, geolocation) are
//! written [`COLUMN_BLOCK`] profiles per HDF5 call.
//!
//! [`RawFileWriter::write_profiles`] takes a batch: its records are checked in parallel
//! and each variable's chunks filled by a worker of its own, then what the batch
//! completes is queued and written in the order single records would have done it.
//!
//! Same bytes whatever the thread count: a chunk's bytes depend on its data only, the
//! queue's order and the moments it is written depend only on the order of the records,
//! not on how they are grouped in calls. So the same spec and the same records in the
//! same order give the same file: a writer fed profiles 0, 1, 2, … (as `simulate` and
//! `merge` do) writes the same bytes whoever feeds it, one at a time or in batches.
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
use std::path::{Path, PathBuf};

use rayon::prelude::*;

use super::check::{RecordShape, Row};
use super::chunk::{self, Filling};
use super::column_stream::{ColumnRefused, ColumnStream};
use super::hdf5_ds::write_chunk;
use super::layout::{self, OpenFile};
use super::planes;
use super::spec::{ProfileRecord, RawFileSpec};
use crate::error::describe_hdf5_error;
use crate::error::{Error, Result};

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
/// tables and output buffer, ~300 kB).
pub fn buffer_bytes(row_bytes: usize, variables: usize, threads: usize) -> f64 {
    let chunk = layout::TARGET_CHUNK_BYTES.max(row_bytes) as f64;
    let flush = FLUSH_BYTES as f64 + chunk;
    variables as f64 * chunk + 2.0 * flush + 1.125 * flush + threads as f64 * 300e3
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

/// A chunk a batch completed: (position in the batch, variable, chunk index, bytes).
type Completed = (usize, usize, usize, Vec<u8>);

/// [`COLUMN_BLOCK`] profiles of the (profile) variables being filled.
struct ColumnBlock {
    time: Vec<f64>,
    n_shots: Vec<u64>,
    /// `pulse_energy`, channels × profiles, row-major.
    pulse_energy: Vec<f64>,
    /// The spec's (profile) variables, in its order.
    values: Vec<Vec<f64>>,
    /// `profile_column` and `profile_column_weight`, slots × profiles, row-major.
    columns: Vec<i32>,
    weights: Vec<f64>,
    present: usize,
}

/// Streams a raw lidar file, one profile at a time.
pub struct RawFileWriter {
    /// The user-facing path, for messages.
    display: PathBuf,
    /// `None` once closed (by `finish`, or by `Drop`).
    open: Option<OpenFile>,
    /// The streamed (column, …) truth ([`RawFileSpec::streamed_columns`]); `None` once
    /// closed.
    columns: Option<ColumnStream>,
    /// What records are checked against.
    shape: RecordShape,
    /// The chunks being filled of each of [`OpenFile::rows`].
    vars: Vec<Filling>,
    /// Complete chunks, in the order they were completed.
    ready: Vec<ReadyChunk>,
    ready_bytes: usize,
    /// Blocks of the (profile) variables being filled, by block index.
    blocks: BTreeMap<usize, ColumnBlock>,
    /// Chunk buffers already written, for reuse (at most [`SPARE_BYTES`] in all).
    spare: Vec<Vec<u8>>,
    /// Why an earlier write failed: the file is then unusable.
    failed: Option<String>,
    /// One bit per profile: written yet?
    written: Vec<u64>,
    n_written: usize,
}

impl RawFileWriter {
    /// Creates the file at exactly `path` (a fresh temporary name from
    /// [`crate::safe_file`]) and writes everything known up front. `display` is
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
        let mut open = layout::create_layout(path, spec).map_err(|e| {
            fail(format!(
                "cannot write: {}",
                describe_hdf5_error(&e.to_string())
            ))
        })?;
        let vars = open
            .rows
            .iter()
            .map(|v| {
                Filling::new(
                    v.elem_bytes,
                    v.chunk_rows,
                    spec.counts_per_profile(),
                    spec.n_profiles,
                )
            })
            .collect();
        let columns = ColumnStream::new(std::mem::take(&mut open.streamed), spec.n_columns);
        Ok(RawFileWriter {
            display: display.to_path_buf(),
            columns: Some(columns),
            open: Some(open),
            shape: RecordShape::of(spec),
            vars,
            ready: Vec::new(),
            ready_bytes: 0,
            blocks: BTreeMap::new(),
            spare: Vec::new(),
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
    /// file's [`super::spec::CountWidth`] (never wrapped or clamped). A failure to write (a
    /// full disk) leaves the writer unusable: every later call errors, and the caller
    /// drops the file.
    pub fn write_profile(&mut self, rec: &ProfileRecord) -> Result<()> {
        self.usable()?;
        let i = rec.index;
        let checked = self.shape.check(rec).and_then(|()| {
            match self.written.get(i / 64).map(|w| w & (1 << (i % 64))) {
                Some(0) => Ok(()),
                _ => Err(format!("profile {i} written twice")),
            }
        });
        checked.map_err(|r| Error::output(&self.display, r))?;
        if let Err(reason) = self.accept_one(rec) {
            self.failed = Some(reason.clone());
            return Err(Error::output(&self.display, reason));
        }
        self.written[i / 64] |= 1 << (i % 64);
        self.n_written += 1;
        Ok(())
    }

    /// Writes several profiles: the same file, byte for byte, as
    /// [`RawFileWriter::write_profile`] on each in turn, with the checks made and the
    /// chunks filled in parallel (one variable per worker). For a caller with nothing else
    /// for the threads to do: the writer alone, 64 profiles per call, rewrites the orbit's
    /// file in 0.57 s on two threads against 0.79 s one at a time, but 10–15 % slower on
    /// one thread (the records are read twice, checked then filled), and `simulate`,
    /// which overlaps the writer with its drawing, gained nothing from it: it hands
    /// profiles one at a time. Every record is checked before any is buffered: a refused
    /// batch (the first refused record named, or a profile given twice) leaves the writer
    /// as it was.
    pub fn write_profiles(&mut self, recs: &[ProfileRecord]) -> Result<()> {
        self.usable()?;
        self.check_batch(recs)
            .map_err(|r| Error::output(&self.display, r))?;
        if let Err(reason) = self.accept(recs) {
            self.failed = Some(reason.clone());
            return Err(Error::output(&self.display, reason));
        }
        for rec in recs {
            self.written[rec.index / 64] |= 1 << (rec.index % 64);
        }
        self.n_written += recs.len();
        Ok(())
    }

    /// Checks that every profile was written, writes what is still buffered and closes
    /// the file, flushing it. The caller syncs and renames it (through
    /// [`crate::safe_file`]).
    pub fn finish(mut self) -> Result<()> {
        self.usable()?;
        let n_profiles = self.shape.n_profiles;
        if self.n_written != n_profiles {
            let missing = (0..n_profiles).find(|&i| self.written[i / 64] & (1 << (i % 64)) == 0);
            return Err(Error::output(
                &self.display,
                format!(
                    "incomplete: {} of {} profiles written (first missing: {})",
                    self.n_written,
                    n_profiles,
                    missing.map_or_else(|| "?".into(), |i| i.to_string())
                ),
            ));
        }
        self.flush()
            .map_err(|reason| Error::output(&self.display, reason))?;
        if self.vars.iter().any(|f| !f.is_empty()) || !self.blocks.is_empty() {
            return Err(Error::output(
                &self.display,
                "internal: every profile was written but a chunk is incomplete",
            ));
        }
        if let Some(mut columns) = self.columns.take() {
            columns.finish().map_err(|e| {
                Error::output(
                    &self.display,
                    format!("cannot write: {}", describe_hdf5_error(&e.to_string())),
                )
            })?;
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

    /// Every check of a batch, before anything is buffered: each record's own checks
    /// (in parallel; the first refusal in the batch's order is reported), and no profile
    /// written before or twice in the batch.
    fn check_batch(&self, recs: &[ProfileRecord]) -> std::result::Result<(), String> {
        let shape = &self.shape;
        let checks: Vec<std::result::Result<(), String>> = if recs.len() > 1 {
            recs.par_iter().map(|r| shape.check(r)).collect()
        } else {
            recs.iter().map(|r| shape.check(r)).collect()
        };
        checks
            .into_iter()
            .collect::<std::result::Result<(), String>>()?;
        let mut indices: Vec<usize> = recs.iter().map(|r| r.index).collect();
        indices.sort_unstable();
        let twice = indices
            .windows(2)
            .find(|w| w[0] == w[1])
            .map(|w| w[0])
            .or_else(|| {
                indices
                    .iter()
                    .copied()
                    .find(|&i| self.written[i / 64] & (1 << (i % 64)) != 0)
            });
        match twice {
            Some(i) => Err(format!("profile {i} written twice")),
            None => Ok(()),
        }
    }

    /// Buffers a checked record: its rows into their chunks (by variable, each chunk it
    /// completes queued), its (profile) values into their block (written if complete),
    /// then a flush of the queue if it is full.
    fn accept_one(&mut self, rec: &ProfileRecord) -> std::result::Result<(), String> {
        let (rows, columns) = self.shape.split(rec);
        for (k, row) in rows.into_iter().enumerate() {
            if let Some((chunk, data)) = self.vars[k].put(rec.index, row, &mut self.spare)? {
                self.ready_bytes += data.len();
                self.ready.push(ReadyChunk {
                    var: k,
                    chunk,
                    data,
                });
            }
        }
        self.put_columns(rec, &columns)?;
        if self.ready_bytes >= FLUSH_BYTES {
            self.flush()?;
        }
        Ok(())
    }

    /// Buffers a checked batch and writes what it completes, in the order
    /// [`RawFileWriter::write_profile`] one record at a time would: for each record, the
    /// chunks it completes (by variable), its (profile) block if it completes one, then a
    /// flush of the queue if it is full.
    fn accept(&mut self, recs: &[ProfileRecord]) -> std::result::Result<(), String> {
        let shape = &self.shape;
        let split: Vec<(Vec<Row>, Vec<&[f64]>)> = recs.iter().map(|r| shape.split(r)).collect();
        // buffers for the chunks each variable opens in this batch
        let mut pools: Vec<Vec<Vec<u8>>> = Vec::with_capacity(self.vars.len());
        for var in &self.vars {
            let mut new_chunks: Vec<usize> = recs
                .iter()
                .filter(|r| !var.is_open(r.index))
                .map(|r| r.index / var.chunk_rows())
                .collect();
            new_chunks.dedup();
            let take = new_chunks.len().min(self.spare.len());
            pools.push(self.spare.split_off(self.spare.len() - take));
        }
        let fill = |(k, (var, pool)): (usize, (&mut Filling, &mut Vec<Vec<u8>>))| {
            let mut done = Vec::new();
            for (i, (rows, _)) in split.iter().enumerate() {
                if let Some((c, data)) = var.put(recs[i].index, rows[k], pool)? {
                    done.push((i, k, c, data));
                }
            }
            Ok(done)
        };
        let filled: Vec<std::result::Result<Vec<Completed>, String>> = if recs.len() > 1 {
            self.vars
                .par_iter_mut()
                .zip(pools.par_iter_mut())
                .enumerate()
                .map(fill)
                .collect()
        } else {
            self.vars
                .iter_mut()
                .zip(pools.iter_mut())
                .enumerate()
                .map(fill)
                .collect()
        };
        self.spare.extend(pools.into_iter().flatten());
        let mut completed: Vec<Completed> = Vec::new();
        for f in filled {
            completed.extend(f?);
        }
        completed.sort_by_key(|&(i, k, _, _)| (i, k));
        let mut completed = completed.into_iter().peekable();
        for (i, rec) in recs.iter().enumerate() {
            while let Some((_, var, chunk, data)) = completed.next_if(|c| c.0 == i) {
                self.ready_bytes += data.len();
                self.ready.push(ReadyChunk { var, chunk, data });
            }
            self.put_columns(rec, &split[i].1)?;
            if self.ready_bytes >= FLUSH_BYTES {
                self.flush()?;
            }
        }
        Ok(())
    }

    /// Puts the (profile) values of a record into their block, and writes the block when
    /// it is complete.
    fn put_columns(
        &mut self,
        rec: &ProfileRecord,
        values: &[&[f64]],
    ) -> std::result::Result<(), String> {
        let (b, r) = (rec.index / COLUMN_BLOCK, rec.index % COLUMN_BLOCK);
        let start = b * COLUMN_BLOCK;
        let len = COLUMN_BLOCK.min(self.shape.n_profiles - start);
        let slots = self.shape.column_slots;
        let block = self.blocks.entry(b).or_insert_with(|| ColumnBlock {
            time: vec![0.0; len],
            n_shots: vec![0; len],
            pulse_energy: vec![0.0; len * self.shape.n_channels],
            values: values.iter().map(|v| vec![0.0; len * v.len()]).collect(),
            columns: vec![0; len * slots],
            weights: vec![0.0; len * slots],
            present: 0,
        });
        block.columns[r * slots..(r + 1) * slots].copy_from_slice(rec.columns);
        block.weights[r * slots..(r + 1) * slots].copy_from_slice(rec.column_weights);
        block.time[r] = rec.time_s;
        block.n_shots[r] = rec.n_shots;
        let ch = self.shape.n_channels;
        block.pulse_energy[r * ch..(r + 1) * ch].copy_from_slice(rec.pulse_energy_j);
        for (column, v) in block.values.iter_mut().zip(values) {
            column[r * v.len()..(r + 1) * v.len()].copy_from_slice(v);
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
            let as_2d = |e: ndarray::ShapeError| hdf5::Error::from(e.to_string());
            let energy = ndarray::ArrayView2::from_shape((len, ch), &block.pulse_energy[..])
                .map_err(as_2d)?;
            open.pulse_energy.write_slice(energy, (range.clone(), ..))?;
            for (ds, column) in open.columns.iter().zip(&block.values) {
                match ds.ndim() {
                    1 => ds.write_slice(&column[..], range.clone())?,
                    _ => {
                        let width = column.len() / len;
                        let rows = ndarray::ArrayView2::from_shape((len, width), &column[..])
                            .map_err(as_2d)?;
                        ds.write_slice(rows, (range.clone(), ..))?
                    }
                }
            }
            if let Some((columns, weights)) = &open.profile_columns {
                let shape = (len, slots);
                let as_2d = |e: ndarray::ShapeError| hdf5::Error::from(e.to_string());
                let c =
                    ndarray::ArrayView2::from_shape(shape, &block.columns[..]).map_err(as_2d)?;
                let w =
                    ndarray::ArrayView2::from_shape(shape, &block.weights[..]).map_err(as_2d)?;
                columns.write_slice(c, (range.clone(), ..))?;
                weights.write_slice(w, (range.clone(), ..))?;
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
        let open = self.open.as_ref().ok_or("the writer is already closed")?;
        // compressed in parallel, in any order; `collect` keeps the queue's order
        let encoded: Vec<(ReadyChunk, Stored)> = ready
            .into_par_iter()
            .map(|c| {
                let v = &open.rows[c.var];
                let stored = if v.by_planes {
                    planes::deflate_planes(&c.data, v.elem_bytes)
                } else {
                    chunk::deflate(&c.data)
                };
                (c, stored)
            })
            .collect();
        for (c, stored) in encoded {
            let bytes = stored?;
            if self.spare.iter().map(Vec::len).sum::<usize>() + c.data.len() <= SPARE_BYTES {
                self.spare.push(c.data);
            }
            let v = &open.rows[c.var];
            let first = c.chunk * v.chunk_rows;
            write_chunk(&v.ds, &[first as u64, 0, 0], &bytes).map_err(|e| {
                let last = (first + v.chunk_rows).min(self.shape.n_profiles) - 1;
                format!(
                    "cannot write profiles {first}–{last} of `{}`: {}",
                    v.name,
                    describe_hdf5_error(&e.to_string())
                )
            })?;
        }
        Ok(())
    }
}

impl Drop for RawFileWriter {
    /// An unfinished writer closes its file; [`crate::safe_file`] deletes it.
    fn drop(&mut self) {
        self.columns.take();
        if let Some(open) = self.open.take() {
            let _ = open.close();
        }
    }
}

impl RawFileWriter {
    /// Writes column `c`'s truth ([`super::spec::ProfileSink::write_column`]); a refused
    /// column leaves the writer as it was, a failed write leaves it unusable.
    pub fn write_column(&mut self, c: usize, rows: &[&[f64]]) -> Result<()> {
        self.usable()?;
        let Some(columns) = self.columns.as_mut() else {
            return Err(Error::output(&self.display, "the writer is already closed"));
        };
        columns.put(c, rows).map_err(|e| match e {
            ColumnRefused::Refused(why) => Error::output(&self.display, why),
            ColumnRefused::Failed(why) => {
                let why = format!("cannot write: {}", describe_hdf5_error(&why));
                self.failed = Some(why.clone());
                Error::output(&self.display, why)
            }
        })
    }
}

impl super::spec::ProfileSink for RawFileWriter {
    fn write_profile(&mut self, rec: &ProfileRecord) -> Result<()> {
        RawFileWriter::write_profile(self, rec)
    }

    fn write_column(&mut self, column: usize, rows: &[&[f64]]) -> Result<()> {
        RawFileWriter::write_column(self, column, rows)
    }
}
