//! The exact bin integral (model.md §1) against independent brute-force quadrature and
//! closed forms, including bins cut by cloud edges and the hard cases of issue 2.

mod common;
use common::{brute_force_signal, scenario};

fn assert_close(a: &[f64], b: &[f64], rel: f64, floor: f64, what: &str) {
    assert_eq!(a.len(), b.len());
    for (i, (x, y)) in a.iter().zip(b).enumerate() {
        if x.abs().max(y.abs()) < floor {
            continue;
        }
        assert!(
            (x - y).abs() <= rel * y.abs(),
            "{what}: bin {i}: {x} vs {y} (rel {})",
            (x - y).abs() / y.abs()
        );
    }
}

#[test]
fn signal_matches_brute_force_quadrature_for_every_paper_scenario() {
    for n in 1..=6 {
        let sc = scenario(&format!("paper/scenario{n}.toml"), &[]);
        let e = sc.expected().unwrap();
        let brute = brute_force_signal(&sc, 0.05);
        // 5 cm midpoint steps: a cloud edge inside a step costs the quadrature at most
        // 0.05 m of cloud, < 3e-4 of any bin here
        assert_close(&e.signal, &brute, 1e-3, 1e-12, &format!("scenario {n}"));
    }
}

#[test]
fn cloud_edges_inside_bins_are_integrated_exactly() {
    // a cloud whose edges fall mid-bin: 10.1234–10.4567 km, optically thick
    let sc = scenario(
        "paper/scenario1.toml",
        &[
            "atmosphere.layers.0.base_km=10.1234",
            "atmosphere.layers.0.top_km=10.4567",
            "atmosphere.layers.0.extinction_per_km=5",
        ],
    );
    let e = sc.expected().unwrap();
    let brute = brute_force_signal(&sc, 0.01);
    assert_close(&e.signal, &brute, 1e-4, 1e-12, "cut cloud");
    // the bins holding the cloud's edges: a midpoint sample C·β·T²·ΔR/r² at the bin
    // centre is wrong there by far more than 10 %, the exact integral is not
    let g = &sc.geometry;
    let edge_bins: Vec<usize> = (0..e.n_bins())
        .filter(|&i| {
            let (ra, rb) = g.bin_range_bounds(i);
            let (z_top, z_bot) = (g.altitude_at_range(ra), g.altitude_at_range(rb));
            [10_123.4, 10_456.7]
                .iter()
                .any(|edge| z_bot < *edge && *edge < z_top)
        })
        .collect();
    assert_eq!(edge_bins.len(), 2);
    for i in edge_bins {
        let r = e.range_m[i];
        let beta = sc.atmosphere.optics_at(e.altitude_m[i]).beta_channel;
        let midpoint = sc.instrument.signal_constant * beta * e.t2[i] * g.bin_range_m / (r * r);
        assert!(
            (midpoint / e.signal[i] - 1.0).abs() > 0.1,
            "bin {i}: midpoint {midpoint} vs {}",
            e.signal[i]
        );
    }
}

#[test]
fn clear_vacuum_slab_has_the_closed_form() {
    // no molecules, no aerosol, one non-attenuating layer (alpha -> 0): ∫β/r² = β(1/a − 1/b)
    let sc = scenario(
        "paper/scenario1.toml",
        &[
            "atmosphere.molecular.model=none",
            "atmosphere.aerosol.surface_extinction_per_km=0",
            "atmosphere.layers.0.extinction_per_km=1e-12",
            "atmosphere.layers.0.lidar_ratio_sr=1",
            "atmosphere.layers.0.base_km=0",
            "atmosphere.layers.0.top_km=40",
            "acquisition.top_altitude_km=40",
        ],
    );
    let e = sc.expected().unwrap();
    let beta = 1e-12 * 1e-3; // m⁻¹ sr⁻¹ (α = 1e-15 m⁻¹, S = 1 sr)
    for i in 0..e.n_bins() {
        let (a, b) = sc.geometry.bin_range_bounds(i);
        let b = b.min(sc.geometry.range_at_altitude(0.0));
        if b <= a {
            continue;
        }
        let exact = sc.instrument.signal_constant * beta * (1.0 / a - 1.0 / b);
        assert!(
            (e.signal[i] - exact).abs() <= 1e-9 * exact,
            "bin {i}: {} vs {exact}",
            e.signal[i]
        );
    }
}

