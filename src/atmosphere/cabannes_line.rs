//! The Doppler-broadened Cabannes line and the fraction of it a spectral filter passes
//! (model.md §8 "High spectral resolution"; docs/model.md §4i): what an HSRL's
//! molecular channel sees, `f_m(T)`, and what it leaks of the particle line, `f_p`.
//!
//! **Line.** Molecules in thermal motion shift the backscattered light by `2v/λ`; with
//! the Maxwell velocity distribution along the beam (standard deviation `sqrt(kT/m)`)
//! the Cabannes line is a Gaussian in frequency offset ν from the laser line with
//! standard deviation
//!
//! ```text
//! σ_ν(T) = (2/λ)·sqrt(k·T/m)                                              (H1)
//! ```
//!
//! (`m` the mean mass of an air molecule, US76's 28.9644 kg kmol⁻¹ / N_A): 1.10 GHz at
//! 532 nm and 300 K, a half width at half maximum of `σ_ν·sqrt(2 ln 2)` = 1.30 GHz
//! (model.md: ~1.3 GHz); model.md's `(1/λ)·sqrt(8kT/m)` is the 1/e half width,
//! `sqrt(2)·σ_ν`. This is the Doppler (Knudsen) limit: at sea-level pressure collisions
//! narrow the line and add Brillouin side bands (the Tenti S6 model, y ≈ 0.5–0.8 at
//! 355–532 nm near the ground), which change `f_m` of a narrow notch by a few per cent;
//! not modelled here. Particles move too slowly to broaden their line: it is a line at
//! ν = 0.
//!
//! **Filter.** A table of (frequency offset, transmission) points, offsets strictly
//! increasing, transmission linear between points and equal to the end values beyond
//! them (an iodine cell's notch, a Fabry–Pérot's peak). Then, exactly,
//!
//! ```text
//! f_m(T) = ∫ t(ν)·N(ν; 0, σ_ν(T)) dν,    f_p = t(0)                           (H2)
//! ```
//!
//! where on a segment [x₀, x₁] with t = t₀ + s·(ν − x₀), in units of σ (z = ν/σ),
//! `∫ = (t₀ − s·x₀)·[Φ(z₁) − Φ(z₀)] + s·σ·[φ(z₀) − φ(z₁)]`, Φ and φ the standard normal
//! distribution and density (Φ through `erfc`, accurate in the tails). Cost: one erfc and
//! one exp per table point.

use statrs::function::erf::erfc;

use super::us76::M0;
use crate::constants::{AVOGADRO_PER_MOL, BOLTZMANN_J_PER_K};

/// Mean mass of an air molecule, kg.
pub fn air_molecule_mass_kg() -> f64 {
    M0 / AVOGADRO_PER_MOL / 1e3
}

/// Standard deviation of the Doppler-broadened Cabannes line in backscatter at
/// `wavelength_nm` and `temperature_k`, Hz (Eq. H1).
pub fn doppler_sigma_hz(wavelength_nm: f64, temperature_k: f64) -> f64 {
    let v_sigma = (BOLTZMANN_J_PER_K * temperature_k / air_molecule_mass_kg()).sqrt();
    2.0 * v_sigma / (wavelength_nm * 1e-9)
}

/// A filter's transmission against frequency offset from the laser line: points
/// `(offset_hz, transmission)`, offsets strictly increasing, linear between them and
/// constant beyond.
#[derive(Debug, Clone, PartialEq)]
pub struct SpectralFilter {
    points: Vec<(f64, f64)>,
}

impl SpectralFilter {
    /// The filter of `points`; errors (a reason, for the caller to name the key) unless
    /// there is at least one point, every value is finite, offsets strictly increase and
    /// transmissions lie in [0, 1].
    pub fn new(points: Vec<(f64, f64)>) -> Result<SpectralFilter, String> {
        if points.is_empty() {
            return Err("a filter table needs at least one point".into());
        }
        if let Some((f, t)) = points
            .iter()
            .find(|(f, t)| !f.is_finite() || !(0.0..=1.0).contains(t))
        {
            return Err(format!(
                "point ({f}, {t}): offsets must be finite and transmissions within [0, 1]"
            ));
        }
        if let Some(w) = points.windows(2).find(|w| w[1].0 <= w[0].0) {
            return Err(format!(
                "offsets must increase strictly ({} Hz then {} Hz)",
                w[0].0, w[1].0
            ));
        }
        Ok(SpectralFilter { points })
    }

    /// Transmission at offset `offset_hz` (linear between points, constant beyond).
    pub fn transmission(&self, offset_hz: f64) -> f64 {
        let p = &self.points;
        let i = p.partition_point(|&(f, _)| f <= offset_hz);
        if i == 0 {
            return p[0].1;
        }
        if i == p.len() {
            return p[p.len() - 1].1;
        }
        let ((x0, t0), (x1, t1)) = (p[i - 1], p[i]);
        t0 + (t1 - t0) * (offset_hz - x0) / (x1 - x0)
    }

    /// `f_p`: the fraction of the particle line (at zero offset) the filter passes.
    pub fn particle_transmission(&self) -> f64 {
        self.transmission(0.0)
    }

