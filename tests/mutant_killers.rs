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
