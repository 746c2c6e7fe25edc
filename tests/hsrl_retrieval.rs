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
    let names = strings(&f, "channel_name");
    let k = |name: &str| names.iter().position(|c| c == name).unwrap();
    let (t, m) = (k("355_copolar_total"), k("355_copolar_molecular"));
    assert_eq!(strings(&f, "channel_kind")[m], "hsrl_molecular");
    let (fm, fp) = (
        floats(&f, "molecular_transmission")[m],
        floats(&f, "particle_transmission")[m],
    );
    assert_eq!((fm, fp), (0.6, 0.02));
    assert_eq!(floats(&f, "molecular_transmission")[t], 1.0);
    let (worst_beta, worst_alpha, judged) = hsrl_worst(&f, &|_| fm, fp);
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

/// The preset's molecular channel behind a filter table instead of constants: a notch
/// (2 % within ±0.5 GHz of the laser line, 90 % beyond ±1.5 GHz, linear between).
const NOTCH: &str = "spectral_filter = { offset_ghz = [-1.5, -0.5, 0.5, 1.5], transmission = [0.9, 0.02, 0.02, 0.9] }\n";

/// The ATLID-like preset with its molecular channel behind [`NOTCH`].
fn notch_config(dir: &std::path::Path) -> std::path::PathBuf {
    let base = std::fs::read_to_string(config_path("instruments/atlid_like.toml")).unwrap();
    let constants = "molecular_transmission = 0.6     # f_m: the Cabannes line's wings (ASSUMED)\nparticle_transmission = 0.02     # f_p: particle line leaking through the filter (ASSUMED)\n";
    assert!(base.contains(constants));
    let path = dir.join("notch.toml");
    std::fs::write(&path, base.replacen(constants, NOTCH, 1)).unwrap();
    path
}

/// `f_m` of [`NOTCH`] for a Gaussian line of standard deviation `sigma_ghz`, by
/// Simpson's rule over ±12 σ on 24,000 intervals (written here from Eq. H2, not from
/// lidarsim's closed form).
fn notch_fm(sigma_ghz: f64) -> f64 {
    let t = |nu: f64| {
        let a = nu.abs();
        if a <= 0.5 {
            0.02
        } else if a >= 1.5 {
            0.9
        } else {
            0.02 + (0.9 - 0.02) * (a - 0.5)
        }
    };
    let n = 24_000;
    let h = 24.0 * sigma_ghz / n as f64;
    let g = |nu: f64| {
        t(nu) * (-0.5 * (nu / sigma_ghz).powi(2)).exp()
            / (sigma_ghz * (2.0 * std::f64::consts::PI).sqrt())
    };
    let sum: f64 = (0..=n)
        .map(|j| {
            let w = if j == 0 || j == n {
                1.0
            } else if j % 2 == 1 {
                4.0
            } else {
                2.0
            };
            w * g(-12.0 * sigma_ghz + j as f64 * h)
        })
        .sum();
    sum * h / 3.0
}

