//! `lidarsim simulate`: determinism, file contents, the Poisson law of the counts, bad input.

mod common;
use std::path::{Path, PathBuf};
use std::process::Command;

use common::config_path;

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("lidarsim-sim-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn simulate(cfg: &str, out: &Path, extra: &[&str], threads: Option<&str>) -> std::process::Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_lidarsim"));
    cmd.args([
        "simulate",
        config_path(cfg).to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ])
    .args(extra);
    if let Some(t) = threads {
        cmd.env("RAYON_NUM_THREADS", t);
    }
    cmd.output().unwrap()
}

fn read_counts(path: &Path) -> Vec<u64> {
    let f = hdf5::File::open(path).unwrap();
    let ds = f.dataset("counts").unwrap();
    ds.read_raw::<u64>().unwrap_or_else(|_| {
        ds.read_raw::<u32>()
            .map(|v| v.into_iter().map(u64::from).collect())
            .unwrap_or_else(|_| {
                ds.read_raw::<u16>()
                    .unwrap()
                    .into_iter()
                    .map(u64::from)
                    .collect()
            })
    })
}

#[test]
fn same_seed_same_counts_whatever_the_thread_count() {
    let dir = scratch("det");
    for method in ["shot", "aggregate"] {
        let a = dir.join(format!("{method}-1.h5"));
        let b = dir.join(format!("{method}-2.h5"));
        let c = dir.join(format!("{method}-seed.h5"));
        for (out, threads, seed) in [(&a, "1", "7"), (&b, "2", "7"), (&c, "2", "8")] {
            let o = simulate(
                "paper/scenario2.toml",
                out,
                &["--method", method, "--profiles", "20", "--seed", seed],
                Some(threads),
            );
            assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        }
        assert_eq!(read_counts(&a), read_counts(&b), "{method}: 1 vs 2 threads");
        assert_ne!(read_counts(&a), read_counts(&c), "{method}: seeds 7 and 8");
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn the_file_has_every_interface_variable_with_units() {
    let dir = scratch("vars");
    let out = dir.join("s1.h5");
    let o = simulate(
        "paper/scenario1.toml",
        &out,
        &["--profiles", "3", "--components"],
        None,
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let f = hdf5::File::open(&out).unwrap();
    for name in [
        "counts",
        "altitude",
        "range",
        "time",
        "n_shots",
        "expected_signal",
        "expected_background",
        "expected_dark",
        "expected_counts",
        "snr_eq4",
        "range_weight",
        "lidar_constant",
        "attenuated_backscatter",
        "beta_mol",
        "beta_aer",
        "beta_cld",
        "alpha_total",
        "t2",
        "signal_counts",
        "background_counts",
        "dark_counts",
    ] {
        let ds = f.dataset(name).unwrap_or_else(|_| panic!("{name} missing"));
        assert!(
            ds.attr("units").is_ok() && ds.attr("long_name").is_ok(),
            "{name} lacks CF attributes"
        );
    }
    assert_eq!(f.dataset("counts").unwrap().shape(), vec![3, 1, 334]);
    for attr in [
        "Conventions",
        "title",
        "source",
        "history",
        "config",
        "seed",
        "method",
        "date_created",
        "lidarsim_format_version",
    ] {
        assert!(f.attr(attr).is_ok(), "root attribute {attr} missing");
    }
    // components add up to the counts
    let total = read_counts(&out);
    let part = |n: &str| f.dataset(n).unwrap().read_raw::<u32>().unwrap();
    let (s, b, d) = (
        part("signal_counts"),
        part("background_counts"),
        part("dark_counts"),
    );
    for i in 0..total.len() {
        assert_eq!(total[i], u64::from(s[i] + b[i] + d[i]));
    }
    // a summary paragraph on stderr
    assert!(String::from_utf8_lossy(&o.stderr).contains("shot-bins/s"));
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn bad_input_leaves_no_file() {
    let dir = scratch("bad");
    let out = dir.join("x.h5");
    let o = simulate(
        "paper/scenario1.toml",
        &out,
        &["--set", "instrument.pulse_energy_j=nan"],
        None,
    );
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("instrument.pulse_energy_j"));
    let o = simulate(
        "paper/scenario1.toml",
        &dir.join("no/such/dir/x.h5"),
        &[],
        None,
    );
    assert_eq!(o.status.code(), Some(2));
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("no/such/dir/x.h5"),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let o = simulate("paper/scenario1.toml", &out, &["--method", "fastest"], None);
    assert_eq!(o.status.code(), Some(2));
    assert_eq!(
        std::fs::read_dir(&dir).unwrap().count(),
        0,
        "nothing written"
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn aggregate_is_refused_where_counts_are_not_poisson() {
    let dir = scratch("dead");
    let out = dir.join("j.h5");
    let o = simulate(
        "paper/scenario1.toml",
        &out,
        &[
            "--set",
            "instrument.detector.dead_time_s=3.5e-9",
            "--method",
            "aggregate",
        ],
        None,
    );
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("aggregate") && err.contains("dead time"),
        "{err}"
    );
    assert!(!out.exists());
    // auto falls back to the shot path and says so in the summary
    let o = simulate(
        "paper/scenario1.toml",
        &out,
        &[
            "--set",
            "instrument.detector.dead_time_s=3.5e-9",
            "--profiles",
            "2",
        ],
        None,
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stderr).contains("method shot"));
    // jitter alone keeps the exact aggregate: the profile's energies are drawn first
    let o = simulate(
        "paper/scenario1.toml",
        &out,
        &[
            "--set",
            "instrument.pulse_energy_jitter=0.05",
            "--profiles",
            "2",
        ],
        None,
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stderr).contains("method aggregate"));
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn validate_sees_exactly_the_counts_simulate_writes() {
    use lidarsim::validate::RealizationSource;
    let dir = scratch("same");
    let out = dir.join("s3.h5");
    let o = simulate(
        "paper/scenario3.toml",
        &out,
        &["--profiles", "5", "--seed", "31", "--method", "shot"],
        None,
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let file = read_counts(&out);
    let sc = common::scenario("paper/scenario3.toml", &[]);
    let e = sc.expected().unwrap();
    let source = lidarsim::validate::SimulatorSource::new(
        &e,
        lidarsim::simulate::ResolvedMethod::Shot,
        0.0,
        31,
        sc.shots_per_profile(),
    );
    let n = e.n_bins();
    for p in 0..5u64 {
        let mut c = vec![0u64; n];
        source.draw(p, &mut c);
        assert_eq!(
            &file[p as usize * n..(p as usize + 1) * n],
            &c[..],
            "profile {p}"
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// KS distance between Poisson(μ) and `max(0, round(μ + √μ·g))`, written here from its
/// definition: `sup_k |F_Poisson(k) − Φ((k + ½ − μ)/√μ)|` over every k that matters.
fn normal_approximation_ks(mu: f64) -> f64 {
    let kmax = (mu + 12.0 * mu.sqrt() + 40.0) as u64;
    let (mut pmf, mut cdf, mut worst) = ((-mu).exp(), 0.0, 0.0f64);
    for k in 0..kmax {
        if k > 0 {
            pmf *= mu / k as f64;
        }
        cdf += pmf;
        let z = (k as f64 + 0.5 - mu) / mu.sqrt();
        let phi = 0.5 * statrs::function::erf::erfc(-z / std::f64::consts::SQRT_2);
        worst = worst.max((cdf - phi).abs());
    }
    worst
}

/// The threshold μ* of a tolerance τ, from the bound `src/sampling/approx/` documents,
/// solved here: `c/√μ·(1 + 1/(8μ) + 1e-6) = τ`, `c = 1/(6√(2π))` (bisection).
fn threshold_for(tau: f64) -> f64 {
    let c = 1.0 / (6.0 * (2.0 * std::f64::consts::PI).sqrt());
    let bound = |mu: f64| c / mu.sqrt() * (1.0 + 0.125 / mu + 1e-6);
    let (mut lo, mut hi) = (1.0f64, 1e12f64);
    for _ in 0..200 {
        let mid = (lo * hi).sqrt();
        if bound(mid) > tau { lo = mid } else { hi = mid }
    }
    hi
}

/// The threshold keeps its promise: at every mean from μ* to 1.2·μ* (step 0.01) the
/// normal approximation's exact KS distance, computed here, is within τ = 1e-2; and the
/// promise is tight: some mean within 2 % below μ* exceeds it.
#[test]
fn the_normal_threshold_keeps_the_tolerance() {
    let mu_star = threshold_for(1e-2);
    assert!((44.0..45.0).contains(&mu_star), "{mu_star}");
    let mut mu = mu_star;
    while mu < 1.2 * mu_star {
        let ks = normal_approximation_ks(mu);
        assert!(ks <= 1e-2, "KS({mu}) = {ks}");
        mu += 0.01;
    }
    let exceeded =
        (1..=200).any(|k| normal_approximation_ks(mu_star * (1.0 - 1e-4 * k as f64)) > 1e-2);
    assert!(exceeded, "the threshold is not tight");
}

#[test]
fn tolerance_picks_the_fastest_method_within_it() {
    use lidarsim::simulate::{ResolvedMethod, fastest_within};
    let sc = common::scenario(
        "paper/scenario1.toml",
        &["acquisition.accumulation_time_s=100"],
    );
    let e = sc.expected().unwrap();
    let m = sc.shots_per_profile();
    // 1 J, 1000 shots: every bin has M·λ ≫ 44, the normal approximation is within 1e-2
    let t2 = fastest_within(1e-2, &e, m, true);
    let want = threshold_for(1e-2);
    assert!(
        matches!(t2, ResolvedMethod::AggregateNormal { threshold } if (threshold / want - 1.0).abs() < 1e-3),
        "{t2:?} vs {want}"
    );
    // a tolerance so tight no bin qualifies keeps the exact aggregate
    assert_eq!(fastest_within(1e-9, &e, m, true), ResolvedMethod::Aggregate);
    // a scene that needs shots keeps them
    assert_eq!(fastest_within(1e-2, &e, m, false), ResolvedMethod::Shot);
    // sparse profiles of few shots: the shot path is cheaper than one draw per bin
    let sparse = common::scenario(
        "paper/scenario1.toml",
        &[
            "instrument.pulse_energy_j=0.001",
            "acquisition.accumulation_time_s=1",
        ],
    );
    let es = sparse.expected().unwrap();
    assert_eq!(
        fastest_within(1e-3, &es, sparse.shots_per_profile(), true),
        ResolvedMethod::Shot
    );
    // the CLI records the choice and refuses a tolerance with a forced method
    let dir = scratch("tol");
    let out = dir.join("t.h5");
    let o = simulate(
        "paper/scenario1.toml",
        &out,
        &[
            "--tolerance",
            "1e-2",
            "--set",
            "acquisition.accumulation_time_s=100",
        ],
        None,
    );
    assert!(String::from_utf8_lossy(&o.stderr).contains("method aggregate-normal"));
    let f = hdf5::File::open(&out).unwrap();
    let threshold: f64 = f
        .attr("normal_approximation_threshold")
        .unwrap()
        .read_scalar()
        .unwrap();
    assert!(
        (threshold / want - 1.0).abs() < 1e-3,
        "{threshold} vs {want}"
    );
    let o = simulate(
        "paper/scenario1.toml",
        &dir.join("u.h5"),
        &["--tolerance", "1e-2", "--method", "shot"],
        None,
    );
    assert_eq!(o.status.code(), Some(2));
    assert!(!dir.join("u.h5").exists());
    std::fs::remove_dir_all(&dir).ok();
}
