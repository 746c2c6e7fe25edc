//! The raw-file writer alone: the (profile, channel, bin) variables of a file written by
//! `lidarsim simulate` (its counts and, in a changing scene, its f64 truth) written again
//! through `RawFileWriter`, in order, `--batch` profiles per call (default 64, as
//! `simulate` hands them; 1 is `write_profile` one at a time); the median wall time and
//! CPU time of `--repeat` runs (default 5). Threads: `RAYON_NUM_THREADS`.
//!
//!     lidarsim simulate configs/instruments/caliop_532.toml -o /tmp/agg.h5 \
//!         --method aggregate --profiles 20000
//!     RAYON_NUM_THREADS=1 cargo bench --bench raw_writer -- /tmp/agg.h5

use std::time::Instant;

use hdf5::types::TypeDescriptor;
use lidarsim::output::raw_file::{
    CountWidth, Dims, ProfileRecord, RawFileSpec, RawFileWriter, Variable,
};

fn main() {
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with("--bench"))
        .collect();
    let Some(path) = args.first() else {
        eprintln!("usage: cargo bench --bench raw_writer -- FILE.h5 [--repeat N] [--batch N]");
        return;
    };
    let repeat: usize = args
        .iter()
        .position(|a| a == "--repeat")
        .and_then(|i| args.get(i + 1))
        .and_then(|s| s.parse().ok())
        .unwrap_or(5);
    let batch: usize = args
        .iter()
        .position(|a| a == "--batch")
        .and_then(|i| args.get(i + 1))
        .and_then(|s| s.parse().ok())
        .unwrap_or(64)
        .max(1);
    let f = hdf5::File::open(path).expect("open the file");
    let counts_ds = f.dataset("counts").expect("counts");
    let shape = counts_ds.shape();
    let (profiles, channels, bins) = (shape[0], shape[1], shape[2]);
    let width = match counts_ds.dtype().unwrap().to_descriptor().unwrap() {
        TypeDescriptor::Unsigned(hdf5::types::IntSize::U2) => CountWidth::U16,
        TypeDescriptor::Unsigned(hdf5::types::IntSize::U4) => CountWidth::U32,
        _ => CountWidth::U64,
    };
    let counts: Vec<u64> = counts_ds.read_raw().expect("read counts");
    let truth: Vec<(String, Vec<f64>)> = f
        .member_names()
        .unwrap()
        .into_iter()
        .filter(|n| n != "counts")
        .filter_map(|n| {
            let ds = f.dataset(&n).ok()?;
            (ds.ndim() == 3 && ds.dtype().ok()?.is::<f64>())
                .then(|| (n.clone(), ds.read_raw::<f64>().unwrap()))
        })
        .collect();
    let time: Vec<f64> = f.dataset("time").unwrap().read_raw().unwrap();
    let n_shots: Vec<u64> = f.dataset("n_shots").unwrap().read_raw().unwrap();
    let spec = RawFileSpec {
        n_bins: bins,
        n_profiles: profiles,
        first_profile: 0,
        channels: (0..channels).map(|c| format!("ch{c}")).collect(),
        count_width: width,
        components: false,
        time_units: "seconds since 2000-01-01 00:00:00".into(),
        channel_text: vec![],
        n_columns: 0,
        streamed_columns: false,
        column_slots: 0,
        variables: truth
            .iter()
            .map(|(name, _)| Variable {
                name: name.clone(),
                dims: Dims::ProfileChannelBin,
                long_name: name.clone(),
                units: "1".into(),
                attributes: vec![],
                data: vec![],
            })
            .collect(),
        root_attributes: vec![],
        profile_coordinates: vec![],
    };
    let row = channels * bins;
    let raw_bytes = profiles * row * (width.bytes() + 8 * truth.len());
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("w.h5");
    let mut times = Vec::new();
    let mut cpu = Vec::new();
    for _ in 0..repeat {
        let c = cpu_seconds();
        let t = Instant::now();
        let mut w = RawFileWriter::create(&out, &out, &spec).unwrap();
        for first in (0..profiles).step_by(batch) {
            let last = (first + batch).min(profiles);
            let values: Vec<Vec<&[f64]>> = (first..last)
                .map(|p| {
                    truth
                        .iter()
                        .map(|(_, v)| &v[p * row..(p + 1) * row])
                        .collect()
                })
                .collect();
            let energy = vec![0.1; channels];
            let recs: Vec<ProfileRecord> = (first..last)
                .zip(&values)
                .map(|(p, values)| ProfileRecord {
                    pulse_energy_j: &energy,
                    index: p,
                    time_s: time[p],
                    n_shots: n_shots[p],
                    counts: &counts[p * row..(p + 1) * row],
                    components: None,
                    values,
                    columns: &[],
                    column_weights: &[],
                })
                .collect();
            w.write_profiles(&recs).unwrap();
        }
        w.finish().unwrap();
        times.push(t.elapsed().as_secs_f64());
        cpu.push(cpu_seconds() - c);
    }
    cpu.sort_by(f64::total_cmp);
    times.sort_by(f64::total_cmp);
    let med = times[times.len() / 2];
    println!(
        "{path}: {profiles} profiles × {channels} channels × {bins} bins, counts {} + {} f64 variables \
         ({:.0} MB raw), {batch} per call; {} threads: median {med:.3} s of {repeat} (best {:.3} s), {:.0} MB/s; CPU time (all threads) median {:.3} s; file {} bytes",
        width.name(),
        truth.len(),
        raw_bytes as f64 / 1e6,
        rayon::current_num_threads(),
        times[0],
        raw_bytes as f64 / med / 1e6,
        cpu[cpu.len() / 2],
        std::fs::metadata(&out).unwrap().len()
    );
}

/// User + system CPU time of this process so far (every thread), s: the work done,
/// whatever else the machine runs.
fn cpu_seconds() -> f64 {
    let mut u = std::mem::MaybeUninit::<libc::rusage>::zeroed();
    // SAFETY: getrusage fills the struct it is given.
    let u = unsafe {
        libc::getrusage(libc::RUSAGE_SELF, u.as_mut_ptr());
        u.assume_init()
    };
    let tv = |t: libc::timeval| t.tv_sec as f64 + t.tv_usec as f64 * 1e-6;
    tv(u.ru_utime) + tv(u.ru_stime)
}