/// With a filter table `f_m` follows the air's temperature: the file's
/// `molecular_transmission` (column, channel, bin) is, in every bin of the molecular
/// channel, the share of a Gaussian Cabannes line of `σ_ν = (2/λ)·sqrt(k·T/m)` (T the
/// file's `temperature`, m = 28.9644 g/mol / N_A) the notch passes, to 1e-6 (a filter
/// table read 1 % off, or a line width from the wrong temperature, fails); 1 in the
/// other channels; `particle_transmission` is t(0) = 0.02; and the two-channel retrieval
/// with the file's per-bin `f_m` recovers the particle backscatter within 1e-3 and the
/// extinction within 1e-2 (measured: 7.0e-5 and 2.9e-5); `validate` is CONSISTENT both
/// ways of drawing.
#[test]
fn a_filter_table_makes_the_molecular_share_follow_the_temperature() {
    let dir = scratch("hsrl-notch");
    let f = simulate(&dir, &notch_config(&dir), "n.h5", "2");
    let names = strings(&f, "channel_name");
    let n = names.len();
    let m = names
        .iter()
        .position(|c| c == "355_copolar_molecular")
        .unwrap();
    assert_eq!(floats(&f, "particle_transmission")[m], 0.02);
    let fm = rows(&f, "molecular_transmission", n);
    let temperature = floats(&f, "temperature");
    let altitude = floats(&f, "altitude");
    let (k_b, avogadro) = (1.380649e-23, 6.02214076e23);
    let mass = 28.9644e-3 / avogadro;
    let mut judged = 0;
    for i in (0..temperature.len()).filter(|&i| altitude[i] > 0.0 && altitude[i] < 80_000.0) {
        let sigma_ghz = 2.0 * (k_b * temperature[i] / mass).sqrt() / 354.8e-9 / 1e9;
        let want = notch_fm(sigma_ghz);
        assert!(
            (fm[m][i] - want).abs() < 1e-6,
            "bin {i}: {} vs {want}",
            fm[m][i]
        );
        for c in (0..n).filter(|&c| c != m) {
            assert_eq!(fm[c][i], 1.0);
        }
        judged += 1;
    }
    assert!(judged > 100, "{judged}");
    let near = |z: f64| {
        (0..altitude.len())
            .min_by(|&a, &b| (altitude[a] - z).abs().total_cmp(&(altitude[b] - z).abs()))
            .unwrap()
    };
    let (surface, top) = (fm[m][near(500.0)], fm[m][near(15_000.0)]);
    assert!(
        surface - top > 0.02,
        "f_m {surface} near the ground, {top} aloft"
    );
    let (worst_beta, worst_alpha, judged) = hsrl_worst(&f, &|i| fm[m][i], 0.02);
    eprintln!("{judged} bins: backscatter {worst_beta:e}, extinction {worst_alpha:e}");
    assert!(judged > 30, "{judged}");
    assert!(worst_beta < 1e-3, "backscatter {worst_beta}");
    assert!(worst_alpha < 1e-2, "extinction {worst_alpha}");
    validate_consistent_both_ways(&dir, &notch_config(&dir));
}

/// An HSRL molecular channel's keys: both transmissions required, f_p below f_m, and
/// refused on another kind; a filter table refused on another kind, beside the
/// transmissions, with offsets that do not increase, with columns of different lengths,
/// or passing more of the particle line than of the Cabannes line; each error one line
/// naming the channel's key.
#[test]
fn hsrl_keys_are_checked() {
    let base = std::fs::read_to_string(config_path("instruments/atlid_like.toml")).unwrap();
    let fp = "particle_transmission = 0.02";
    let total = "name = \"355_copolar_total\"\n";
    assert!(base.contains(fp) && base.contains(total));
    let dir = scratch("hsrl-keys");
    let notch = std::fs::read_to_string(notch_config(&dir)).unwrap();
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
        (
            base.replacen(total, &format!("{total}{NOTCH}"), 1),
            &["instrument.channels[0].spectral_filter", "hsrl_molecular"][..],
        ),
        (
            base.replacen(fp, &format!("{fp}\n{NOTCH}"), 1),
            &[
                "instrument.channels[1].molecular_transmission",
                "one or the other",
            ][..],
        ),
        (
            notch.replacen("[-1.5, -0.5, 0.5, 1.5]", "[-1.5, 0.5, -0.5, 1.5]", 1),
            &[
                "instrument.channels[1].spectral_filter",
                "increase strictly",
            ][..],
        ),
        (
            notch.replacen("[0.9, 0.02, 0.02, 0.9]", "[0.9, 0.02, 0.9]", 1),
            &["instrument.channels[1].spectral_filter", "4 offsets and 3"][..],
        ),
        (
            notch.replacen("[0.9, 0.02, 0.02, 0.9]", "[0.02, 0.9, 0.9, 0.02]", 1),
            &[
                "instrument.channels[1].spectral_filter",
                "more of the molecules",
            ][..],
        ),
    ] {
        let e = common::refusal(&text, &format!("{words:?}"));
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

/// The two-channel retrieval of the preset's expected signals (module doc), the
/// molecular channel's `f_m` of bin `i` given by `fm`: the worst relative errors of the
/// particle backscatter and extinction over the bins of the layers more than two bins from
/// their edges, and how many bins that was.
fn hsrl_worst(f: &hdf5::File, fm: &dyn Fn(usize) -> f64, fp: f64) -> (f64, f64, usize) {
    let names = strings(f, "channel_name");
    let n = names.len();
    let k = |name: &str| names.iter().position(|c| c == name).unwrap();
    let (t, m, x) = (
        k("355_copolar_total"),
        k("355_copolar_molecular"),
        k("355_crosspolar"),
    );
    let crosstalk = floats(f, "crosstalk");
    assert!(crosstalk.iter().all(|&c| c == crosstalk[0]));
    let cx = crosstalk[0];
    let (signal, c, weight) = (
        rows(f, "expected_signal", n),
        floats(f, "lidar_constant"),
        floats(f, "range_weight"),
    );
    let att = |ch: usize, i: usize| signal[ch][i] / (c[ch] * weight[i]);
    let (beta_mol, depol_mol) = (rows(f, "beta_mol", n), rows(f, "depol_mol", n));
    let (beta_aer, beta_cld) = (rows(f, "beta_aer", n), rows(f, "beta_cld", n));
    let (alpha_mol, alpha_o3) = (rows(f, "alpha_mol", n), rows(f, "alpha_o3", n));
    let (alpha_aer, alpha_cld) = (rows(f, "alpha_aer", n), rows(f, "alpha_cld", n));
    let range = floats(f, "range");
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
        let p_co = co * (fm(i) - r) / (r - fp);
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
    (worst_beta, worst_alpha, judged)
}

/// A filter table needs the air's temperature: with a molecular profile of number
/// densities only the run is refused in one line naming the profile's key (exit 2), and
/// no output file is left.
#[test]
fn a_filter_table_refuses_a_profile_without_temperatures() {
    let dir = scratch("hsrl-notch-density");
    let cfg = notch_config(&dir);
    let text = std::fs::read_to_string(&cfg).unwrap();
    let us76 = "model = \"us76\"";
    assert!(text.contains(us76));
    std::fs::write(
        dir.join("n.txt"),
        "altitude_km number_density_m3\n0 2.5e25\n10 8.6e24\n30 3.8e23\n",
    )
    .unwrap();
    std::fs::write(&cfg, text.replacen(us76, "model = { file = \"n.txt\" }", 1)).unwrap();
    let o = common::cli::lidarsim(
        &dir,
        &["simulate", cfg.to_str().unwrap(), "-o", "x.h5"],
        &[],
    );
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("atmosphere.molecular.model.file") && err.contains("temperature"),
        "{err}"
    );
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(!dir.join("x.h5").exists());
}