#[test]
fn optical_depth_500_cloud_gives_finite_signal_and_zero_below() {
    // a 1 km cloud with α = 500 km⁻¹ (τ = 500) whose top is the start of bin 96
    let probe = scenario("paper/scenario1.toml", &[]);
    let top_m = probe
        .geometry
        .altitude_at_range(probe.geometry.bin_range_bounds(96).0);
    let top = format!("atmosphere.layers.0.top_km={}", top_m / 1e3);
    let base = format!("atmosphere.layers.0.base_km={}", top_m / 1e3 - 1.0);
    let sc = scenario(
        "paper/scenario1.toml",
        &["atmosphere.layers.0.extinction_per_km=500", &top, &base],
    );
    let e = sc.expected().unwrap();
    assert!(
        e.signal
            .iter()
            .chain(&e.t2)
            .all(|v| v.is_finite() && *v >= 0.0)
    );
    assert!(
        e.signal[97..].iter().all(|s| *s < 1e-100),
        "no light below τ = 500"
    );
    // bin 96 lies inside the cloud: ∫ β T²(top) e^{−2α_tot x}/r² dx = β T²(top)/(2 α_tot r²)
    // up to 1/r² varying over the 1 mm decay length (relative 2/(2α r) ≈ 3e-6)
    let r_top = sc.geometry.bin_range_bounds(96).0;
    let o = sc.atmosphere.optics_at(top_m - 0.5);
    let expected =
        sc.instrument.signal_constant * o.beta_channel * sc.path.two_way_transmission(r_top)
            / (2.0 * o.alpha_effective * r_top * r_top);
    assert!(
        (e.signal[96] - expected).abs() < 1e-5 * expected,
        "{} vs {expected}",
        e.signal[96]
    );
}

#[test]
fn one_metre_layer_is_resolved() {
    let sc = scenario(
        "paper/scenario1.toml",
        &[
            "atmosphere.layers.0.base_km=10.0",
            "atmosphere.layers.0.top_km=10.001",
            "atmosphere.layers.0.extinction_per_km=50",
        ],
    );
    let e = sc.expected().unwrap();
    let brute = brute_force_signal(&sc, 0.01);
    assert_close(&e.signal, &brute, 1e-4, 1e-12, "1 m layer");
}

#[test]
fn other_wavelengths_scale_like_rayleigh() {
    let at = |wl: &str| {
        let sc = scenario(
            "paper/scenario6.toml",
            &[
                &format!("instrument.wavelength_nm={wl}"),
                "atmosphere.molecular.model=us76",
                "acquisition.top_altitude_km=40",
            ],
        );
        let e = sc.expected().unwrap();
        assert!(e.signal.iter().all(|s| s.is_finite() && *s >= 0.0));
        e.point[0].beta_mol
    };
    let (b355, b532, b1064) = (at("355"), at("532"), at("1064"));
    // β_mol ∝ σ(λ)/S_mol(λ) (Bucholtz): 532→355 ≈ ×5.2, 532→1064 ≈ ÷16.7, from this
    // test's formulas within 1e-4
    let beta_of = |wl: f64| {
        let (s, _) = common::reference::molecular_lidar_ratio_and_depolarization(
            common::reference::rayleigh_rho_n(wl),
            false,
        );
        common::reference::rayleigh_cross_section_m2(wl) / s
    };
    let (up, down) = (
        beta_of(355.0) / beta_of(532.0),
        beta_of(532.0) / beta_of(1064.0),
    );
    assert!(
        ((b355 / b532) / up - 1.0).abs() < 1e-4,
        "{} vs {up}",
        b355 / b532
    );
    assert!(
        ((b532 / b1064) / down - 1.0).abs() < 1e-4,
        "{} vs {down}",
        b532 / b1064
    );
    assert!(
        (up - 5.2).abs() < 0.2 && (down - 16.7).abs() < 0.5,
        "{up} {down}"
    );
}

#[test]
fn ground_lidar_with_geometric_overlap_matches_brute_force() {
    let sc = scenario(
        "ground/ground_532_overlap.toml",
        &["acquisition.top_altitude_km=5"],
    );
    let e = sc.expected().unwrap();
    let brute = brute_force_signal(&sc, 0.01);
    assert_close(&e.signal, &brute, 1e-3, 1e-9, "ground overlap");
    // the pre-trigger bins see nothing, the overlap hides the first bins, then the
    // signal rises
    assert_eq!(sc.geometry.pretrigger_bins, 256);
    assert!(e.signal[..=256].iter().all(|&s| s == 0.0));
    assert!(e.signal[300] > 0.0);
    assert!(e.signal.iter().all(|s| s.is_finite()));
}

