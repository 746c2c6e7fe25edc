//! The molecular line through the receiver's filter, and depolarization recovered from
//! simulated parallel and perpendicular counts (docs/model.md §4a): the Cabannes line,
//! the whole line, and (`line = "filter"`) the Cabannes line with the rotational Raman
//! lines inside the filter, against this test's own direct sum of Behrendt & Nakamura
//! (2002) (`common::reference::rotational_raman_share_through`).

mod common;

use common::reference::{
    molecular_lidar_ratio_and_depolarization_with_rr as seen_by_reference,
    rotational_raman_share_through as rr_share,
};
use lidarsim::atmosphere::rotational_raman;
use lidarsim::simulate::ResolvedMethod;
use lidarsim::validate::{RealizationSource, SimulatorSource};

/// Volume depolarization from `profiles` simulated profiles of the parallel and the
/// perpendicular channel over `bins`: background-subtracted sums, their ratio, and the
/// ratio's standard deviation (Poisson counts); and the model's ratio, from this test's
/// own calculation of each channel's bin integrals (`tests/common/reference.rs`: own
/// optics, polarization shares and T²), checked against the simulator's expectation.
fn depolarization(
    overrides: &[&str],
    bins: std::ops::Range<usize>,
    profiles: u64,
) -> (f64, f64, f64) {
    let run = |channel: &str, seed: u64| {
        let mut ov = overrides.to_vec();
        let c = format!("instrument.channel={channel}");
        ov.push(&c);
        let sc = common::scenario("paper/scenario1.toml", &ov);
        let e = sc.expected().unwrap();
        let shots = sc.shots_per_profile();
        let source = SimulatorSource::new(&e, ResolvedMethod::Aggregate, 0.0, seed, shots);
        let mut total = 0u64;
        let mut counts = vec![0u64; e.n_bins()];
        for p in 0..profiles {
            counts.iter_mut().for_each(|c| *c = 0);
            source.draw(p, &mut counts);
            total += counts[bins.clone()].iter().sum::<u64>();
        }
        let rest = (e.background + e.dark) * (shots * profiles) as f64 * bins.len() as f64;
        let sim: f64 = e.signal[bins.clone()].iter().sum();
        let c = common::reference::signal_constant(&sc.loaded.config);
        let brute = common::reference::brute_force(&sc, 1.0);
        let model: f64 = brute.integral[bins.clone()].iter().map(|x| c * x).sum();
        assert!(
            (sim / model - 1.0).abs() < 1e-3,
            "{channel}: {sim} vs {model}"
        );
        (total as f64 - rest, total as f64, model)
    };
    let (par, par_total, par_model) = run("parallel", 1);
    let (perp, perp_total, perp_model) = run("perpendicular", 2);
    let ratio = perp / par;
    let sd = ratio * (perp_total / (perp * perp) + par_total / (par * par)).sqrt();
    (ratio, sd, perp_model / par_model)
}

/// Clear air (no aerosol, no cloud below 8 km) at night: through a 37 pm etalon the
/// molecular depolarization recovered from the counts is 0.0036 (the Cabannes line),
/// through a 20 nm filter 0.0144 (the whole line), each within 4 sd of the model (false
/// alarm 6e-5 each), and the two are told apart (power: the Cabannes model is rejected
/// for the whole line's counts and the converse, at more than 10 sd).
#[test]
fn clear_air_depolarization_follows_the_filter() {
    let clear = [
        "atmosphere.aerosol.surface_extinction_per_km=0",
        "instrument.pulse_energy_j=1",
    ];
    let mut found = Vec::new();
    for (filter, want) in [("0.037", 0.0036), ("20", 0.0144)] {
        let f = format!("instrument.filter_width_nm={filter}");
        let mut ov = clear.to_vec();
        ov.push(&f);
        // bins 307..327: 8 km down to 2 km (334 bins of 300 m from 100 km)
        let (ratio, sd, model) = depolarization(&ov, 307..327, 200);
        assert!((model - want).abs() < 1e-4, "{filter} nm: model {model}");
        assert!(
            (ratio - model).abs() < 4.0 * sd,
            "{filter} nm: {ratio} ± {sd} vs {model}"
        );
        found.push((ratio, sd));
    }
    let ((a, sa), (b, sb)) = (found[0], found[1]);
    assert!(
        (b - a) > 10.0 * (sa * sa + sb * sb).sqrt(),
        "{a} ± {sa} vs {b} ± {sb}"
    );
}

