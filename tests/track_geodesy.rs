//! The along-track distance is the length of the ground track that the file's own
//! latitudes and longitudes describe (docs/model.md "Orbit"; `src/scene/orbit.rs`), and
//! the scene's segments are laid on that same distance. The reference here is computed
//! from the file alone: the sum of haversine great-circle lengths between successive
//! profile centres on the sphere of radius 6,371,008.8 m (the mean Earth radius the
//! model uses, IUGG R1). Successive centres are 5.1 km apart; the chord-versus-track
//! error of such a sum is below 1e-9 relative.

mod common;

use std::path::PathBuf;

const EARTH_RADIUS_M: f64 = 6_371_008.8;

fn haversine_m(lat_a: f64, lon_a: f64, lat_b: f64, lon_b: f64) -> f64 {
    let (la, lb) = (lat_a.to_radians(), lat_b.to_radians());
    let dl = (lon_b - lon_a).to_radians();
    let h = ((lb - la) / 2.0).sin().powi(2) + la.cos() * lb.cos() * (dl / 2.0).sin().powi(2);
    2.0 * EARTH_RADIUS_M * h.sqrt().min(1.0).asin()
}

/// Runs the shipped orbit config (200 profiles of 15 shots, ~1,016 km): its directory
/// and file.
fn orbit_run(name: &str) -> (PathBuf, hdf5::File) {
    let dir = std::env::temp_dir().join(format!("lidarsim-geodesy-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("run.h5");
    let cfg = common::config_path("instruments/caliop_orbit.toml");
    common::cli::ok(common::cli::lidarsim(
        &dir,
        &[
            "simulate",
            cfg.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ],
        &[],
    ));
    let f = hdf5::File::open(&out).unwrap();
    (dir, f)
}

fn read(f: &hdf5::File, name: &str) -> Vec<f64> {
    f.dataset(name).unwrap().read_raw().unwrap()
}

/// The file's cumulative haversine length from its first profile centre.
fn haversine_track(lat: &[f64], lon: &[f64]) -> Vec<f64> {
    let mut s = vec![0.0];
    for k in 1..lat.len() {
        let step = haversine_m(lat[k - 1], lon[k - 1], lat[k], lon[k]);
        s.push(s[k - 1] + step);
    }
    s
}

/// Over the ~1,016 km of the shipped orbit, `along_track_distance` grows as the
/// great-circle length of the file's own track: within 0.1 % (the criterion;
/// asserted to 1e-5), where `v_g·t` (the inertial ground speed) is 0.8–1.2 % short.
#[test]
fn along_track_distance_is_the_great_circle_length_of_the_files_track() {
    let (dir, f) = orbit_run("length");
    let (lat, lon, d) = (
        read(&f, "latitude"),
        read(&f, "longitude"),
        read(&f, "along_track_distance"),
    );
    let s = haversine_track(&lat, &lon);
    let n = d.len();
    let total = s[n - 1];
    assert!(total > 1_000e3, "{total}");
    for k in 1..n {
        let file = d[k] - d[0];
        assert!(
            (file / s[k] - 1.0).abs() < 1e-5,
            "profile {k}: {file} vs {}",
            s[k]
        );
    }
    // the old definition, v_g·t, would fail this test
    let v_g = lidarsim::geometry::ground_track_speed_m_per_s(705e3);
    let inertial = v_g * (n - 1) as f64 * 15.0 / 20.16;
    assert!(total / inertial - 1.0 > 0.005, "{total} vs {inertial}");
    // the first profile's centre is half a profile from the first shot
    let first = haversine_m(lat[0], lon[0], lat[1], lon[1]) / 2.0;
    assert!((d[0] / first - 1.0).abs() < 1e-3, "{} vs {first}", d[0]);
    std::fs::remove_dir_all(&dir).ok();
}

/// The cirrus segment starts 250 km along the track (`length_km = 250` of the first
/// segment): the profile that straddles the boundary sees the cirrus in exactly the
/// shots that lie beyond 250 km of the file's own track (its truth is the mean over its
/// shots), the profiles before see none, the profiles after see it in every shot.
#[test]
fn a_segment_boundary_falls_at_its_length_along_the_files_track() {
    let (dir, f) = orbit_run("boundary");
    let (lat, lon, alt) = (
        read(&f, "latitude"),
        read(&f, "longitude"),
        read(&f, "altitude"),
    );
    let signal = common::h5::per_profile(&f, "expected_signal");
    let n_bins = alt.len();
    let z10 = (0..n_bins)
        .min_by(|&a, &b| (alt[a] - 10e3).abs().total_cmp(&(alt[b] - 10e3).abs()))
        .unwrap();
    let at = |p: usize| signal[p * n_bins + z10];
    // distance of each profile's centre from the first shot: the first centre is half a
    // profile step from the first shot
    let s = haversine_track(&lat, &lon);
    let half = s[1] / 2.0;
    let centre: Vec<f64> = s.iter().map(|x| x + half).collect();
    let boundary = 250e3;
    // shot j of profile k (15 shots, centre at 7.5 shots) lies at
    // centre_k + (j − 7.5)·step/15
    let k = (0..centre.len())
        .find(|&k| centre[k] + 6.5 * (centre[k + 1] - centre[k]) / 15.0 >= boundary)
        .unwrap();
    let step = centre[k + 1] - centre[k];
    let beyond = (0..15)
        .filter(|&j| centre[k] + (j as f64 - 7.5) * step / 15.0 >= boundary)
        .count();
    // margin: the boundary is not within 1 % of a shot spacing of a shot
    let nearest = (0..15)
        .map(|j| (centre[k] + (j as f64 - 7.5) * step / 15.0 - boundary).abs())
        .fold(f64::INFINITY, f64::min);
    assert!(nearest > 0.01 * step / 15.0, "{nearest}");
    eprintln!("boundary in profile {k}: {beyond} of 15 shots beyond 250 km");
    let (clear, cirrus) = (at(k - 1), at(k + 1));
    assert!(cirrus > 5.0 * clear, "{clear} {cirrus}");
    assert!((at(k - 2) / clear - 1.0).abs() < 1e-12);
    assert!((at(k + 2) / cirrus - 1.0).abs() < 1e-12);
    let fraction = (at(k) - clear) / (cirrus - clear);
    assert!(
        (fraction * 15.0 - beyond as f64).abs() < 1e-6,
        "profile {k}: {:.4} of 15 shots in the cirrus, {beyond} expected",
        fraction * 15.0
    );
    std::fs::remove_dir_all(&dir).ok();
}
