//! Multiple scattering that depends on the cloud and the field of view (docs/model.md
//! §4j): the quasi-small-angle (QSA) return of Hogan's photon variance–covariance (PVC)
//! method, O(N) along the beam.
//!
//! **Physics.** Particles much larger than the wavelength put about half their
//! extinction into a narrow forward diffraction lobe of 1/e half-width
//! `Θ = λ/(π·r_e)` (Hogan 2008, J. Atmos. Sci. 65, 3621, §2). Photons scattered into it
//! stay near the beam and, when they are backscattered inside the receiver's field of
//! view, add to the return: the apparent backscatter exceeds the single-scattering one.
//! The `constant` model folds this into a fixed factor η on each layer's optical depth;
//! here it follows from the particles' size, the beam divergence, the field of view and
//! the range.
//!
//! **Algorithm (Hogan 2008, §3–4, the fast two-Gaussian form).** The photons that have
//! not left the forward beam are described by their energy and the second moments of
//! their lateral position and direction, `⟨x²⟩`, `⟨xθ⟩` and `⟨θ²⟩` (1/e radii squared,
//! as the beam's `r²ρ_t²`). Across a step Δ of constant particle extinction α and lobe
//! width Θ the moment equations `d⟨x²⟩/dr = 2⟨xθ⟩`, `d⟨xθ⟩/dr = ⟨θ²⟩`,
//! `d⟨θ²⟩/dr = αΘ²` (the lobe's photons on the way out and back) integrate exactly:
//!
//! ```text
//! ⟨θ²⟩ += αΘ²Δ,  ⟨xθ⟩ += ⟨θ²⟩Δ + αΘ²Δ²/2,  ⟨x²⟩ += 2⟨xθ⟩Δ + ⟨θ²⟩Δ² + αΘ²Δ³/3
//! ```
//!
//! (with the old values on the right). The population loses energy as `e^{−(α+2α_air)Δ}`
//! on the round trip (the lobe's half of the extinction keeps its photons), the
//! unscattered beam as `e^{−2(α+α_air)Δ}`. Photons scattered few times stay within the
//! field of view while those scattered many times spread beyond it, so one Gaussian
//! would misplace both: a second, "reduced" population is stepped alike but, whenever
//! its scattered part grows wider than the field of view, cut back to it (energy and
//! covariance by `W/⟨x²⟩`, the direction variance in proportion to its correlation with
//! the position). The scattered photons are then two Gaussians: the reduced population's
//! (narrow) and the rest (wide). The enhancement `M(r)` is the energy of both inside a
//! top-hat field of view of half-angle ρ_r (radius² `W = r²ρ_r²`: a fraction
//! `1 − e^{−W/⟨x²⟩}` of each) over that of the unscattered beam's (`1 − e^{−ρ_r²/ρ_t²}`).
//! Within a step `1 + M` is taken to vary exponentially; the apparent attenuated
//! backscatter is `β·T²·(1 + M)` averaged over the step.
//!
//! **Not modelled.** The anisotropic phase function near 180° (Hogan's droplet and
//! pristine-ice factor), the wide-angle diffuse return (Hogan & Battaglia 2008;
//! `small_and_wide_angle`, refused for now), the pulse's stretching in time, and Raman
//! channels (refused).
//!
//! **Cost.** One pass over the beam's steps, about 40 operations, an `exp` and a `ln`
//! each (`benches/multiple_scattering.rs`).
//!
//! The same small-angle physics is also published as C code (Hogan's `multiscatter`
//! package, LGPL); `validation/reports/multiple_scattering.md` compares with its
//! results on its own example inputs.

use crate::config::{
    Checker, CloudPhase, LayerConfig, LayerKind, MultipleScatteringModel, ScenarioConfig,
};
use crate::error::Result;

