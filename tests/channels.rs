//! Receiver channels, the laser's energy (jitter, drift, monitor) and their combination
//! with dead time (docs/model.md §4b–4c, issue 8).

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use lidarsim::config::{Channel, LayerKind};
use lidarsim::laser::PulseEnergy;
use lidarsim::scenario::Lidar;
use lidarsim::simulate::{self, ResolvedMethod};
use lidarsim::validate::{self, ChannelBins, RealizationSource, SimulatorSource};

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("lidarsim-ch-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn lidarsim(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_lidarsim"))
        .args(args)
        .env("SOURCE_DATE_EPOCH", "1700000000")
        .output()
        .unwrap()
}

fn source(
    lidar: &Lidar,
    method: ResolvedMethod,
    seed: u64,
) -> (SimulatorSource, Vec<lidarsim::scenario::ExpectedProfile>) {
    let expected = lidar.expected().unwrap();
    let energy = simulate::run_energy(lidar, seed, 0.0).unwrap();
    let s = SimulatorSource::for_lidar(lidar, &expected, method, energy, seed);
    (s, expected)
}

/// The judged combination: dead time, two polarization channels and pulse-energy jitter
/// together (the ground two-polarization preset, 1000 shots per profile). `validate`
/// finds the recorded counts CONSISTENT with the dead-time model (overall false-alarm
/// rate < 2e-3), and the ideal Poisson expectation (with jitter, without dead time) is
/// rejected on the mean where the ~30 MHz bins lose ~10 % of their counts.
#[test]
fn dead_time_two_polarizations_and_jitter_validate_together() {
    let lidar = common::lidar(
        "ground/ground_532_depol.toml",
        &["acquisition.accumulation_time_s=0.4"],
    );
    assert_eq!(lidar.channels.len(), 2);
    assert!(
        lidar
            .channels
            .iter()
            .all(|c| c.instrument.dead_time.is_some())
    );
    assert!(lidar.first().instrument.pulse_energy_jitter > 0.0);
    let opts = validate::ValidateOptions {
        realizations: 200,
        method: None,
        seed: Some(17),
        json: None,
    };
    let report = validate::run(&lidar, &opts).unwrap();
    assert!(report.consistent, "{:#?}", report.checks);
    assert_eq!(report.method, "shot");
    assert_eq!(report.channels, ["532_parallel", "532_perpendicular"]);

    let (src, expected) = source(&lidar, ResolvedMethod::Shot, 17);
    let shots = lidar.first().shots_per_profile();
    let mut ideal = Vec::new();
    let mut altitudes = Vec::new();
    let mut channels = Vec::new();
    for (c, e) in lidar.channels.iter().zip(&expected) {
        let offset = ideal.len();
        ideal.extend(validate::bin_models(
            e,
            shots,
            c.instrument.pulse_energy_jitter,
        ));
        altitudes.extend_from_slice(&e.altitude_m);
        channels.push(ChannelBins {
            name: c.channel_name.clone(),
            bins: offset..ideal.len(),
            background: vec![],
        });
    }
    let (_, checks) = validate::validate_channels(&src, &ideal, &altitudes, 200, &channels);
    let mean = checks.iter().find(|c| c.statistic == "mean").unwrap();
    assert!(!mean.pass, "the ideal law was not rejected: {mean:#?}");
}

/// Jitter alone keeps `aggregate` exact: the profile's energies are drawn first and the
/// counts are Poisson given them, so `validate --method aggregate` is CONSISTENT with
/// the mixed-Poisson model (false alarm < 2e-3), and the model without jitter is
/// rejected on the variance (σ = 0.1 adds 1 % of λ_sig²·M to the variance).
#[test]
fn aggregate_with_jitter_has_the_mixed_poisson_law() {
    let lidar = common::lidar(
        "paper/scenario1.toml",
        &["instrument.pulse_energy_jitter=0.1"],
    );
    assert_eq!(
        simulate::resolve_method(lidarsim::config::Method::Auto, &lidar).unwrap(),
        ResolvedMethod::Aggregate
    );
    let opts = validate::ValidateOptions {
        realizations: 2000,
        method: Some(lidarsim::config::Method::Aggregate),
        seed: Some(3),
        json: None,
    };
    let report = validate::run(&lidar, &opts).unwrap();
    assert!(report.consistent, "{:#?}", report.checks);
    let (src, expected) = source(&lidar, ResolvedMethod::Aggregate, 3);
    let e = &expected[0];
    let plain = validate::bin_models(e, lidar.first().shots_per_profile(), 0.0);
    let (_, checks) =
        validate::validate_source(&src, &plain, &e.altitude_m, 2000, &e.background_bin_indices);
    let var = checks.iter().find(|c| c.statistic == "variance").unwrap();
    assert!(!var.pass, "jitter's variance not seen: {var:#?}");
}

