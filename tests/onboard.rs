//! Onboard averaging (issue 10): the CALIOP scheme's layout, exact integer sums, and the
//! law of an averaged stationary scene.

mod common;

use lidarsim::onboard::{Averager, Scheme};
use lidarsim::sampling::{ShotSampler, shot_profile};
use lidarsim::validate::{self, BinModel, RealizationSource};

fn caliop_native(angle: &str) -> lidarsim::scenario::Scenario {
    common::scenario(
        "instruments/caliop_532.toml",
        &[
            "acquisition.top_altitude_km=40",
            "acquisition.bottom_altitude_km=-2",
            &format!("platform.off_nadir_deg={angle}"),
        ],
    )
}

fn layout(sc: &lidarsim::scenario::Scenario, scheme: &str) -> Vec<lidarsim::onboard::RegionLayout> {
    let g = &sc.geometry;
    let native_vertical = g.bin_range_m * g.local_cos_at(0.0);
    Scheme::parse(scheme)
        .unwrap()
        .layout(g.n_bins, &|i| g.bin_centre_altitude_m(i), native_vertical)
        .unwrap()
}

/// The CALIOP scheme on CALIOP's 30 m grid: 583 bins (33 + 55 + 200 + 290 + 5) of 300,
/// 180, 60, 30 and 300 m, summing 15, 5, 3, 1 and 1 shots, at nadir and 3° off nadir;
/// `uniform:N` and `none` keep the native bins.
#[test]
fn the_caliop_scheme_has_583_bins() {
    for angle in ["0", "3"] {
        let sc = caliop_native(angle);
        let l = layout(&sc, "caliop");
        let bins: Vec<usize> = l.iter().map(|r| r.bins).collect();
        assert_eq!(bins, [33, 55, 200, 290, 5], "{angle}°");
        assert_eq!(bins.iter().sum::<usize>(), 583);
        let merge: Vec<usize> = l.iter().map(|r| r.merge).collect();
        assert_eq!(merge, [10, 6, 2, 1, 10]);
        let shots: Vec<u32> = l.iter().map(|r| r.shots).collect();
        assert_eq!(shots, [15, 5, 3, 1, 1]);
        // contiguous from the top of the window
        for w in l.windows(2) {
            assert_eq!(w[1].first_bin, w[0].first_bin + w[0].merge * w[0].bins);
        }
        let top = sc.geometry.bin_centre_altitude_m(l[0].first_bin);
        assert!((top - 39.985e3).abs() < 30.0, "{top}");
    }
    let sc = caliop_native("0");
    assert_eq!(layout(&sc, "uniform:15")[0].shots, 15);
    assert_eq!(layout(&sc, "none")[0].bins, sc.geometry.n_bins);
    assert!(Scheme::parse("uniform:0").is_err() && Scheme::parse("no/such/file.toml").is_err());
}

/// The downlinked counts are integer sums: over 45 shots (3 × 15) every region's counts
/// add up to the native counts of the same bins and shots, exactly.
#[test]
fn downlinked_counts_sum_the_native_counts_exactly() {
    let sc = caliop_native("3");
    let e = sc.expected().unwrap();
    let sampler = ShotSampler::new(&e.total_per_shot());
    let mut avg = Averager::new(layout(&sc, "caliop"), e.n_bins());
    let regions = avg.regions().to_vec();
    let mut native_sum = vec![0u64; regions.len()];
    let mut downlinked = vec![0u64; regions.len()];
    for shot in 0..45u64 {
        let mut native = vec![0u64; e.n_bins()];
        shot_profile(&sampler, 9, shot, 1, &mut native);
        for (k, r) in regions.iter().enumerate() {
            native_sum[k] += native[r.first_bin..r.first_bin + r.merge * r.bins]
                .iter()
                .sum::<u64>();
        }
        avg.add_shot(&native, |k, sums| downlinked[k] += sums.iter().sum::<u64>());
    }
    assert_eq!(native_sum, downlinked);
    assert!(downlinked[..4].iter().all(|&c| c > 0), "{downlinked:?}");
}

