//! The pure rotational Raman (RR) lines of N₂ and O₂ around the laser line, and what a
//! receiver filter passes of the molecular return: the Cabannes line plus the RR lines
//! inside the filter (docs/model.md §4a, `atmosphere.molecular.line = "filter"`).
//!
//! **Lines** (Behrendt & Nakamura 2002, Opt. Express 10, 805, their Eqs. 1–9 and
//! Table 1; after Penney, St. Peters & Lapp 1974, J. Opt. Soc. Am. 64, 712). A linear
//! molecule in rotational level J has the energy
//!
//! ```text
//! E(J) = h·c·[B₀·J(J+1) − D₀·J²(J+1)²]                                      (R1)
//! ```
//!
//! and scatters into the Stokes line J → J+2 (shift −[E(J+2) − E(J)]/(hc)) and, for
//! J ≥ 2, the anti-Stokes line J → J−2 (shift +[E(J) − E(J−2)]/(hc)). The line's
//! backscatter is proportional to
//!
//! ```text
//! x_s·γ_s²·p_J(T)·b_J·(ν_line/ν₀)⁴,   p_J = g_J·(2J+1)·exp(−E(J)/kT) / Q(T)      (R2)
//! ```
//!
//! with the species' abundance `x_s`, polarizability anisotropy `γ_s²`, the nuclear-spin
//! statistical weight `g_J`, `Q = Σ_J g_J(2J+1)exp(−E(J)/kT)` summed exactly, and the
//! Placzek–Teller coefficients
//!
//! ```text
//! b(J→J+2) = 3(J+1)(J+2) / [2(2J+1)(2J+3)],   b(J→J−2) = 3J(J−1) / [2(2J+1)(2J−1)]   (R3)
//! ```
//!
//! (B&N's `X(J)` are `(2/3)(2J+1)·b`; their `(2I+1)²kT/(2hcB)` is the high-temperature
//! value of Q, 0.3–0.4 % below the exact sum used here at 288 K: it moves the passed share
//! F through 1 nm at 532 nm by 9e-5, `tests/molecular_line.rs`). The third branch,
//! J → J (b = J(J+1)/[(2J−1)(2J+3)], ≈ 1/4), lies on the laser line and belongs to the
//! Cabannes line. Every RR line has the backscatter depolarization 3/4.
//!
//! **Shares.** The whole line's RR part, `1 − rayleigh::cabannes_fraction(ρn)`, stays the
//! single source of the RR strength (from Bucholtz's ρn of air); the lines split it:
//! the channel sees `f_C + (1 − f_C)·F`, `F = Σ t(Δλ)·s / Σ s` over the lines of (R2),
//! `t` the filter's transmission at the line's offset Δλ from the laser line.
//! Consistency: the lines' own sum, `(7ε/(45+7ε))·Σ_s w_s Σ_J p_J (b_S(ν_S/ν₀)⁴ +
//! b_AS(ν_AS/ν₀)⁴)` (`w_s = x_sγ_s²/Σx γ²`), is 3.1e-4 of the whole line below
//! `1 − f_C` at 532 nm and 288 K ([`unnormalized_rr_share`]; the exact Q branch holds
//! slightly more than 1/4 of the anisotropic part, and the ν⁴ of the Stokes lines is
//! smaller).
//!
//! Not modelled: CO₂ (0.04 % of air; its lines crowd the laser line, B₀ = 0.39 cm⁻¹, and
//! carry ~0.2 % of air's RR: through 1 nm at 532 nm F would rise by ~2 %, the
//! depolarization by ~0.3 %); Ar has no RR; the weak O₂ fine-structure lines (³Σ
//! ground state) within ~2 cm⁻¹ of the laser line; the dispersion of γ² (Penney's values
//! are at 488 nm; only the N₂/O₂ ratio enters).

use crate::constants::{BOLTZMANN_J_PER_K, PLANCK_J_S, SPEED_OF_LIGHT_M_PER_S};

