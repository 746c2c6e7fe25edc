//! Kills the cargo-mutants survivors in `Instrument::from_config` (validation/reports/
//! mutants.md): every factor of Eq. 2 and of the dark counts differs from 1 here, so a
//! `*` turned into `+` or `/` anywhere moves the result by far more than 1 %.

mod common;

use common::scenario;

#[test]
fn signal_constant_and_dark_counts_with_no_unit_factor() {
    let sc = scenario(
        "paper/scenario6.toml",
        &[
            "instrument.optical_efficiency=0.9",
            "instrument.pulse_energy_j=0.3",
            "instrument.quantum_efficiency=0.35",
            "instrument.dark_count_rate_hz=350",
        ],
    );
    // Eq. 2: C = K·E0·(λ/hc)·A·TR·TF·Q, constants from CODATA written here
    let (h, c) = (6.626_070_15e-34, 299_792_458.0);
    let want = 0.9 * 0.3 * (532e-9 / (h * c)) * 0.1 * 0.8 * 0.7 * 0.35;
    let got = sc.instrument.signal_constant;
    assert!((got / want - 1.0).abs() < 1e-9, "{got} vs {want}");
    // dark counts per bin: rate · Δt = 350 s⁻¹ · 2 µs
    let dark = sc.instrument.dark_per_bin;
    assert!((dark / 7e-4 - 1.0).abs() < 1e-12, "{dark}");
}

/// `tests/configs/caliop_3ch_photon_counting.toml` (the CALIOP-like three channels as
/// photon counters with a per-channel dead-time table) with `from` replaced by `to`
/// (once), loaded.
fn three_channels(from: &str, to: &str) -> lidarsim::error::Result<lidarsim::loaded::LoadedConfig> {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/configs/caliop_3ch_photon_counting.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(from.is_empty() || text.contains(from), "{from}");
    lidarsim::loaded::load_str(&text.replacen(from, to, 1), &path, &[])
}

/// A channel's `detector` table is merged key by key into the instrument's: the 1064 nm
/// channel sets only its dead time and keeps the instrument's (paralyzable) model; the
/// other channels keep both (`src/receiver/mod.rs` `merge_table`; cargo-mutants survivors
/// "replace merge_table with ()" and "delete match arm").
#[test]
fn a_channel_detector_table_merges_into_the_instrument_one() {
    let loaded = three_channels(
        "dead_time_model = \"nonparalyzable\"",
        "dead_time_model = \"paralyzable\"",
    )
    .unwrap();
    let detector = |k: usize| {
        let d = loaded.channels[k]
            .config
            .instrument
            .detector
            .as_ref()
            .unwrap();
        (d.dead_time_s, d.dead_time_model)
    };
    use lidarsim::detector::DeadTimeModel::Paralyzable;
    assert_eq!(detector(0), (3.5e-9, Paralyzable));
    assert_eq!(detector(2), (5e-9, Paralyzable));
}

/// A receiver has at most 32 channels: 32 load, 33 are refused naming the key
/// (survivors "replace > with >=" and "with ==" in `expand`).
#[test]
fn thirty_two_channels_load_and_thirty_three_do_not() {
    let extra = |n: usize| {
        (0..n)
            .map(|k| format!("\n[[instrument.channels]]\nname = \"extra {k}\"\n"))
            .collect::<String>()
    };
    // the file's three channels end with the 1064 nm one's detector line
    let anchor = "detector = { dead_time_s = 5e-9 }  # ASSUMED";
    let loaded = three_channels(anchor, &format!("{anchor}\n{}", extra(29))).unwrap();
    assert_eq!(loaded.channels.len(), 32);
    let e = three_channels(anchor, &format!("{anchor}\n{}", extra(30)))
        .expect_err("33 channels accepted")
        .to_string();
    assert!(e.contains("instrument.channels") && e.contains("33"), "{e}");
}

/// Channel names have 1 to 64 characters (survivors "replace || with &&", "replace >
/// with ==" and "with >=" in `channel_label`).
#[test]
fn channel_names_have_one_to_sixty_four_characters() {
    let name = |s: &str| three_channels("name = \"1064_total\"", &format!("name = \"{s}\""));
    assert_eq!(
        name(&"n".repeat(64)).unwrap().channels[2].name,
        "n".repeat(64)
    );
    for bad in [String::new(), "n".repeat(65)] {
        let e = name(&bad).expect_err("accepted").to_string();
        assert!(
            e.contains("instrument.channels[2].name") && e.contains("1 to 64"),
            "{e}"
        );
    }
}

/// A channel's own polarization replaces the instrument's, whichever of its two names
/// (`polarization`, `channel`) either uses (survivor "delete match arm").
#[test]
fn a_channel_polarization_replaces_the_instrument_one() {
    use lidarsim::config::Channel;
    let loaded =
        three_channels("[instrument]\n", "[instrument]\nchannel = \"parallel\"\n").unwrap();
    let pol = |k: usize| loaded.channels[k].config.instrument.channel;
    assert_eq!(
        [pol(0), pol(1), pol(2)],
        [Channel::Parallel, Channel::Perpendicular, Channel::Parallel]
    );
}

