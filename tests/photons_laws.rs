//! The laws of the photon file's events (issue 42, docs/photons.md), against references
//! written here, not taken from the code under test:
//!
//! * inside the bin that holds the surface, the echo's events follow the laser pulse's
//!   Gaussian (FWHM `instrument.pulse_fwhm_s`, on the range axis c·t/2) centred on the
//!   surface range, truncated to the bin: Kolmogorov–Smirnov at false-alarm rate
//!   α = 1e-3 (asymptotic critical value √(ln(2/α)/2)/√n = 1.9495/√n; fixed seed), and
//!   the same events reject uniform placement;
//! * a 16-pixel detector at 100 MHz total records 16 × one pixel's renewal rate at
//!   λ/16, `(λ/16)/(1 + (λ/16)·τ)` (non-paralyzable, Müller 1973), within 0.5 %, and
//!   each pixel's events its 16th of it within 2 % (the run's statistical error: ~4e-4
//!   of the sum, ~1.6e-3 of a pixel: 10σ at least, no false alarm);
//! * the origins: among the sky-background and dark events, the dark ones are
//!   Binomial(N, d/(d + b)) with d, b the raw file's `expected_dark` and
//!   `expected_background` (dead time is blind to the origin): |z| < 3.29, α = 1e-3
//!   (fixed seed); a dark share 1 % off moves z by ~7.

mod common;

use common::cli::{scratch, simulate_with_photons};

const C: f64 = 299_792_458.0;
/// KS critical value × √n at α = 1e-3.
const KS_1E3: f64 = 1.9495;

fn ints<T: hdf5::H5Type + Copy>(f: &hdf5::File, name: &str) -> Vec<T> {
    f.dataset(name).unwrap().read_raw::<T>().unwrap()
}

fn ks(sorted: &[f64], cdf: impl Fn(f64) -> f64) -> f64 {
    let n = sorted.len() as f64;
    sorted
        .iter()
        .enumerate()
        .map(|(i, &x)| {
            let f = cdf(x);
            (f - i as f64 / n).abs().max(((i + 1) as f64 / n - f).abs())
        })
        .fold(0.0, f64::max)
}

/// erf from the complementary error function's Chebyshev fit (Press et al.,
/// *Numerical Recipes*, `erfcc`: fractional error below 1.2e-7, far below a KS
/// distance of 1e-3).
fn erf(x: f64) -> f64 {
    let z = x.abs();
    let t = 1.0 / (1.0 + 0.5 * z);
    let r = t
        * (-z * z - 1.265_512_23
            + t * (1.000_023_68
                + t * (0.374_091_96
                    + t * (0.096_784_18
                        + t * (-0.186_288_06
                            + t * (0.278_868_07
                                + t * (-1.135_203_98
                                    + t * (1.488_515_87
                                        + t * (-0.822_152_23 + t * 0.170_872_77)))))))))
            .exp();
    if x >= 0.0 { 1.0 - r } else { r - 1.0 }
}

#[test]
fn surface_echo_events_follow_the_pulse_inside_the_bin() {
    let dir = scratch("ph-ks");
    simulate_with_photons(&dir, "instruments/icesat2_like.toml", "20", &[]);
    let f = hdf5::File::open(dir.join("ph.h5")).unwrap();
    let starts: Vec<f64> = ints(&f, "bins/range_start");
    let dr: f64 = f.attr("bin_range_m").unwrap().read_scalar().unwrap();
    let range: Vec<f64> = ints(&f, "heights/range");
    let origin: Vec<u8> = ints(&f, "heights/truth_origin");
    // the preset: 496 km at nadir, the snow at 2 km, a 1.5 ns pulse
    let r_s = 496e3 - 2e3;
    let sigma_m = 1.5e-9 / (8.0 * 2f64.ln()).sqrt() * C / 2.0;
    let b = starts.iter().rposition(|&s| s <= r_s).unwrap();
    let ra = starts[b];
    let mut x: Vec<f64> = range
        .iter()
        .zip(&origin)
        .filter(|(_, o)| **o == 4)
        .map(|(r, _)| {
            assert!(
                *r >= ra && *r < ra + dr,
                "a surface event at {r} m, outside its bin"
            );
            (r - ra) / dr
        })
        .collect();
    x.sort_by(f64::total_cmp);
    let n = x.len();
    assert!(n > 2000, "too few surface events ({n})");
    let (mu, s) = ((r_s - ra) / dr, sigma_m / dr);
    let phi = |u: f64| 0.5 * (1.0 + erf((u - mu) / (s * 2f64.sqrt())));
    let (lo, hi) = (phi(0.0), phi(1.0));
    let model = |u: f64| ((phi(u) - lo) / (hi - lo)).clamp(0.0, 1.0);
    let crit = KS_1E3 / (n as f64).sqrt();
    let d = ks(&x, model);
    assert!(d < crit, "KS {d} ≥ {crit} (n = {n}): not the pulse's shape");
    let d_uniform = ks(&x, |u| u.clamp(0.0, 1.0));
    assert!(
        d_uniform > crit,
        "uniform placement not rejected: {d_uniform} < {crit}"
    );
    eprintln!(
        "surface events {n}: KS {d:.4} vs pulse, {d_uniform:.4} vs uniform, critical {crit:.4}"
    );
}

