//! The raw-file writer that keeps up (issue 11, part 2): whole chunks shuffled and
//! deflated by the writer's workers and stored with HDF5's direct chunk write must read
//! back through the dataset's declared filters exactly as written, lay their bytes out
//! as HDF5's own shuffle filter does. (The same file whatever the thread count:
//! `tests/raw_writer_threads.rs`, a binary of its own because its child processes would
//! inherit, and hold the locks of, the files these tests write in-process.)

mod common;

use std::path::{Path, PathBuf};

use lidarsim::output::raw_file::chunk;
use lidarsim::output::raw_file::{
    CountWidth, Dims, ProfileRecord, RawFileSpec, RawFileWriter, Variable,
};

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("lidarsim-writer-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A deterministic, Poisson-looking count for (profile, value, stream): mostly small,
/// sometimes up to `max`.
fn count(p: usize, i: usize, stream: usize, max: u64) -> u64 {
    let h = ((p * 1_000_003 + i * 7919 + stream * 104_729) as u64)
        .wrapping_mul(0x9E37_79B9_7F4A_7C15)
        .rotate_left(17);
    match h % 97 {
        0 => max,
        1..=9 => h % (max + 1),
        _ => h % 13,
    }
}

fn truth(p: usize, i: usize, k: usize) -> f64 {
    ((p as f64 + 1.0) * 1e-3 + i as f64 * 1e-7).sin() * 10f64.powi(-(k as i32) * 3) + k as f64
}

fn spec(
    n_profiles: usize,
    channels: usize,
    n_bins: usize,
    width: CountWidth,
    components: bool,
) -> RawFileSpec {
    let pcb = |name: &str| Variable {
        name: name.into(),
        dims: Dims::ProfileChannelBin,
        long_name: name.into(),
        units: "1".into(),
        attributes: vec![],
        data: vec![],
    };
    RawFileSpec {
        n_bins,
        n_profiles,
        first_profile: 0,
        channels: (0..channels).map(|c| format!("ch{c}")).collect(),
        count_width: width,
        components,
        time_units: "seconds since 2000-01-01 00:00:00".into(),
        channel_text: vec![],
        n_columns: 0,
        streamed_columns: false,
        column_slots: 0,
        variables: vec![
            pcb("truth_a"),
            Variable {
                name: "latitude".into(),
                dims: Dims::Profile,
                long_name: "latitude".into(),
                units: "degrees_north".into(),
                attributes: vec![],
                data: vec![],
            },
            pcb("truth_b"),
        ],
        root_attributes: vec![],
        profile_coordinates: vec![],
    }
}

/// The data of profile `p`: components, counts, two f64 rows and a latitude, a function
/// of the index only.
struct Profile {
    parts: Vec<Vec<u64>>,
    counts: Vec<u64>,
    a: Vec<f64>,
    lat: [f64; 1],
    b: Vec<f64>,
}

fn profile(spec: &RawFileSpec, p: usize) -> Profile {
    let n = spec.counts_per_profile();
    let max = spec.count_width.max_value().min(1 << 40);
    let parts: Vec<Vec<u64>> = (0..3)
        .map(|s| (0..n).map(|i| count(p, i, s, max / 4)).collect())
        .collect();
    let counts = (0..n)
        .map(|i| parts[0][i] + parts[1][i] + parts[2][i])
        .collect();
    Profile {
        counts,
        parts,
        a: (0..n).map(|i| truth(p, i, 0)).collect(),
        lat: [p as f64 * 0.01 - 40.0],
        b: (0..n).map(|i| truth(p, i, 1)).collect(),
    }
}

/// Each channel's pulse energy of every profile, J (a channel's laser line of its own:
/// 0.11 J, 0.12 J, …).
const ENERGY_J: [f64; 16] = {
    let mut e = [0.0; 16];
    let mut c = 0;
    while c < 16 {
        e[c] = 0.11 + 0.01 * c as f64;
        c += 1;
    }
    e
};

fn record<'a>(
    spec: &RawFileSpec,
    p: usize,
    d: &'a Profile,
    values: &'a [&'a [f64]],
) -> ProfileRecord<'a> {
    ProfileRecord {
        index: p,
        time_s: p as f64 * 1.5 + 0.75,
        n_shots: 15 + p as u64,
        pulse_energy_j: &ENERGY_J[..spec.channels.len()],
        counts: &d.counts,
        components: spec
            .components
            .then(|| [&d.parts[0][..], &d.parts[1][..], &d.parts[2][..]]),
        values,
        columns: &[],
        column_weights: &[],
    }
}