/// An error is named by the channel's key where the channel set it (`polarization` for
/// its alias `channel` too), and by the instrument's key, with the channel's name, where
/// the instrument did (survivors "replace || with &&", "&& with ||", "== with !=" in
/// `rename_key`).
#[test]
fn channel_errors_name_the_key_where_it_was_set() {
    let error = |from: &str, to: &str| three_channels(from, to).expect_err("accepted").to_string();
    let e = error("wavelength_nm = 1064.0", "wavelength_nm = -5.0");
    assert!(e.contains("instrument.channels[2].wavelength_nm"), "{e}");
    // one laser, one digitizer, one telescope: a channel cannot set them (survivor
    // "replace match guard SHARED_KEYS.contains(&shared) with false")
    let e = error(
        "wavelength_nm = 1064.0",
        "wavelength_nm = 1064.0\nrep_rate_hz = 10.0",
    );
    assert!(
        e.contains("instrument.channels[2].rep_rate_hz") && e.contains("shared"),
        "{e}"
    );
    let e = error("polarization = \"parallel\"", "polarization = \"sideways\"");
    assert!(e.contains("instrument.channels[0].polarization"), "{e}");
    // the instrument's cross-talk reaches the 1064 nm channel, which says it sees the
    // total: the key is the instrument's, the channel is named in the reason
    let path = common::config_path("instruments/caliop_3ch.toml");
    let text = std::fs::read_to_string(&path)
        .unwrap()
        .replacen(
            "[instrument]\n",
            "[instrument]\nchannel = \"parallel\"\ncrosstalk = 0.01\n",
            1,
        )
        .replacen(
            "wavelength_nm = 1064.0",
            "wavelength_nm = 1064.0\npolarization = \"total\"",
            1,
        );
    let e = lidarsim::loaded::load_str(&text, &path, &[])
        .expect_err("accepted")
        .to_string();
    assert!(
        e.contains("key `instrument.crosstalk`") && e.contains("(in channel 1064_total)"),
        "{e}"
    );
}

/// The ozone cross-section's edges: from 350 nm (inclusive) the Huggins band's 1-nm bins
/// (DBM, 228 K: 8.185e-27 m² over [350, 351), 4.654e-27 over [359, 360)), from 360 nm
/// (inclusive) the 360–370 nm bin's 1.18e-27, NaN below 350 nm (survivors "replace < with
/// <=" in `cross_section_m2`, at either edge).
#[test]
fn the_ozone_cross_section_starts_at_350_nm() {
    use lidarsim::atmosphere::ozone::cross_section_m2;
    assert_eq!(cross_section_m2(350.0), 8.185e-27);
    assert_eq!(cross_section_m2(359.999), 4.654e-27);
    assert_eq!(cross_section_m2(360.0), 1.18e-27);
    assert!(cross_section_m2(349.999).is_nan());
}

/// The ozone column over an interval of a few nanometres is `n·Δz` to 1e-9, where the
/// closed form `(n0 − n1)·Δz/ln(n0/n1)` loses its digits (survivors in
/// `segment_integral`'s near-equal branch). Δz is taken as the floats represent it.
#[test]
fn a_nanometre_of_ozone_column_is_the_density_times_the_thickness() {
    use lidarsim::atmosphere::ozone::column_m2;
    for z in [500.0, 22_000.0, 33_333.0] {
        let top: f64 = z + 4e-9;
        let dz = top - z; // exact (Sterbenz)
        let want = common::reference::ozone_number_density_m3(z) * dz;
        let got = column_m2(z, top);
        assert!((got / want - 1.0).abs() < 1e-9, "{z} m: {got} vs {want}");
    }
}

/// The ground example config with a molecular profile file of the given rows
/// (`altitude_km number_density_m3`), loaded (the file is read at load time).
fn with_profile_file(rows: impl Iterator<Item = String>) -> lidarsim::scenario::Scenario {
    let dir = tempfile::tempdir().unwrap();
    let profile = dir.path().join("profile.txt");
    let rows: String = rows.collect();
    std::fs::write(&profile, format!("altitude_km number_density_m3\n{rows}")).unwrap();
    scenario(
        "ground/profile_file_example.toml",
        &[&format!(
            "atmosphere.molecular.model.file=\"{}\"",
            profile.display()
        )],
    )
}

