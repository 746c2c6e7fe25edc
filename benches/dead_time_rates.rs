//! Cost of the dead-time detector against the ideal one, rate by rate (issues 21 and 41):
//! one profile of a constant true rate n over [`BINS`] bins of 2 µs, τ = 3.5 ns, drawn
//! by the ideal detector (`sampling::shot_profile`, what `simulate --method shot` runs
//! without dead time) and through the dead time (`dead_time::DeadTimedShots::profile`,
//! what it runs with), one thread, the least CPU time of [`REPEAT`] runs each. Prints a
//! Markdown table of ns per shot-bin and the ratio.
//!
//! ```text
//! RAYON_NUM_THREADS=1 cargo bench --bench dead_time_rates
//! PATH_DT=walk RATES="1e6 3e8" MODELS=par RAYON_NUM_THREADS=1 cargo bench --bench dead_time_rates
//! SHOTS=100 RAYON_NUM_THREADS=1 cargo bench --bench dead_time_rates   # profiles of 100 shots
//! ```

use lidarsim::detector::dead_time::{DeadTimePath, DeadTimedShots};
use lidarsim::detector::{DeadTime, DeadTimeModel};
use lidarsim::sampling::{ShotSampler, shot_profile};

const TAU: f64 = 3.5e-9;
const DT: f64 = 2e-6;
const BINS: usize = 200;
const REPEAT: usize = 5;

/// This thread's CPU time, s (not the wall clock: the machine is shared, and a thread
/// waiting for a core is not drawing).
fn cpu_time() -> f64 {
    let mut t = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: a valid pointer to a timespec, a clock every Linux has.
    unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut t) };
    t.tv_sec as f64 + t.tv_nsec as f64 * 1e-9
}

/// CPU seconds of the fastest of `REPEAT` calls of `f`.
fn best(mut f: impl FnMut(u64)) -> f64 {
    (0..REPEAT)
        .map(|i| {
            let t = cpu_time();
            f(i as u64);
            cpu_time() - t
        })
        .fold(f64::INFINITY, f64::min)
}

fn main() {
    // RATES="1e6 3e8" and MODELS="non" or "par" measure a subset
    let rates: Vec<f64> = std::env::var("RATES").map_or_else(
        // 0.01 photons a bin (5 kHz in bins of 2 µs) to 300 MHz
        |_| {
            vec![
                5e3, 2.5e4, 5e4, 1e5, 2.5e5, 5e5, 1e6, 3e6, 1e7, 3e7, 5e7, 1e8, 2e8, 3e8,
            ]
        },
        |s| {
            s.split_whitespace()
                .map(|x| x.parse().expect("a rate"))
                .collect()
        },
    );
    let models = std::env::var("MODELS").unwrap_or_default();
    // PATH=walk or PATH=photons forces a path (default: the one `simulate` picks)
    let path = match std::env::var("PATH_DT").as_deref() {
        Ok("walk") => DeadTimePath::Walk,
        Ok("photons") => DeadTimePath::Photons,
        Ok("columns") => DeadTimePath::Columns,
        _ => DeadTimePath::Auto,
    };
    println!(
        "| model | n (Hz) | photons / bin | path | ideal (ns / shot-bin) | dead time (ns / shot-bin) | ratio |"
    );
    println!("|---|---|---|---|---|---|---|");
    for model in [DeadTimeModel::Nonparalyzable, DeadTimeModel::Paralyzable] {
        let name = format!("{model:?}").to_lowercase();
        if !models.split_whitespace().all(|m| name.starts_with(m)) {
            continue;
        }
        let dead = DeadTime {
            tau_s: TAU,
            model,
            bin_width_s: DT,
            pixels: 1,
        };
        for &n in &rates {
            let lambda = n * DT;
            let sampler = ShotSampler::new(&[lambda; BINS]);
            // ~2e6 photons or 2e5 shot-bins per run, whichever is more; SHOTS=100 draws
            // profiles of 100 shots (the paper's), as many as make 2e5 shot-bins a run
            let (shots, profiles) = match std::env::var("SHOTS") {
                Ok(s) => {
                    let shots: u64 = s.parse().expect("SHOTS: a number of shots");
                    (shots, (2e5 / (shots * BINS as u64) as f64).ceil() as u64)
                }
                Err(_) => (
                    ((2e6 / (lambda * BINS as f64)).max(2e5 / BINS as f64) as u64)
                        .clamp(200, 65_536),
                    1,
                ),
            };
            if std::env::var("STRATEGY").is_ok() {
                eprintln!("{lambda}: {}", sampler.strategy());
            }
            let recorded = DeadTimedShots::new(sampler.clone(), dead).with_path(path);
            let which = if recorded.takes_columns(shots) {
                "columns"
            } else if recorded.walks() {
                "walk"
            } else {
                "photons"
            };
            let mut acc = vec![0u64; BINS];
            // warm up (tables built on first use)
            recorded.profile(1, 0, shots.min(1000), &mut acc);
            let ideal = best(|i| {
                for p in i * profiles..(i + 1) * profiles {
                    shot_profile(&sampler, 7, p, shots, &mut acc);
                }
            });
            let dead_s = best(|i| {
                for p in i * profiles..(i + 1) * profiles {
                    recorded.profile(7, p, shots, &mut acc);
                }
            });
            let per = |s: f64| s * 1e9 / ((shots * profiles) as f64 * BINS as f64);
            println!(
                "| {model:?} | {n:.0e} | {lambda:.3} | {which} | {:.2} | {:.2} | {:.2} |",
                per(ideal),
                per(dead_s),
                dead_s / ideal
            );
            std::hint::black_box(&acc);
        }
    }
}
