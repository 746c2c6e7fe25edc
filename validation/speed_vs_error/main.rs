//! Speed against error of every sampler (issue 4, item 4).
//!
//! For each method — `shot` with every bin on the dense path, `shot` with every bin on
//! the sparse/alias path, `shot` with the cost-model split, `aggregate` (exact), and the
//! normal approximation `aggregate-normal` at several tolerances — on the paper's
//! scenarios at several (fL, TC): the time per profile (median, one thread) and the
//! error against the exact law (per-bin Kolmogorov–Smirnov distance between the
//! empirical count distribution of R profiles and Poisson(M·λ), relative errors of the
//! mean, variance and Eq. 4 S/N), each beside the noise floor of R exact draws. Writes
//! `speed_vs_error.md` and `speed_vs_error.png` into the output folder.
//!
//! ```text
//! cargo run --release --example speed_vs_error -- [--out validation/reports] [--quick]
//! ```
//!
//! Deterministic: every profile comes from `stream_rng(seed, profile, block)` with fixed
//! seeds; only the timings change from run to run.
//!
//! The program's parts: the cases and methods (`cases.rs`), the timing and the error
//! statistics (`measure.rs`), the check of the approximation's KS bound (`bound.rs`), the
//! report (`report.rs`, its reading `reading.rs`) and the figure (`plot.rs`).

#[path = "../figure.rs"]
mod figure;

mod bound;
mod cases;
mod measure;
mod plot;
mod reading;
mod report;

use std::path::{Path, PathBuf};
use std::time::Instant;

use lidarsim::sampling::approx::{aggregate_approx_profile, normal_approx_ks, normal_threshold};
use lidarsim::sampling::{self, PathChoice, ShotSampler};
use lidarsim::scenario::Scenario;

use bound::bound_check;
use cases::{Method, cases};
use measure::{bin_stats, ks_floor, profiles_for, sample, time_interleaved};
use plot::plot;
use report::{fmt_time, report, sci};

const COMMAND: &str = "cargo run --release --example speed_vs_error -- --out validation/reports";
const QUICK_COMMAND: &str =
    "cargo run --release --example speed_vs_error -- --out validation/reports --quick";

/// Draws profile `p` into a zeroed accumulator.
type DrawFn = dyn Fn(u64, &mut [u64]) + Sync;

/// Run-size settings of a mode.
struct Mode {
    quick: bool,
    /// Wall-time budget for the R error profiles of one (method, case), s.
    error_budget_s: f64,
    r_min: usize,
    r_max: usize,
    /// Least total timed profile time per point, s.
    timing_s: f64,
}

/// One line of the table.
struct Row {
    case: String,
    rep_rate_hz: f64,
    accumulation_s: f64,
    shots: u64,
    bins: usize,
    method: Method,
    r: usize,
    time_s: f64,
    max_ks: f64,
    ks_floor: f64,
    /// Max over approximated bins of the exact KS distance, and their number.
    ks_bound: Option<(f64, usize)>,
    rel_mean: (f64, f64),
    rel_var: (f64, f64),
    rel_snr: (f64, f64),
    n_sel: usize,
    sel_range_km: (f64, f64),
}

fn main() {
    let mut out = PathBuf::from("validation/reports");
    let mut quick = false;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--out" => out = PathBuf::from(args.next().expect("--out needs a folder")),
            "--quick" => quick = true,
            "-h" | "--help" => {
                eprintln!("usage: {COMMAND} [--quick]");
                return;
            }
            other => panic!("unknown argument {other:?} (use --out DIR, --quick)"),
        }
    }
    let mode = if quick {
        Mode {
            quick,
            error_budget_s: 0.15,
            r_min: 100,
            r_max: 2000,
            timing_s: 0.2,
        }
    } else {
        Mode {
            quick,
            error_budget_s: 1.5,
            r_min: 300,
            r_max: 50000,
            timing_s: 0.2,
        }
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("rayon pool");
    let start = Instant::now();
    pool.install(|| run(&out, &mode));
    eprintln!("done in {:.1} s", start.elapsed().as_secs_f64());
}