/// A molecular profile file that ends below 86 km is continued by US76 scaled to meet it
/// at its top row: N(z) = N_file(top)/N_US76(top) · N_US76(z) above (docs/model.md;
/// survivor "replace * with +" in `Molecules::number_density_m3`). The file holds 0.9 of
/// the reference US76 up to 30 km; above, 0.9 of the reference US76 to 1e-6.
#[test]
fn a_profile_file_is_continued_by_scaled_us76_above_its_top() {
    let sc = with_profile_file((0..=30).map(|km| {
        let n = 0.9 * common::reference::us76_number_density_m3(km as f64 * 1e3);
        format!("{km} {n:e}\n")
    }));
    for z in [30_000.0, 35_000.0, 50_000.0, 80_000.0] {
        let got = sc.atmosphere.molecules.number_density_m3(z);
        let want = 0.9 * common::reference::us76_number_density_m3(z);
        assert!((got / want - 1.0).abs() < 1e-6, "{z} m: {got} vs {want}");
    }
}

/// A profile file reaching above US76's top (86 km) is not continued: above its own top
/// there are no molecules (survivor "replace match guard p.top_altitude_m() <
/// us76::TOP_ALTITUDE_M with true", which made it ∞·0 = NaN there).
#[test]
fn a_profile_file_above_86_km_ends_at_its_top() {
    let sc = with_profile_file(
        (0..=90).map(|km| format!("{km} {:e}\n", 2.5e25 * (-(km as f64) / 7.0).exp())),
    );
    let m = &sc.atmosphere.molecules;
    assert_eq!(m.number_density_m3(95_000.0), 0.0);
    let at_88 = m.number_density_m3(88_000.0);
    assert!(
        (at_88 / (2.5e25 * (-88.0f64 / 7.0).exp()) - 1.0).abs() < 1e-9,
        "{at_88}"
    );
    assert!(m.continuation_note().is_none());
}

/// The largest clean repetition rate (docs/model.md §3): `1/max(A, −B)` with
/// `A = 2(r_s − r_n)/c`, `B = 2(r_a − r_f)/c`, written here; infinite when both are ≤ 0
/// (survivor "replace * with +" in `clean_windows_max_rep_rate_hz`).
#[test]
fn the_clean_window_rate_is_one_over_the_longer_echo_span() {
    use lidarsim::geometry::clean_windows_max_rep_rate_hz as clean;
    let c = 299_792_458.0;
    // A wins: returns from 500–600 km range, window 480–610 km
    let a = 2.0 * (600e3 - 480e3) / c;
    assert!((clean((500e3, 600e3), (480e3, 610e3)) * a - 1.0).abs() < 1e-12);
    // −B wins: a window reaching far below the returns
    let b = 2.0 * (500e3 - 900e3) / c;
    assert!((clean((500e3, 600e3), (590e3, 900e3)) * -b - 1.0).abs() < 1e-12);
    assert_eq!(clean((500e3, 600e3), (700e3, 400e3)), f64::INFINITY);
}

/// A window of more than 10⁷ bins is refused naming `instrument.bin_width_s` (survivor
/// "replace > with ==" in `Geometry::from_config`).
#[test]
fn at_most_ten_million_bins() {
    // scenario 6 from 600 km, nadir, a 200 km window of 1e-10 s (1.5 cm) bins: 1.33e7 bins
    let e = lidarsim::scenario::Scenario::load(
        &common::config_path("paper/scenario6.toml"),
        &[
            "instrument.bin_width_s=1e-10".to_string(),
            "acquisition.top_altitude_km=200".to_string(),
        ],
    )
    .expect_err("1.33e7 bins accepted")
    .to_string();
    assert!(
        e.contains("instrument.bin_width_s") && e.contains("more than the 10000000"),
        "{e}"
    );
}

/// A space-borne beam more than asin(R/(R+H)) off nadir misses the Earth and is refused;
/// a nadir beam never is (survivor "replace == with !=" in `check_reach`).
#[test]
fn a_beam_that_misses_the_earth_is_refused() {
    let load = |angle: &str| {
        lidarsim::scenario::Scenario::load(
            &common::config_path("instruments/caliop_532.toml"),
            &[format!("platform.off_nadir_deg={angle}")],
        )
    };
    // CALIOP at 705 km: the limit is asin(6371/7076) = 64.2°
    let e = load("70")
        .expect_err("a beam past the limb accepted")
        .to_string();
    assert!(
        e.contains("platform.off_nadir_deg") && e.contains("misses the Earth"),
        "{e}"
    );
    assert!(load("0").is_ok());
}

/// Shots per profile `M = round(fL·TC)` (paper Eq. 4's M), for the CALIOP-like rate
/// (20.16 Hz) at several accumulation times (survivor "replace shots_per_profile -> u64
/// with 0").
#[test]
fn shots_per_profile_is_the_rate_times_the_accumulation_time_rounded() {
    let sc = scenario("instruments/caliop_532.toml", &[]);
    for (tc, m) in [(1.0, 20), (0.7440, 15), (100.0, 2016), (3.0, 60)] {
        assert_eq!(sc.instrument.shots_per_profile(tc), m, "TC {tc} s");
    }
}

