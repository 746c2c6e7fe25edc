//! The seed paper's scenarios on its own kind of molecular atmosphere (issue 39 item 5):
//! the NRLMSIS 2.1 profile files of `configs/atmospheres/` (made by
//! `tools/make_msis_profiles.py`) against the embedded US76.
//!
//! The reference does not call the code under test: it reads the two profile files
//! itself (N = p/(k_B·T), ln N linear between rows), and predicts each scenario's MSIS
//! S/N at 10 and 15 km from the US76 run's per-bin columns (the aerosol and cloud
//! backscatter, T², background and dark, which the molecules do not change but through
//! β_mol and T²) scaled by what the two molecular densities differ:
//!
//! ```text
//! signal' = signal · (β_m·N'/N + β_a + β_c) / (β_m + β_a + β_c) · exp(−2·S_m·(β_m/N)·∫_z^top (N' − N) dz)
//! S/N'    = M·signal' / sqrt(M·(signal' + background + dark))        (paper Eq. 4, written here)
//! ```
//!
//! with S_m = 8π/3 the molecular extinction-to-backscatter ratio (a 2 % error in it
//! moves the prediction by < 1e-4: the molecular optical depth between the two
//! atmospheres differs by ~1e-3 above 10 km). Measured: the prediction holds within
//! 2e-4 (tolerance 5e-4) in the 24 cases, where MSIS and US76 differ by 1.4–3.9 % at
//! 15 km and by up to 0.4 % at 10 km (inside the cirrus or the aerosol); the molecular
//! density in the reference made 1 % larger fails it by 5e-3 (scenario 1, 10 km).

mod common;

use common::cli::{lidarsim, ok, scratch};
use common::config_path;
use std::path::Path;

const K_B: f64 = 1.380649e-23;
const S_MOL_SR: f64 = 8.0 * std::f64::consts::PI / 3.0;

/// A molecular profile file read here: altitudes (m) and ln N (m⁻³).
struct Profile {
    z_m: Vec<f64>,
    ln_n: Vec<f64>,
}

impl Profile {
    fn read(path: &Path) -> Profile {
        let text = std::fs::read_to_string(path).unwrap();
        let mut rows = text
            .lines()
            .filter(|l| !l.trim().is_empty() && !l.trim_start().starts_with('#'));
        let header = rows.next().unwrap();
        assert_eq!(
            header.split_whitespace().collect::<Vec<_>>(),
            ["altitude_km", "pressure_hpa", "temperature_k"]
        );
        let (mut z_m, mut ln_n) = (vec![], vec![]);
        for r in rows {
            let v: Vec<f64> = r.split_whitespace().map(|x| x.parse().unwrap()).collect();
            z_m.push(v[0] * 1e3);
            ln_n.push((v[1] * 100.0 / (K_B * v[2])).ln());
        }
        Profile { z_m, ln_n }
    }

    /// N at `z` (ln N linear between rows, 0 above the top).
    fn n(&self, z: f64) -> f64 {
        let top = *self.z_m.last().unwrap();
        if z > top {
            return 0.0;
        }
        let i = self
            .z_m
            .partition_point(|&a| a <= z)
            .clamp(1, self.z_m.len() - 1);
        let (z0, z1) = (self.z_m[i - 1], self.z_m[i]);
        let w = (z - z0) / (z1 - z0);
        (self.ln_n[i - 1] * (1.0 - w) + self.ln_n[i] * w).exp()
    }

    /// Mean N over `[z0, z1]` (midpoint rule, 1 m steps).
    fn mean_n(&self, z0: f64, z1: f64) -> f64 {
        let steps = ((z1 - z0) / 1.0).ceil().max(1.0) as usize;
        let h = (z1 - z0) / steps as f64;
        (0..steps)
            .map(|k| self.n(z0 + (k as f64 + 0.5) * h))
            .sum::<f64>()
            / steps as f64
    }

    /// ∫_z^{top} N dz (midpoint rule, 1 m steps).
    fn column_above(&self, z: f64) -> f64 {
        let top = *self.z_m.last().unwrap();
        self.mean_n(z, top) * (top - z)
    }
}

/// One bin of `expect --csv`.
#[derive(Debug, Clone, Copy)]
struct Bin {
    altitude_m: f64,
    beta_mol: f64,
    beta_aer: f64,
    beta_cld: f64,
    signal: f64,
    background: f64,
    dark: f64,
    snr: f64,
}

fn expect_csv(dir: &Path, config: &Path, overrides: &[String]) -> Vec<Bin> {
    let out = dir.join("expect.csv");
    let mut args = vec![
        "expect".to_string(),
        config.to_str().unwrap().to_string(),
        "--csv".to_string(),
        out.to_str().unwrap().to_string(),
    ];
    for o in overrides {
        args.push("--set".into());
        args.push(o.clone());
    }
    let a: Vec<&str> = args.iter().map(String::as_str).collect();
    ok(lidarsim(dir, &a, &[]));
    let text = std::fs::read_to_string(&out).unwrap();
    let mut lines = text.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| head.iter().position(|h| *h == name).unwrap();
    let c = [
        col("altitude_m"),
        col("beta_mol"),
        col("beta_aer"),
        col("beta_cld"),
        col("signal"),
        col("background"),
        col("dark"),
        col("snr"),
    ];
    lines
        .map(|l| {
            let v: Vec<f64> = l.split(',').map(|x| x.parse().unwrap()).collect();
            Bin {
                altitude_m: v[c[0]],
                beta_mol: v[c[1]],
                beta_aer: v[c[2]],
                beta_cld: v[c[3]],
                signal: v[c[4]],
                background: v[c[5]],
                dark: v[c[6]],
                snr: v[c[7]],
            }
        })
        .collect()
}