    /// `f_m`: the fraction of a Cabannes line of standard deviation `sigma_hz` the filter
    /// passes (Eq. H2, exact for the piecewise-linear table).
    pub fn molecular_transmission(&self, sigma_hz: f64) -> f64 {
        let p = &self.points;
        let z = |x: f64| x / sigma_hz;
        let (first, last) = (p[0], p[p.len() - 1]);
        let mut sum = first.1 * normal_cdf(z(first.0)) + last.1 * normal_cdf(-z(last.0));
        for w in p.windows(2) {
            let ((x0, t0), (x1, t1)) = (w[0], w[1]);
            let s = (t1 - t0) / (x1 - x0);
            let (z0, z1) = (z(x0), z(x1));
            sum += (t0 - s * x0) * (normal_cdf(z1) - normal_cdf(z0))
                + s * sigma_hz * (normal_pdf(z0) - normal_pdf(z1));
        }
        sum
    }
}

/// Standard normal distribution function Φ(z), through erfc (no cancellation in either
/// tail).
fn normal_cdf(z: f64) -> f64 {
    0.5 * erfc(-z / std::f64::consts::SQRT_2)
}

/// Standard normal density φ(z).
fn normal_pdf(z: f64) -> f64 {
    (-0.5 * z * z).exp() / (2.0 * std::f64::consts::PI).sqrt()
}

#[cfg(test)]
mod tests {
    //! The closed form against a brute-force quadrature of (H2) written here (Simpson on
    //! a fine grid over ±12 σ; its own error at the table's kinks is ~2e-9, a 1 % error in
    //! the closed form 4e-3), and the line's width against model.md's figure.
    use super::*;

    fn quadrature(f: &SpectralFilter, sigma: f64) -> f64 {
        let n = 200_000;
        let (a, b) = (-12.0 * sigma, 12.0 * sigma);
        let h = (b - a) / n as f64;
        let g = |x: f64| {
            f.transmission(x) * (-0.5 * (x / sigma).powi(2)).exp()
                / (sigma * (2.0 * std::f64::consts::PI).sqrt())
        };
        let mut s = g(a) + g(b);
        for i in 1..n {
            s += g(a + i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 };
        }
        s * h / 3.0
    }

    /// An iodine-like notch: 1e-3 at the line's centre within ±0.6 GHz, edges 0.3 GHz wide.
    fn notch() -> SpectralFilter {
        SpectralFilter::new(vec![
            (-0.9e9, 1.0),
            (-0.6e9, 1e-3),
            (0.6e9, 1e-3),
            (0.9e9, 1.0),
        ])
        .unwrap()
    }

    #[test]
    fn the_doppler_width_at_532_nm_is_model_mds() {
        let sigma = doppler_sigma_hz(532.0, 300.0);
        let hwhm = sigma * (2.0 * 2f64.ln()).sqrt();
        assert!((hwhm / 1.30e9 - 1.0).abs() < 0.01, "{hwhm:e}");
        // σ ∝ sqrt(T)/λ
        let ratio = doppler_sigma_hz(355.0, 200.0) / sigma;
        assert!((ratio - (532.0 / 355.0) * (200.0f64 / 300.0).sqrt()).abs() < 1e-12);
    }

    #[test]
    fn a_flat_filter_passes_its_transmission() {
        let f = SpectralFilter::new(vec![(0.0, 0.37)]).unwrap();
        assert!((f.molecular_transmission(1e9) - 0.37).abs() < 1e-15);
        let g = SpectralFilter::new(vec![(-1e9, 0.5), (1e9, 0.5)]).unwrap();
        assert!((g.molecular_transmission(0.8e9) - 0.5).abs() < 1e-15);
    }

    #[test]
    fn the_closed_form_is_the_quadrature() {
        let f = notch();
        for t in [200.0, 250.0, 300.0] {
            let sigma = doppler_sigma_hz(532.0, t);
            let (exact, quad) = (f.molecular_transmission(sigma), quadrature(&f, sigma));
            assert!((exact - quad).abs() < 1e-8, "{t} K: {exact} against {quad}");
        }
        // an asymmetric Fabry-Pérot-like peak off centre
        let fp = SpectralFilter::new(vec![(-2e9, 0.0), (0.5e9, 0.8), (1.5e9, 0.1)]).unwrap();
        let sigma = doppler_sigma_hz(355.0, 240.0);
        let (exact, quad) = (fp.molecular_transmission(sigma), quadrature(&fp, sigma));
        assert!((exact - quad).abs() < 1e-8, "{exact} against {quad}");
    }

    #[test]
    fn a_notch_passes_more_of_a_warmer_line_and_leaks_its_centre() {
        let f = notch();
        let cold = f.molecular_transmission(doppler_sigma_hz(532.0, 200.0));
        let warm = f.molecular_transmission(doppler_sigma_hz(532.0, 300.0));
        assert!(warm > cold && cold > 0.0 && warm < 1.0, "{cold} {warm}");
        assert_eq!(f.particle_transmission(), 1e-3);
    }

    #[test]
    fn bad_tables_are_refused() {
        assert!(SpectralFilter::new(vec![]).is_err());
        assert!(SpectralFilter::new(vec![(0.0, 1.2)]).is_err());
        assert!(SpectralFilter::new(vec![(0.0, f64::NAN)]).is_err());
        assert!(SpectralFilter::new(vec![(1.0, 0.5), (1.0, 0.6)]).is_err());
        assert!(SpectralFilter::new(vec![(f64::INFINITY, 0.5)]).is_err());
    }
}