/// A cirrus seen by the two polarization channels of one receiver (cross-talk 1 %, a
/// more sensitive perpendicular detector): the model's bin ratio, corrected for the
/// channels' constants and the cross-talk, is the cloud's volume depolarization at the
/// bin centre (to 1e-3), and the ratio recovered from the counts matches the model
/// within 4 sd (false alarm 6e-5).
#[test]
fn volume_depolarization_of_a_cirrus_from_two_channels() {
    let lidar = common::lidar(
        "ground/ground_532_depol.toml",
        &[
            "instrument.detector.dead_time_s=0",
            "instrument.pulse_energy_jitter=0",
            "acquisition.accumulation_time_s=0.2",
        ],
    );
    let (par, perp) = (&lidar.channels[0], &lidar.channels[1]);
    assert_eq!(par.instrument.channel, Channel::Parallel);
    assert_eq!(perp.instrument.channel, Channel::Perpendicular);
    let x = perp.atmosphere.polarization.crosstalk;
    assert!(x > 0.0);
    let (src, expected) = source(&lidar, ResolvedMethod::Aggregate, 9);
    let n = expected[0].n_bins();
    // bins wholly inside the cirrus (9-11 km, 30 m bins from the ground)
    let cloud: Vec<usize> = (0..n)
        .filter(|&i| (9.1e3..10.9e3).contains(&expected[0].altitude_m[i]))
        .collect();
    let uncross = |r: f64| (r * (1.0 - x) - x) / ((1.0 - x) - r * x);
    let constants = par.instrument.signal_constant / perp.instrument.signal_constant;
    // the model: one bin against the point truth at its centre
    let mid = cloud[cloud.len() / 2];
    let r_model = expected[1].signal[mid] / expected[0].signal[mid] * constants;
    let z = expected[0].altitude_m[mid];
    let atm = &par.atmosphere;
    let o = atm.optics_at(z);
    let d_mol = atm.molecules.depolarization;
    let d_cld = atm
        .layers
        .iter()
        .find(|l| l.kind == LayerKind::Cloud)
        .unwrap()
        .depolarization;
    let d_aer = atm.aerosol.as_ref().unwrap().depolarization;
    let perp_beta = o.beta_mol * d_mol / (1.0 + d_mol)
        + o.beta_aer * d_aer / (1.0 + d_aer)
        + o.beta_cld * d_cld / (1.0 + d_cld);
    let par_beta =
        o.beta_mol / (1.0 + d_mol) + o.beta_aer / (1.0 + d_aer) + o.beta_cld / (1.0 + d_cld);
    let truth = perp_beta / par_beta;
    assert!(
        (uncross(r_model) - truth).abs() < 1e-3 * truth,
        "model {} vs truth {truth}",
        uncross(r_model)
    );
    // the counts: background-subtracted sums over the cloud, 100 profiles
    let profiles = 100u64;
    let shots = lidar.first().shots_per_profile() as f64;
    let mut sums = [0u64; 2];
    let mut counts = vec![0u64; 2 * n];
    for p in 0..profiles {
        counts.iter_mut().for_each(|c| *c = 0);
        src.draw(p, &mut counts);
        for (k, s) in sums.iter_mut().enumerate() {
            *s += cloud.iter().map(|&i| counts[k * n + i]).sum::<u64>();
        }
    }
    let net = |k: usize| {
        let e = &expected[k];
        sums[k] as f64 - (e.background + e.dark) * shots * profiles as f64 * cloud.len() as f64
    };
    let r = net(1) / net(0) * constants;
    let sd = r * (sums[1] as f64 / net(1).powi(2) + sums[0] as f64 / net(0).powi(2)).sqrt();
    let r_sum_model = cloud.iter().map(|&i| expected[1].signal[i]).sum::<f64>()
        / cloud.iter().map(|&i| expected[0].signal[i]).sum::<f64>()
        * constants;
    assert!(
        (r - r_sum_model).abs() < 4.0 * sd,
        "recovered {r} ± {sd}, model {r_sum_model}"
    );
    // and the test has power: without the cross-talk correction the ratio is off
    assert!(
        (uncross(r) - r).abs() > 5.0 * sd,
        "r {r}, uncrossed {}, sd {sd}",
        uncross(r)
    );
}

