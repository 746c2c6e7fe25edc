//! The measurement behind the raw writer's stored noise planes
//! (`lidarsim::output::raw_file::planes`, `validation/reports/writer.md`): for the byte
//! planes of shuffled chunks of real lidarsim variables, their order-0 entropy against
//! what deflate (miniz_oxide level 1, a raw segment per plane) makes of them, then the
//! size and speed of whole chunks encoded by planes with several entropy thresholds for
//! storing a plane, against one deflate stream per chunk. One thread, the best of 5 passes
//! in the thread's CPU time (steadier than wall time on a shared machine).
//!
//! ```text
//! python3 validation/writer_deflate_choice/dump.py FILE.h5 ... --out /tmp/chunks
//! cargo run --release --example noise_planes -- /tmp/chunks [TARGET_BYTES]
//! ```
//!
//! Files are named `LABEL_VAR_ELEMBYTES_ROWELEMS.bin` (raw native bytes, `dump.py`); each
//! is cut into chunks of about TARGET bytes (524,288) of whole profiles, as the writer's.

use std::collections::BTreeMap;

use lidarsim::output::raw_file::chunk::{deflate, put_row};
use lidarsim::output::raw_file::planes::{encode, entropy_milli};

/// Store thresholds tried, in thousandths of 8 bits per byte (1001: never stored).
const THRESHOLDS: [u64; 8] = [900, 950, 960, 965, 970, 980, 990, 1001];

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(dir) = args.first() else {
        eprintln!("usage: noise_planes DATA_DIR [TARGET_BYTES]");
        std::process::exit(2);
    };
    let target: usize = args
        .get(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(512 << 10);
    let mut files: Vec<_> = std::fs::read_dir(dir)
        .expect("a readable directory")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .collect();
    files.sort();
    // (entropy bucket of 10/1000) → (planes, raw bytes, deflated bytes)
    let mut buckets: BTreeMap<u64, (usize, usize, usize)> = BTreeMap::new();
    for p in files {
        let name = p
            .file_stem()
            .unwrap_or_default()
            .to_string_lossy()
            .to_string();
        let Some((elem, chunks)) = read_chunks(&p, &name, target) else {
            continue;
        };
        println!("{name}: {} chunks of {} B", chunks.len(), chunks[0].len());
        per_plane(&chunks, elem, &mut buckets);
        per_threshold(&chunks, elem);
    }
    println!("all planes by entropy (thousandths of 8 bits): planes, deflated / raw");
    for (b, (k, raw, z)) in buckets {
        println!(
            "  {:4}–{:4}: {k:5} planes, {:.4}",
            b,
            b + 9,
            z as f64 / raw as f64
        );
    }
}

/// The file's chunks in shuffled layout, and its element size.
fn read_chunks(path: &std::path::Path, name: &str, target: usize) -> Option<(usize, Vec<Vec<u8>>)> {
    let parts: Vec<&str> = name.split('_').collect();
    let elem: usize = parts.get(parts.len().checked_sub(2)?)?.parse().ok()?;
    let row_elems: usize = parts.last()?.parse().ok()?;
    let data = std::fs::read(path).ok()?;
    let rows = (target / (row_elems * elem)).max(1);
    let elems = rows * row_elems;
    let chunks: Vec<Vec<u8>> = data
        .chunks_exact(elems * elem)
        .map(|raw| {
            let mut buf = vec![0u8; raw.len()];
            let words: Vec<u64> = raw
                .chunks_exact(elem)
                .map(|b| {
                    let mut w = [0u8; 8];
                    w[..elem].copy_from_slice(b);
                    u64::from_le_bytes(w)
                })
                .collect();
            put_row(&mut buf, elems, 0, elem, &words, |v| v);
            buf
        })
        .collect();
    (!chunks.is_empty()).then_some((elem, chunks))
}

/// Each plane index's mean entropy and deflated ratio; every plane into `buckets`.
fn per_plane(chunks: &[Vec<u8>], elem: usize, buckets: &mut BTreeMap<u64, (usize, usize, usize)>) {
    for j in 0..elem {
        let (mut h, mut raw, mut z) = (0u64, 0usize, 0usize);
        let (mut lo, mut hi) = (u64::MAX, 0u64);
        for c in chunks {
            let n = c.len() / elem;
            let plane = &c[j * n..(j + 1) * n];
            let e = entropy_milli(plane);
            // a raw segment's bytes: the stream less header, final block and Adler-32
            let size = encode(&[(plane, false)]).map_or(n, |s| s.len() - 11);
            h += e;
            (lo, hi) = (lo.min(e), hi.max(e));
            raw += n;
            z += size;
            let b = buckets.entry(e / 10 * 10).or_default();
            *b = (b.0 + 1, b.1 + n, b.2 + size);
        }
        println!(
            "  plane {j}: entropy {:.3} ({:.3}–{:.3}) of 8 bits, deflated to {:.3}",
            h as f64 / chunks.len() as f64 / 1000.0,
            lo as f64 / 1000.0,
            hi as f64 / 1000.0,
            z as f64 / raw as f64
        );
    }
}

/// Size and speed of the chunks deflated whole, and by planes at each threshold.
fn per_threshold(chunks: &[Vec<u8>], elem: usize) {
    let raw: usize = chunks.iter().map(Vec::len).sum();
    let time = |f: &dyn Fn(&[u8]) -> usize| {
        let mut best = f64::INFINITY;
        let mut size = 0;
        for _ in 0..5 {
            let t = thread_cpu_s();
            size = chunks.iter().map(|c| f(c)).sum::<usize>();
            best = best.min(thread_cpu_s() - t);
        }
        (size, best)
    };
    let report = |label: &str, (size, t): (usize, f64)| {
        println!(
            "    {label:<22} ratio {:.4}  {:6.0} MB/s",
            size as f64 / raw as f64,
            raw as f64 / t / 1e6
        );
    };
    report("whole chunk", time(&|c| deflate(c).map_or(0, |z| z.len())));
    for th in THRESHOLDS {
        // the writer's rule at threshold `th`: by planes if any is stored, else whole
        let by_planes = |c: &[u8]| {
            let n = c.len() / elem;
            let planes: Vec<(&[u8], bool)> = c
                .chunks_exact(n)
                .map(|p| (p, entropy_milli(p) >= th))
                .collect();
            let z = if planes.iter().any(|p| p.1) {
                encode(&planes)
            } else {
                deflate(c)
            };
            z.map_or(0, |z| z.len())
        };
        let label = if th > 1000 {
            "never stored".to_string()
        } else {
            format!("store ≥ {th}")
        };
        report(&label, time(&by_planes));
    }
    let segmented = |c: &[u8]| {
        let planes: Vec<(&[u8], bool)> =
            c.chunks_exact(c.len() / elem).map(|p| (p, false)).collect();
        encode(&planes).map_or(0, |z| z.len())
    };
    report("by planes, none stored", time(&segmented));
}

/// This thread's CPU time, in seconds.
fn thread_cpu_s() -> f64 {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `ts` is a valid timespec for the call to fill.
    unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut ts) };
    ts.tv_sec as f64 + ts.tv_nsec as f64 * 1e-9
}