/// Effective radius of cloud droplets when a layer gives none, µm.
pub const DEFAULT_DROPLET_RADIUS_UM: f64 = 10.0;
/// Effective radius of ice crystals when a layer gives none, µm.
pub const DEFAULT_ICE_RADIUS_UM: f64 = 30.0;
/// Effective radius of aerosol particles when a layer or the background aerosol gives
/// none, µm.
pub const DEFAULT_AEROSOL_RADIUS_UM: f64 = 0.5;
/// A cloud without `phase` is ice from this particle depolarization up (spherical
/// droplets depolarize nothing when singly scattered; ice crystals 0.2–0.5).
pub const ICE_DEPOLARIZATION: f64 = 0.1;

/// The default of `multiple_scattering.wide_angle_cutoff_rad`, rad: particles with a
/// wider forward lobe (effective radius below `λ/(0.1π)`, 1.7 µm at 532 nm: the
/// background aerosol) scatter out of any lidar's field of view and outside the
/// small-angle approximation; their extinction only attenuates, as the air's does.
/// Hogan suggests the same cutoff for aerosol (`multiscatter -wide-angle-cutoff 0.1`).
pub const DEFAULT_WIDE_ANGLE_CUTOFF_RAD: f64 = 0.1;

/// Steps no thicker than this two-way optical depth: `1 + M` is taken exponential within
/// a step: the bins' ratios move by at most 1.5e-3 against steps 25 times thinner
/// (`validation/reports/multiple_scattering.md`).
const MAX_STEP_OPTICAL_DEPTH: f64 = 0.05;

/// A layer's phase: as given, or from its depolarization.
pub fn phase(l: &LayerConfig) -> CloudPhase {
    l.phase
        .unwrap_or(if l.depolarization >= ICE_DEPOLARIZATION {
            CloudPhase::Ice
        } else {
            CloudPhase::Water
        })
}

/// A layer's effective radius, µm: as given, or the default of its kind and phase.
pub fn effective_radius_um(l: &LayerConfig) -> f64 {
    l.effective_radius_um.unwrap_or(match (l.kind, phase(l)) {
        (LayerKind::Aerosol, _) => DEFAULT_AEROSOL_RADIUS_UM,
        (LayerKind::Cloud, CloudPhase::Water) => DEFAULT_DROPLET_RADIUS_UM,
        (LayerKind::Cloud, CloudPhase::Ice) => DEFAULT_ICE_RADIUS_UM,
    })
}

/// Asymmetry factor of cloud droplets when a layer gives none (HB08; Mie, 10 µm, 532 nm).
pub const DEFAULT_DROPLET_ASYMMETRY: f64 = 0.85;
/// Asymmetry factor of ice crystals when a layer gives none (HB08).
pub const DEFAULT_ICE_ASYMMETRY: f64 = 0.75;
/// Asymmetry factor of aerosol particles (the background aerosol, and layers that give
/// none).
pub const DEFAULT_AEROSOL_ASYMMETRY: f64 = 0.7;

/// A layer's asymmetry factor g (wide-angle scattering): `asymmetry_factor`, or the
/// default of its kind and phase.
pub fn asymmetry_factor(l: &LayerConfig) -> f64 {
    l.asymmetry_factor.unwrap_or(match (l.kind, phase(l)) {
        (LayerKind::Aerosol, _) => DEFAULT_AEROSOL_ASYMMETRY,
        (LayerKind::Cloud, CloudPhase::Water) => DEFAULT_DROPLET_ASYMMETRY,
        (LayerKind::Cloud, CloudPhase::Ice) => DEFAULT_ICE_ASYMMETRY,
    })
}

/// The 1/e half-width of the forward diffraction lobe, `Θ = λ/(π·r_e)`, rad (Hogan
/// 2008, §2).
pub fn forward_lobe_half_width_rad(wavelength_nm: f64, effective_radius_um: f64) -> f64 {
    wavelength_nm * 1e-9 / (std::f64::consts::PI * effective_radius_um * 1e-6)
}