/// A linear molecule's rotational constants and weights (Behrendt & Nakamura 2002,
/// Table 1).
#[derive(Debug, Clone, Copy)]
pub struct Species {
    /// Chemical name.
    pub name: &'static str,
    /// Rotational constant B₀, cm⁻¹.
    pub b0_per_cm: f64,
    /// Centrifugal distortion constant D₀, cm⁻¹.
    pub d0_per_cm: f64,
    /// Nuclear-spin statistical weight g_J of even and of odd J.
    pub spin_weight_even_odd: [f64; 2],
    /// Relative volume abundance in dry air.
    pub abundance: f64,
    /// Anisotropy of the polarizability γ², 10⁻⁴⁸ cm⁶.
    pub gamma_squared: f64,
}

/// ¹⁴N₂: I = 1, g = 6 (even J), 3 (odd J).
pub const N2: Species = Species {
    name: "N2",
    b0_per_cm: 1.989_57,
    d0_per_cm: 5.76e-6,
    spin_weight_even_odd: [6.0, 3.0],
    abundance: 0.7808,
    gamma_squared: 0.51,
};

/// ¹⁶O₂: I = 0, only odd J populated.
pub const O2: Species = Species {
    name: "O2",
    b0_per_cm: 1.437_68,
    d0_per_cm: 4.85e-6,
    spin_weight_even_odd: [0.0, 1.0],
    abundance: 0.2095,
    gamma_squared: 1.27,
};

/// The species whose lines are modelled.
pub const SPECIES: [Species; 2] = [N2, O2];

/// Highest initial J summed (its population is below 1e-20 of the total at 400 K).
const J_MAX: u32 = 100;

/// The temperature at which a channel's line shares are evaluated, K: fixed, the
/// standard air of Bucholtz's ρn (docs/model.md §4a states the error over the
/// troposphere).
pub const REFERENCE_TEMPERATURE_K: f64 = 288.15;

/// One rotational Raman line.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Line {
    /// The scattering species' name.
    pub species: &'static str,
    /// Initial rotational level.
    pub j: u32,
    /// Shift from the laser line, cm⁻¹: negative for Stokes (J → J+2), positive for
    /// anti-Stokes (J → J−2).
    pub shift_per_cm: f64,
    /// Relative backscatter (R2), `w_s·p_J·b_J·(ν_line/ν₀)⁴`: the lines of all species
    /// sum to ≈ 3/4 (the anisotropic part outside the J → J branch).
    pub strength: f64,
}

impl Line {
    /// The line's offset from the laser line in wavelength, nm (positive to the red).
    pub fn offset_nm(&self, wavelength_nm: f64) -> f64 {
        1e7 / (1e7 / wavelength_nm + self.shift_per_cm) - wavelength_nm
    }
}

/// Rotational term E(J)/(hc), cm⁻¹ (R1).
fn term_per_cm(s: &Species, j: u32) -> f64 {
    let jj = f64::from(j) * f64::from(j + 1);
    s.b0_per_cm * jj - s.d0_per_cm * jj * jj
}

/// The RR lines of N₂ and O₂ at `wavelength_nm` and `temperature_k` (R1–R3).
pub fn lines(wavelength_nm: f64, temperature_k: f64) -> Vec<Line> {
    let nu0 = 1e7 / wavelength_nm;
    // hc/k in cm·K
    let c2 = PLANCK_J_S * SPEED_OF_LIGHT_M_PER_S * 100.0 / BOLTZMANN_J_PER_K;
    let total_gamma2: f64 = SPECIES.iter().map(|s| s.abundance * s.gamma_squared).sum();
    let mut out = Vec::new();
    for s in &SPECIES {
        let weight = |j: u32| {
            s.spin_weight_even_odd[(j % 2) as usize]
                * f64::from(2 * j + 1)
                * (-c2 * term_per_cm(s, j) / temperature_k).exp()
        };
        let q: f64 = (0..=J_MAX).map(weight).sum();
        let w_s = s.abundance * s.gamma_squared / total_gamma2;
        for j in 0..=J_MAX {
            let p = weight(j) / q;
            if p == 0.0 {
                continue;
            }
            let jf = f64::from(j);
            let mut push = |shift: f64, b: f64| {
                let nu4 = ((nu0 + shift) / nu0).powi(4);
                out.push(Line {
                    species: s.name,
                    j,
                    shift_per_cm: shift,
                    strength: w_s * p * b * nu4,
                })
            };
            let b_stokes =
                3.0 * (jf + 1.0) * (jf + 2.0) / (2.0 * (2.0 * jf + 1.0) * (2.0 * jf + 3.0));
            push(-(term_per_cm(s, j + 2) - term_per_cm(s, j)), b_stokes);
            if j >= 2 {
                let b_anti = 3.0 * jf * (jf - 1.0) / (2.0 * (2.0 * jf + 1.0) * (2.0 * jf - 1.0));
                push(term_per_cm(s, j) - term_per_cm(s, j - 2), b_anti);
            }
        }
    }
    out
}