fn run(out: &Path, mode: &Mode) {
    std::fs::create_dir_all(out).expect("create the output folder");
    let t_all = Instant::now();
    eprintln!("checking the KS bound of the normal approximation on a dense grid ...");
    let check = bound_check(mode.quick);
    eprintln!("  {} means checked in {:.1} s", check.points, check.seconds);

    let cases = cases();
    let methods = Method::all();
    let total = cases.len() * methods.len();
    let mut rows = Vec::new();
    for (ci, case) in cases.iter().enumerate() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("configs/paper")
            .join(case.file);
        let sc = Scenario::load(&path, &case.overrides).expect("load the scenario");
        let e = sc.expected().expect("the model");
        let shots = sc.shots_per_profile();
        let lambda = e.total_per_shot();
        let snr = e.snr_eq4(shots as f64);
        let m = shots as f64;
        let rest = m * (e.background + e.dark);
        let mu: Vec<f64> = lambda.iter().map(|l| l * m).collect();
        let sel: Vec<usize> = (0..lambda.len())
            .filter(|&i| m * e.signal[i] >= 1.0)
            .collect();
        let sel_km = sel
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |a, &i| {
                let z = e.altitude_m[i] / 1e3;
                let z = if z.abs() < 0.05 { 0.0 } else { z };
                (a.0.min(z), a.1.max(z))
            });
        // samplers of every method, built once per case
        let built: Vec<(Method, Option<f64>, Box<DrawFn>)> = methods
            .iter()
            .enumerate()
            .map(|(mi, &method)| {
                let seed = 0x5EED_0000 + (ci as u64) * 64 + mi as u64;
                let threshold = match method {
                    Method::AggregateNormal(t) => Some(normal_threshold(t)),
                    _ => None,
                };
                let draw: Box<DrawFn> = match method {
                    Method::ShotDense | Method::ShotSparse | Method::ShotAuto => {
                        let choice = match method {
                            Method::ShotDense => PathChoice::AllDense,
                            Method::ShotSparse => PathChoice::AllSparse,
                            _ => PathChoice::Auto,
                        };
                        let s = ShotSampler::with_choice(&lambda, choice);
                        Box::new(move |p, acc| sampling::shot_profile(&s, seed, p, shots, acc))
                    }
                    Method::Aggregate => {
                        let l = lambda.clone();
                        Box::new(move |p, acc| sampling::aggregate_profile(&l, seed, p, shots, acc))
                    }
                    Method::AggregateNormal(_) => {
                        let l = lambda.clone();
                        let th = threshold.expect("threshold");
                        Box::new(move |p, acc| {
                            aggregate_approx_profile(&l, seed, p, shots, th, acc)
                        })
                    }
                };
                (method, threshold, draw)
            })
            .collect();
        let draws: Vec<&DrawFn> = built.iter().map(|b| &*b.2).collect();
        let times = time_interleaved(&draws, lambda.len(), mode);
        for ((method, threshold, draw), time_s) in built.iter().zip(times) {
            let (method, threshold) = (*method, *threshold);
            let t_row = Instant::now();
            let r = profiles_for(mode, time_s);
            let counts = sample(&**draw, lambda.len(), r);
            let stats = bin_stats(&counts, r, &mu, &e.signal, m, rest, &snr, &sel);
            let ks_bound = threshold.map(|th| {
                let above: Vec<f64> = mu.iter().copied().filter(|&x| x >= th && x > 0.0).collect();
                let b = above
                    .iter()
                    .map(|&x| normal_approx_ks(x))
                    .fold(0.0, f64::max);
                (b, above.len())
            });
            let row = Row {
                case: case.label.to_string(),
                rep_rate_hz: case.rep_rate_hz,
                accumulation_s: case.accumulation_s,
                shots,
                bins: lambda.len(),
                method,
                r,
                time_s,
                max_ks: stats.max_ks,
                ks_floor: ks_floor(lambda.len(), r),
                ks_bound,
                rel_mean: stats.rel_mean,
                rel_var: stats.rel_var,
                rel_snr: stats.rel_snr,
                n_sel: sel.len(),
                sel_range_km: sel_km,
            };
            eprintln!(
                "[{:>3}/{total}] {:<14} {:>3} Hz × {:>3} s {:<24} R = {:>5}  {:>10}/profile  max KS {:.4} (floor {:.4}){}  [{:.1} s]",
                rows.len() + 1,
                row.case,
                row.rep_rate_hz,
                row.accumulation_s,
                row.method.name(),
                row.r,
                fmt_time(row.time_s),
                row.max_ks,
                row.ks_floor,
                row.ks_bound
                    .map(|(b, n)| format!(", exact bound {} on {n} bins", sci(b, 2)))
                    .unwrap_or_default(),
                t_row.elapsed().as_secs_f64()
            );
            rows.push(row);
        }
    }
    let md = report(&rows, &check, mode, t_all.elapsed().as_secs_f64());
    let md_path = out.join("speed_vs_error.md");
    std::fs::write(&md_path, md).expect("write the report");
    let png_path = out.join("speed_vs_error.png");
    plot(&rows, &png_path, mode);
    eprintln!("wrote {} and {}", md_path.display(), png_path.display());
}