/// Writes every profile of `spec` in `order`, one at a time.
fn write_all(path: &Path, spec: &RawFileSpec, order: &[usize]) {
    write_batches(path, spec, order, 1);
}

/// Writes every profile of `spec` in `order`, `batch` records per call (one record per
/// call through `write_profile`).
fn write_batches(path: &Path, spec: &RawFileSpec, order: &[usize], batch: usize) {
    let mut w = RawFileWriter::create(path, path, spec).unwrap();
    for (b, group) in order.chunks(batch).enumerate() {
        let data: Vec<Profile> = group.iter().map(|&p| profile(spec, p)).collect();
        let values: Vec<Vec<&[f64]>> = data
            .iter()
            .map(|d| vec![&d.a[..], &d.lat[..], &d.b[..]])
            .collect();
        let recs: Vec<ProfileRecord> = group
            .iter()
            .zip(&data)
            .zip(&values)
            .map(|((&p, d), v)| record(spec, p, d, v))
            .collect();
        if batch == 1 {
            w.write_profile(&recs[0]).unwrap();
        } else {
            w.write_profiles(&recs).unwrap();
        }
        assert_eq!(w.profiles_written(), b * batch + group.len());
    }
    w.finish().unwrap();
}

/// Reads the file back through HDF5's filter pipeline and checks every value.
fn check_all(path: &Path, spec: &RawFileSpec) {
    let f = hdf5::File::open(path).unwrap();
    let n = spec.counts_per_profile();
    let max = spec.count_width.max_value().min(1 << 40);
    let counts: Vec<u64> = f.dataset("counts").unwrap().read_raw().unwrap();
    let parts: Vec<Vec<u64>> = ["signal_counts", "background_counts", "dark_counts"]
        .iter()
        .filter(|_| spec.components)
        .map(|v| f.dataset(v).unwrap().read_raw().unwrap())
        .collect();
    let a: Vec<f64> = f.dataset("truth_a").unwrap().read_raw().unwrap();
    let b: Vec<f64> = f.dataset("truth_b").unwrap().read_raw().unwrap();
    let time: Vec<f64> = f.dataset("time").unwrap().read_raw().unwrap();
    let n_shots: Vec<u64> = f.dataset("n_shots").unwrap().read_raw().unwrap();
    let energy: Vec<f64> = f.dataset("pulse_energy").unwrap().read_raw().unwrap();
    let lat: Vec<f64> = f.dataset("latitude").unwrap().read_raw().unwrap();
    assert_eq!(counts.len(), spec.n_profiles * n);
    for p in 0..spec.n_profiles {
        for i in 0..n {
            let want: Vec<u64> = (0..3).map(|s| count(p, i, s, max / 4)).collect();
            assert_eq!(
                counts[p * n + i],
                want.iter().sum::<u64>(),
                "counts {p} {i}"
            );
            for (s, part) in parts.iter().enumerate() {
                assert_eq!(part[p * n + i], want[s], "component {s} {p} {i}");
            }
            assert_eq!(a[p * n + i].to_bits(), truth(p, i, 0).to_bits());
            assert_eq!(b[p * n + i].to_bits(), truth(p, i, 1).to_bits());
        }
        assert_eq!(time[p], p as f64 * 1.5 + 0.75);
        assert_eq!(n_shots[p], 15 + p as u64);
        let ch = spec.channels.len();
        assert_eq!(energy[p * ch..(p + 1) * ch], ENERGY_J[..ch]);
        assert_eq!(lat[p], p as f64 * 0.01 - 40.0);
    }
}

