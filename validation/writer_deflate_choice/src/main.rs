//! Speed and ratio of deflate encoders on shuffled chunks of real lidarsim variables, one
//! thread, the best of 3 passes (see Cargo.toml for the commands). Each file of the data
//! directory (from dump.py) is cut into chunks of about TARGET bytes of whole profiles,
//! shuffled as HDF5's shuffle filter does, and compressed chunk by chunk.

use std::io::Write;
use std::time::Instant;

fn shuffle(elem: usize, src: &[u8]) -> Vec<u8> {
    let n = src.len() / elem;
    let mut dst = vec![0u8; src.len()];
    for j in 0..elem {
        for i in 0..n {
            dst[j * n + i] = src[i * elem + j];
        }
    }
    dst
}

fn zlib_c(level: i32, src: &[u8]) -> Vec<u8> {
    unsafe {
        let mut len = libz_sys::compressBound(src.len() as _);
        let mut out = vec![0u8; len as usize];
        let r = libz_sys::compress2(out.as_mut_ptr(), &mut len, src.as_ptr(), src.len() as _, level);
        assert_eq!(r, 0);
        out.truncate(len as usize);
        out
    }
}

fn zlib_rs(level: u32, src: &[u8]) -> Vec<u8> {
    let mut e = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::new(level));
    e.write_all(src).unwrap();
    e.finish().unwrap()
}

fn libdeflate(c: &mut libdeflater::Compressor, src: &[u8]) -> Vec<u8> {
    let mut out = vec![0u8; c.zlib_compress_bound(src.len())];
    let n = c.zlib_compress(src, &mut out).unwrap();
    out.truncate(n);
    out
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let dir = args.get(1).expect("usage: writer_deflate_choice DATA_DIR [TARGET_BYTES]");
    let target: usize = args.get(2).map_or(512 * 1024, |s| s.parse().unwrap());
    let mut files: Vec<_> = std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().path()).collect();
    files.sort();
    for p in files {
        let name = p.file_stem().unwrap().to_string_lossy().to_string();
        let parts: Vec<&str> = name.split('_').collect();
        let elem: usize = parts[parts.len() - 2].parse().unwrap();
        let row = parts[parts.len() - 1].parse::<usize>().unwrap() * elem;
        let data = std::fs::read(&p).unwrap();
        let rows = (target / row).max(1);
        let chunks: Vec<Vec<u8>> = data.chunks_exact(rows * row).map(|c| shuffle(elem, c)).collect();
        let raw: usize = chunks.iter().map(Vec::len).sum();
        let mut results: Vec<(String, f64, usize)> = vec![];
        let mut run = |label: &str, f: &mut dyn FnMut(&[u8]) -> Vec<u8>| {
            let mut best = f64::INFINITY;
            let mut size = 0;
            for _ in 0..3 {
                let t = Instant::now();
                size = chunks.iter().map(|c| f(c).len()).sum();
                best = best.min(t.elapsed().as_secs_f64());
            }
            results.push((label.to_string(), best, size));
        };
        run("zlib (C) 1 [HDF5 today]", &mut |c| zlib_c(1, c));
        run("zlib-rs 1", &mut |c| zlib_rs(1, c));
        run("zlib-rs 2", &mut |c| zlib_rs(2, c));
        run("miniz_oxide 1", &mut |c| miniz_oxide::deflate::compress_to_vec_zlib(c, 1));
        run("miniz_oxide 3", &mut |c| miniz_oxide::deflate::compress_to_vec_zlib(c, 3));
        for l in [1, 3] {
            let mut comp = libdeflater::Compressor::new(libdeflater::CompressionLvl::new(l).unwrap());
            run(&format!("libdeflate {l}"), &mut |c| libdeflate(&mut comp, c));
        }
        println!("{name}: {} chunks of {} B ({rows} profiles)", chunks.len(), rows * row);
        for (l, t, s) in results {
            println!("  {l:<26} {:7.0} MB/s  ratio {:6.2}", raw as f64 / t / 1e6, raw as f64 / s as f64);
        }
    }
}