/// The energy monitor: with a periodic drift and no jitter every profile's
/// `pulse_energy` is `E0` times the mean drift over its shots (to 1e-12), and the counts
/// follow the energy: each profile's bright-bin sum is within 5 sd of `M(f̄·s + r)`
/// (false alarm < 6e-7 per profile), while the nominal energy misses by more.
#[test]
fn pulse_energy_follows_the_drift_and_the_counts_follow_the_energy() {
    let dir = scratch("drift");
    let out = dir.join("d.h5");
    let cfg = common::config_path("paper/scenario1.toml");
    let period = 40.0;
    let o = lidarsim(&[
        "simulate",
        cfg.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--profiles",
        "8",
        "--set",
        &format!(
            "instrument.energy_drift={{ model = \"periodic\", amplitude = 0.3, period_s = {period} }}"
        ),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stderr).contains("method aggregate"));
    let f = hdf5::File::open(&out).unwrap();
    let energy: Vec<f64> = f.dataset("pulse_energy").unwrap().read_raw().unwrap();
    let counts: Vec<u64> = f.dataset("counts").unwrap().read_raw().unwrap();
    let signal: Vec<f64> = f.dataset("expected_signal").unwrap().read_raw().unwrap();
    let rest: f64 = f
        .dataset("expected_background")
        .unwrap()
        .read_raw::<f64>()
        .unwrap()[0]
        + f.dataset("expected_dark")
            .unwrap()
            .read_raw::<f64>()
            .unwrap()[0];
    let sc = common::scenario("paper/scenario1.toml", &[]);
    let e0 = sc.loaded.config.instrument.pulse_energy_j;
    let m = sc.shots_per_profile();
    let fl = sc.instrument.rep_rate_hz;
    let law = PulseEnergy {
        jitter: 0.0,
        drift: Some(lidarsim::config::EnergyDriftConfig::Periodic {
            amplitude: 0.3,
            period_s: period,
            phase_deg: 0.0,
        }),
        rep_rate_hz: fl,
    };
    let n = signal.len();
    let bright: Vec<usize> = (0..n).filter(|&i| signal[i] * m as f64 > 1e3).collect();
    assert!(!bright.is_empty());
    let mut nominal_misses = 0;
    for (p, &measured) in energy.iter().enumerate() {
        let mean: f64 = (0..m)
            .map(|s| law.drift_factor((p as f64 * m as f64 + s as f64) / fl))
            .sum::<f64>()
            / m as f64;
        assert!(
            (measured - e0 * mean).abs() <= 1e-12 * e0,
            "profile {p}: {measured} vs {}",
            e0 * mean
        );
        let sum: f64 = bright.iter().map(|&i| counts[p * n + i] as f64).sum();
        let want: f64 = bright
            .iter()
            .map(|&i| m as f64 * (mean * signal[i] + rest))
            .sum();
        assert!(
            (sum - want).abs() < 5.0 * want.sqrt(),
            "profile {p}: {sum} vs {want}"
        );
        let nominal: f64 = bright.iter().map(|&i| m as f64 * (signal[i] + rest)).sum();
        nominal_misses += usize::from((sum - nominal).abs() > 5.0 * nominal.sqrt());
    }
    assert!(
        nominal_misses >= 6,
        "the drift is not visible in the counts"
    );
    // jitter: the monitor reads the energies the counts were drawn with, shared by the
    // channels; without jitter or drift it reads E0 exactly
    let o = lidarsim(&[
        "simulate",
        cfg.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--profiles",
        "3",
    ]);
    assert!(o.status.success());
    let f = hdf5::File::open(&out).unwrap();
    let energy: Vec<f64> = f.dataset("pulse_energy").unwrap().read_raw().unwrap();
    assert!(energy.iter().all(|&x| x == e0));
    std::fs::remove_dir_all(&dir).ok();
}

fn strings(f: &hdf5::File, name: &str) -> Vec<String> {
    f.dataset(name)
        .unwrap()
        .read_raw::<hdf5::types::VarLenUnicode>()
        .unwrap()
        .iter()
        .map(|s| s.as_str().to_string())
        .collect()
}

