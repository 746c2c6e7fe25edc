use super::*;
use crate::output::raw_file::chunk::{deflate, inflate, put_row};
use rand::Rng;
use rand_distr::{Distribution, Poisson};
use rand_pcg::Pcg64Mcg;

/// Bytes of a uniform generator: order-0 entropy ~8 bits.
fn noise(len: usize, seed: u64) -> Vec<u8> {
    let mut rng = Pcg64Mcg::new(0x5eed + u128::from(seed));
    (0..len).map(|_| rng.next_u32() as u8).collect()
}

/// Bytes that deflate shrinks (a few values, runs).
fn smooth(len: usize) -> Vec<u8> {
    (0..len).map(|i| (i / 1000 % 7) as u8).collect()
}

/// A shuffled chunk of `rows × width` u32 Poisson counts of mean `mean`.
fn poisson_chunk(rows: usize, width: usize, mean: f64, seed: u64) -> Vec<u8> {
    let mut rng = Pcg64Mcg::new(0x5eed + u128::from(seed));
    let law = Poisson::new(mean).unwrap();
    let elems = rows * width;
    let mut buf = vec![0u8; elems * 4];
    for r in 0..rows {
        let row: Vec<u64> = (0..width).map(|_| law.sample(&mut rng) as u64).collect();
        put_row(&mut buf, elems, r * width, 4, &row, |v| v);
    }
    buf
}

/// Encodes `planes` with the given decisions, checks that the stream inflates back to
/// their concatenation and returns it.
fn round_trip(planes: &[(&[u8], bool)]) -> Vec<u8> {
    let z = encode(planes).unwrap();
    let whole: Vec<u8> = planes.iter().flat_map(|(p, _)| p.iter().copied()).collect();
    assert_eq!(inflate(&z).unwrap(), whole, "{} planes", planes.len());
    z
}

#[test]
fn every_mix_of_stored_and_deflated_planes_inflates_back() {
    let (a, b, c) = (noise(70_000, 1), smooth(131_072), noise(1, 2));
    let d = noise(MAX_STORED, 3);
    let e = noise(MAX_STORED + 1, 4);
    let kinds: [&[u8]; 6] = [&a, &b, &c, &d, &e, &[]];
    for mask in 0u32..64 {
        // every plane kind, stored or deflated by the bits of `mask`
        let planes: Vec<(&[u8], bool)> = kinds
            .iter()
            .enumerate()
            .map(|(k, p)| (*p, mask >> k & 1 == 1))
            .collect();
        round_trip(&planes);
    }
    for planes in [vec![], vec![(&[][..], true)], vec![(&[][..], false)]] {
        let z = round_trip(&planes);
        // header, final empty block, Adler-32 of nothing (1)
        assert_eq!(z, [0x78, 0x01, 0x01, 0x00, 0x00, 0xFF, 0xFF, 0, 0, 0, 1]);
    }
}

#[test]
fn a_stored_plane_is_its_bytes_in_blocks_of_at_most_65535() {
    let p = noise(3 * MAX_STORED + 10, 5);
    let z = round_trip(&[(&p, true)]);
    assert_eq!(z.len(), 2 + p.len() + 4 * 5 + 5 + 4);
    let mut at = 2;
    for block in p.chunks(MAX_STORED) {
        let len = block.len() as u16;
        assert_eq!(z[at], 0x00, "not final, BTYPE 00");
        assert_eq!(z[at + 1..at + 3], len.to_le_bytes());
        assert_eq!(z[at + 3..at + 5], (!len).to_le_bytes());
        assert_eq!(&z[at + 5..at + 5 + block.len()], block);
        at += 5 + block.len();
    }
    assert_eq!(z[at..at + 5], FINAL_EMPTY_BLOCK);
    assert_eq!(
        z[at + 5..],
        simd_adler32::adler32(&p.as_slice()).to_be_bytes()
    );
    // the checksum itself, on the usual example (Adler-32 of "Wikipedia")
    assert_eq!(simd_adler32::adler32(&&b"Wikipedia"[..]), 0x11E6_0398);
}

#[test]
fn a_deflated_plane_starts_afresh_and_ends_on_a_byte_boundary() {
    let p = smooth(100_000);
    let one = round_trip(&[(&p, false)]);
    let two = round_trip(&[(&p, false), (&p, false)]);
    // the second plane's blocks are the first's: no back-reference into the first
    let seg = &one[2..one.len() - 9];
    assert_eq!(&two[2..2 + seg.len()], seg);
    assert_eq!(&two[2 + seg.len()..2 + 2 * seg.len()], seg);
    // a sync flush ends each: an empty stored block, byte-aligned
    assert_eq!(seg[seg.len() - 4..], [0x00, 0x00, 0xFF, 0xFF]);
    assert!(seg.len() < p.len() / 10);
}