/// A detector table with a zero dead time is no dead-time stage: the ideal counter, the
/// `aggregate` method allowed (survivor "replace > with >=" at the dead-time filter of
/// `Instrument::from_config`, previous session).
#[test]
fn a_zero_dead_time_is_no_dead_time_stage() {
    let sc = scenario(
        "paper/scenario1.toml",
        &["instrument.detector.dead_time_s=0"],
    );
    assert!(sc.loaded.config.instrument.detector.is_some());
    assert!(sc.instrument.dead_time.is_none());
    let with = scenario(
        "paper/scenario1.toml",
        &["instrument.detector.dead_time_s=3.5e-9"],
    );
    assert!(with.instrument.dead_time.is_some());
}

/// The recorded count's moments under dead time (docs/model.md §4b), written here:
/// the paralyzable variance `mΔt·(1 − 2nτ·e^(−nτ))` with `m = n·e^(−nτ)`; without
/// jitter the moments are the stationary ones; with the laser's jitter σ the law of
/// total variance adds `Var[m(f)] ≈ σ²·s²` to the variance (s = 3 counts a bin and shot at
/// 1.5 MHz, nτ = 0.005, σ = 0.2: 0.36 on a variance of ~3, within 5 %) and leaves the mean
/// within 1 % (survivors in `recorded_moments` and `recorded_variance`).
#[test]
fn recorded_moments_follow_the_law_of_total_variance() {
    use lidarsim::detector::{DeadTime, DeadTimeModel};
    use lidarsim::laser::PulseEnergy;
    let (tau, dt) = (3.5e-9, 2e-6);
    let energy = |jitter: &str| {
        let sc = scenario(
            "paper/scenario6.toml",
            &[&format!("instrument.pulse_energy_jitter={jitter}")],
        );
        PulseEnergy::from_config(&sc.loaded.config.instrument)
    };
    let (steady, jittered) = (energy("0"), energy("0.2"));
    for model in [DeadTimeModel::Nonparalyzable, DeadTimeModel::Paralyzable] {
        let dead = DeadTime {
            tau_s: tau,
            model,
            bin_width_s: dt,
            pixels: 1,
        };
        if model == DeadTimeModel::Paralyzable {
            let (n, lambda) = (5e7, 5e7 * dt);
            let x: f64 = n * tau;
            let m = n * (-x).exp();
            let want = m * dt * (1.0 - 2.0 * x * (-x).exp());
            let got = dead.recorded_variance(lambda);
            assert!((got / want - 1.0).abs() < 1e-12, "{got} vs {want}");
        }
        let (signal, rest) = (vec![3.0; 20], 0.001);
        let (mean0, var0) = dead.recorded_moments(&signal, rest, &steady);
        let means = dead.recorded_means(&[3.001; 20]);
        // the variance of each bin given the dead time carried in (issue 36)
        let (_, v) = dead.recorded_mean_and_variance(&[3.001; 20]);
        for i in 1..20 {
            assert!(
                (mean0[i] / means[i] - 1.0).abs() < 1e-12,
                "{model:?} mean {i}"
            );
            assert!(
                (var0[i] / v[i] - 1.0).abs() < 1e-12,
                "{model:?} variance {i}"
            );
        }
        let (mean, var) = dead.recorded_moments(&signal, rest, &jittered);
        for i in 5..20 {
            assert!(
                (mean[i] / mean0[i] - 1.0).abs() < 1e-2,
                "{model:?} mean {i}"
            );
            let term = var[i] - var0[i];
            assert!(
                (term / (0.04 * 9.0) - 1.0).abs() < 0.05,
                "{model:?} bin {i}: jitter adds {term}"
            );
        }
    }
}

/// A profile of one and a half shot blocks (`SHOT_BLOCK` = 65,536 shots per block, so
/// 98,304 shots) through the dead-time stage (`recorded_profile`) records those shots'
/// photons, no more: the photons are the shot path's own, shot for shot (the same
/// `stream_rng(seed, profile, block)`), so with any dead time each bin records at most
/// the shot path's count for the same seed — exactly. And the total is the expected
/// one: 4 bins of λ = 0.25 per shot give 98,304 photons on average (Poisson, σ = 314);
/// with τ = 1 ns in 1 µs bins the dead time loses at most the pairs closer than τ,
/// n²·W·τ = (2.5e5 s⁻¹)²·4 µs·1 ns = 2.5e-4 a shot, ≤ 25 in all, and the recorded count
/// varies less than the Poisson one. Tolerance 5σ + 25: a false alarm with probability
/// 6e-7 (two-sided normal tail at 5σ; the seed is fixed). A last block drawn whole, as
/// if 131,072 shots had been fired, is 105σ off (survivor "replace - with +" in
/// `recorded_profile`'s shots of the last block).
#[test]
fn a_profile_longer_than_a_shot_block_records_each_shot_once() {
    use lidarsim::detector::dead_time::recorded_profile;
    use lidarsim::detector::{DeadTime, DeadTimeModel};
    use lidarsim::sampling::{SHOT_BLOCK, ShotSampler, shot_profile};
    let shots = SHOT_BLOCK + SHOT_BLOCK / 2;
    assert_eq!(shots, 98_304);
    let sampler = ShotSampler::new(&[0.25; 4]);
    let (seed, profile) = (2026, 11);
    let mut photons = vec![0u64; 4];
    shot_profile(&sampler, seed, profile, shots, &mut photons);
    for model in [DeadTimeModel::Nonparalyzable, DeadTimeModel::Paralyzable] {
        let dead = DeadTime {
            tau_s: 1e-9,
            model,
            bin_width_s: 1e-6,
            pixels: 1,
        };
        let mut recorded = vec![0u64; 4];
        recorded_profile(&sampler, &dead, seed, profile, shots, &mut recorded);
        for (b, (r, p)) in recorded.iter().zip(&photons).enumerate() {
            assert!(r <= p, "{model:?} bin {b}: {r} recorded of {p} photons");
        }
        let total = recorded.iter().sum::<u64>() as f64;
        let mean = 0.25 * 4.0 * shots as f64;
        assert!(
            (total - mean).abs() < 5.0 * mean.sqrt() + 25.0,
            "{model:?}: {total} recorded, {mean} expected"
        );
    }
}

