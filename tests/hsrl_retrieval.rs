//! HSRL molecular channels (issue 20, model.md §8 "High spectral resolution",
//! docs/model.md §4i): the two-channel HSRL retrieval with the cross-polar channel,
//! written here from the channels' definitions and fed only with the raw file's
//! variables, recovers the particle backscatter and extinction of the ATLID-like preset
//! from its expected signals.
//!
//! With cross-talk x, each species' backscatter split `β∥ = β/(1+δ)`, `β⊥ = β·δ/(1+δ)`,
//! `M = (1−x)·m∥ + x·m⊥` and `P = (1−x)·p∥ + x·p⊥` the co-polar molecular (Cabannes) and
//! particle parts, `M' = (1−x)·m⊥ + x·m∥` and `P'` the cross-polar ones, the attenuated
//! backscatter `X = expected_signal / (lidar_constant · range_weight)` of each channel is
//!
//! ```text
//! X_total = (M + P)·T²,   X_molecular = (f_m·M + f_p·P)·T²,   X_cross = (M' + P')·T²
//! ```
//!
//! so with `R = X_molecular / X_total`: `P = M·(f_m − R)/(R − f_p)`, `T² = X_total/(M + P)`,
//! `P' = X_cross/T² − M'`, the particle backscatter `β_p = P + P'`, and the extinction
//! `α_p = −½·d ln T²/dr − α_mol − α_O3`.

mod common;

use common::cli::scratch;
use common::config_path;
use common::h5::{channel_rows as rows, floats, simulate, strings, validate_consistent_both_ways};

/// Measured over the 43 bins of the three layers more than two bins from their edges:
/// backscatter within 6e-5, extinction within 3e-5. The molecular or the particle line
/// passed 1 % more than the file's f_m or f_p says fails the backscatter by 1 % (checked
/// by hand).
#[test]
fn the_hsrl_retrieval_of_the_expected_signals_recovers_backscatter_and_extinction() {
    let dir = scratch("hsrl-retrieval");
    let f = simulate(
        &dir,
        &config_path("instruments/atlid_like.toml"),
        "a.h5",
        "2",
    );
    let names = strings(&f, "channel");
    let n = names.len();
    let k = |name: &str| names.iter().position(|c| c == name).unwrap();
    let (t, m, x) = (
        k("355_copolar_total"),
        k("355_copolar_molecular"),
        k("355_crosspolar"),
    );
    assert_eq!(strings(&f, "channel_kind")[m], "hsrl_molecular");
    let (fm, fp) = (
        floats(&f, "molecular_transmission")[m],
        floats(&f, "particle_transmission")[m],
    );
    assert_eq!((fm, fp), (0.6, 0.02));
    assert_eq!(floats(&f, "molecular_transmission")[t], 1.0);
    let crosstalk = floats(&f, "crosstalk");
    assert!(crosstalk.iter().all(|&c| c == crosstalk[0]));
    let cx = crosstalk[0];
    let (signal, c, weight) = (
        rows(&f, "expected_signal", n),
        floats(&f, "lidar_constant"),
        floats(&f, "range_weight"),
    );
    let att = |ch: usize, i: usize| signal[ch][i] / (c[ch] * weight[i]);
    let (beta_mol, depol_mol) = (rows(&f, "beta_mol", n), rows(&f, "depol_mol", n));
    let (beta_aer, beta_cld) = (rows(&f, "beta_aer", n), rows(&f, "beta_cld", n));
    let (alpha_mol, alpha_o3) = (rows(&f, "alpha_mol", n), rows(&f, "alpha_o3", n));
    let (alpha_aer, alpha_cld) = (rows(&f, "alpha_aer", n), rows(&f, "alpha_cld", n));
    let range = floats(&f, "range");
    let bins = range.len();
    // the retrieval, bin by bin: particle backscatter and ln T²
    let mut beta_p = vec![f64::NAN; bins];
    let mut ln_t2 = vec![f64::NAN; bins];
    for i in 0..bins {
        if weight[i] <= 0.0 || beta_mol[t][i] <= 0.0 {
            continue;
        }
        let (mol, d) = (beta_mol[t][i], depol_mol[t][i]);
        let (m_par, m_perp) = (mol / (1.0 + d), mol * d / (1.0 + d));
        let co = (1.0 - cx) * m_par + cx * m_perp;
        let cross = (1.0 - cx) * m_perp + cx * m_par;
        let r = att(m, i) / att(t, i);
        let p_co = co * (fm - r) / (r - fp);
        let t2 = att(t, i) / (co + p_co);
        beta_p[i] = p_co + att(x, i) / t2 - cross;
        ln_t2[i] = t2.ln();
    }
    let particle_alpha = |i: usize| alpha_aer[t][i] + alpha_cld[t][i];
    let inside = |i: usize| {
        i >= 2
            && i + 2 < bins
            && (i - 2..=i + 2).all(|j| particle_alpha(j) == particle_alpha(i) && weight[j] > 0.0)
    };
    let (mut worst_beta, mut worst_alpha, mut judged) = (0.0f64, 0.0f64, 0);
    for i in (2..bins - 2).filter(|&i| inside(i) && particle_alpha(i) > 0.0) {
        let truth = beta_aer[t][i] + beta_cld[t][i];
        worst_beta = worst_beta.max((beta_p[i] / truth - 1.0).abs());
        let slope = (ln_t2[i + 1] - ln_t2[i - 1]) / (range[i + 1] - range[i - 1]);
        let alpha = -0.5 * slope - alpha_mol[t][i] - alpha_o3[t][i];
        worst_alpha = worst_alpha.max((alpha / particle_alpha(i) - 1.0).abs());
        judged += 1;
    }
    eprintln!("{judged} bins: backscatter {worst_beta:e}, extinction {worst_alpha:e}");
    assert!(judged > 30, "{judged}");
    assert!(
        worst_beta < 1e-3,
        "backscatter: worst relative error {worst_beta}"
    );
    assert!(
        worst_alpha < 1e-2,
        "extinction: worst relative error {worst_alpha}"
    );
}

