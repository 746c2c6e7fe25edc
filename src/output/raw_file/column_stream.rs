//! The (column, …) truth of a scene whose columns are built as its profiles need them
//! (`RawFileSpec::streamed_columns`): each column's rows arrive once, in any order
//! (`ProfileSink::write_column`), are gathered into the variables' chunks (the same
//! number of columns in every streamed variable's chunk, set by `layout.rs`) and
//! each chunk is written when its last column arrives. Memory: one chunk being filled
//! per variable and open chunk (a run builds its columns in track order, so one or two
//! are open at a time). A chunk still open at the end (the columns a shard's profiles do
//! not see) is written with NaN, the variables' `_FillValue`, where no column came.

use std::collections::BTreeMap;

use hdf5::Dataset;
use rayon::prelude::*;

use super::chunk;
use super::hdf5_ds::write_chunk;

/// Why [`ColumnStream::put`] did not take a column.
pub enum ColumnRefused {
    /// The column is out of range, came before or has rows of the wrong lengths: nothing
    /// taken.
    Refused(String),
    /// Writing its chunk failed (HDF5's message): the file is unusable.
    Failed(String),
}

/// One streamed variable: its dataset, values per column, columns per chunk.
pub struct StreamedVar {
    pub ds: Dataset,
    pub row_len: usize,
    /// `Some(channels)` for (column, channel, bin), `None` for (column, bin).
    pub channels: Option<usize>,
    pub chunk_columns: usize,
}

/// A chunk of columns being filled: per variable its values (NaN where no column came
/// yet) and how many columns came.
struct OpenChunk {
    values: Vec<Vec<f64>>,
    present: usize,
}

/// The streamed column truth of one file.
pub struct ColumnStream {
    vars: Vec<StreamedVar>,
    n_columns: usize,
    open: BTreeMap<usize, OpenChunk>,
    /// One bit per column: written yet?
    written: Vec<u64>,
}

impl ColumnStream {
    /// The stream of `vars` (in the spec's order) over `n_columns` columns.
    pub fn new(vars: Vec<StreamedVar>, n_columns: usize) -> Self {
        ColumnStream {
            vars,
            n_columns,
            open: BTreeMap::new(),
            written: vec![0; n_columns.div_ceil(64)],
        }
    }

    /// Takes column `c`'s rows, one per streamed variable in the spec's order; writes
    /// the chunk it completes. Errors (nothing taken) if `c` is out of range or came
    /// before, or a row's length is not its variable's.
    pub fn put(&mut self, c: usize, rows: &[&[f64]]) -> Result<(), ColumnRefused> {
        let refuse = |why: String| Err(ColumnRefused::Refused(why));
        if c >= self.n_columns {
            return refuse(format!("column {c} of {}", self.n_columns));
        }
        if self.written[c / 64] & (1 << (c % 64)) != 0 {
            return refuse(format!("column {c} written twice"));
        }
        if rows.len() != self.vars.len() {
            return refuse(format!(
                "column {c}: {} rows for {} column variables",
                rows.len(),
                self.vars.len()
            ));
        }
        if let Some((v, r)) = self
            .vars
            .iter()
            .zip(rows)
            .find(|(v, r)| r.len() != v.row_len)
        {
            return refuse(format!(
                "column {c}: {} values for `{}`'s {}",
                r.len(),
                v.ds.name(),
                v.row_len
            ));
        }
        let per = self.vars[0].chunk_columns;
        let chunk = c / per;
        let vars = &self.vars;
        let empty = || OpenChunk {
            values: (vars.iter())
                .map(|v| vec![f64::NAN; v.row_len * per])
                .collect(),
            present: 0,
        };
        let open = self.open.entry(chunk).or_insert_with(empty);
        let at = c % per;
        for ((dst, v), row) in open.values.iter_mut().zip(vars).zip(rows) {
            dst[at * v.row_len..(at + 1) * v.row_len].copy_from_slice(row);
        }
        open.present += 1;
        self.written[c / 64] |= 1 << (c % 64);
        let columns_in_chunk = per.min(self.n_columns - chunk * per);
        if open.present == columns_in_chunk {
            let done = self.open.remove(&chunk).expect("the chunk just filled");
            self.write_chunk(chunk, &done)
                .map_err(|e| ColumnRefused::Failed(e.to_string()))?;
        }
        Ok(())
    }

    /// Writes every chunk not written yet, NaN where no column came (every chunk is
    /// stored: readers refuse a file whose datasets hold fewer bytes than they declare).
    pub fn finish(&mut self) -> hdf5::Result<()> {
        let Some(per) = self.vars.first().map(|v| v.chunk_columns) else {
            return Ok(());
        };
        let mut open = std::mem::take(&mut self.open);
        for chunk in 0..self.n_columns.div_ceil(per) {
            let first = chunk * per;
            let last = (first + per).min(self.n_columns);
            let complete = (first..last).all(|c| self.written[c / 64] & (1 << (c % 64)) != 0);
            let values = match open.remove(&chunk) {
                Some(values) => values,
                // written when its last column came
                None if complete => continue,
                None => self.empty_chunk(),
            };
            self.write_chunk(chunk, &values)?;
        }
        Ok(())
    }

    /// A chunk no column came to: NaN everywhere.
    fn empty_chunk(&self) -> OpenChunk {
        OpenChunk {
            values: (self.vars.iter())
                .map(|v| vec![f64::NAN; v.row_len * v.chunk_columns])
                .collect(),
            present: 0,
        }
    }

    /// Writes chunk `chunk` of every variable as HDF5 stores it (shuffled and deflated
    /// as the dataset's filters would, [`chunk::deflate`]), the variables compressed in
    /// parallel; the edge chunk past the last column is padded with zeros.
    fn write_chunk(&self, chunk: usize, done: &OpenChunk) -> hdf5::Result<()> {
        let encoded: Vec<Result<Vec<u8>, String>> = self
            .vars
            .par_iter()
            .zip(&done.values)
            .map(|(v, values)| {
                let a = chunk * v.chunk_columns;
                let b = (a + v.chunk_columns).min(self.n_columns);
                let mut padded = values.clone();
                padded[(b - a) * v.row_len..].fill(0.0);
                chunk::deflate(&shuffled(&padded))
            })
            .collect();
        for (v, bytes) in self.vars.iter().zip(encoded) {
            let bytes = bytes.map_err(|e| hdf5::Error::from(e.as_str()))?;
            let first = (chunk * v.chunk_columns) as u64;
            let offset: Vec<u64> = match v.channels {
                Some(_) => vec![first, 0, 0],
                None => vec![first, 0],
            };
            write_chunk(&v.ds, &offset, &bytes)?;
        }
        Ok(())
    }
}

/// The bytes of `values` in HDF5's shuffle order: every value's first byte, then every
/// second byte, … (`H5Z_FILTER_SHUFFLE` of 8-byte elements).
fn shuffled(values: &[f64]) -> Vec<u8> {
    let n = values.len();
    let mut out = vec![0u8; 8 * n];
    for (i, v) in values.iter().enumerate() {
        for (j, b) in v.to_le_bytes().into_iter().enumerate() {
            out[j * n + i] = b;
        }
    }
    out
}