/// A longitude is wrapped to [−180°, 180°) (`GroundPoint::longitude_deg`): the start
/// point of an equatorial orbit comes back as given at t = 0, wrapped by hand here:
/// 190° → −170°, 180° → −180°, −540.5° → 179.5°, and one float below −180°
/// (−180 − 2.8e-14), where `rem_euclid` rounds up to exactly 360 and the guard branch
/// must give −180°, not 540° (survivor "replace - with +" in `wrap_longitude_deg`; the
/// unit test's −1e-17 does not reach that branch).
#[test]
fn longitudes_are_wrapped_to_minus_180_to_180() {
    use lidarsim::scene::orbit::Orbit;
    let just_below = f64::from_bits((-180.0f64).to_bits() + 1);
    assert!(just_below < -180.0 && just_below > -180.000_000_000_001);
    for (start, want) in [
        (10.0, 10.0),
        (190.0, -170.0),
        (180.0, -180.0),
        (-540.5, 179.5),
        (just_below, -180.0),
    ] {
        let orbit = Orbit::new(600e3, 0.0, 0.0, start, true).unwrap();
        let got = orbit.position(0.0).longitude_deg;
        assert!((-180.0..180.0).contains(&got), "{start}: {got}");
        assert!((got - want).abs() < 1e-9, "{start}: {got} vs {want}");
    }
}

/// The curtain of [`a_curtain_is_read_column_by_column`]: 3 columns × 3 altitudes.
struct Curtain {
    along_track_km: Vec<f64>,
    altitude_km: Vec<f64>,
    /// Row i is column i, altitude index k within it (as `extinction_aerosol`'s
    /// (along_track, altitude) layout).
    extinction: Vec<f64>,
    lidar_ratio: Vec<f64>,
    depolarization: Vec<f64>,
    wavelength_nm: f64,
}

impl Curtain {
    fn new() -> Curtain {
        Curtain {
            along_track_km: vec![0.0, 5.0, 12.0],
            altitude_km: vec![0.25, 0.75, 1.25],
            extinction: vec![0.1, 0.0, 0.3, 0.4, 0.5, 0.6, 0.0, 0.8, 0.9],
            lidar_ratio: vec![20.0, 0.0, 40.0, 50.0, 60.0, 70.0, 80.0, 90.0, 100.0],
            depolarization: vec![0.01, 0.02, 0.03, 0.04, 0.05, 0.06, 0.07, 0.08, 0.09],
            wavelength_nm: 532.0,
        }
    }

    /// Written as an HDF5 curtain file at `path` (Ångström exponent 1.2), then read.
    fn read(
        &self,
        path: &std::path::Path,
    ) -> lidarsim::error::Result<Vec<lidarsim::config::SegmentConfig>> {
        let f = hdf5::File::create(path).unwrap();
        let (nx, nz) = (self.along_track_km.len(), self.altitude_km.len());
        let dataset = |name: &str, shape: &[usize], v: &[f64]| {
            f.new_dataset::<f64>()
                .shape(shape)
                .create(name)
                .unwrap()
                .write_raw(v)
                .unwrap()
        };
        dataset("along_track_km", &[nx], &self.along_track_km);
        dataset("altitude_km", &[nz], &self.altitude_km);
        dataset("extinction_aerosol", &[nx, nz], &self.extinction);
        dataset("lidar_ratio_aerosol", &[nx, nz], &self.lidar_ratio);
        dataset("depolarization_aerosol", &[nx, nz], &self.depolarization);
        f.dataset("extinction_aerosol")
            .unwrap()
            .new_attr::<f64>()
            .shape(())
            .create("angstrom_exponent")
            .unwrap()
            .write_scalar(&1.2)
            .unwrap();
        f.new_attr::<f64>()
            .shape(())
            .create("wavelength_nm")
            .unwrap()
            .write_scalar(&self.wavelength_nm)
            .unwrap();
        drop(f);
        lidarsim::scene::curtain::segments(path)
    }
}

