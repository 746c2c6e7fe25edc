//! Whole chunks of the (profile, channel, bin) variables, encoded exactly as HDF5's filter
//! pipeline `shuffle → deflate` stores them, so that they can be written with HDF5's
//! direct chunk write (`H5Dwrite_chunk`) and read back through the dataset's declared
//! filters by any HDF5 or netCDF-4 reader.
//!
//! * **Shuffle** (`H5Z_FILTER_SHUFFLE`, HDF5's `H5Zshuffle.c`): a chunk of `n` elements
//!   of `s` bytes is stored as `s` byte planes of `n` bytes each, plane `j` holding byte
//!   `j` (in the dataset's byte order) of every element: stored byte `j·n + i` is byte
//!   `j` of element `i`. HDF5 shuffles the whole chunk buffer, edge chunks included (their
//!   rows past the dataset's end hold the fill value, 0 here); a chunk of one element, or
//!   of one-byte elements, is left as it is, which is the same layout. Chunks here always
//!   hold a whole number of elements, so `H5Zshuffle.c`'s "leftover" bytes never occur.
//!   Rows are scattered into their planes as they arrive ([`put_row`]), so a chunk
//!   buffer is always in shuffled layout and needs no separate pass.
//! * **Deflate** (`H5Z_FILTER_DEFLATE`): a zlib stream (RFC 1950: header, deflate data,
//!   Adler-32), which HDF5 inflates with zlib whatever produced it. The compressor is
//!   `miniz_oxide` at [`DEFLATE_LEVEL`] (chosen by measurement, see
//!   `validation/reports/writer.md`): pure Rust with no CPU-dependent code path, so the
//!   bytes of a chunk depend on its data (and the crate's version, pinned in
//!   `Cargo.lock`) only, whatever the machine or thread that compressed it. The count
//!   variables' chunks are one zlib stream too, assembled byte plane by byte plane with
//!   the planes of noise stored rather than compressed (`planes.rs`).

use std::cell::RefCell;
use std::collections::BTreeMap;
use std::collections::btree_map::Entry;

use miniz_oxide::deflate::core::CompressionStrategy;

use super::check::Row;
use miniz_oxide::DataFormat;
use miniz_oxide::deflate::core::{
    CompressorOxide, TDEFLFlush, TDEFLStatus, compress_to_output, create_comp_flags_from_zip_params,
};

/// Deflate level of every chunked variable: miniz_oxide's level 1 (greedy parsing, one
/// probe) stores shuffled counts as compactly as zlib's level 1 at twice its speed.
pub const DEFLATE_LEVEL: u8 = 1;

/// Writes `row` into a chunk buffer in shuffled layout: the chunk holds `elems` elements
/// of `elem_bytes` bytes (`buf.len() == elems · elem_bytes`), and the row's values are
/// elements `at .. at + row.len()`. `bits` gives a value's bits in the low `8·elem_bytes`
/// bits of a u64 (a count truncated to the file's width was range-checked before;
/// `f64::to_bits` for floats), stored in the machine's byte order as the dataset's
/// native type is.
pub fn put_row<T: Copy>(
    buf: &mut [u8],
    elems: usize,
    at: usize,
    elem_bytes: usize,
    row: &[T],
    bits: impl Fn(T) -> u64,
) {
    debug_assert_eq!(buf.len(), elems * elem_bytes);
    debug_assert!(at + row.len() <= elems);
    match elem_bytes {
        2 => put_planes::<T, 2>(buf, elems, at, row, bits),
        4 => put_planes::<T, 4>(buf, elems, at, row, bits),
        8 => put_planes::<T, 8>(buf, elems, at, row, bits),
        _ => put_planes::<T, 1>(buf, elems, at, row, bits),
    }
}

/// [`put_row`] for `S`-byte elements: one pass over the row per byte plane, with the
/// byte's shift known at compile time.
fn put_planes<T: Copy, const S: usize>(
    buf: &mut [u8],
    elems: usize,
    at: usize,
    row: &[T],
    bits: impl Fn(T) -> u64,
) {
    for (j, plane) in buf.chunks_exact_mut(elems).take(S).enumerate() {
        // byte j of the element as stored (native order)
        let byte = if cfg!(target_endian = "little") {
            j
        } else {
            S - 1 - j
        };
        let shift = 8 * byte as u32;
        let dst = &mut plane[at..at + row.len()];
        for (d, &v) in dst.iter_mut().zip(row) {
            *d = (bits(v) >> shift) as u8;
        }
    }
}