/// The CALIOP-like three-channel preset writes counts (profile, channel, bin) with the
/// channels' names, constants, wavelengths and (analog) detection modes; the point truth is per
/// channel because the wavelengths differ; a one-wavelength run keeps it per bin; the
/// counts do not depend on the thread count.
#[test]
fn three_channels_in_one_file() {
    let dir = scratch("three");
    let cfg = common::config_path("instruments/caliop_3ch.toml");
    let run = |out: &Path, threads: &str| {
        let o = lidarsim(&[
            "simulate",
            cfg.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--profiles",
            "6",
            "--threads",
            threads,
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    };
    let (a, b) = (dir.join("a.h5"), dir.join("b.h5"));
    run(&a, "1");
    run(&b, "2");
    let read = |p: &Path| -> Vec<u64> {
        let f = hdf5::File::open(p).unwrap();
        f.dataset("counts").unwrap().read_raw().unwrap()
    };
    assert_eq!(read(&a), read(&b));
    let f = hdf5::File::open(&a).unwrap();
    let counts = f.dataset("counts").unwrap();
    let bins = f.dataset("altitude").unwrap().shape()[0];
    assert_eq!(counts.shape(), vec![6, 3, bins]);
    assert_eq!(
        strings(&f, "channel_name"),
        ["532_parallel", "532_perpendicular", "1064_total"]
    );
    let wl: Vec<f64> = f.dataset("wavelength").unwrap().read_raw().unwrap();
    assert_eq!(wl, [532.0, 532.0, 1064.0]);
    // CALIOP's detectors are analog (the preset as flown): no dead time on any channel
    let dead: Vec<f64> = f.dataset("dead_time").unwrap().read_raw().unwrap();
    assert_eq!(dead, [0.0, 0.0, 0.0]);
    assert_eq!(
        strings(&f, "detection_mode"),
        ["analog", "analog", "analog"]
    );
    assert_eq!(f.dataset("lidar_constant").unwrap().shape(), vec![3]);
    // the truth: one column (a static scene), per channel
    assert_eq!(f.dataset("beta_mol").unwrap().shape(), vec![1, 3, bins]);
    assert_eq!(f.dataset("expected_counts").unwrap().shape(), vec![3, bins]);
    let beta: Vec<f64> = f.dataset("beta_mol").unwrap().read_raw().unwrap();
    // Rayleigh: β_mol = N·σ(λ)/S_mol, about 16× less at 1064 nm; from this test's
    // Bucholtz formulas: the 532-nm channels' 37-pm etalon passes the Cabannes line, the
    // 1064-nm channel's 450-pm filter the whole line (within 1e-4: a 1 % error fails)
    use common::reference as r;
    let k = bins - 100;
    let ratio = beta[k] / beta[2 * bins + k];
    let beta_of = |wl: f64, cabannes: bool| {
        let (s, _) = r::molecular_lidar_ratio_and_depolarization(r::rayleigh_rho_n(wl), cabannes);
        r::rayleigh_cross_section_m2(wl) / s
    };
    let expected = beta_of(532.0, true) / beta_of(1064.0, false);
    assert!(
        (ratio / expected - 1.0).abs() < 1e-4,
        "{ratio} vs {expected}"
    );
    assert!((15.5..17.5).contains(&expected), "{expected}");
    let single = dir.join("s.h5");
    let o = lidarsim(&[
        "simulate",
        common::config_path("instruments/caliop_532.toml")
            .to_str()
            .unwrap(),
        "-o",
        single.to_str().unwrap(),
        "--profiles",
        "2",
    ]);
    assert!(o.status.success());
    let f = hdf5::File::open(&single).unwrap();
    assert_eq!(f.dataset("beta_mol").unwrap().shape()[..2], [1, 1]);
    assert_eq!(f.dataset("counts").unwrap().shape()[1], 1);
    std::fs::remove_dir_all(&dir).ok();
}

/// Layers reach another wavelength through their Ångström exponent (and a lidar ratio
/// given per wavelength); a cloud keeps its extinction.
#[test]
fn layers_scale_to_each_channel_wavelength() {
    let lidar = common::lidar("instruments/caliop_3ch.toml", &[]);
    let at = |k: usize, kind: LayerKind| {
        lidar.channels[k]
            .atmosphere
            .layers
            .iter()
            .find(|l| l.kind == kind)
            .unwrap()
            .clone()
    };
    let smoke_532 = at(0, LayerKind::Aerosol);
    let smoke_1064 = at(2, LayerKind::Aerosol);
    assert!((smoke_532.extinction_per_m - 0.1e-3).abs() < 1e-15);
    let want = 0.1e-3 * 0.5f64.powf(1.4);
    assert!((smoke_1064.extinction_per_m - want).abs() < 1e-12 * want);
    assert_eq!(smoke_532.lidar_ratio_sr, 70.0);
    assert_eq!(smoke_1064.lidar_ratio_sr, 50.0);
    assert_eq!(
        at(0, LayerKind::Cloud).extinction_per_m,
        at(2, LayerKind::Cloud).extinction_per_m
    );
}

fn config_error(text: &str) -> String {
    let path = Path::new("test.toml");
    match lidarsim::loaded::load_str(text, path, &[]) {
        Ok(_) => panic!("accepted:\n{text}"),
        Err(e) => e.to_string(),
    }
}

/// Channel mistakes are refused in one line naming the channel's key.
#[test]
fn channel_errors_name_their_keys() {
    let base = std::fs::read_to_string(common::config_path("instruments/caliop_3ch.toml")).unwrap();
    let cases = [
        (
            "wavelength_nm = 1064.0\n",
            "wavelength_nm = -5.0\n",
            "instrument.channels[2].wavelength_nm",
        ),
        (
            "name = \"1064_total\"",
            "name = \"532_parallel\"",
            "instrument.channels[2].name",
        ),
        (
            "polarization = \"parallel\"",
            "polarization = \"sideways\"",
            "instrument.channels[0].polarization",
        ),
        (
            "crosstalk = 0.005                # ASSUMED",
            "rep_rate_hz = 10.0\ncrosstalk = 0.005 #",
            "instrument.channels[0].rep_rate_hz",
        ),
        (
            "angstrom_exponent = 1.4",
            "",
            "atmosphere.layers[1].angstrom_exponent",
        ),
        (
            "crosstalk = 0.005\n",
            "crosstalk = 0.9\n",
            "instrument.channels[1].crosstalk",
        ),
    ];
    for (from, to, key) in cases {
        assert!(base.contains(from), "{from}");
        let e = config_error(&base.replacen(from, to, 1));
        assert!(e.contains(key), "{key}: {e}");
        assert!(!e.contains('\n'), "{e}");
    }
    let e = config_error(&base.replace(
        "polarization = \"parallel\"\ncrosstalk = 0.005",
        "polarization = \"total\"\ncrosstalk = 0.005",
    ));
    assert!(
        e.contains("instrument.channels[0].crosstalk") && e.contains("total"),
        "{e}"
    );
}

/// `kind` says what scattering a channel sees: `"elastic"` (the default) is accepted
/// and changes nothing; `"raman"` and `"hsrl_molecular"` are tested in
/// tests/raman_retrieval.rs and tests/hsrl_retrieval.rs; any
/// other value is refused in one line naming the channel's key and the kinds accepted.
#[test]
fn channel_kind_is_elastic_or_refused() {
    let base = std::fs::read_to_string(common::config_path("instruments/caliop_3ch.toml")).unwrap();
    let from = "name = \"532_parallel\"\n";
    assert!(base.contains(from));
    let path = Path::new("test.toml");
    let plain = lidarsim::loaded::load_str(&base, path, &[]).unwrap();
    let elastic = base.replacen(from, &format!("{from}kind = \"elastic\"\n"), 1);
    let kinds = lidarsim::loaded::load_str(&elastic, path, &[]).unwrap();
    for (a, b) in plain.channels.iter().zip(&kinds.channels) {
        assert_eq!(a.kind, lidarsim::receiver::ChannelKind::Elastic);
        assert_eq!(b.kind, lidarsim::receiver::ChannelKind::Elastic);
        assert_eq!(toml::to_string(&a.config), toml::to_string(&b.config));
    }
    let e = config_error(&base.replacen(from, &format!("{from}kind = \"hsrl\"\n"), 1));
    assert_eq!(
        e,
        "test.toml: key `instrument.channels[0].kind`: unknown variant 'hsrl', expected one of 'elastic', 'hsrl_molecular', 'raman'"
    );
}
