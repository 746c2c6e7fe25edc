//! Chunks of fresh random draws (the counts) encoded byte plane by byte plane: one zlib
//! stream per chunk, as `H5Z_FILTER_DEFLATE` stores it, in which each of the shuffled
//! chunk's byte planes is either deflated or, when its bytes are noise that deflate
//! cannot shrink, copied into stored blocks without running the compressor over it.
//!
//! The stream (RFC 1950 §2.2, RFC 1951 §3.2), readable by any inflater (zlib, so every
//! HDF5 and netCDF-4 reader, through the dataset's declared shuffle + deflate filters):
//!
//! * the zlib header, `78 01` (deflate, 32 KiB window, level "fastest"), as
//!   [`super::chunk::deflate`] writes it;
//! * per byte plane, in order: either raw deflate blocks from a compressor reset for that
//!   plane (so no back-reference reaches outside it), none final, ended by a sync flush
//!   (an empty stored block, so the plane's blocks end on a byte boundary); or stored
//!   blocks (§3.2.4) of at most 65,535 bytes, each a header byte `00` (BFINAL 0, BTYPE
//!   00, the rest padding), LEN and NLEN (its ones' complement), little-endian, then the
//!   bytes;
//! * a final empty stored block, `01 00 00 FF FF`;
//! * the Adler-32 of the whole uncompressed chunk (§2.2, §9), big-endian.
//!
//! Which planes are stored ([`is_noise`]) depends on the plane's bytes only, so a chunk's
//! bytes are the same whatever the thread or machine that encoded it.

use miniz_oxide::DataFormat;
use miniz_oxide::deflate::core::TDEFLFlush;

use super::chunk::Deflater;

/// The zlib header: CMF `78` (CM 8 = deflate, CINFO 7 = 32 KiB window), FLG `01` (FLEVEL
/// 0, "fastest", as miniz_oxide writes for level 1; FCHECK makes `0x7801` a multiple of
/// 31), RFC 1950 §2.2.
const ZLIB_HEADER: [u8; 2] = [0x78, 0x01];
/// The most bytes a stored block holds (its LEN is 16 bits), RFC 1951 §3.2.4.
pub const MAX_STORED: usize = 65_535;
/// A final, empty stored block: BFINAL 1, BTYPE 00, padding, LEN 0, NLEN 0xFFFF.
const FINAL_EMPTY_BLOCK: [u8; 5] = [0x01, 0x00, 0x00, 0xFF, 0xFF];
/// A plane is stored when its bytes' order-0 entropy is at least this many thousandths
/// of 8 bits per byte: deflate could then save at most ~3 % of it. Chosen by measurement
/// (`validation/reports/writer.md`, "Noise planes stored").
pub const NOISE_ENTROPY_MILLI: u64 = 970;
/// Fraction bits of the fixed-point base-2 logarithms of [`is_noise`].
const LOG2_FRAC_BITS: u32 = 16;

/// Encodes a shuffled chunk of `elem_bytes`-byte elements into one zlib stream, storing
/// the byte planes that [`is_noise`] finds incompressible and deflating the others.
/// A chunk whose length is not a multiple of `elem_bytes` (never the writer's) is taken
/// as one plane.
pub fn deflate_planes(shuffled: &[u8], elem_bytes: usize) -> Result<Vec<u8>, String> {
    let n = shuffled.len() / elem_bytes.max(1);
    let planes: Vec<(&[u8], bool)> = if n == 0 || n * elem_bytes != shuffled.len() {
        vec![(shuffled, is_noise(shuffled))]
    } else {
        shuffled
            .chunks_exact(n)
            .map(|p| (p, is_noise(p)))
            .collect()
    };
    encode(&planes)
}