/// One region of the averaged product of a stationary scene, as a realization source:
/// the native shots drawn and averaged by `src/onboard`'s [`Averager`] (the code under
/// test), or, to show the check's power, by a deliberately wrong sum written here that
/// drops one native bin of each merged bin.
struct Averaged {
    sampler: ShotSampler,
    layout: Vec<lidarsim::onboard::RegionLayout>,
    region: usize,
    /// `None`: the Averager; `Some(take)`: the wrong sum of `take < merge` native bins.
    wrong_take: Option<usize>,
}

impl RealizationSource for Averaged {
    fn draw(&self, p: u64, counts: &mut [u64]) {
        let r = &self.layout[self.region];
        let shots = u64::from(r.shots);
        let mut avg = Averager::new(self.layout.clone(), self.sampler.bins());
        let mut emitted = 0;
        for s in 0..shots {
            let mut native = vec![0u64; self.sampler.bins()];
            shot_profile(&self.sampler, 21, p * shots + s, 1, &mut native);
            match self.wrong_take {
                None => avg.add_shot(&native, |k, sums| {
                    if k == self.region {
                        counts.copy_from_slice(sums);
                        emitted += 1;
                    }
                }),
                Some(take) => {
                    let span = &native[r.first_bin..r.first_bin + r.merge * r.bins];
                    for (c, chunk) in counts.iter_mut().zip(span.chunks_exact(r.merge)) {
                        *c += chunk[..take].iter().sum::<u64>();
                    }
                }
            }
        }
        if self.wrong_take.is_none() {
            assert_eq!(emitted, 1, "one averaged profile per {shots} shots");
        }
    }
}

/// On a stationary scene without dead time the averaged product of `src/onboard`'s
/// Averager has the law of a direct simulation at the coarse resolution: region 0 of the
/// CALIOP scheme (300 m, 15 shots) against Poisson(M·Σλ over the merged bins) written
/// here, CONSISTENT for the mean, variance and S/N (false-alarm rate < 2e-3); the same
/// check rejects a sum that drops one native bin of ten (a 10 % bias), so it has the
/// power to see a wrong average (the CALIOP-like instrument at night, 2,000 averaged
/// profiles).
#[test]
fn an_averaged_stationary_scene_has_the_coarse_law() {
    let sc = caliop_native("0");
    let e = sc.expected().unwrap();
    let full = layout(&sc, "caliop");
    let r = full[0].clone();
    let sampler = ShotSampler::new(&e.total_per_shot());
    let models: Vec<BinModel> = (0..r.bins)
        .map(|j| {
            let bins = r.first_bin + j * r.merge..r.first_bin + (j + 1) * r.merge;
            let s: f64 = e.signal[bins.clone()].iter().sum();
            let rest = (e.background + e.dark) * r.merge as f64;
            BinModel::new(s, rest, f64::from(r.shots), 0.0)
        })
        .collect();
    let alt: Vec<f64> = (0..r.bins)
        .map(|j| e.altitude_m[r.first_bin + j * r.merge])
        .collect();
    let source = |wrong_take| Averaged {
        sampler: sampler.clone(),
        layout: full.clone(),
        region: 0,
        wrong_take,
    };
    let (_, checks) = validate::validate_source(&source(None), &models, &alt, 2000, &[]);
    assert!(checks.iter().all(|c| c.pass), "{checks:#?}");
    let (_, checks) =
        validate::validate_source(&source(Some(r.merge - 1)), &models, &alt, 2000, &[]);
    assert!(
        !checks[0].pass,
        "a wrong sum was not rejected: {:#?}",
        checks[0]
    );
}