#[test]
fn ground_lidar_seeing_range_zero_is_a_config_error() {
    let ov: Vec<String> = vec!["instrument.overlap={model=\"none\"}".into()];
    let err = lidarsim::scenario::Scenario::load(
        &common::config_path("ground/ground_532_overlap.toml"),
        &ov,
    )
    .expect_err("1/r² diverges at r = 0");
    let msg = err.to_string();
    assert!(
        msg.contains("ground_532_overlap.toml")
            && msg.contains("bottom_altitude_km")
            && msg.contains("diverges"),
        "{msg}"
    );
    // raising the window removes the divergence
    let ov2 = vec![
        ov[0].clone(),
        "acquisition.bottom_altitude_km=0.1".into(),
        "acquisition.pretrigger_bins=0".into(),
    ];
    let sc = lidarsim::scenario::Scenario::load(
        &common::config_path("ground/ground_532_overlap.toml"),
        &ov2,
    )
    .unwrap();
    assert!(
        sc.expected()
            .unwrap()
            .signal
            .iter()
            .all(|s| s.is_finite() && *s > 0.0)
    );
}

#[test]
fn extreme_off_nadir_60_degrees_follows_the_slant_path() {
    let nadir = scenario("paper/scenario6.toml", &[]).expected().unwrap();
    let sc = scenario(
        "paper/scenario6.toml",
        &[
            "platform.off_nadir_deg=60",
            "platform.earth_curvature=false",
        ],
    );
    let slant = sc.expected().unwrap();
    assert!(slant.signal.iter().all(|s| s.is_finite()));
    // T² to the same altitude: optical depth doubles at 60°, T²_slant = T²_nadir²
    let z = 2000.0;
    let t2_nadir = scenario("paper/scenario6.toml", &[])
        .path
        .two_way_transmission(600_000.0 - z);
    let t2_slant = sc
        .path
        .two_way_transmission(sc.geometry.range_at_altitude(z));
    assert!(
        (t2_slant - t2_nadir * t2_nadir).abs() < 1e-9,
        "{t2_slant} vs {}",
        t2_nadir * t2_nadir
    );
    assert!(slant.n_bins() > nadir.n_bins());
}

/// Earth curvature (docs/model.md §3): from 600 km at 30° off nadir the beam meets the ground
/// at ~704 km (flat Earth: 693 km); the range-altitude mapping inverts itself; nadir is
/// the flat formula exactly; an angle whose beam misses the Earth is refused with the
/// limit in the message.
#[test]
fn a_spherical_earth_lengthens_slant_paths() {
    let curved = scenario("paper/scenario1.toml", &["platform.off_nadir_deg=30"]);
    let flat = scenario(
        "paper/scenario1.toml",
        &[
            "platform.off_nadir_deg=30",
            "platform.earth_curvature=false",
        ],
    );
    let ground = curved.geometry.range_at_altitude(0.0);
    assert!((ground - 704.1e3).abs() < 0.5e3, "{ground}");
    assert!((flat.geometry.range_at_altitude(0.0) - 692.8e3).abs() < 0.5e3);
    for z in [-500.0, 0.0, 10e3, 86e3, 500e3] {
        let r = curved.geometry.range_at_altitude(z);
        assert!(
            (curved.geometry.altitude_at_range(r) - z).abs() < 1e-6,
            "{z}"
        );
    }
    // the local zenith angle grows towards the ground: sin θ = (R+H) sin φ/(R+z)
    assert!(curved.geometry.local_cos_at(0.0) < 30f64.to_radians().cos());
    let nadir = scenario("paper/scenario1.toml", &[]);
    let nadir_flat = scenario("paper/scenario1.toml", &["platform.earth_curvature=false"]);
    assert_eq!(
        nadir.expected().unwrap().signal,
        nadir_flat.expected().unwrap().signal
    );
    let e = lidarsim::scenario::Scenario::load(
        &common::config_path("paper/scenario1.toml"),
        &["platform.off_nadir_deg=70".to_string()],
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("misses the Earth") && e.contains("66.05"), "{e}");
}