/// A top-hat filter of full width `width_nm` centred on the laser line, transmission 1
/// inside (the peak `filter_transmission` multiplies every line alike): the filter the
/// sky background already assumes (`N_bkg ∝ Δλ·T_F`, paper Eq. 3).
pub fn top_hat(width_nm: f64) -> impl Fn(f64) -> f64 {
    move |offset_nm: f64| {
        if offset_nm.abs() <= 0.5 * width_nm {
            1.0
        } else {
            0.0
        }
    }
}

/// `F`: the share of the RR lines' backscatter a filter of transmission `t(offset_nm)`
/// passes.
pub fn passed_rr_share(wavelength_nm: f64, temperature_k: f64, t: impl Fn(f64) -> f64) -> f64 {
    let l = lines(wavelength_nm, temperature_k);
    let total: f64 = l.iter().map(|x| x.strength).sum();
    let passed: f64 = l
        .iter()
        .map(|x| x.strength * t(x.offset_nm(wavelength_nm)))
        .sum();
    passed / total
}

/// The lines' own RR share of the whole line's backscatter, `(7ε/(45+7ε))·Σ strength`,
/// to set against `1 − rayleigh::cabannes_fraction(ρn)` (the consistency check).
pub fn unnormalized_rr_share(rho_n: f64, wavelength_nm: f64, temperature_k: f64) -> f64 {
    let e = super::rayleigh::anisotropy(rho_n);
    let sum: f64 = lines(wavelength_nm, temperature_k)
        .iter()
        .map(|x| x.strength)
        .sum();
    7.0 * e / (45.0 + 7.0 * e) * sum
}

/// What a channel sees of the elastic molecular line.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SeenLine {
    /// Share of the whole line's backscatter: `f_C + (1 − f_C)·F`.
    pub share: f64,
    /// Linear depolarization ratio of that backscatter.
    pub depolarization: f64,
    /// `F`, the share of the RR lines passed (0: the Cabannes line alone, 1: the whole
    /// line).
    pub rr_passed: f64,
}

/// Below this `F` the filter passes the Cabannes line alone, above `1 −` it the whole
/// line (the lines left out carry less than 3e-8 of the backscatter): the limits are
/// then the Cabannes and the whole line's values exactly.
const NEGLIGIBLE_RR: f64 = 1e-6;

/// The molecular line through a filter that passes the share `rr_passed` (F) of the RR
/// lines: the Cabannes line (`rayleigh::cabannes_fraction`, `cabannes_depolarization`)
/// plus F of the RR part, whose depolarization is 3/4 (a perpendicular share 3/7).
pub fn seen_line(rho_n: f64, rr_passed: f64) -> SeenLine {
    use super::rayleigh::{cabannes_depolarization, cabannes_fraction, gamma};
    let f_c = cabannes_fraction(rho_n);
    if rr_passed < NEGLIGIBLE_RR {
        let depolarization = cabannes_depolarization(rho_n);
        return SeenLine {
            share: f_c,
            depolarization,
            rr_passed: 0.0,
        };
    }
    if rr_passed > 1.0 - NEGLIGIBLE_RR {
        return SeenLine {
            share: 1.0,
            depolarization: gamma(rho_n),
            rr_passed: 1.0,
        };
    }
    let d_c = cabannes_depolarization(rho_n);
    let rr = (1.0 - f_c) * rr_passed;
    let share = f_c + rr;
    let perpendicular = f_c * d_c / (1.0 + d_c) + rr * 3.0 / 7.0;
    SeenLine {
        share,
        depolarization: perpendicular / (share - perpendicular),
        rr_passed,
    }
}