/// Checks `[multiple_scattering]`, `instrument.beam_divergence_rad` and every layer's
/// particle keys.
pub fn validate(config: &ScenarioConfig, c: &Checker) -> Result<()> {
    if let Some(d) = config.instrument.beam_divergence_rad {
        c.positive("instrument.beam_divergence_rad", d, 0.1)?;
    }
    if let Some(r) = config
        .atmosphere
        .aerosol
        .as_ref()
        .and_then(|a| a.effective_radius_um)
    {
        c.range("atmosphere.aerosol.effective_radius_um", r, 0.01, 1e4)?;
    }
    let segments = config
        .scene
        .iter()
        .flat_map(|s| s.segments.iter().enumerate());
    let segment_layers = segments.flat_map(|(i, seg)| {
        seg.layers
            .iter()
            .flatten()
            .enumerate()
            .map(move |(n, l)| (format!("scene.segments[{i}].layers[{n}]."), l))
    });
    let top_layers = config
        .atmosphere
        .layers
        .iter()
        .enumerate()
        .map(|(n, l)| (format!("atmosphere.layers[{n}]."), l));
    for (key, l) in top_layers.chain(segment_layers) {
        validate_layer(c, &key, l)?;
    }
    if let Some(cut) = config.multiple_scattering.wide_angle_cutoff_rad {
        c.positive("multiple_scattering.wide_angle_cutoff_rad", cut, 1.0)?;
    }
    let model = match config.multiple_scattering.model {
        MultipleScatteringModel::Constant => return Ok(()),
        MultipleScatteringModel::SmallAngle => "small_angle",
        MultipleScatteringModel::SmallAndWideAngle => "small_and_wide_angle",
    };
    if config.instrument.beam_divergence_rad.is_none() {
        return Err(c.fail(
            "instrument.beam_divergence_rad",
            format!(
                "is needed by multiple_scattering.model = \"{model}\": the laser beam's 1/e \
                 half-width, rad (e.g. 5e-5 for CALIOP's 100 µrad full beam)"
            ),
        ));
    }
    Ok(())
}

fn validate_layer(c: &Checker, key: &str, l: &LayerConfig) -> Result<()> {
    if let Some(r) = l.effective_radius_um {
        c.range(&format!("{key}effective_radius_um"), r, 0.01, 1e4)?;
    }
    if let Some(g) = l.asymmetry_factor {
        c.range(&format!("{key}asymmetry_factor"), g, 0.0, 0.99)?;
    }
    if l.phase.is_some() && l.kind != LayerKind::Cloud {
        return Err(c.fail(
            &format!("{key}phase"),
            "is a cloud's (water or ice); an aerosol layer has none",
        ));
    }
    Ok(())
}

/// The transmitter and receiver the forward-scattered photons are seen through.
#[derive(Debug, Clone, Copy)]
pub struct Footprint {
    /// The beam's 1/e angular half-width ρ_t, rad.
    pub divergence_rad: f64,
    /// The top-hat field of view's half-angle ρ_r, rad.
    pub fov_half_angle_rad: f64,
}

/// One step along the beam, of constant optics, for [`small_angle_ratios`].
#[derive(Debug, Clone, Copy, Default)]
pub struct Step {
    /// Length, m.
    pub width_m: f64,
    /// Extinction α of the particles in the model (a narrow forward lobe), m⁻¹.
    pub alpha_particle_per_m: f64,
    /// `Σ α_k Θ_k²` over the particle species, m⁻¹ rad².
    pub alpha_theta2_per_m: f64,
    /// The rest of the extinction (molecules, absorbing gases, particles with a wide
    /// lobe), m⁻¹.
    pub alpha_air_per_m: f64,
}

/// The photons of one population: energy relative to the unscattered beam's and the
/// second moments of position and direction.
#[derive(Debug, Clone, Copy)]
struct Population {
    energy: f64,
    width2: f64,
    cov: f64,
    zeta2: f64,
}

impl Population {
    /// The unscattered beam of 1/e angular half-width² `rho_t2` at range `r`.
    fn beam(r: f64, rho_t2: f64) -> Population {
        Population {
            energy: 1.0,
            width2: r * r * rho_t2,
            cov: r * rho_t2,
            zeta2: rho_t2,
        }
    }

