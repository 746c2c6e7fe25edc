//! Chunks of fresh random draws (the counts) encoded byte plane by byte plane: one zlib
//! stream per chunk, as `H5Z_FILTER_DEFLATE` stores it, in which each of the shuffled
//! chunk's byte planes is either deflated or, when its bytes are noise that deflate
//! cannot shrink, copied into stored blocks without running the compressor over it.
//!
//! The stream (RFC 1950 §2.2, RFC 1951 §3.2), readable by any inflater (zlib, so every
//! HDF5 and netCDF-4 reader, through the dataset's declared shuffle + deflate filters):
//!
//! * the zlib header, `78 01` (deflate, 32 KiB window, level "fastest"), as
//!   [`deflate`] writes it;
//! * per byte plane, in order: either raw deflate blocks from a compressor reset for that
//!   plane (so no back-reference reaches outside it), none final, ended by a sync flush
//!   (an empty stored block, so the plane's blocks end on a byte boundary); or stored
//!   blocks (§3.2.4) of at most 65,535 bytes, each a header byte `00` (BFINAL 0, BTYPE
//!   00, the rest padding), LEN and NLEN (its ones' complement), little-endian, then the
//!   bytes;
//! * a final empty stored block, `01 00 00 FF FF`;
//! * the Adler-32 of the whole uncompressed chunk (§2.2, §9), big-endian, by
//!   `simd-adler32` (the implementation miniz_oxide itself uses in this build, through
//!   its `simd` feature; `adler2`, its fallback, is scalar and took 3 % of a scenario-1
//!   run against 0.4 %).
//!
//! Which planes are stored ([`is_noise`]) depends on the plane's bytes only, so a chunk's
//! bytes are the same whatever the thread or machine that encoded it.

use miniz_oxide::DataFormat;
use miniz_oxide::deflate::core::TDEFLFlush;

use super::chunk::{Deflater, deflate};

/// The zlib header: CMF `78` (CM 8 = deflate, CINFO 7 = 32 KiB window), FLG `01` (FLEVEL
/// 0, "fastest", as miniz_oxide writes for level 1; FCHECK makes `0x7801` a multiple of
/// 31), RFC 1950 §2.2.
const ZLIB_HEADER: [u8; 2] = [0x78, 0x01];
/// The most bytes a stored block holds (its LEN is 16 bits), RFC 1951 §3.2.4.
pub const MAX_STORED: usize = 65_535;
/// A final, empty stored block: BFINAL 1, BTYPE 00, padding, LEN 0, NLEN 0xFFFF.
const FINAL_EMPTY_BLOCK: [u8; 5] = [0x01, 0x00, 0x00, 0xFF, 0xFF];
/// A plane is stored when its bytes' order-0 entropy is at least this many thousandths
/// of 8 bits per byte. Measured on the low-byte planes of counts (scenario 1 at seven
/// accumulation times, `validation/noise_planes.rs`, `validation/reports/writer.md`
/// "Noise planes stored"), deflate level 1 shrinks such a plane to its entropy plus
/// 0.2–0.6 % (0.949 → 0.951, 0.970 → 0.976, 0.987 → 0.993): from 0.965 on it could save
/// at most ~3 % of the plane, and storing it instead makes the chunk ~1.7× faster.
pub const NOISE_ENTROPY_MILLI: u64 = 965;
/// Bytes of a plane that [`entropy_milli`] looks at, about: measured, a full histogram
/// costs a quarter of a counts chunk's deflate time, a sample of 4,096 bytes ~1 %,
/// within ±0.003 of the full plane's entropy.
const SAMPLE_BYTES: usize = 4096;
/// Fraction bits of the fixed-point base-2 logarithms of [`entropy_milli`].
const LOG2_FRAC_BITS: u32 = 16;