/// The config's fL·TC (paper Eq. 4 takes M as a real number).
fn shots(config: &Path) -> f64 {
    let t: toml::Table = std::fs::read_to_string(config).unwrap().parse().unwrap();
    let f = |s: &str, k: &str| t[s][k].as_float().unwrap();
    f("instrument", "rep_rate_hz") * f("acquisition", "accumulation_time_s")
}

fn eq4(signal: f64, background: f64, dark: f64, m: f64) -> f64 {
    m * signal / (m * (signal + background + dark)).sqrt()
}

/// The bin whose centre is nearest `z` among those whose cloud backscatter equals both
/// neighbours' (a layer edge inside a bin or next to it makes the bin's signal an
/// integral across the edge, which this reference does not resolve).
fn nearest(bins: &[Bin], z: f64) -> (usize, Bin) {
    let inside = |k: usize| {
        k > 0
            && k + 1 < bins.len()
            && bins[k - 1].beta_cld == bins[k].beta_cld
            && bins[k + 1].beta_cld == bins[k].beta_cld
    };
    let i = (0..bins.len())
        .filter(|&k| inside(k))
        .min_by(|&a, &b| {
            let d = |k: usize| (bins[k].altitude_m - z).abs();
            d(a).total_cmp(&d(b))
        })
        .unwrap();
    (i, bins[i])
}

#[test]
fn the_paper_scenarios_s_n_on_msis_differs_from_us76_by_what_the_densities_differ() {
    let dir = scratch("msis_paper");
    let us76 = Profile::read(&config_path("atmospheres/us76_1km.txt"));
    let mut largest_change = 0.0f64;
    for season in ["january", "july"] {
        let file = format!("atmospheres/nrlmsis21_buenos_aires_{season}.txt");
        let msis = Profile::read(&config_path(&file));
        for k in 1..=6 {
            let config = config_path(&format!("paper/scenario{k}.toml"));
            let m = shots(&config);
            let base = expect_csv(&dir, &config, &[]);
            let over = format!("atmosphere.molecular.model={{file=\"../{file}\"}}");
            let on_msis = expect_csv(&dir, &config, &[over]);
            assert_eq!(base.len(), on_msis.len());
            for z_km in [10.0, 15.0] {
                let (i, b) = nearest(&base, z_km * 1e3);
                let half = (base[i].altitude_m - base[i + 1].altitude_m).abs() / 2.0;
                let (lo, hi) = (b.altitude_m - half, b.altitude_m + half);
                // The reference's own Eq. 4 reproduces the US76 run's S/N.
                let snr_us = eq4(b.signal, b.background, b.dark, m);
                assert!(
                    (snr_us / b.snr - 1.0).abs() < 1e-9,
                    "{k} {z_km}: {snr_us} {}",
                    b.snr
                );
                let ratio_n = msis.mean_n(lo, hi) / us76.mean_n(lo, hi);
                let sigma_b = b.beta_mol / us76.mean_n(lo, hi);
                let d_column = msis.column_above(b.altitude_m) - us76.column_above(b.altitude_m);
                let beta = b.beta_mol + b.beta_aer + b.beta_cld;
                let signal = b.signal * (b.beta_mol * ratio_n + b.beta_aer + b.beta_cld) / beta
                    * (-2.0 * S_MOL_SR * sigma_b * d_column).exp();
                let predicted = eq4(signal, b.background, b.dark, m);
                let got = on_msis[i].snr;
                assert!(
                    (got / predicted - 1.0).abs() < 5e-4,
                    "{season} scenario {k} at {z_km} km: S/N on MSIS {got}, predicted {predicted} \
                     (US76 {})",
                    b.snr
                );
                largest_change = largest_change.max((got / b.snr - 1.0).abs());
            }
        }
    }
    // The comparison means something: the two atmospheres give visibly different S/N.
    assert!(largest_change > 0.01, "largest S/N change {largest_change}");
}

/// The shipped profiles are NRLMSIS's, not US76 relabelled: the two differ by percents
/// in the troposphere (warmer subtropical summer, colder winter tropopause) and the
/// header names the model and the site.
#[test]
fn the_msis_profiles_are_their_own_atmosphere() {
    let us76 = Profile::read(&config_path("atmospheres/us76_1km.txt"));
    for season in ["january", "july"] {
        let file = config_path(&format!("atmospheres/nrlmsis21_buenos_aires_{season}.txt"));
        let text = std::fs::read_to_string(&file).unwrap();
        assert!(text.contains("NRLMSIS 2.1") && text.contains("Buenos Aires"));
        let msis = Profile::read(&file);
        assert_eq!(msis.z_m.len(), 87);
        let d15 = (msis.n(15e3) / us76.n(15e3) - 1.0).abs();
        assert!(
            d15 > 0.01 && d15 < 0.2,
            "{season}: N at 15 km differs by {d15}"
        );
    }
}

/// The shipped `configs/paper/scenario1_msis.toml` is scenario 1 with the July profile,
/// nothing else changed: its per-bin model equals scenario 1's with the override.
#[test]
fn the_shipped_msis_scenario_is_scenario_1_on_the_july_profile() {
    let dir = scratch("msis_paper_shipped");
    let shipped = expect_csv(&dir, &config_path("paper/scenario1_msis.toml"), &[]);
    let over =
        "atmosphere.molecular.model={file=\"../atmospheres/nrlmsis21_buenos_aires_july.txt\"}";
    let by_hand = expect_csv(
        &dir,
        &config_path("paper/scenario1.toml"),
        &[over.to_string()],
    );
    assert_eq!(shipped.len(), by_hand.len());
    for (a, b) in shipped.iter().zip(&by_hand) {
        assert_eq!((a.signal, a.snr, a.beta_mol), (b.signal, b.snr, b.beta_mol));
    }
}