/// A filter table's limits at their edges: integers are numbers; 1 to 10,000 points
/// (10,000 accepted, 10,001 and an empty table refused); each error names the key.
#[test]
fn filter_tables_are_checked_at_their_limits() {
    let dir = scratch("hsrl-notch-limits");
    let notch = std::fs::read_to_string(notch_config(&dir)).unwrap();
    let table = |offsets: &[f64], t: &[f64]| {
        let list = common::toml_list;
        notch.replacen(
            NOTCH.trim_end(),
            &format!(
                "spectral_filter = {{ offset_ghz = [{}], transmission = [{}] }}",
                list(offsets),
                list(t)
            ),
            1,
        )
    };
    let notch_of = |n: usize| -> (Vec<f64>, Vec<f64>) {
        let f: Vec<f64> = (0..n)
            .map(|i| -5.0 + 10.0 * i as f64 / (n - 1) as f64)
            .collect();
        let t = f
            .iter()
            .map(|x| if x.abs() < 0.5 { 0.02 } else { 0.9 })
            .collect();
        (f, t)
    };
    let load = |text: &str| lidarsim::loaded::load_str(text, std::path::Path::new("a.toml"), &[]);
    let integers = notch.replacen(
        NOTCH.trim_end(),
        "spectral_filter = { offset_ghz = [-2, -1, 1, 2], transmission = [1, 0, 0, 1] }",
        1,
    );
    let (f, t) = notch_of(10_000);
    for text in [integers, table(&f, &t)] {
        if let Err(e) = load(&text) {
            panic!("refused: {e}");
        }
    }
    let (f, t) = notch_of(10_001);
    for (text, words) in [
        (table(&f, &t), "needs 1 to 10000 values, has 10001"),
        (table(&[], &[]), "needs 1 to 10000 values, has 0"),
    ] {
        let e = common::refusal(&text, words);
        assert!(
            e.contains("instrument.channels[1].spectral_filter") && e.contains(words),
            "{e}"
        );
    }
}