/// Encodes a shuffled chunk of `elem_bytes`-byte elements into one zlib stream: if
/// [`is_noise`] finds any of its byte planes incompressible, by planes ([`encode`]),
/// those stored and the others deflated; otherwise deflated whole ([`deflate`]: measured
/// on such chunks, 1–6 % faster than by planes for 1–3 % more bytes, and the bytes the
/// writer stored before planes were). A chunk whose length is not a multiple of
/// `elem_bytes` (never the writer's) is taken as one plane.
pub fn deflate_planes(shuffled: &[u8], elem_bytes: usize) -> Result<Vec<u8>, String> {
    let n = shuffled.len() / elem_bytes.max(1);
    let planes: Vec<(&[u8], bool)> = if n == 0 || n * elem_bytes != shuffled.len() {
        vec![(shuffled, is_noise(shuffled))]
    } else {
        shuffled.chunks_exact(n).map(|p| (p, is_noise(p))).collect()
    };
    if planes.iter().any(|&(_, stored)| stored) {
        encode(&planes)
    } else {
        deflate(shuffled)
    }
}

/// One zlib stream of `planes` (bytes, stored?) in order, as the module describes.
pub fn encode(planes: &[(&[u8], bool)]) -> Result<Vec<u8>, String> {
    // stored planes take their length and 5 bytes a block; deflated ones, judged
    // compressible, most often under half of theirs (more is grown into if needed)
    let room: usize = planes
        .iter()
        .map(|&(p, stored)| {
            if stored {
                p.len() + 5 * p.len().div_ceil(MAX_STORED)
            } else {
                p.len() / 2 + 16
            }
        })
        .sum();
    let mut out = Vec::with_capacity(ZLIB_HEADER.len() + room + FINAL_EMPTY_BLOCK.len() + 4);
    out.extend_from_slice(&ZLIB_HEADER);
    let mut adler = simd_adler32::Adler32::new();
    for &(plane, stored) in planes {
        adler.write(plane);
        if plane.is_empty() {
            continue;
        }
        if stored {
            put_stored(&mut out, plane);
        } else {
            Deflater::with(|d| {
                d.compress_into(plane, DataFormat::Raw, TDEFLFlush::Sync, &mut out)
            })?;
        }
    }
    out.extend_from_slice(&FINAL_EMPTY_BLOCK);
    out.extend_from_slice(&adler.finish().to_be_bytes());
    out.shrink_to_fit();
    Ok(out)
}

/// Appends `data` as non-final stored blocks (RFC 1951 §3.2.4), from a byte boundary.
fn put_stored(out: &mut Vec<u8>, data: &[u8]) {
    for block in data.chunks(MAX_STORED) {
        // `chunks` gives at most MAX_STORED = u16::MAX bytes
        let len = u16::try_from(block.len()).unwrap_or(u16::MAX);
        out.push(0x00);
        out.extend_from_slice(&len.to_le_bytes());
        out.extend_from_slice(&(!len).to_le_bytes());
        out.extend_from_slice(block);
    }
}

/// Whether a plane's bytes are noise that deflate cannot shrink by more than ~3 %: their
/// order-0 entropy ([`entropy_milli`]) is at least [`NOISE_ENTROPY_MILLI`]/1000 of 8
/// bits per byte. Deflate's Huffman codes (RFC 1951 §3.2.2) code bytes no shorter than
/// their order-0 entropy, and its LZ77 matches (§4) find next to nothing in fresh random
/// draws: measured, such planes deflate to their entropy plus ~0.6 %. Data repeated from
/// row to row (a changing scene's truth) is another matter, which is why only fresh draws
/// are encoded by planes.
pub fn is_noise(plane: &[u8]) -> bool {
    !plane.is_empty() && entropy_milli(plane) >= NOISE_ENTROPY_MILLI
}

