//! The molecular line through the receiver's filter, and depolarization recovered from
//! simulated parallel and perpendicular counts (docs/model.md §4a).

mod common;

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
