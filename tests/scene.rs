//! The scene below and around the beam (model.md §7, issue 9): the surface echo, a
//! molecular profile continued above its top, Earth curvature.

mod common;

use lidarsim::scenario::Scenario;

/// The surface bin's expected signal is `C·(ρ cos θ/π)·T²(r_s)/r_s²` within 1 % (the
/// rest is the thin layer of air inside the bin), at nadir and 30° off nadir (spherical
/// Earth, cos θ the local incidence); the beam sees nothing below the surface; the
/// ocean preset's albedo is 0.05.
#[test]
fn the_surface_echo_follows_the_lambertian_law() {
    for angle in ["0", "30"] {
        let sc = common::scenario(
            "instruments/caliop_532.toml",
            &[
                "surface.albedo=0.3",
                "surface.altitude_km=0.2",
                &format!("platform.off_nadir_deg={angle}"),
            ],
        );
        let e = sc.expected().unwrap();
        let g = &sc.geometry;
        let r_s = g.range_at_altitude(200.0);
        let bin = (0..e.n_bins())
            .find(|&i| {
                let (a, b) = g.bin_range_bounds(i);
                r_s >= a && r_s < b
            })
            .unwrap();
        let cos = g.local_cos_at(200.0);
        let want = sc.instrument.signal_constant * 0.3 * cos / std::f64::consts::PI
            * sc.path.two_way_transmission(r_s)
            / (r_s * r_s);
        let got = e.signal[bin];
        assert!((got / want - 1.0).abs() < 0.01, "{angle}°: {got} vs {want}");
        assert!(
            e.signal[bin + 1..].iter().all(|&s| s == 0.0),
            "{angle}°: light below the surface"
        );
        assert!(e.signal[bin] > 100.0 * e.signal[bin - 1]);
    }
    let ocean = common::scenario("instruments/caliop_532.toml", &["surface.kind=\"ocean\""]);
    let land = common::scenario("instruments/caliop_532.toml", &["surface.kind=\"land\""]);
    let peak = |sc: &Scenario| {
        sc.expected()
            .unwrap()
            .signal
            .iter()
            .fold(0.0f64, |m, &s| m.max(s))
    };
    assert!((peak(&land) / peak(&ocean) - 3.0).abs() < 0.05);
    let e = Scenario::load(
        &common::config_path("ground/ground_532_overlap.toml"),
        &["surface.albedo=0.3".to_string()],
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("surface") && e.contains("ground"), "{e}");
}

/// A molecular profile file that stops at 30 km continues with US76 above, scaled to
/// match at its top row (here a profile 10 % denser than US76: 10 % denser above too),
/// and the run says so; a file reaching 86 km is used alone.
#[test]
fn a_short_profile_continues_with_us76() {
    let dir = std::env::temp_dir().join(format!("lidarsim-scene-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut text = String::from("altitude_km number_density_m3\n");
    for k in 0..=30 {
        let z = k as f64 * 1e3;
        let n = 1.1 * lidarsim::atmosphere::us76::number_density_m3(z);
        text.push_str(&format!("{} {n:e}\n", k as f64));
    }
    let profile = dir.join("short.txt");
    std::fs::write(&profile, text).unwrap();
    let sc = common::scenario(
        "paper/scenario1.toml",
        &[&format!(
            "atmosphere.molecular.model={{ file = \"{}\" }}",
            profile.display()
        )],
    );
    let m = &sc.atmosphere.molecules;
    for z in [35e3, 50e3, 80e3] {
        let want = 1.1 * lidarsim::atmosphere::us76::number_density_m3(z);
        assert!((m.number_density_m3(z) / want - 1.0).abs() < 1e-9, "{z}");
    }
    assert_eq!(m.top_m(), lidarsim::atmosphere::us76::TOP_ALTITUDE_M);
    let note = m.continuation_note().unwrap();
    assert!(
        note.contains("30.0 km") && note.contains("1.1000"),
        "{note}"
    );
    let e = sc.expected().unwrap();
    assert!(e.signal.iter().all(|s| s.is_finite()));
    let full = common::scenario("ground/profile_file_example.toml", &[]);
    assert!(full.atmosphere.molecules.continuation_note().is_none());
    std::fs::remove_dir_all(&dir).ok();
}