/// The order-0 entropy of `bytes` in thousandths of 8 bits per byte, rounded down (0 for
/// no bytes), estimated from a sample: every `s`-th byte, `s` the odd number at or just
/// above `⌊len / SAMPLE_BYTES⌋` (odd, so that rows of a power-of-two number of bins are
/// not sampled at the same few bins): 2,731 to 5,461 bytes of a plane of 8 KiB or
/// more, every byte of a shorter one, so under 2 · `SAMPLE_BYTES` in all cases. The
/// plug-in estimate `Σ c·log2(n/c)` over the sample's byte histogram (`n` bytes, `c` of
/// each value) plus Miller and Madow's correction for its bias, `(k − 1) / (2 ln 2)` bits
/// for `k` values seen. Integer arithmetic throughout, so the same on every machine.
pub fn entropy_milli(bytes: &[u8]) -> u64 {
    let step = (bytes.len() / SAMPLE_BYTES).max(1) | 1;
    let (hist, n) = histogram(bytes, step);
    if n == 0 {
        return 0;
    }
    let log_n = log2_of(n);
    let mut bits = 0u128;
    let mut seen = 0u128;
    for &c in hist.iter().filter(|&&c| c > 0) {
        bits += u128::from(c) * u128::from(log_n.saturating_sub(log2_of(c)));
        seen += 1;
    }
    // 2^16 / (2 ln 2), the correction per value seen in fixed point
    bits += (seen - 1) * 47_274;
    let milli = bits * 1000 / ((u128::from(n) * 8) << LOG2_FRAC_BITS);
    u64::try_from(milli.min(1000)).unwrap_or(1000)
}

/// The histogram of every `step`-th byte of `bytes` (`step` ≥ 1), and how many were
/// counted: over two tables, so that runs of one value do not wait on one counter.
fn histogram(bytes: &[u8], step: usize) -> ([u64; 256], u64) {
    // at most 2 · SAMPLE_BYTES bytes are counted: u32 counters suffice
    let mut t = [[0u32; 256]; 2];
    let mut sample = bytes.iter().step_by(step.max(1));
    while let Some(&a) = sample.next() {
        t[0][usize::from(a)] += 1;
        let Some(&b) = sample.next() else { break };
        t[1][usize::from(b)] += 1;
    }
    let mut n = 0;
    let mut h = [0u64; 256];
    for (v, slot) in h.iter_mut().enumerate() {
        *slot = u64::from(t[0][v]) + u64::from(t[1][v]);
        n += *slot;
    }
    (h, n)
}

/// `log2(x)` in fixed point with [`LOG2_FRAC_BITS`] fraction bits, rounded down (to
/// within 2^-16 for `x` below 2^32; 0 for 0): the integer part from the leading bit, the
/// fraction bit by bit by squaring the mantissa (a Q31 number in [1, 2), so that its
/// square fits in 64 bits). Looked up for the counts of a sample ([`LOG2_TABLE`]).
const fn log2_fixed(x: u64) -> u64 {
    if x == 0 {
        return 0;
    }
    let int = 63 - x.leading_zeros();
    let mut m = if int <= 31 {
        x << (31 - int)
    } else {
        x >> (int - 31)
    };
    let mut frac = 0u64;
    let mut bit = LOG2_FRAC_BITS;
    while bit > 0 {
        bit -= 1;
        m = (m * m) >> 31;
        if m >= 2 << 31 {
            m >>= 1;
            frac |= 1 << bit;
        }
    }
    ((int as u64) << LOG2_FRAC_BITS) | frac
}

/// [`log2_fixed`] of 0 to 2 · [`SAMPLE_BYTES`] − 1, every count a sample can hold,
/// computed at compile time: computing the 256 logarithms of a plane's histogram each
/// time cost more than the sampling.
static LOG2_TABLE: [u32; 2 * SAMPLE_BYTES] = {
    let mut t = [0u32; 2 * SAMPLE_BYTES];
    let mut i = 0;
    while i < t.len() {
        t[i] = log2_fixed(i as u64) as u32;
        i += 1;
    }
    t
};

/// [`log2_fixed`] of `x`, looked up when [`LOG2_TABLE`] holds it.
fn log2_of(x: u64) -> u64 {
    match usize::try_from(x).ok().and_then(|i| LOG2_TABLE.get(i)) {
        Some(&v) => u64::from(v),
        None => log2_fixed(x),
    }
}

#[cfg(test)]
mod tests;
