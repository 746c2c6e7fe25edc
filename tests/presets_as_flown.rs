//! Presets that say what the real instruments do (issue 36): CALIOP's detectors are
//! analog and its 30–34 km calibration region near-molecular; ground lidars behind
//! 0.3–1 nm filters see the Cabannes line, not the whole molecular line; the ATLID-like
//! preset records a background region. Each reads the shipped config.

mod common;

use common::{config_path, lidar};

/// `caliop_3ch.toml`, the instrument as flown, detects in analog on every channel
/// (PMTs at 532 nm, an APD at 1064 nm: Hunt et al. 2009), with CALIOP's effective
/// 22-bit range of its dual 14-bit digitizers; on main it counted photons.
#[test]
fn caliop_3ch_detects_in_analog_as_caliop_does() {
    let l = lidar("instruments/caliop_3ch.toml", &[]);
    assert_eq!(l.channels.len(), 3);
    for c in &l.channels {
        let a = c.instrument.analog.as_ref();
        assert!(a.is_some(), "{}: not analog", c.channel_name);
        assert!(c.instrument.dead_time.is_none(), "{}", c.channel_name);
        let d = c.loaded.config.instrument.detector.as_ref().unwrap();
        assert_eq!(d.adc_bits, Some(22), "{}", c.channel_name);
    }
}

/// The CALIOP-like presets' stratosphere is today's background aerosol: β_aer/β_mol at
/// most 0.01 in every bin of 30–34 km at 532 nm (CALIOP's calibration region, taken as
/// molecular), and still an aerosol there (above 1e-3). On main (Elterman 1968) the
/// ratio is 0.08–0.12 there. The hand values: 1e-5 km⁻¹ at 30 km over 50 sr against
/// β_mol(30 km) ≈ 2.3e-5 km⁻¹ sr⁻¹: 0.009.
#[test]
fn the_caliop_calibration_region_is_near_molecular() {
    for (rel, channels) in [
        ("instruments/caliop_3ch.toml", 2usize),
        ("instruments/caliop_532.toml", 1),
    ] {
        let l = lidar(rel, &[]);
        for c in l.channels.iter().take(channels) {
            let e = c.expected().unwrap();
            let mut judged = 0;
            for (z, o) in e.altitude_m.iter().zip(&e.point) {
                if !(30_000.0..=34_000.0).contains(z) {
                    continue;
                }
                let ratio = o.beta_aer / o.beta_mol;
                assert!(
                    (1e-3..=0.01).contains(&ratio),
                    "{rel} {}: beta_aer/beta_mol {ratio} at {z} m",
                    c.channel_name
                );
                judged += 1;
            }
            assert!(judged > 100, "{rel}: {judged} bins");
        }
    }
}

/// Every shipped ground preset's elastic channel behind a filter of at most 1 nm sees
/// the Cabannes line and the rotational Raman lines inside its filter: a molecular
/// depolarization between the Cabannes line's (3ε/(180 + 4ε), 0.0037 at 532 nm) and
/// the whole line's (0.0144), that of the reference's own line sum
/// (`common::reference::rotational_raman_share_through`, 2 %), and at 532 nm behind 1 nm
/// 0.0036–0.0046 (ARC: 0.0041), not the whole line's 0.0144.
#[test]
fn ground_filters_of_a_nanometre_see_the_cabannes_line_and_its_nearest_wings() {
    let dir = config_path("ground");
    let mut judged = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().and_then(|x| x.to_str()) != Some("toml") {
            continue;
        }
        let rel = format!("ground/{}", path.file_name().unwrap().to_str().unwrap());
        for c in &lidar(&rel, &[]).channels {
            let width = c.loaded.config.instrument.filter_width_nm;
            if c.atmosphere.raman.is_some() || width > 1.0 {
                continue;
            }
            let wl = c.loaded.config.instrument.wavelength_nm;
            let rho_n = reference_rho_n(wl);
            let (_, cabannes) =
                common::reference::molecular_lidar_ratio_and_depolarization(rho_n, true);
            let (_, whole) =
                common::reference::molecular_lidar_ratio_and_depolarization(rho_n, false);
            let rr = match c.loaded.config.atmosphere.molecular.line {
                lidarsim::config::MolecularLine::Filter => {
                    common::reference::rotational_raman_share_through(wl, width, 288.15)
                }
                _ => 0.0,
            };
            let (_, want) =
                common::reference::molecular_lidar_ratio_and_depolarization_with_rr(rho_n, rr);
            let seen = c.atmosphere.no_optics().depol_mol;
            assert!(
                seen >= cabannes * (1.0 - 1e-9) && seen < 0.5 * whole,
                "{rel} {} ({width} nm): molecular depolarization {seen}",
                c.channel_name
            );
            if wl == 532.0 && width == 1.0 {
                assert!((0.0036..=0.0046).contains(&seen), "{rel}: {seen}");
            }
            assert!((seen / want - 1.0).abs() < 2e-2, "{rel}: {seen} vs {want}");
            judged += 1;
        }
    }
    assert!(judged >= 10, "{judged} channels");
}

/// Bucholtz's ρn at `wavelength_nm` (the reference module's own formula).
fn reference_rho_n(wavelength_nm: f64) -> f64 {
    common::reference::rayleigh_rho_n(wavelength_nm)
}

/// The ATLID-like preset records, as ATLID does, a background region far above the
/// atmosphere: at least 100 signal-free bins (on main: none above the 40 km window top).
#[test]
fn atlid_like_records_a_background_region() {
    for c in &lidar("instruments/atlid_like.toml", &[]).channels {
        let e = c.expected().unwrap();
        assert!(
            e.background_bins >= 100,
            "{}: {} signal-free bins",
            c.channel_name,
            e.background_bins
        );
    }
}