/// One zlib stream of `planes` (bytes, stored?) in order, as the module describes.
pub fn encode(planes: &[(&[u8], bool)]) -> Result<Vec<u8>, String> {
    // stored planes take their length and 5 bytes a block; deflated ones at most theirs
    // once judged compressible (more is grown into if needed)
    let room: usize = planes
        .iter()
        .map(|(p, _)| p.len() + 5 * p.len().div_ceil(MAX_STORED) + 16)
        .sum();
    let mut out = Vec::with_capacity(ZLIB_HEADER.len() + room + FINAL_EMPTY_BLOCK.len() + 4);
    out.extend_from_slice(&ZLIB_HEADER);
    let mut adler = adler2::Adler32::new();
    for &(plane, stored) in planes {
        adler.write_slice(plane);
        if plane.is_empty() {
            continue;
        }
        if stored {
            put_stored(&mut out, plane);
        } else {
            Deflater::with(|d| d.compress_into(plane, DataFormat::Raw, TDEFLFlush::Sync, &mut out))?;
        }
    }
    out.extend_from_slice(&FINAL_EMPTY_BLOCK);
    out.extend_from_slice(&adler.checksum().to_be_bytes());
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
/// order-0 entropy `H = Σ c·log2(n/c)` over the byte histogram (`c` of each value, `n`
/// bytes) is at least [`NOISE_ENTROPY_MILLI`]/1000 of `8n` bits. Deflate's Huffman
/// codes (RFC 1951 §3.2.2) cannot code bytes below their order-0 entropy, and its LZ77
/// matches find nothing in fresh random draws: a measured plane of Poisson low bytes at
/// 0.99 of 8 bits deflated to 0.975 of its size (the Huffman tables' cost), while data
/// repeated from row to row (a changing scene's truth) would, which is why only fresh
/// draws are encoded by planes. Integer arithmetic throughout, so the decision is the
/// same on every machine.
pub fn is_noise(plane: &[u8]) -> bool {
    !plane.is_empty() && entropy_milli(plane) >= NOISE_ENTROPY_MILLI
}

/// The order-0 entropy of `bytes` in thousandths of 8 bits per byte, rounded down (0 for
/// no bytes): `1000 · Σ c·log2(n/c) / 8n` over the byte histogram.
pub fn entropy_milli(bytes: &[u8]) -> u64 {
    let n = bytes.len() as u64;
    if n == 0 {
        return 0;
    }
    let log_n = log2_fixed(n);
    // Σ c·(log2 n − log2 c) in fixed point: at most n·8·2^16, far within u128
    let bits: u128 = histogram(bytes)
        .iter()
        .filter(|&&c| c > 0)
        .map(|&c| u128::from(c) * u128::from(log_n.saturating_sub(log2_fixed(c))))
        .sum();
    let milli = bits * 1000 / (u128::from(8 * n) << LOG2_FRAC_BITS);
    u64::try_from(milli).unwrap_or(u64::MAX)
}

/// The counts of each byte value, over four tables (so that runs of one value do not
/// wait on one counter).
fn histogram(bytes: &[u8]) -> [u64; 256] {
    let mut t = [[0u64; 256]; 4];
    let mut quads = bytes.chunks_exact(4);
    for q in &mut quads {
        t[0][usize::from(q[0])] += 1;
        t[1][usize::from(q[1])] += 1;
        t[2][usize::from(q[2])] += 1;
        t[3][usize::from(q[3])] += 1;
    }
    for &b in quads.remainder() {
        t[0][usize::from(b)] += 1;
    }
    let mut h = [0u64; 256];
    for (v, slot) in h.iter_mut().enumerate() {
        *slot = t.iter().map(|row| row[v]).sum();
    }
    h
}

/// `log2(x)` in fixed point with [`LOG2_FRAC_BITS`] fraction bits, rounded down (to
/// within 2^-16 for `x` below 2^33; 0 for 0): the integer part from the leading bit, the
/// fraction bit by bit by squaring the mantissa.
fn log2_fixed(x: u64) -> u64 {
    if x == 0 {
        return 0;
    }
    let int = u64::from(63 - x.leading_zeros());
    // mantissa in [1, 2) as a Q32 number
    let mut m: u128 = if int <= 32 {
        u128::from(x) << (32 - int)
    } else {
        u128::from(x >> (int - 32))
    };
    let mut frac = 0u64;
    for bit in (0..LOG2_FRAC_BITS).rev() {
        m = (m * m) >> 32;
        if m >= 2 << 32 {
            m >>= 1;
            frac |= 1 << bit;
        }
    }
    (int << LOG2_FRAC_BITS) | frac
}

#[cfg(test)]
mod tests;