/// An HSRL molecular channel's keys: both transmissions required, f_p below f_m, and
/// refused on another kind; each error one line naming the channel's key.
#[test]
fn hsrl_keys_are_checked() {
    let base = std::fs::read_to_string(config_path("instruments/atlid_like.toml")).unwrap();
    let fp = "particle_transmission = 0.02";
    let total = "name = \"355_copolar_total\"\n";
    assert!(base.contains(fp) && base.contains(total));
    for (text, words) in [
        (
            base.replacen(fp, "", 1),
            &["instrument.channels[1].particle_transmission", "required"][..],
        ),
        (
            base.replacen(fp, "particle_transmission = 0.7", 1),
            &["instrument.channels[1].particle_transmission", "blocks"][..],
        ),
        (
            base.replacen(total, &format!("{total}molecular_transmission = 0.5\n"), 1),
            &[
                "instrument.channels[0].molecular_transmission",
                "hsrl_molecular",
            ][..],
        ),
    ] {
        let e = match lidarsim::loaded::load_str(&text, std::path::Path::new("a.toml"), &[]) {
            Ok(_) => panic!("accepted: {words:?}"),
            Err(e) => e.to_string(),
        };
        assert!(!e.contains('\n'), "{e}");
        for w in words {
            assert!(e.contains(w), "{e}");
        }
    }
}

/// `validate` on the ATLID-like preset, both ways of drawing: CONSISTENT.
#[test]
fn validate_is_consistent_on_the_preset() {
    let dir = scratch("hsrl-consistent");
    validate_consistent_both_ways(&dir, &config_path("instruments/atlid_like.toml"));
    std::fs::remove_dir_all(&dir).ok();
}

/// The surface echo is an unbroadened line at the laser's wavelength: an HSRL molecular
/// channel sees `f_p` of it, a Raman channel none (its filter blocks the laser line).
/// Raising the albedo from 0.3 to 0.6 adds to each channel's expected signal exactly
/// `particle_transmission` times what it adds to the co-polar total channel (same
/// lidar constant and polarization), and nothing to a Raman channel's.
#[test]
fn the_surface_echo_passes_the_particle_share_and_no_raman_line() {
    let base = std::fs::read_to_string(config_path("instruments/atlid_like.toml")).unwrap();
    let raman = "[[instrument.channels]]\nname = \"387_raman_N2\"\nkind = \"raman\"\n\n[platform]";
    let text = base.replacen("[platform]", raman, 1);
    let added = |albedo: &str| -> Vec<Vec<f64>> {
        let over = vec![format!("surface.albedo={albedo}")];
        let loaded =
            lidarsim::loaded::load_str(&text, std::path::Path::new("a.toml"), &over).unwrap();
        let lidar = lidarsim::scenario::Lidar::from_loaded(loaded).unwrap();
        lidar
            .expected()
            .unwrap()
            .into_iter()
            .map(|e| e.signal)
            .collect()
    };
    let (low, high) = (added("0.3"), added("0.6"));
    let delta: Vec<f64> = (0..4)
        .map(|k| low[k].iter().zip(&high[k]).map(|(a, b)| b - a).sum())
        .collect();
    assert!(delta[0] > 0.0);
    assert!((delta[1] / delta[0] / 0.02 - 1.0).abs() < 1e-9, "{delta:?}");
    assert_eq!(delta[3], 0.0, "{delta:?}");
}