const TAU_S: f64 = 3.2e-9;
const BIN_S: f64 = 2e-8;
const TOTAL_HZ: f64 = 1e8;
/// Bins skipped at the window's start (the detector starts live: a transient of a few τ).
const SKIP: u32 = 10;

#[test]
fn per_pixel_dead_time_of_the_events() {
    let dir = scratch("ph-pixels");
    let sets = [
        format!("instrument.dark_count_rate_hz={TOTAL_HZ}"),
        "instrument.pulse_energy_j=1e-12".to_string(),
        "background.radiance=0".to_string(),
        "instrument.detector.pixels=16".to_string(),
    ];
    let more: Vec<&str> = sets.iter().flat_map(|s| ["--set", s.as_ref()]).collect();
    simulate_with_photons(&dir, "instruments/icesat2_like.toml", "2", &more);
    let f = hdf5::File::open(dir.join("ph.h5")).unwrap();
    let bins = ints::<f64>(&f, "bins/range_start").len() as u32;
    let shots: u64 = f.attr("shots_per_profile").unwrap().read_scalar().unwrap();
    let profiles: u64 = f.attr("profiles").unwrap().read_scalar().unwrap();
    let bin: Vec<u32> = ints(&f, "heights/ph_id_bin");
    let pixel: Vec<u16> = ints(&f, "heights/ph_id_pixel");
    let mut per_pixel = [0u64; 16];
    for (b, p) in bin.iter().zip(&pixel) {
        if *b >= SKIP {
            per_pixel[*p as usize] += 1;
        }
    }
    let time_s = (shots * profiles) as f64 * f64::from(bins - SKIP) * BIN_S;
    let n = TOTAL_HZ / 16.0;
    let one = n / (1.0 + n * TAU_S);
    let total = per_pixel.iter().sum::<u64>() as f64 / time_s;
    let rel = total / (16.0 * one) - 1.0;
    assert!(
        rel.abs() < 5e-3,
        "16 pixels record {total:.5e} Hz, 16 × renewal {:.5e} ({rel:+.2e})",
        16.0 * one
    );
    for (p, &k) in per_pixel.iter().enumerate() {
        let r = k as f64 / time_s / one - 1.0;
        assert!(r.abs() < 2e-2, "pixel {p}: {r:+.2e} from the renewal rate");
    }
}

#[test]
fn dark_and_background_events_in_their_shares() {
    let dir = scratch("ph-shares");
    let sets = [
        "background.radiance=7e17",
        "instrument.dark_count_rate_hz=3.3e6",
    ];
    let more: Vec<&str> = sets.iter().flat_map(|s| ["--set", *s]).collect();
    simulate_with_photons(&dir, "instruments/icesat2_like.toml", "10", &more);
    let raw = hdf5::File::open(dir.join("raw.h5")).unwrap();
    let d = common::h5::floats(&raw, "expected_dark")[0];
    let b = common::h5::floats(&raw, "expected_background")[0];
    let f = hdf5::File::open(dir.join("ph.h5")).unwrap();
    let origin: Vec<u8> = ints(&f, "heights/truth_origin");
    let dark = origin.iter().filter(|&&o| o == 6).count() as f64;
    let sky = origin.iter().filter(|&&o| o == 5).count() as f64;
    let n = dark + sky;
    let p = d / (d + b);
    let z = (dark - n * p) / (n * p * (1.0 - p)).sqrt();
    eprintln!("dark {dark}, sky {sky}, expected share {p:.5}, z = {z:.2}");
    assert!(n > 1e6, "too few events ({n})");
    assert!(
        z.abs() < 3.29,
        "dark events {dark} of {n}: z = {z:.2} from the share {p}"
    );
}