#[test]
fn corrupt_streams_are_refused_by_the_inflater() {
    let (p, q) = (noise(70_000, 6), smooth(50_000));
    let z = round_trip(&[(&p, true), (&q, false)]);
    // LEN, NLEN of the first stored block, the stored bytes, the Adler-32
    for at in [3, 5, 100, z.len() - 1] {
        let mut bad = z.clone();
        bad[at] ^= 0x10;
        assert!(inflate(&bad).is_err(), "byte {at} flipped");
    }
    // a stream without its final block
    let cut = [&z[..z.len() - 9], &z[z.len() - 4..]].concat();
    assert!(inflate(&cut).is_err());
}

#[test]
fn the_header_is_the_whole_chunk_compressors() {
    let z = deflate(&smooth(1000)).unwrap();
    assert_eq!(z[..2], ZLIB_HEADER);
    assert_eq!((u16::from(z[0]) << 8 | u16::from(z[1])) % 31, 0);
}

#[test]
fn poisson_counts_store_the_low_bytes_and_deflate_the_rest() {
    // 392 profiles × 334 bins of counts around 100,000, as scenario 1's aggregate chunks
    // of 1000 s: their low bytes are uniform, the next ones spread over a few values
    let chunk = poisson_chunk(392, 334, 1e5, 7);
    let n = chunk.len() / 4;
    let planes: Vec<&[u8]> = chunk.chunks_exact(n).collect();
    let noise_planes: Vec<bool> = planes.iter().map(|p| is_noise(p)).collect();
    assert_eq!(noise_planes, [true, false, false, false]);
    let z = deflate_planes(&chunk, 4).unwrap();
    assert_eq!(inflate(&z).unwrap(), chunk);
    // the low bytes are in the stream as they are, right after the header
    assert_eq!(&z[2 + 5..2 + 5 + MAX_STORED], &planes[0][..MAX_STORED]);
    // within 2 % of the whole chunk's deflate
    let whole = deflate(&chunk).unwrap();
    assert!(
        z.len() * 100 <= whole.len() * 102,
        "{} vs {}",
        z.len(),
        whole.len()
    );
    // the same bytes from a fresh thread
    let again = std::thread::spawn(move || deflate_planes(&chunk, 4).unwrap());
    assert_eq!(again.join().unwrap(), z);
}

#[test]
fn odd_chunk_lengths_are_one_plane() {
    for (len, elem) in [(0usize, 4usize), (3, 4), (10, 4), (9, 0), (5, 1), (8, 8)] {
        let data = noise(len, len as u64);
        let z = deflate_planes(&data, elem).unwrap();
        assert_eq!(
            inflate(&z).unwrap(),
            data,
            "{len} bytes of {elem}-byte elements"
        );
    }
}

#[test]
fn noise_is_told_by_entropy() {
    assert!(is_noise(&noise(100_000, 8)));
    assert!(!is_noise(&smooth(100_000)));
    assert!(!is_noise(&[]));
    assert!(!is_noise(&[7; 1000]));
    // every value equally often: 8 bits exactly; 128 values: 7 bits, 0.875 of 8
    let all: Vec<u8> = (0..65_536u32).map(|i| i as u8).collect();
    assert!(is_noise(&all));
    let half: Vec<u8> = (0..65_536u32).map(|i| (i % 128) as u8).collect();
    assert!(!is_noise(&half));
    // around the threshold: value 0 with probability p, else any of the 255 others;
    // entropy h(p) + (1 − p)·log2 255 crosses 8·965/1000 bits near p = 0.09
    let skewed = |p_milli: u64| -> Vec<u8> {
        let mut rng = Pcg64Mcg::new(0xbad5eed);
        (0..256_000)
            .map(|_| {
                let r = rng.next_u64();
                if r % 1000 < p_milli {
                    0
                } else {
                    (r >> 32) as u8 % 255 + 1
                }
            })
            .collect()
    };
    assert!(is_noise(&skewed(50)));
    assert!(!is_noise(&skewed(120)));
}

#[test]
fn fixed_point_log2_is_within_its_last_bit() {
    for x in [
        1u64,
        2,
        3,
        5,
        255,
        256,
        1000,
        65_535,
        1 << 20,
        123_456_789,
        u32::MAX as u64,
    ] {
        let exact = (x as f64).log2() * f64::from(1u32 << LOG2_FRAC_BITS);
        let got = log2_fixed(x) as f64;
        assert!((exact - got).abs() <= 2.0, "log2({x}): {got} vs {exact}");
    }
    assert_eq!(log2_fixed(0), 0);
    for x in [0u64, 1, 7, 4096, 8191, 8192, 1 << 20] {
        assert_eq!(log2_of(x), log2_fixed(x), "the table at {x}");
    }
    assert_eq!(log2_fixed(1 << 40), 40 << LOG2_FRAC_BITS);
    assert!(log2_fixed(u64::MAX) >= 63 << LOG2_FRAC_BITS);
}