/// `lidarsim onboard` end to end: the CALIOP product's groups (583 bins, their
/// resolutions and shots as attributes), their counts the exact sums of the very native
/// counts `simulate` draws for one-shot profiles with the same seed, and the report's
/// rows for every scheme given.
#[test]
fn the_onboard_product_sums_the_native_shots() {
    let dir = std::env::temp_dir().join(format!("lidarsim-onboard-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let cfg = common::config_path("instruments/caliop_532.toml");
    let window = [
        "--set",
        "acquisition.top_altitude_km=40",
        "--set",
        "acquisition.bottom_altitude_km=-2",
    ];
    let (product, raw, own_raw) = (dir.join("p.h5"), dir.join("raw.h5"), dir.join("own.h5"));
    let run = |args: &[&str]| {
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_lidarsim"))
            .args(args)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        o
    };
    let mut a = vec![
        "onboard",
        cfg.to_str().unwrap(),
        "--scheme",
        "caliop",
        "--scheme",
        "uniform:15",
    ];
    a.extend(window);
    a.extend([
        "--set",
        "acquisition.profiles=6",
        "--seed",
        "4",
        "-o",
        product.to_str().unwrap(),
        "--report",
        "-",
        "--raw",
        own_raw.to_str().unwrap(),
    ]);
    let o = run(&a);
    let report = String::from_utf8(o.stdout).unwrap();
    assert_eq!(report.lines().count(), 1 + 5 + 1, "{report}");
    assert!(report.starts_with("scheme,region,altitude_min_km,altitude_max_km,vertical_resolution_m,shots_averaged,bins,snr_eq4_median,snr_empirical_median,data_rate_bps"));
    let mut s = vec![
        "simulate",
        cfg.to_str().unwrap(),
        "--method",
        "shot",
        "--seed",
        "4",
    ];
    s.extend(window);
    s.extend([
        "--set",
        "acquisition.accumulation_time_s=0.0496031746031746",
        "--profiles",
        "90",
        "-o",
        raw.to_str().unwrap(),
    ]);
    run(&s);
    let raw = hdf5::File::open(&raw).unwrap();
    let native: Vec<u64> = raw
        .dataset("counts")
        .unwrap()
        .read_raw::<u64>()
        .unwrap_or_else(|_| {
            raw.dataset("counts")
                .unwrap()
                .read_raw::<u16>()
                .unwrap()
                .iter()
                .map(|&c| u64::from(c))
                .collect()
        });
    let n_bins = raw.dataset("altitude").unwrap().shape()[0];
    // --raw writes the very same draw
    let own = hdf5::File::open(&own_raw).unwrap();
    assert_eq!(
        own.dataset("counts").unwrap().read_raw::<u16>().unwrap(),
        raw.dataset("counts").unwrap().read_raw::<u16>().unwrap()
    );
    assert_eq!(
        raw.dataset("n_shots").unwrap().read_raw::<u64>().unwrap()[0],
        1
    );
    let sc = caliop_native("3");
    let regions = layout(&sc, "caliop");
    let f = hdf5::File::open(&product).unwrap();
    let mut total_bins = 0;
    for (k, r) in regions.iter().enumerate() {
        let g = f.group(&format!("region_{k}")).unwrap();
        let counts = g.dataset("counts").unwrap();
        let shape = counts.shape();
        assert_eq!(shape, vec![90 / r.shots as usize, 1, r.bins]);
        total_bins += shape[2];
        let shots: u32 = g.attr("shots_averaged").unwrap().read_scalar().unwrap();
        assert_eq!(shots, r.shots);
        let product_sum: u64 = counts
            .read_raw::<u32>()
            .unwrap()
            .iter()
            .map(|&c| u64::from(c))
            .sum();
        let native_sum: u64 = (0..90)
            .map(|p| {
                native[p * n_bins + r.first_bin..p * n_bins + r.first_bin + r.merge * r.bins]
                    .iter()
                    .sum::<u64>()
            })
            .sum();
        assert_eq!(product_sum, native_sum, "region {k}");
    }
    assert_eq!(total_bins, 583);
    std::fs::remove_dir_all(&dir).ok();
}

/// Over broken cloud (40 % of thick boundary-layer cells of 2 km) the averaging bias of
/// the report grows with the horizontal averaging: none for single shots, more for 5,
/// 15 and 75 shots (the cells are drawn from the seed: a deterministic check).
#[test]
fn the_averaging_bias_grows_with_the_averaging_length_over_broken_cloud() {
    let dir = std::env::temp_dir().join(format!("lidarsim-onboard-bias-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let cfg = common::config_path("instruments/caliop_532.toml");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_lidarsim"))
        .args(["onboard", cfg.to_str().unwrap()])
        .args(["--set", "acquisition.top_altitude_km=20", "--set", "acquisition.profiles=200"])
        .args([
            "--set",
            "atmosphere.layers=[{kind=\"cloud\", base_km=1.0, top_km=1.5, extinction_per_km=10.0, lidar_ratio_sr=18.0, cloud_fraction=0.4, cell_length_km=2.0}]",
        ])
        .args(["--scheme", "uniform:1", "--scheme", "uniform:5", "--scheme", "uniform:15", "--scheme", "uniform:75"])
        .args(["-o", dir.join("p.h5").to_str().unwrap(), "--report", "-"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let report = String::from_utf8(o.stdout).unwrap();
    assert!(
        report
            .lines()
            .next()
            .unwrap()
            .ends_with(",averaging_bias_median")
    );
    let bias: Vec<f64> = report
        .lines()
        .skip(1)
        .map(|l| l.rsplit(',').next().unwrap().parse().unwrap())
        .collect();
    assert_eq!(bias[0], 0.0, "{report}");
    assert!(bias.windows(2).all(|w| w[1] > w[0]), "{bias:?}");
    std::fs::remove_dir_all(&dir).ok();
}

/// A scheme from a TOML file: its regions laid on the native grid; a malformed or
/// inconsistent file is refused in one line naming the problem.
#[test]
fn a_scheme_file_is_read_and_checked() {
    let dir = std::env::temp_dir().join(format!("lidarsim-scheme-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let good = dir.join("two.toml");
    std::fs::write(
        &good,
        "[[regions]]\ntop_km = 20.0\nbottom_km = 10.0\nvertical_resolution_m = 150.0\nshots_averaged = 10\n\n\
         [[regions]]\ntop_km = 10.0\nbottom_km = 0.0\nvertical_resolution_m = 30.0\nshots_averaged = 2\n",
    )
    .unwrap();
    let sc = caliop_native("0");
    let l = layout(&sc, good.to_str().unwrap());
    assert_eq!(
        l.iter()
            .map(|r| (r.bins, r.merge, r.shots))
            .collect::<Vec<_>>(),
        [(67, 5, 10), (333, 1, 2)]
    );
    let bad = dir.join("gap.toml");
    std::fs::write(
        &bad,
        "[[regions]]\ntop_km = 20.0\nbottom_km = 10.0\nvertical_resolution_m = 150.0\nshots_averaged = 10\n\n\
         [[regions]]\ntop_km = 9.0\nbottom_km = 0.0\nvertical_resolution_m = 30.0\nshots_averaged = 2\n",
    )
    .unwrap();
    let e = Scheme::parse(bad.to_str().unwrap())
        .unwrap_err()
        .to_string();
    assert!(e.contains("regions[1]") && !e.contains('\n'), "{e}");
    std::fs::write(&bad, "[[regions]]\ntop_km = \"high\"\n").unwrap();
    assert!(Scheme::parse(bad.to_str().unwrap()).is_err());
    std::fs::remove_dir_all(&dir).ok();
}

/// The product declares its conventions and describes every variable: `Conventions`, and
/// a `long_name` on every dataset of every region, `units` on all but the channel names
/// (compliance-checker `cf:1.10` then finds no error in it; docs/file-format.md).
#[test]
fn the_product_describes_its_variables() {
    let dir = std::env::temp_dir().join(format!("lidarsim-product-cf-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("p.h5");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_lidarsim"))
        .args(["onboard"])
        .arg(common::config_path("instruments/caliop_532.toml"))
        .args(["--scheme", "caliop", "-o"])
        .arg(&out)
        .args([
            "--set",
            "acquisition.profiles=2",
            "--set",
            "acquisition.bottom_altitude_km=-2",
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let f = hdf5::File::open(&out).unwrap();
    let text = |loc: &hdf5::Location, name: &str| -> Option<String> {
        let v: hdf5::types::VarLenUnicode = loc.attr(name).ok()?.read_scalar().ok()?;
        Some(v.as_str().to_string())
    };
    assert_eq!(text(&f, "Conventions").as_deref(), Some("CF-1.10"));
    let groups = f.groups().unwrap();
    assert_eq!(groups.len(), 5);
    for g in groups {
        for d in g.datasets().unwrap() {
            assert!(
                text(&d, "long_name").is_some(),
                "{} has no long_name",
                d.name()
            );
            if !d.name().ends_with("/channel_name") {
                assert!(text(&d, "units").is_some(), "{} has no units", d.name());
            }
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}