/// A tabulated curtain written here, 3 columns × 3 altitudes (docs/scenes.md,
/// `src/scene/curtain.rs`), read into segments and compared with the columns worked out
/// by hand: columns start at 0, 5 and 12 km, so the segments are 5, 7 and 7 km long (the
/// last one takes the previous spacing); cells centred at 0.25, 0.75, 1.25 km with
/// 0.5 km spacing span 0–0.5, 0.5–1, 1–1.5 km; a zero-extinction cell is left out (its
/// lidar ratio of 0 is then allowed); each layer carries its own cell's extinction, lidar
/// ratio and depolarization, the Ångström exponent and the file's wavelength. Then the
/// refusals: a lidar ratio of 0.5 sr or a negative extinction in a cell, a wavelength of
/// 0, altitudes not increasing (survivors in `segments`: the last column's length, the
/// cell index `i·nz + k`, the wavelength check; in `check_axis` and `check_values`).
#[test]
fn a_curtain_is_read_column_by_column() {
    use lidarsim::config::LayerKind;
    let dir = tempfile::tempdir().unwrap();
    let c = Curtain::new();
    let segments = c.read(&dir.path().join("good.h5")).unwrap();
    let lengths: Vec<f64> = segments.iter().map(|s| s.length_km).collect();
    assert_eq!(lengths, [5.0, 7.0, 7.0]);
    for (i, segment) in segments.iter().enumerate() {
        let layers = segment.layers.as_ref().unwrap();
        let cells: Vec<usize> = (0..3).filter(|k| c.extinction[3 * i + k] > 0.0).collect();
        assert_eq!(layers.len(), cells.len(), "column {i}");
        for (layer, &k) in layers.iter().zip(&cells) {
            let cell = 3 * i + k;
            assert_eq!(layer.kind, LayerKind::Aerosol);
            assert_eq!(
                (layer.base_km, layer.top_km),
                (0.5 * k as f64, 0.5 * (k + 1) as f64)
            );
            assert_eq!(
                (
                    layer.extinction_per_km,
                    layer.lidar_ratio_sr,
                    layer.depolarization
                ),
                (
                    c.extinction[cell],
                    c.lidar_ratio[cell],
                    c.depolarization[cell]
                ),
                "column {i}, cell {k}"
            );
            assert_eq!(layer.angstrom_exponent, Some(1.2));
            assert_eq!(layer.reference_wavelength_nm, Some(532.0));
        }
    }
    let refused = |name: &str, edit: fn(&mut Curtain)| {
        let mut bad = Curtain::new();
        edit(&mut bad);
        bad.read(&dir.path().join(name))
            .expect_err(name)
            .to_string()
    };
    let e = refused("ratio.h5", |c| c.lidar_ratio[4] = 0.5);
    assert!(e.contains("`lidar_ratio_aerosol` cell 4"), "{e}");
    let e = refused("negative.h5", |c| c.extinction[7] = -0.1);
    assert!(e.contains("`extinction_aerosol` cell 7"), "{e}");
    let e = refused("wavelength.h5", |c| c.wavelength_nm = 0.0);
    assert!(e.contains("`wavelength_nm` is 0"), "{e}");
    let e = refused("decreasing.h5", |c| c.altitude_km.reverse());
    assert!(
        e.contains("`altitude_km` is not strictly increasing"),
        "{e}"
    );
}

/// A window whose mean-rate grid would pass `MAX_GRID_STEPS` (5e7 steps) takes the
/// stationary formulas per bin (docs/model.md §4b, `DeadTime::recorded_means`): a 1 ms
/// bin with τ = 1 ns needs 64·Δt/τ = 6.4e7 steps, so its mean recorded count is
/// `n·Δt/(1 + nτ)` (non-paralyzable) and `n·Δt·e^(−nτ)` (paralyzable), written here, to
/// 1e-13 — where the solver, whose detector starts live, gives the first bin 0.004
/// counts more (4.5e-8 and 5.1e-8 of it at n = 1e8 s⁻¹, computed with the solver's
/// recurrence on a 1 µs bin: the transient does not depend on Δt) (survivor "replace >
/// with ==" at the switch, which ran the solver on every window).
#[test]
fn a_window_past_the_grid_limit_takes_the_stationary_formulas() {
    use lidarsim::detector::{DeadTime, DeadTimeModel};
    let (tau, dt, n) = (1e-9, 1e-3, 1e8);
    assert!(64.0 * dt / tau > lidarsim::detector::dead_time::MAX_GRID_STEPS);
    for model in [DeadTimeModel::Nonparalyzable, DeadTimeModel::Paralyzable] {
        let dead = DeadTime {
            tau_s: tau,
            model,
            bin_width_s: dt,
            pixels: 1,
        };
        let want = match model {
            DeadTimeModel::Nonparalyzable => n * dt / (1.0 + n * tau),
            DeadTimeModel::Paralyzable => n * dt * (-n * tau).exp(),
        };
        let got = dead.recorded_means(&[n * dt]);
        assert!(
            (got[0] / want - 1.0).abs() < 1e-13,
            "{model:?}: {} vs {want}",
            got[0]
        );
    }
}