/// A chunk being filled.
struct OpenChunk {
    /// Shuffled bytes, `chunk_rows × row_elems` elements.
    data: Vec<u8>,
    /// Rows written into it so far.
    present: usize,
}

/// The chunks being filled of one (profile, channel, bin) variable, by chunk index. For
/// profiles sent in order, one at a time.
pub struct Filling {
    elem_bytes: usize,
    chunk_rows: usize,
    row_elems: usize,
    n_profiles: usize,
    open: BTreeMap<usize, OpenChunk>,
}

impl Filling {
    /// A variable of `n_profiles` rows of `row_elems` elements of `elem_bytes` bytes,
    /// `chunk_rows` rows per chunk.
    pub fn new(elem_bytes: usize, chunk_rows: usize, row_elems: usize, n_profiles: usize) -> Self {
        Filling {
            elem_bytes,
            chunk_rows,
            row_elems,
            n_profiles,
            open: BTreeMap::new(),
        }
    }

    /// Profiles per chunk.
    pub fn chunk_rows(&self) -> usize {
        self.chunk_rows
    }

    /// Whether no chunk is being filled.
    pub fn is_empty(&self) -> bool {
        self.open.is_empty()
    }

    /// Whether the chunk of profile `row` is being filled already.
    pub fn is_open(&self, row: usize) -> bool {
        self.open.contains_key(&(row / self.chunk_rows))
    }