#[test]
fn profiles_in_any_order_read_back_exactly_with_edge_chunks_and_components() {
    let dir = scratch("roundtrip");
    // 300 profiles of 2 × 1000 values: u16 counts have 131 rows per chunk (edge chunk of
    // 38), f64 ones 32 (edge of 12); the (profile) variables are one block
    for (k, (width, order)) in [
        (CountWidth::U16, (0..300).collect::<Vec<_>>()),
        // reversed, then interleaved: chunks complete in another order
        (CountWidth::U32, (0..300).rev().collect()),
        (
            CountWidth::U64,
            (0..150).flat_map(|i| [i, 299 - i]).collect(),
        ),
    ]
    .into_iter()
    .enumerate()
    {
        let s = spec(300, 2, 1000, width, true);
        let path = dir.join(format!("w{k}.h5"));
        write_all(&path, &s, &order);
        check_all(&path, &s);
        let f = hdf5::File::open(&path).unwrap();
        let counts = f.dataset("counts").unwrap();
        let rows = (512 * 1024 / (2000 * width.bytes())).min(300);
        assert_eq!(counts.chunk(), Some(vec![rows, 2, 1000]));
        let a = f.dataset("truth_a").unwrap();
        assert_eq!(
            a.chunk(),
            Some(vec![32, 2, 1000]),
            "f64 chunk rows of its own"
        );
        let info = common::chunk_info(&counts);
        assert_eq!(info.len(), 300usize.div_ceil(rows));
        for (c, (offset, mask, _)) in info.iter().enumerate() {
            assert_eq!(offset, &vec![(c * rows) as u64, 0, 0]);
            assert_eq!(*mask, 0);
        }
        assert_eq!(common::chunk_info(&a).len(), 300usize.div_ceil(32));
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// A batch is the same as its records one at a time, byte for byte, whatever the batch
/// size and order (`simulate` sends batches, `merge` single profiles).
#[test]
fn batches_write_the_same_bytes_as_single_profiles() {
    let dir = scratch("batches");
    let s = spec(500, 2, 700, CountWidth::U32, true);
    let in_order: Vec<usize> = (0..500).collect();
    let shuffled: Vec<usize> = (0..500).map(|i| (i * 37) % 500).collect();
    for (name, order) in [("in-order", &in_order), ("shuffled", &shuffled)] {
        let single = dir.join(format!("{name}-1.h5"));
        write_batches(&single, &s, order, 1);
        let want = std::fs::read(&single).unwrap();
        for batch in [2, 7, 64, 500] {
            let path = dir.join(format!("{name}-{batch}.h5"));
            write_batches(&path, &s, order, batch);
            assert!(
                std::fs::read(&path).unwrap() == want,
                "{name}, batches of {batch}: bytes differ"
            );
        }
        check_all(&single, &s);
    }
    // 9,000 profiles of 200 bins: queue flushes (16 MiB) between the writes of the
    // (profile) blocks (4,096 profiles), in the same order either way
    let s = spec(9000, 1, 200, CountWidth::U16, false);
    let order: Vec<usize> = (0..9000).collect();
    let (one, many) = (dir.join("long-1.h5"), dir.join("long-64.h5"));
    write_batches(&one, &s, &order, 1);
    write_batches(&many, &s, &order, 64);
    assert!(std::fs::read(&one).unwrap() == std::fs::read(&many).unwrap());
    check_all(&many, &s);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_refused_batch_buffers_nothing() {
    let dir = scratch("refused-batch");
    let s = spec(6, 1, 5, CountWidth::U16, false);
    let path = dir.join("r.h5");
    let mut w = RawFileWriter::create(&path, Path::new("shown.h5"), &s).unwrap();
    let data: Vec<Profile> = (0..6).map(|p| profile(&s, p)).collect();
    let values: Vec<Vec<&[f64]>> = data
        .iter()
        .map(|d| vec![&d.a[..], &d.lat[..], &d.b[..]])
        .collect();
    let rec = |p: usize| record(&s, p, &data[p], &values[p]);
    // profile 3 twice in one batch
    let e = w
        .write_profiles(&[rec(0), rec(3), rec(1), rec(3)])
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("shown.h5") && e.contains("profile 3 written twice"),
        "{e}"
    );
    assert_eq!(w.profiles_written(), 0);
    // a bad record in the middle: the whole batch is refused, the first bad one named
    let mut bad = rec(2);
    bad.time_s = f64::INFINITY;
    let e = w
        .write_profiles(&[rec(0), rec(1), bad, rec(4)])
        .unwrap_err()
        .to_string();
    assert!(e.contains("profile 2: time"), "{e}");
    assert_eq!(w.profiles_written(), 0);
    w.write_profiles(&[rec(0), rec(1), rec(2)]).unwrap();
    let e = w.write_profiles(&[rec(5), rec(1)]).unwrap_err().to_string();
    assert!(e.contains("profile 1 written twice"), "{e}");
    w.write_profiles(&[rec(5), rec(3), rec(4)]).unwrap();
    assert_eq!(w.profiles_written(), 6);
    w.finish().unwrap();
    check_all(&path, &s);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn more_profiles_than_a_column_block_and_a_row_larger_than_a_chunk() {
    let dir = scratch("blocks");
    // 9000 profiles: the (profile) variables span three blocks of 4096, the last partial
    let s = spec(9000, 1, 3, CountWidth::U16, false);
    let path = dir.join("many.h5");
    let order: Vec<usize> = (0..9000).map(|i| (i * 7) % 9000).collect();
    write_all(&path, &s, &order);
    check_all(&path, &s);
    // one profile of 3 × 40,000 f64 (960 kB) is more than a chunk: one profile per chunk
    let s = spec(5, 3, 40_000, CountWidth::U32, false);
    let path = dir.join("wide.h5");
    write_all(&path, &s, &[4, 0, 3, 1, 2]);
    check_all(&path, &s);
    let f = hdf5::File::open(&path).unwrap();
    assert_eq!(
        f.dataset("truth_b").unwrap().chunk(),
        Some(vec![1, 3, 40_000])
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// A dataset in `into` holding `values` (built by the test, not read back from the
/// writer's file), written by HDF5 through its own filters (the chunks of `like`,
/// shuffle, deflate 1).
fn hdf5_pipeline_copy<T: hdf5::H5Type>(
    like: &hdf5::Dataset,
    values: &[T],
    into: &hdf5::File,
    name: &str,
) -> hdf5::Dataset {
    let c = into
        .new_dataset::<T>()
        .shape(like.shape())
        .chunk(like.chunk().unwrap())
        .shuffle()
        .deflate(1)
        .create(name)
        .unwrap();
    c.write_raw(values).unwrap();
    c
}

/// The bytes HDF5's shuffle filter makes of one chunk, built here from the values:
/// byte k of element e at `k·N + e` (N elements a chunk, C order, little-endian), for
/// every element inside the dataset's extent (`None` for the edge chunk's padding).
fn shuffled_chunk(
    shape: &[usize],
    chunk_dims: &[usize],
    offset: &[u64],
    elem: usize,
    value_le: &dyn Fn(usize) -> Vec<u8>,
) -> Vec<Option<u8>> {
    let n: usize = chunk_dims.iter().product();
    let mut out = vec![None; n * elem];
    for e in 0..n {
        // the element's index in the chunk, then in the dataset
        let mut rem = e;
        let mut flat = 0;
        let mut inside = true;
        for d in 0..shape.len() {
            let stride: usize = chunk_dims[d + 1..].iter().product();
            let idx = offset[d] as usize + rem / stride;
            rem %= stride;
            inside &= idx < shape[d];
            flat = flat * shape[d] + idx.min(shape[d] - 1);
        }
        if inside {
            for (k, byte) in value_le(flat).into_iter().enumerate() {
                out[k * n + e] = Some(byte);
            }
        }
    }
    out
}

/// The writer's stored chunks inflate to the shuffled bytes of the values, built in the
/// test from the values it wrote (`shuffled_chunk`), and HDF5's own pipeline (shuffle,
/// then deflate), fed the same values, lays them out alike: same layout, only the
/// deflate encoder differs.
#[test]
fn stored_chunks_unpack_to_hdf5s_own_shuffled_bytes() {
    let dir = scratch("layout");
    let s = spec(70, 1, 2500, CountWidth::U32, false);
    let ours = dir.join("ours.h5");
    write_all(&ours, &s, &(0..70).collect::<Vec<_>>());
    let n = s.counts_per_profile();
    let data: Vec<Profile> = (0..70).map(|p| profile(&s, p)).collect();
    let counts: Vec<u32> = (0..70 * n)
        .map(|k| u32::try_from(data[k / n].counts[k % n]).unwrap())
        .collect();
    let truth_a: Vec<f64> = (0..70 * n).map(|k| truth(k / n, k % n, 0)).collect();
    let f = hdf5::File::open(&ours).unwrap();
    let theirs = hdf5::File::create(dir.join("theirs.h5")).unwrap();
    for (name, elem) in [("counts", 4), ("truth_a", 8)] {
        let ds = f.dataset(name).unwrap();
        let chunk_dims = ds.chunk().unwrap();
        assert_eq!(ds.shape(), vec![70, 1, 2500]);
        let (copy, value_le): (_, Box<dyn Fn(usize) -> Vec<u8>>) = if elem == 4 {
            (
                hdf5_pipeline_copy::<u32>(&ds, &counts, &theirs, name),
                Box::new(|k| counts[k].to_le_bytes().to_vec()),
            )
        } else {
            (
                hdf5_pipeline_copy::<f64>(&ds, &truth_a, &theirs, name),
                Box::new(|k| truth_a[k].to_le_bytes().to_vec()),
            )
        };
        let (a, b) = (common::chunk_info(&ds), common::chunk_info(&copy));
        assert_eq!(a.len(), b.len());
        assert!(a.len() >= 2, "{name}: an edge chunk is tested");
        for ((oa, _, sa), (ob, _, sb)) in a.iter().zip(&b) {
            assert_eq!(oa, ob);
            let mine = chunk::inflate(&common::raw_chunk(&ds, oa, *sa)).unwrap();
            let hdf5s = chunk::inflate(&common::raw_chunk(&copy, ob, *sb)).unwrap();
            assert_eq!(mine.len(), chunk_dims.iter().product::<usize>() * elem);
            let want = shuffled_chunk(&ds.shape(), &chunk_dims, oa, elem, &value_le);
            assert!(want.iter().filter(|w| w.is_some()).count() >= elem * 2500);
            for (k, (byte, w)) in mine.iter().zip(&want).enumerate() {
                if let Some(w) = w {
                    assert_eq!(byte, w, "{name} chunk at {oa:?}: shuffled byte {k}");
                }
            }
            assert!(
                mine == hdf5s,
                "{name} chunk at {oa:?}: shuffled bytes differ from HDF5's"
            );
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// Counts whose two low bytes are noise (fresh draws of large means): those byte planes
/// are stored as deflate stored blocks, the others deflated, in one zlib stream per
/// chunk that HDF5 reads back through the declared filters, and that inflates to the
/// bytes of HDF5's own pipeline.
#[test]
fn noise_planes_are_stored_and_read_back_through_hdf5s_filters() {
    let dir = scratch("noise");
    // 2500 u32 counts a profile: 52 rows a chunk, planes of 130,000 bytes; 70 profiles
    let s = spec(70, 1, 2500, CountWidth::U32, false);
    let n = s.counts_per_profile();
    let noisy = |p: usize, i: usize| {
        1_000_000 + (((p * 1_000_003 + i * 7919) as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 48)
    };
    let path = dir.join("noise.h5");
    let mut w = RawFileWriter::create(&path, &path, &s).unwrap();
    for p in 0..s.n_profiles {
        let counts: Vec<u64> = (0..n).map(|i| noisy(p, i)).collect();
        let (a, b): (Vec<f64>, Vec<f64>) = (0..n).map(|i| (truth(p, i, 0), truth(p, i, 1))).unzip();
        let lat = [0.0];
        let values: [&[f64]; 3] = [&a, &lat, &b];
        let d = Profile {
            parts: vec![],
            counts,
            a: vec![],
            lat,
            b: vec![],
        };
        w.write_profile(&record(&s, p, &d, &values)).unwrap();
    }
    w.finish().unwrap();
    let f = hdf5::File::open(&path).unwrap();
    let ds = f.dataset("counts").unwrap();
    let back: Vec<u64> = ds.read_raw().unwrap();
    let want: Vec<u64> = (0..s.n_profiles * n).map(|k| noisy(k / n, k % n)).collect();
    assert!(back == want, "counts read back through HDF5's filters");
    let theirs = hdf5::File::create(dir.join("theirs.h5")).unwrap();
    let want32: Vec<u32> = want.iter().map(|&c| u32::try_from(c).unwrap()).collect();
    let copy = hdf5_pipeline_copy::<u32>(&ds, &want32, &theirs, "counts");
    let (a, b) = (common::chunk_info(&ds), common::chunk_info(&copy));
    for (k, ((oa, _, sa), (ob, _, sb))) in a.iter().zip(&b).enumerate() {
        let mine = common::raw_chunk(&ds, oa, *sa);
        assert_eq!(
            chunk::inflate(&mine).unwrap(),
            chunk::inflate(&common::raw_chunk(&copy, ob, *sb)).unwrap()
        );
        if k == 0 {
            // zlib header, then a stored block of 65,535 bytes: the low bytes as they are
            assert_eq!(mine[..7], [0x78, 0x01, 0x00, 0xFF, 0xFF, 0x00, 0x00]);
            assert!(mine.len() < 52 * n * 4 * 55 / 100, "higher planes deflated");
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn refusals_name_the_file_and_leave_the_writer_usable() {
    let dir = scratch("refuse");
    let path = dir.join("r.h5");
    let s = spec(3, 1, 4, CountWidth::U16, false);
    let mut w = RawFileWriter::create(&path, Path::new("shown.h5"), &s).unwrap();
    let a = [0.5; 4];
    let lat = [1.0];
    let values: Vec<&[f64]> = vec![&a, &lat, &a];
    let rec = |index: usize, counts: &'static [u64]| ProfileRecord {
        index,
        time_s: 1.0,
        n_shots: 1,
        pulse_energy_j: &[0.1],
        counts,
        components: None,
        values: &[],
        columns: &[],
        column_weights: &[],
    };
    let ok = ProfileRecord {
        values: &values,
        ..rec(0, &[1, 2, 3, 4])
    };
    w.write_profile(&ok).unwrap();
    let twice = w.write_profile(&ok).unwrap_err().to_string();
    assert!(
        twice.contains("shown.h5") && twice.contains("written twice"),
        "{twice}"
    );
    let too_big = ProfileRecord {
        values: &values,
        ..rec(1, &[1, 70_000, 3, 4])
    };
    let e = w.write_profile(&too_big).unwrap_err().to_string();
    assert!(e.contains("70000") && e.contains("u16"), "{e}");
    let nan = [f64::NAN, 0.0, 0.0, 0.0];
    let bad_values: Vec<&[f64]> = vec![&a, &lat, &nan];
    let e = w
        .write_profile(&ProfileRecord {
            values: &bad_values,
            ..rec(1, &[1, 2, 3, 4])
        })
        .unwrap_err()
        .to_string();
    assert!(e.contains("non-finite"), "{e}");
    let e = w
        .write_profile(&ProfileRecord {
            values: &values,
            ..rec(3, &[1, 2, 3, 4])
        })
        .unwrap_err()
        .to_string();
    assert!(e.contains("out of range"), "{e}");
    // refused records changed nothing: profile 1 can still be written
    w.write_profile(&ProfileRecord {
        values: &values,
        ..rec(2, &[4, 3, 2, 1])
    })
    .unwrap();
    assert_eq!(w.profiles_written(), 2);
    let e = w.finish().unwrap_err().to_string();
    assert!(
        e.contains("shown.h5") && e.contains("2 of 3") && e.contains("first missing: 1"),
        "{e}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn streamed_columns_read_back_in_any_order_with_nan_where_none_came() {
    // 2 channels × 3,000 bins: 10 columns a chunk (512 KiB), 45 columns, the last chunk
    // an edge one; columns come out of order, 12 and 40–44 never (a shard's unseen ones)
    let dir = scratch("columns");
    let path = dir.join("c.h5");
    let (channels, n_bins, n_columns) = (2, 3000, 45);
    let mut spec = spec(3, channels, n_bins, CountWidth::U32, false);
    spec.n_columns = n_columns;
    spec.column_slots = 1;
    spec.streamed_columns = true;
    for (name, dims) in [("t_ccb", Dims::ColumnChannelBin), ("t_cb", Dims::ColumnBin)] {
        spec.variables.push(Variable {
            name: name.into(),
            dims,
            long_name: name.into(),
            units: "1".into(),
            attributes: vec![],
            data: vec![],
        });
    }
    let value = |c: usize, i: usize, k: usize| truth(c, i, k + 2);
    let rows = |c: usize| -> (Vec<f64>, Vec<f64>) {
        (
            (0..channels * n_bins).map(|i| value(c, i, 0)).collect(),
            (0..n_bins).map(|i| value(c, i, 1)).collect(),
        )
    };
    let missing = |c: usize| c == 12 || c >= 40;
    let order: Vec<usize> = (0..n_columns)
        .map(|k| (k * 17) % n_columns)
        .filter(|&c| !missing(c))
        .collect();
    let mut w = RawFileWriter::create(&path, &path, &spec).unwrap();
    for &c in &order {
        let (a, b) = rows(c);
        w.write_column(c, &[&a, &b]).unwrap();
    }
    // refused, naming the file, the writer usable after
    let (a, b) = rows(3);
    let twice = w.write_column(3, &[&a, &b]).unwrap_err().to_string();
    assert!(twice.contains("c.h5") && twice.contains("twice"), "{twice}");
    let short = w.write_column(12, &[&a[1..], &b]).unwrap_err().to_string();
    assert!(short.contains("values for"), "{short}");
    assert!(w.write_column(45, &[&a, &b]).is_err());
    for p in 0..3 {
        let d = profile(&spec, p);
        let values: Vec<&[f64]> = vec![&d.a, &d.lat, &d.b];
        let rec = ProfileRecord {
            columns: &[0],
            column_weights: &[1.0],
            ..record(&spec, p, &d, &values)
        };
        w.write_profile(&rec).unwrap();
    }
    w.finish().unwrap();
    let f = hdf5::File::open(&path).unwrap();
    let read = |name: &str| f.dataset(name).unwrap().read_raw::<f64>().unwrap();
    let (ccb, cb) = (read("t_ccb"), read("t_cb"));
    assert_eq!(ccb.len(), n_columns * channels * n_bins);
    for c in 0..n_columns {
        let (a, b) = rows(c);
        let (got_a, got_b) = (
            &ccb[c * a.len()..(c + 1) * a.len()],
            &cb[c * b.len()..(c + 1) * b.len()],
        );
        if missing(c) {
            assert!(got_a.iter().chain(got_b).all(|x| x.is_nan()), "column {c}");
        } else {
            assert!(got_a == &a[..] && got_b == &b[..], "column {c}");
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}