    /// The moments after a step of length `d` with lobe source `a = αΘ²` (the exact
    /// integral of the moment equations), the energy gaining `e^{αΔ}` on the
    /// unscattered beam's.
    fn advance(&mut self, d: f64, a: f64, gain: f64) {
        self.width2 += self.zeta2 * d * d + 2.0 * self.cov * d + a * d * d * d / 3.0;
        self.cov += self.zeta2 * d + 0.5 * a * d * d;
        self.zeta2 += a * d;
        self.energy *= gain;
    }

    /// The energy-weighted difference `self − other` (the photons in one and not in the
    /// other); `None` where it holds (almost) no energy.
    fn minus(&self, other: &Population) -> Option<Population> {
        let energy = self.energy - other.energy;
        (energy > 1e-12 * self.energy).then(|| Population {
            energy,
            width2: (self.energy * self.width2 - other.energy * other.width2) / energy,
            cov: (self.energy * self.cov - other.energy * other.cov) / energy,
            zeta2: (self.energy * self.zeta2 - other.energy * other.zeta2) / energy,
        })
    }

    /// The energy-weighted sum.
    fn plus(&self, other: &Population) -> Population {
        let energy = self.energy + other.energy;
        Population {
            energy,
            width2: (self.energy * self.width2 + other.energy * other.width2) / energy,
            cov: (self.energy * self.cov + other.energy * other.cov) / energy,
            zeta2: (self.energy * self.zeta2 + other.energy * other.zeta2) / energy,
        }
    }

    /// Cut back to a 1/e radius² of `w_max`: the photons beyond it leave (energy and
    /// covariance by `w_max/⟨x²⟩`), the direction variance falling in proportion to its
    /// squared correlation with the position.
    fn cut_to(&mut self, w_max: f64) {
        let f = w_max / self.width2;
        let c2 = (self.cov * self.cov / (self.width2 * self.zeta2)).min(1.0);
        self.energy *= f;
        self.cov *= f;
        self.zeta2 *= c2 * f + 1.0 - c2;
        self.width2 = w_max;
    }
}

/// `(1 − e^{−k})/k`, 1 at k = 0, for any real k.
pub fn mean_exp(k: f64) -> f64 {
    if k.abs() < 1e-8 {
        1.0 - 0.5 * k
    } else {
        -(-k).exp_m1() / k
    }
}

/// The apparent over the single-scattering attenuated backscatter of each step, averaged
/// over the step, for a beam that starts at range `start_range_m` (no particles nearer)
/// and crosses `steps` in order: 1 where nothing has been forward scattered.
pub fn small_angle_ratios(footprint: Footprint, start_range_m: f64, steps: &[Step]) -> Vec<f64> {
    let rho_t2 = footprint.divergence_rad.powi(2);
    let rho_r2 = footprint.fov_half_angle_rad.powi(2);
    // the unscattered beam's share inside the field of view
    let unscattered_seen = -(-rho_r2 / rho_t2).exp_m1();
    let beam = |r: f64| Population::beam(r, rho_t2);
    let mut total = beam(start_range_m);
    let mut reduced = total;
    let mut range = start_range_m;
    let mut m_prev = 0.0;
    let mut out = Vec::with_capacity(steps.len());
    for s in steps {
        let d = s.width_m;
        let a = s.alpha_theta2_per_m;
        let gain = (s.alpha_particle_per_m * d).exp();
        total.advance(d, a, gain);
        reduced.advance(d, a, gain);
        range += d;
        let unscattered = beam(range);
        let w_max = range * range * rho_r2;
        let mut m = 0.0;
        if let Some(mut narrow) = reduced.minus(&unscattered) {
            // the wide photons before this step's cut: those cut now join them from the
            // next step on, as Hogan's published implementation counts them
            let wide_energy = total.energy - reduced.energy;
            if narrow.width2 > w_max {
                narrow.cut_to(w_max);
                reduced = unscattered.plus(&narrow);
            }
            let seen = |energy: f64, width2: f64| -(-w_max / width2).exp_m1() * energy;
            m = seen(narrow.energy, narrow.width2);
            if wide_energy > 0.0 {
                let moment = total.energy * total.width2 - reduced.energy * reduced.width2;
                m += seen(wide_energy, (moment / wide_energy).max(narrow.width2));
            }
            m /= unscattered_seen;
        }
        let od = 2.0 * (s.alpha_particle_per_m + s.alpha_air_per_m) * d;
        let q = ((1.0 + m) / (1.0 + m_prev)).ln();
        let ratio = (1.0 + m_prev) * mean_exp(od - q) / mean_exp(od);
        out.push(if ratio.is_finite() { ratio } else { 1.0 });
        m_prev = m;
        if !m.is_finite() || total.energy > 1e250 {
            // beyond an optical depth of ~575 nothing returns: stop before overflowing
            out.resize(steps.len(), 1.0);
            break;
        }
    }
    out
}