/// Dead time crosses bin edges (docs/model.md §4b): in a window of 50 bins of 10 ns with
/// λ = 2 photons a bin and τ = 5 ns (nτ = 1), the sampler's mean recorded count per bin
/// past the first ten (the live start's transient has died out) is the stationary one,
/// Müller's `nΔt/(1 + nτ)` = 1 (non-paralyzable) and `nΔt·e^(−nτ)` = 0.736 (paralyzable),
/// written here. 30 profiles of 200 shots, each from its own streams; the check is the
/// mean of the 30 within 6 standard errors (their own spread): a false alarm with
/// probability 1.6e-6 per model (Student's t, 29 degrees of freedom; fixed seeds). A
/// detector made live again at each bin's start records 13 % and 36 % more (a Monte Carlo
/// of this window) (survivor "replace < with >" in `record_shot`'s runs of adjacent bins).
#[test]
fn dead_time_carries_across_bin_edges() {
    use lidarsim::detector::dead_time::recorded_profile;
    use lidarsim::detector::{DeadTime, DeadTimeModel};
    use lidarsim::sampling::ShotSampler;
    let (tau, dt, lambda) = (5e-9, 1e-8, 2.0);
    let n: f64 = lambda / dt;
    let sampler = ShotSampler::new(&[lambda; 50]);
    for (model, want) in [
        (DeadTimeModel::Nonparalyzable, n * dt / (1.0 + n * tau)),
        (DeadTimeModel::Paralyzable, n * dt * (-n * tau).exp()),
    ] {
        let dead = DeadTime {
            tau_s: tau,
            model,
            bin_width_s: dt,
            pixels: 1,
        };
        let means: Vec<f64> = (0..30)
            .map(|profile| {
                let mut acc = vec![0u64; 50];
                recorded_profile(&sampler, &dead, 25, profile, 200, &mut acc);
                acc[10..].iter().sum::<u64>() as f64 / (200.0 * 40.0)
            })
            .collect();
        let mean = means.iter().sum::<f64>() / 30.0;
        let var = means.iter().map(|m| (m - mean).powi(2)).sum::<f64>() / 29.0;
        let error = (var / 30.0).sqrt();
        assert!(
            (mean - want).abs() < 6.0 * error,
            "{model:?}: {mean} ± {error} recorded a bin, want {want}"
        );
    }
}

/// The scene along the track (docs/model.md §4f, `src/scene/track.rs`), from the orbit
/// example's segments with values worked out by hand: a scene of segments is a changing
/// scene even without broken layers, a scene without `[scene]` is not; at 6.9 km/s and
/// 20.16 shots a second a shot every 342.26 m, so the first 250 km segment holds shots
/// 0–730 (250 km·20.16/6.9 km = 730.4) and a 1,000-shot profile is two runs of 731 and
/// 269 shots; a broken layer of cloud fraction f = 0.4 in 4 km cells (clear stretches of
/// 6 km on average) covers 0.4 of 20,000 km sampled every 200 m, within 5σ, σ² =
/// 2f(1−f)/((1/4 km + 1/6 km)·20,000 km) = (0.0076)² (two-state Markov process, Cox 1962
/// §7.2; a false alarm with probability 6e-7, normal tail, fixed seed); 1.2e7 cells of
/// 1 m are refused, naming the count (survivors in `is_changing` (`i > 0` → `i < 0`),
/// `column_at` (which cell holds x), `runs` (a run split at each column change) and
/// `check_cell_count` (`cell_length_km·1e3` → `+`)).
#[test]
fn a_track_sees_its_segments_and_broken_cells() {
    use lidarsim::config::SegmentConfig;
    use lidarsim::scene::track::{AlongTrack, Column, Track};
    let base = lidarsim::loaded::load(&common::config_path("instruments/caliop_orbit.toml"), &[])
        .unwrap()
        .config;
    let with_segments = |segments: Vec<SegmentConfig>| {
        let mut cfg = base.clone();
        cfg.scene.as_mut().unwrap().segments = segments;
        cfg
    };
    let segments = &base.scene.as_ref().unwrap().segments;
    let (clear, cirrus, broken) = (&segments[0], &segments[1], &segments[2]);
    assert_eq!((clear.length_km, cirrus.length_km), (250.0, 250.0));
    // segments without broken layers still change along the track
    let two = with_segments(vec![clear.clone(), cirrus.clone()]);
    assert!(Track::is_changing(&two));
    let plain = common::scenario("instruments/caliop_532.toml", &[])
        .loaded
        .config;
    assert!(!Track::is_changing(&plain));
    // 1,000 shots at 6.9 km/s: the segment boundary at 250 km after shot 730
    assert_eq!(two.instrument.rep_rate_hz, 20.16);
    let track = Track::new(&two, 1, AlongTrack::Speed(6_900.0), 1_000, 1).unwrap();
    let column = |segment| Column {
        segment,
        present: 0,
    };
    assert_eq!(track.runs(0), [(column(0), 731), (column(1), 269)]);
    // a broken layer's cloudy fraction, 20,000 km of it
    let mut long = broken.clone();
    long.length_km = 20_000.0;
    let layer = &long.layers.as_ref().unwrap()[0];
    assert_eq!(
        (layer.cloud_fraction, layer.cell_length_km),
        (Some(0.4), Some(4.0))
    );
    let cfg = with_segments(vec![long.clone()]);
    let track = Track::new(&cfg, 7, AlongTrack::Speed(6_900.0), 1, 1).unwrap();
    let samples = 100_000;
    let cloudy = (0..samples)
        .filter(|k| track.column_at(200.0 * *k as f64 + 100.0).present == 1)
        .count() as f64
        / samples as f64;
    let sigma = (2.0f64 * 0.4 * 0.6 / ((1.0 / 4.0 + 1.0 / 6.0) * 20_000.0)).sqrt();
    assert!(
        (cloudy - 0.4).abs() < 5.0 * sigma,
        "cloudy fraction {cloudy}, σ = {sigma}"
    );
    // 1.2e7 one-metre cells: refused
    let mut tiny = long;
    tiny.length_km = 30_000.0;
    let l = &mut tiny.layers.as_mut().unwrap()[0];
    l.cell_length_km = Some(0.001);
    let e = Track::new(
        &with_segments(vec![tiny]),
        7,
        AlongTrack::Speed(6_900.0),
        1,
        1,
    )
    .expect_err("1.2e7 cells accepted")
    .to_string();
    assert!(e.contains("1.2e7 cells"), "{e}");
}