/// In the cirrus of scenario 1 (δ = 0.4), the volume depolarization recovered from the
/// parallel and perpendicular counts matches the truth (the channels' expected signals)
/// within 4 sd (false alarm 6e-5). Power: the same statistic rejects a depolarization
/// 2 % off either way.
#[test]
fn cirrus_depolarization_is_recovered() {
    let sc = common::scenario("paper/scenario1.toml", &[]);
    let e = sc.expected().unwrap();
    let cloud: Vec<usize> = (0..e.n_bins())
        .filter(|&i| (10_200.0..11_800.0).contains(&e.altitude_m[i]))
        .collect();
    let bins = cloud[0]..cloud[cloud.len() - 1] + 1;
    let (ratio, sd, model) = depolarization(&[], bins, 20);
    assert!(model > 0.3 && model < 0.4, "{model}");
    assert!(
        (ratio - model).abs() < 4.0 * sd,
        "{ratio} ± {sd} vs {model}"
    );
    for f in [0.98, 1.02] {
        assert!(
            (ratio - f * model).abs() > 4.0 * sd,
            "no power at {f}: {ratio} ± {sd} vs {model}"
        );
    }
}

/// ARC's molecular depolarization through a 1 nm filter at 532 nm (docs/model.md §4a).
const ARC_1NM_532: f64 = 0.0041;

/// The channel's molecular line with `line = "filter"` behind a top-hat of `width` nm:
/// (depolarization, lidar ratio sr, the raw file's line name).
fn through_filter(width: &str, wavelength: &str) -> (f64, f64, String) {
    let f = format!("instrument.filter_width_nm={width}");
    let w = format!("instrument.wavelength_nm={wavelength}");
    let sc = common::scenario(
        "paper/scenario1.toml",
        &["atmosphere.molecular.line=filter", &f, &w],
    );
    let a = &sc.atmosphere;
    (
        a.molecules.depolarization,
        a.molecular_lidar_ratio_sr(),
        a.molecular_line_name(),
    )
}

/// Through a 1 nm filter at 532 nm the Cabannes line and the four nearest rotational
/// Raman lines (N₂ J = 0 and 2, O₂ N = 1 and 3) give a molecular depolarization within 3 %
/// of ARC's 0.0041, the lidar ratio and depolarization within 1e-4 of this test's own
/// direct sum of Behrendt & Nakamura's line formula at 288.15 K (the code sums the
/// partition function exactly, the reference takes B&N's high-temperature form: their
/// passed shares F differ by 9e-5), F itself within 3e-4; a 37 pm etalon gives the
/// Cabannes line (0.0037), a 20 nm filter the whole line (0.0144). At 355 nm a 1 nm
/// filter passes more of the wings. Power: a 1 % error in the strength of the nearest N₂
/// line (J = 0 → 2) moves F by 2.2e-3 and fails this test and the presets' below (done
/// once by hand, see the commit).
#[test]
fn a_1_nm_filter_passes_the_nearest_rotational_raman_lines() {
    let rho = common::reference::rayleigh_rho_n(532.0);
    let (delta, ratio, name) = through_filter("1", "532");
    assert_eq!(name, "cabannes+partial_rr");
    assert!((delta / ARC_1NM_532 - 1.0).abs() < 0.03, "{delta}");
    let f_ref = rr_share(532.0, 1.0, 288.15);
    let f_code = rotational_raman::passed_rr_share(532.0, 288.15, rotational_raman::top_hat(1.0));
    assert!((f_code / f_ref - 1.0).abs() < 3e-4, "F {f_code} vs {f_ref}");
    let (s_ref, delta_ref) = seen_by_reference(rho, f_ref);
    assert!(
        (delta / delta_ref - 1.0).abs() < 1e-4,
        "{delta} vs {delta_ref}"
    );
    assert!((ratio / s_ref - 1.0).abs() < 1e-4, "{ratio} vs {s_ref}");
    // between the limits: above the Cabannes line's, well below the whole line's
    assert!(delta > 0.0040 && delta < 0.0045 && ratio > 8.69 && ratio < 8.71);

    // the limits
    let (cabannes, s_c, name_c) = through_filter("0.037", "532");
    assert_eq!(name_c, "cabannes");
    assert!((cabannes - 0.0037).abs() < 5e-5, "{cabannes}");
    let (s, d) = seen_by_reference(rho, 0.0);
    assert!((s_c / s - 1.0).abs() < 1e-12 && (cabannes / d - 1.0).abs() < 1e-12);
    let (whole, s_w, name_w) = through_filter("20", "532");
    assert_eq!(name_w, "whole");
    assert!((whole - 0.0144).abs() < 5e-5, "{whole}");
    let (s, d) = seen_by_reference(rho, 1.0);
    assert!((s_w / s - 1.0).abs() < 1e-12 && (whole / d - 1.0).abs() < 1e-12);
    // a 0.5 nm filter keeps every line out (the nearest lies 0.338 nm away)
    assert_eq!(through_filter("0.5", "532").2, "cabannes");

    // 355 nm: the same 1 nm holds 2.25 times the wavenumbers
    let rho = common::reference::rayleigh_rho_n(355.0);
    let (delta, _, _) = through_filter("1", "354.7");
    let (_, delta_ref) = seen_by_reference(rho, rr_share(354.7, 1.0, 288.15));
    assert!(
        (delta / delta_ref - 1.0).abs() < 1e-4,
        "{delta} vs {delta_ref}"
    );
    assert!(delta > 0.0064 && delta < 0.0070, "{delta}");
}