    /// Puts profile `row` (checked: in range, not put before, `row_elems` values) into
    /// its chunk, taking a buffer from `spare` (or a new one) for a new chunk; returns the
    /// chunk's index and bytes when this row completes it. Errors only if a new chunk's
    /// memory cannot be had.
    pub fn put(
        &mut self,
        row: usize,
        values: Row,
        spare: &mut Vec<Vec<u8>>,
    ) -> Result<Option<(usize, Vec<u8>)>, String> {
        let (c, r) = (row / self.chunk_rows, row % self.chunk_rows);
        let elems = self.chunk_rows * self.row_elems;
        let rows_in_chunk = self.chunk_rows.min(self.n_profiles - c * self.chunk_rows);
        let open = match self.open.entry(c) {
            Entry::Occupied(e) => e.into_mut(),
            Entry::Vacant(e) => {
                let size = elems * self.elem_bytes;
                let data = match spare.pop() {
                    // every byte of a full chunk is overwritten by its rows; an edge
                    // chunk's rows past the end hold the fill value, 0
                    Some(mut b) => {
                        b.resize(size, 0);
                        if rows_in_chunk < self.chunk_rows {
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
        let at = r * self.row_elems;
        match values {
            Row::Counts(v) => put_row(&mut open.data, elems, at, self.elem_bytes, v, |c| c),
            Row::Floats(v) => put_row(&mut open.data, elems, at, self.elem_bytes, v, f64::to_bits),
        }
        open.present += 1;
        if open.present < rows_in_chunk {
            return Ok(None);
        }
        Ok(self.open.remove(&c).map(|done| (c, done.data)))
    }
}

/// A compressor at [`DEFLATE_LEVEL`], reused from chunk to chunk (one per thread):
/// `reset` clears every table, so a chunk's bytes do not depend on the chunks compressed
/// before it.
///
/// Output goes through miniz_oxide's callback (`compress_to_output`), which always
/// writes through the compressor's internal buffer, so the stream is a function of the
/// input only. (Given an output slice instead, miniz_oxide writes into it directly while
/// more than its internal buffer, ~83 KiB, is left and through that buffer otherwise,
/// stopping and resuming when the slice is full, which moves block boundaries: a first
/// version of the writer whose slice depended on the thread's history wrote different
/// bytes with one and two threads, `validation/reports/writer.md`.)
pub(super) struct Deflater {
    compressor: CompressorOxide,
}

thread_local! {
    static DEFLATER: RefCell<Option<Box<Deflater>>> = const { RefCell::new(None) };
}

impl Deflater {
    fn new() -> Box<Deflater> {
        let flags = create_comp_flags_from_zip_params(
            i32::from(DEFLATE_LEVEL),
            15, // zlib header and Adler-32, 32 KiB window
            CompressionStrategy::Default as i32,
        );
        Box::new(Deflater {
            compressor: CompressorOxide::new(flags),
        })
    }

    /// Runs `f` with this thread's compressor.
    pub(super) fn with<R>(f: impl FnOnce(&mut Deflater) -> R) -> R {
        DEFLATER.with(|cell| f(cell.borrow_mut().get_or_insert_with(Deflater::new)))
    }

    /// Appends to `out` the whole of `input` compressed in `format` and ended by `flush`:
    /// [`TDEFLFlush::Finish`] for a complete zlib stream (RFC 1950 §2.2: header, final
    /// block, Adler-32), [`TDEFLFlush::Sync`] for raw deflate blocks (RFC 1951 §3.2),
    /// none of them final, ending with an empty stored block, so byte-aligned.
    pub(super) fn compress_into(
        &mut self,
        input: &[u8],
        format: DataFormat,
        flush: TDEFLFlush,
        out: &mut Vec<u8>,
    ) -> Result<(), String> {
        self.compressor.set_format_and_level(format, DEFLATE_LEVEL);
        self.compressor.reset();
        let (status, used) = compress_to_output(&mut self.compressor, input, flush, |bytes| {
            out.extend_from_slice(bytes);
            true
        });
        let expected = match flush {
            TDEFLFlush::Finish => TDEFLStatus::Done,
            _ => TDEFLStatus::Okay,
        };
        if status != expected || used != input.len() {
            return Err(format!(
                "deflate failed ({status:?} after {used} of {} bytes)",
                input.len()
            ));
        }
        Ok(())
    }
}

/// Deflates a shuffled chunk into one zlib stream, as `H5Z_FILTER_DEFLATE` stores it
/// (with this thread's compressor).
pub fn deflate(shuffled: &[u8]) -> Result<Vec<u8>, String> {
    // room for what a chunk that compresses well takes; more is grown into if needed,
    // the rest given back (in place: a shrinking realloc does not copy)
    let mut out = Vec::with_capacity(shuffled.len() / 4 + 64);
    Deflater::with(|d| d.compress_into(shuffled, DataFormat::Zlib, TDEFLFlush::Finish, &mut out))?;
    out.shrink_to_fit();
    Ok(out)
}

/// Undoes [`deflate`] (any zlib stream); for checks.
pub fn inflate(stored: &[u8]) -> Result<Vec<u8>, String> {
    miniz_oxide::inflate::decompress_to_vec_zlib(stored)
        .map_err(|e| format!("not a zlib stream: {e}"))
}

/// Undoes the shuffle of a chunk of `elem_bytes`-byte elements: back to the elements'
/// bytes one after the other; for checks.
pub fn unshuffle(shuffled: &[u8], elem_bytes: usize) -> Vec<u8> {
    let n = shuffled.len() / elem_bytes.max(1);
    let mut out = vec![0u8; shuffled.len()];
    for (j, plane) in shuffled.chunks_exact(n.max(1)).enumerate() {
        for (i, &b) in plane.iter().enumerate() {
            out[i * elem_bytes + j] = b;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// HDF5's shuffle, transcribed from `H5Z__filter_shuffle` in `H5Zshuffle.c`
    /// (compression direction): `dest[i·n + j] = src[j·s + i]` for byte `i` of element
    /// `j`, plus any leftover bytes copied at the end.
    fn hdf5_shuffle(src: &[u8], s: usize) -> Vec<u8> {
        let n = src.len() / s;
        if s <= 1 || n <= 1 {
            return src.to_vec();
        }
        let mut dest = vec![0u8; src.len()];
        for i in 0..s {
            for j in 0..n {
                dest[i * n + j] = src[j * s + i];
            }
        }
        let leftover = src.len() % s;
        dest[n * s..].copy_from_slice(&src[n * s..n * s + leftover]);
        dest
    }

    #[test]
    fn rows_put_one_by_one_equal_hdf5_shuffle_of_the_whole_chunk() {
        for (elem_bytes, rows, width) in [
            (2usize, 5usize, 7usize),
            (4, 3, 11),
            (8, 4, 5),
            (8, 1, 1),
            (8, 3, 37),
            (8, 2, 16),
        ] {
            let elems = rows * width;
            let mut buf = vec![0u8; elems * elem_bytes];
            let mut native = Vec::new();
            // rows out of order, the last one missing (an edge chunk's padding)
            let order: Vec<usize> = (0..rows.saturating_sub(1)).rev().collect();
            let mask = if elem_bytes == 8 {
                u64::MAX
            } else {
                (1u64 << (8 * elem_bytes)) - 1
            };
            let value = |r: usize, k: usize| {
                (0x0123_4567_89ab_cdefu64.wrapping_mul((r * width + k + 1) as u64)) & mask
            };
            for &r in &order {
                let row: Vec<u64> = (0..width).map(|k| value(r, k)).collect();
                put_row(&mut buf, elems, r * width, elem_bytes, &row, |v| v);
            }
            for r in 0..rows {
                for k in 0..width {
                    let v = if order.contains(&r) { value(r, k) } else { 0 };
                    native.extend_from_slice(&v.to_ne_bytes()[..elem_bytes]);
                }
            }
            assert_eq!(
                buf,
                hdf5_shuffle(&native, elem_bytes),
                "{elem_bytes} B × {elems}"
            );
            assert_eq!(unshuffle(&buf, elem_bytes), native);
        }
    }

    #[test]
    fn f64_rows_keep_their_bits() {
        let row = [1.5f64, -0.0, 3.25e-300, f64::MAX];
        let mut buf = vec![0u8; 32];
        put_row(&mut buf, 4, 0, 8, &row, f64::to_bits);
        let back: Vec<f64> = unshuffle(&buf, 8)
            .chunks_exact(8)
            .map(|b| f64::from_ne_bytes(b.try_into().unwrap()))
            .collect();
        assert_eq!(
            back.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
            row.map(f64::to_bits)
        );
    }

    #[test]
    fn deflate_makes_a_zlib_stream_that_inflates_back() {
        let data: Vec<u8> = (0..100_000u32).map(|i| (i % 251 / 7) as u8).collect();
        let z = deflate(&data).unwrap();
        // zlib header: CM = 8 (deflate), window 32 KiB, FCHECK makes it a multiple of 31
        assert_eq!(z[0], 0x78);
        assert_eq!((u16::from(z[0]) << 8 | u16::from(z[1])) % 31, 0);
        assert!(z.len() < data.len() / 4);
        assert_eq!(inflate(&z).unwrap(), data);
        assert_eq!(
            deflate(&data).unwrap(),
            z,
            "the same data gives the same bytes"
        );
        // incompressible input
        let noise: Vec<u8> = (0..3_000_000u64)
            .map(|i| (i.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 56) as u8)
            .collect();
        let zn = deflate(&noise).unwrap();
        assert!(zn.len() <= noise.len() + noise.len() / 1000 + 64);
        assert_eq!(inflate(&zn).unwrap(), noise);
        // a compressor whose buffers grew on other data gives the same bytes as a fresh one
        assert_eq!(deflate(&data).unwrap(), z);
        let fresh = std::thread::spawn(move || deflate(&data).unwrap())
            .join()
            .unwrap();
        assert_eq!(fresh, z);
    }

    /// Chunks of f64 that compress poorly (as the orbit's truth does, to about 3/4),
    /// where miniz_oxide's output depends on its output room: a thread that compressed a
    /// large chunk first and fresh threads give the same bytes for every chunk.
    #[test]
    fn the_bytes_do_not_depend_on_the_thread_history() {
        let elems = 48 * 1354;
        let chunks: Vec<Vec<u8>> = (0..4)
            .map(|c| {
                let row: Vec<f64> = (0..elems)
                    .map(|i| {
                        // smooth, with noisy low mantissa bits: compresses to about 3/4
                        let x = (c * elems + i) as f64;
                        let noise = (x as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 40;
                        (1.0 + (x * 1e-3).sin().abs()) * (1.0 + noise as f64 * 1e-16)
                    })
                    .collect();
                let mut buf = vec![0u8; elems * 8];
                put_row(&mut buf, elems, 0, 8, &row, f64::to_bits);
                buf
            })
            .collect();
        let big: Vec<u8> = (0..5_000_000u64)
            .map(|i| (i.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 56) as u8)
            .collect();
        let worked = {
            let chunks = chunks.clone();
            std::thread::spawn(move || {
                deflate(&big).unwrap();
                chunks
                    .iter()
                    .map(|c| deflate(c).unwrap())
                    .collect::<Vec<_>>()
            })
        };
        let fresh: Vec<Vec<u8>> = chunks
            .iter()
            .map(|c| {
                let c = c.clone();
                std::thread::spawn(move || deflate(&c).unwrap())
                    .join()
                    .unwrap()
            })
            .collect();
        assert_eq!(worked.join().unwrap(), fresh);
        for (c, z) in chunks.iter().zip(&fresh) {
            assert_eq!(&inflate(z).unwrap(), c);
        }
    }
}