/// Issue 36 item 20: the diattenuation's sign for each polarization, end to end (the
/// Δ90 runs at ±45° cannot see it: both axes then receive `(A + B)/2`). From
/// `ground_532_depol.toml` at D = 0 the two channels' expected signals (the
/// perpendicular one over its 1.5 times the quantum efficiency) give each bin's
/// parallel and perpendicular light (cross-talk x = 0.01: `par = (1−x)β∥ + xβ⊥`,
/// `perp = (1−x)β⊥ + xβ∥`, solved here); at D = ±0.2 the receiving optics pass `(1+D)`
/// of β∥ and `(1−D)` of β⊥, so each channel's signal must be
/// `(1−x)(1±D)β + x(1∓D)β'` of those, to 1e-9 in every bin with signal. A sign error on
/// either polarization moves the perpendicular channel by ≥ 2D·(1−x)·β⊥/perp, 10–40 %.
#[test]
fn the_diattenuation_passes_1_plus_d_parallel_and_1_minus_d_perpendicular() {
    let signals = |d: f64| -> (Vec<f64>, Vec<f64>) {
        let set = format!("instrument.diattenuation={d}");
        let lidar = common::lidar("ground/ground_532_depol.toml", &[set.as_str()]);
        let e = lidar.expected().unwrap();
        let name = |k: usize| lidar.channels[k].channel_name.clone();
        assert_eq!(
            (name(0), name(1)),
            ("532_parallel".into(), "532_perpendicular".into())
        );
        // the perpendicular tube's quantum efficiency is 0.3, the parallel one's 0.2
        let perp = e[1].photon_signal().iter().map(|s| s / 1.5).collect();
        (e[0].photon_signal().to_vec(), perp)
    };
    let x = 0.01;
    let (par0, perp0) = signals(0.0);
    for d in [0.2, -0.2] {
        let (par, perp) = signals(d);
        let mut tested = 0;
        for b in 0..par0.len() {
            if par0[b] <= 0.0 {
                continue;
            }
            // [par0, perp0] = [[1−x, x], [x, 1−x]]·[β∥, β⊥]
            let det = (1.0 - x) * (1.0 - x) - x * x;
            let beta_par = ((1.0 - x) * par0[b] - x * perp0[b]) / det;
            let beta_perp = ((1.0 - x) * perp0[b] - x * par0[b]) / det;
            let (a, bb) = ((1.0 + d) * beta_par, (1.0 - d) * beta_perp);
            let want_par = (1.0 - x) * a + x * bb;
            let want_perp = (1.0 - x) * bb + x * a;
            assert!(
                (par[b] / want_par - 1.0).abs() < 1e-9,
                "D {d} bin {b}: parallel"
            );
            assert!(
                (perp[b] / want_perp - 1.0).abs() < 1e-9,
                "D {d} bin {b}: perpendicular {} vs {want_perp}",
                perp[b]
            );
            tested += 1;
        }
        assert!(tested > 100, "{tested} bins with signal");
    }
}