/// The shipped ground presets behind 0.5–1 nm filters take `line = "filter"`: every
/// elastic 532 nm channel's molecular depolarization is within 3 % of ARC's 0.0041 (or
/// the Cabannes line's behind cirrus_small_angle's 0.5 nm), the 355 nm channels' that of
/// the reference, and the raw file's `beta_mol` is `alpha_mol` over this test's lidar
/// ratio, its `line` attribute `cabannes+partial_rr`.
#[test]
fn the_ground_presets_see_the_lines_their_filters_pass() {
    for preset in [
        "ground_532_depol",
        "ground_532_overlap",
        "profile_file_example",
        "cirrus_small_angle",
        "pollyxt_like",
        "pollyxt_like_glued",
    ] {
        let rel = format!("ground/{preset}.toml");
        let lidar = common::lidar(&rel, &[]);
        for c in &lidar.channels {
            let cfg = &c.loaded.config;
            assert_eq!(
                cfg.atmosphere.molecular.line,
                lidarsim::config::MolecularLine::Filter,
                "{preset}"
            );
            if c.atmosphere.raman.is_some() {
                continue;
            }
            let (wl, width) = (cfg.instrument.wavelength_nm, cfg.instrument.filter_width_nm);
            let rho = common::reference::rayleigh_rho_n(wl);
            let (s_ref, delta_ref) = seen_by_reference(rho, rr_share(wl, width, 288.15));
            let delta = c.atmosphere.molecules.depolarization;
            let who = format!("{preset} {}", c.channel_name);
            assert!(
                (delta / delta_ref - 1.0).abs() < 1e-4,
                "{who}: {delta} vs {delta_ref}"
            );
            let s = c.atmosphere.molecular_lidar_ratio_sr();
            assert!((s / s_ref - 1.0).abs() < 1e-4, "{who}: {s} vs {s_ref}");
            if wl == 532.0 && width >= 0.676 {
                assert!((delta / ARC_1NM_532 - 1.0).abs() < 0.03, "{who}: {delta}");
            }
        }
    }
    // the raw file
    let dir = common::cli::scratch("molecular-line-filter");
    let f = common::h5::simulate(
        &dir,
        &common::config_path("ground/ground_532_depol.toml"),
        "g.h5",
        "1",
    );
    let beta = f.dataset("beta_mol").unwrap();
    let line: hdf5::types::VarLenUnicode = beta.attr("line").unwrap().read_scalar().unwrap();
    assert_eq!(line.as_str(), "cabannes+partial_rr");
    let (s_ref, _) = seen_by_reference(0.02842, rr_share(532.0, 1.0, 288.15));
    let beta = common::h5::floats(&f, "beta_mol");
    let alpha = common::h5::floats(&f, "alpha_mol");
    let mut checked = 0;
    for (b, a) in beta.iter().zip(&alpha) {
        if *a > 0.0 {
            assert!((b * s_ref / a - 1.0).abs() < 1e-4, "{b} vs {a}/{s_ref}");
            checked += 1;
        }
    }
    assert!(checked > 100, "{checked}");
    std::fs::remove_dir_all(&dir).ok();
}

/// Clear air through a 1 nm filter with `line = "filter"`: the simulator's expected
/// parallel and perpendicular signals follow this test's brute-force reference (the
/// reference's molecular line from its own line sum, 1e-3), the model's depolarization
/// is the reference's (≈ 0.0042), and the one recovered from the counts lies within 4 sd
/// of it (false alarm 6e-5).
#[test]
fn clear_air_depolarization_through_a_1_nm_filter() {
    let ov = [
        "atmosphere.aerosol.surface_extinction_per_km=0",
        "instrument.pulse_energy_j=1",
        "instrument.filter_width_nm=1",
        "atmosphere.molecular.line=filter",
    ];
    let (ratio, sd, model) = depolarization(&ov, 307..327, 200);
    let rho = common::reference::rayleigh_rho_n(532.0);
    let (_, want) = seen_by_reference(rho, rr_share(532.0, 1.0, 288.15));
    assert!((model / want - 1.0).abs() < 1e-3, "model {model} vs {want}");
    assert!(
        (ratio - model).abs() < 4.0 * sd,
        "{ratio} ± {sd} vs {model}"
    );
    // power: the Cabannes line's 0.0037, which the presets took before, is rejected at
    // more than 10 sd (measured: 0.004170 ± 0.000017 against 0.00366)
    let (_, cabannes) = seen_by_reference(rho, 0.0);
    assert!(
        (ratio - cabannes) > 10.0 * sd,
        "{ratio} ± {sd} vs {cabannes}"
    );
}