/// Hu et al. (2006, Opt. Lett. 31, 1809, Eq. 1): a water cloud's layer-integrated
/// multiple-scattering factor η and its layer-integrated linear depolarization δ are
/// tied by `η = ((1 − δ)/(1 + δ))²`, so `δ = (1 − √η)/(1 + √η)` (Monte Carlo
/// simulations of CALIPSO-like footprints, within about ±0.05 in δ: their Fig. 2).
pub fn hu_depolarization(eta: f64) -> f64 {
    let s = eta.clamp(0.0, 1.0).sqrt();
    (1.0 - s) / (1.0 + s)
}

/// The layer-integrated multiple-scattering factor η of a water cloud: the η for which single scattering with the optical depth scaled by η,
/// `Σ single_i·e^{2(1−η)τ_i}`, gives the apparent return `Σ apparent_i` (Platt's
/// definition of η, `γ' = ∫β e^{−2ητ}`); bisection on [0, 1].
fn integrated_factor(single: &[f64], apparent: f64, tau: &[f64]) -> f64 {
    let excess = |eta: f64| -> f64 {
        single
            .iter()
            .zip(tau)
            .map(|(s, t)| s * (2.0 * (1.0 - eta) * t).exp())
            .sum::<f64>()
            - apparent
    };
    if excess(1.0) >= 0.0 {
        return 1.0;
    }
    if excess(0.0) <= 0.0 {
        return 0.0;
    }
    let (mut lo, mut hi) = (0.0, 1.0);
    for _ in 0..50 {
        let mid = 0.5 * (lo + hi);
        if excess(mid) > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// The linear depolarization of the apparent return of each bin of one water cloud:
/// `single` and `apparent` its bins' single-scattering and apparent returns (any
/// common unit, every polarization, the enhancement by particles nearer than the cloud
/// taken out), `tau` the cloud's optical depth from its entry to each bin centre.
///
/// Droplets depolarize nothing singly; the multiply scattered part of bin k's return,
/// `m_k = 1 − single_k/apparent_k`, is given one perpendicular share q throughout the
/// cloud, chosen so that the cloud's integrated depolarization is Hu's
/// ([`hu_depolarization`]) of its integrated factor η ([`integrated_factor`]):
/// `q·Σ m_k·apparent_k / Σ apparent_k = δ/(1 + δ)` (q at most ½: the multiply
/// scattered light at most unpolarized). Bin k's depolarization is then
/// `q·m_k/(1 − q·m_k)`: 0 at the cloud's top, rising with the share of multiply
/// scattered light.
pub fn water_cloud_depolarization(single: &[f64], apparent: &[f64], tau: &[f64]) -> Vec<f64> {
    let total: f64 = apparent.iter().sum();
    let ms_share = |k: usize| {
        if apparent[k] > 0.0 {
            (1.0 - single[k] / apparent[k]).clamp(0.0, 1.0)
        } else {
            0.0
        }
    };
    let multiply: f64 = (0..apparent.len()).map(|k| ms_share(k) * apparent[k]).sum();
    if multiply <= 0.0 {
        return vec![0.0; apparent.len()];
    }
    let d = hu_depolarization(integrated_factor(single, total, tau));
    let q = (d / (1.0 + d) * total / multiply).min(0.5);
    (0..apparent.len())
        .map(|k| {
            let p = q * ms_share(k);
            p / (1.0 - p)
        })
        .collect()
}

/// Steps no thicker than [`MAX_STEP_OPTICAL_DEPTH`]: how many to cut `width_m` into.
pub fn pieces(width_m: f64, alpha_total_per_m: f64) -> usize {
    let od = 2.0 * alpha_total_per_m * width_m;
    ((od / MAX_STEP_OPTICAL_DEPTH).ceil() as usize).clamp(1, 4096)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cloud(n: usize, width: f64, alpha: f64, r_um: f64) -> Vec<Step> {
        let theta = forward_lobe_half_width_rad(532.0, r_um);
        vec![
            Step {
                width_m: width,
                alpha_particle_per_m: alpha,
                alpha_theta2_per_m: alpha * theta * theta,
                alpha_air_per_m: 1e-5,
            };
            n
        ]
    }

    fn footprint(fov_half_angle_rad: f64) -> Footprint {
        Footprint {
            divergence_rad: 1e-4,
            fov_half_angle_rad,
        }
    }

    #[test]
    fn clear_air_is_single_scattering_exactly() {
        let fp = footprint(1e-3);
        let steps = cloud(100, 10.0, 0.0, 10.0);
        assert!(
            small_angle_ratios(fp, 1e3, &steps)
                .iter()
                .all(|r| *r == 1.0)
        );
    }

    /// `(1 − e^{−k})/k` at 0 and on both sides of the series' switch at 1e-8 (the series
    /// `1 − k/2 + k²/6` to 1e-17; the library's `expm1` to two ulps).
    #[test]
    fn mean_exp_near_zero() {
        assert_eq!(mean_exp(0.0), 1.0);
        for k in [1e-9, -1e-9, 2e-8, -2e-8] {
            let series = 1.0 - 0.5 * k + k * k / 6.0;
            assert!((mean_exp(k) - series).abs() < 4e-16, "{k}: {}", mean_exp(k));
        }
    }

    /// Hu's relation at its ends and at η = ½: δ = (1 − √½)/(1 + √½) = 3 − 2√2.
    #[test]
    fn hu_relation_values() {
        assert_eq!(hu_depolarization(1.0), 0.0);
        assert_eq!(hu_depolarization(0.0), 1.0);
        let half = 3.0 - 2.0 * std::f64::consts::SQRT_2;
        assert!((hu_depolarization(0.5) - half).abs() < 1e-15);
    }

    /// A cloud without multiply scattered light stays unpolarized; with it, the
    /// depolarization rises from 0 with the multiply scattered share.
    #[test]
    fn water_depolarization_follows_the_multiple_scattering_share() {
        let tau = [0.1, 0.3, 0.5];
        let single = [1.0, 0.7, 0.5];
        assert_eq!(
            water_cloud_depolarization(&single, &single, &tau),
            vec![0.0; 3]
        );
        let apparent = [1.0, 0.9, 0.85];
        let d = water_cloud_depolarization(&single, &apparent, &tau);
        assert!(d[0] == 0.0 && d[1] > 0.0 && d[2] > d[1], "{d:?}");
    }

    #[test]
    fn thick_cloud_stays_finite() {
        let fp = footprint(1e-2);
        let steps = cloud(20_000, 1.0, 0.1, 10.0);
        let r = small_angle_ratios(fp, 1e3, &steps);
        assert!(
            r.iter().all(|x| x.is_finite() && *x >= 1.0 - 1e-12),
            "{:?}",
            &r[..5]
        );
    }
}