/// The molecular line through a top-hat filter of full width `width_nm` at
/// `wavelength_nm`, the lines' shares at [`REFERENCE_TEMPERATURE_K`].
pub fn through_top_hat(rho_n: f64, wavelength_nm: f64, width_nm: f64) -> SeenLine {
    let f = passed_rr_share(wavelength_nm, REFERENCE_TEMPERATURE_K, top_hat(width_nm));
    seen_line(rho_n, f)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::atmosphere::rayleigh::{cabannes_fraction, depolarization_rho_n, gamma};

    #[test]
    fn the_nearest_lines_are_n2s_at_0_338_nm_and_o2s_at_0_407_nm() {
        let l = lines(532.0, 288.15);
        let nearest = |name: &str| {
            l.iter()
                .filter(|x| x.species == name)
                .map(|x| x.offset_nm(532.0).abs())
                .fold(f64::INFINITY, f64::min)
        };
        // N2 J=0→2: 6B = 11.94 cm⁻¹; O2 N=1→3 (even N absent): 10B = 14.38 cm⁻¹
        assert!((nearest("N2") - 0.3375).abs() < 5e-4, "{}", nearest("N2"));
        assert!((nearest("O2") - 0.4069).abs() < 5e-4, "{}", nearest("O2"));
    }

    #[test]
    fn the_lines_sum_to_the_whole_lines_rr_part_within_1e_3() {
        for wl in [354.7, 532.0, 1064.0] {
            let rho = depolarization_rho_n(wl);
            for t in [200.0, 288.15, 300.0] {
                let lines = unnormalized_rr_share(rho, wl, t);
                let whole = 1.0 - cabannes_fraction(rho);
                assert!(
                    (lines - whole).abs() < 1e-3,
                    "{wl} nm {t} K: {lines} vs {whole}"
                );
            }
        }
        let rho = depolarization_rho_n(532.0);
        let d = unnormalized_rr_share(rho, 532.0, 288.15) - (1.0 - cabannes_fraction(rho));
        assert!((d + 3.1e-4).abs() < 0.3e-4, "{d}");
    }

    #[test]
    fn the_limits_are_the_cabannes_and_the_whole_line() {
        let rho = depolarization_rho_n(532.0);
        let narrow = through_top_hat(rho, 532.0, 0.037);
        assert_eq!(narrow.share, cabannes_fraction(rho));
        assert_eq!(narrow.rr_passed, 0.0);
        let wide = through_top_hat(rho, 532.0, 20.0);
        assert_eq!((wide.share, wide.depolarization), (1.0, gamma(rho)));
        // continuity of the formula at either end
        let near0 = seen_line(rho, 2e-6);
        assert!((near0.depolarization - narrow.depolarization).abs() < 1e-7);
        let near1 = seen_line(rho, 1.0 - 2e-6);
        assert!((near1.depolarization - gamma(rho)).abs() < 1e-7);
        assert!((near1.share - 1.0).abs() < 1e-7);
    }

    #[test]
    fn a_1_nm_filter_at_532_nm_passes_the_four_nearest_lines() {
        let l = lines(532.0, 288.15);
        let passed: Vec<_> = l
            .iter()
            .filter(|x| x.offset_nm(532.0).abs() <= 0.5)
            .collect();
        assert_eq!(passed.len(), 4, "{passed:?}");
        let rho = depolarization_rho_n(532.0);
        let s = through_top_hat(rho, 532.0, 1.0);
        // ARC: 0.0041 through a 1 nm filter
        assert!((s.depolarization / 0.0041 - 1.0).abs() < 0.03, "{s:?}");
    }

    #[test]
    fn colder_air_concentrates_the_lines_near_the_laser_line() {
        let t = top_hat(1.0);
        let warm = passed_rr_share(532.0, 300.0, &t);
        let cold = passed_rr_share(532.0, 200.0, &t);
        assert!(cold > warm && warm > 0.0, "{cold} {warm}");
    }
}
