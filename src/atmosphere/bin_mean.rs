//! The optics by species averaged over a range bin ([`BinMean`]): what the bin's counts
//! integrate, where the point truth gives the bin centre (docs/file-format.md
//! "Bin-averaged optics"). One source of truth with the model's path integral: the mean
//! is taken over the very slabs the beam path is laid from ([`Atmosphere::slabs_iter`]
//! over the path's span, each with the optics of its mid-altitude), each weighted by the
//! length of range it covers in the bin; exact for the layers' top hats.

use super::{Atmosphere, Slab};

/// The bin-averaged extinction and backscatter of the particles, by species:
/// `(1/(r_b − r_a)) ∫_{r_a}^{r_b} x(r) dr` over the bin's range (0 where the beam sees
/// no atmosphere: below the surface, above the atmosphere, before the trigger).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct BinMean {
    /// Aerosol extinction (profile and aerosol layers), m⁻¹.
    pub alpha_aer: f64,
    /// Cloud extinction, m⁻¹.
    pub alpha_cld: f64,
    /// Aerosol backscatter, m⁻¹ sr⁻¹.
    pub beta_aer: f64,
    /// Cloud backscatter, m⁻¹ sr⁻¹.
    pub beta_cld: f64,
    /// Aerosol extinction weighted by each contribution's multiple-scattering factor,
    /// `Σ η·α` (what attenuates), m⁻¹.
    pub ms_alpha_aer: f64,
    /// Cloud extinction weighted by each layer's multiple-scattering factor, m⁻¹.
    pub ms_alpha_cld: f64,
}

impl BinMean {
    /// `self + w·(slab's optics)`.
    fn add(&mut self, w: f64, s: &Slab) {
        self.alpha_aer += w * s.optics.alpha_aer;
        self.alpha_cld += w * s.optics.alpha_cld;
        self.beta_aer += w * s.optics.beta_aer;
        self.beta_cld += w * s.optics.beta_cld;
        self.ms_alpha_aer += w * s.optics.ms_alpha_aer;
        self.ms_alpha_cld += w * s.optics.ms_alpha_cld;
    }

    /// The bin's effective multiple-scattering factor of the aerosol, `⟨ηα⟩/⟨α⟩` (1
    /// without aerosol): the bin's attenuating aerosol optical depth over its own.
    pub fn ms_factor_aer(&self) -> f64 {
        ms_factor(self.ms_alpha_aer, self.alpha_aer)
    }

    /// The same of the cloud (1 without cloud).
    pub fn ms_factor_cld(&self) -> f64 {
        ms_factor(self.ms_alpha_cld, self.alpha_cld)
    }
}

/// `⟨ηα⟩/⟨α⟩`, 1 where there is no extinction: also the onboard product's rule for a
/// region bin's factor from its native bins' sums.
pub fn ms_factor(ms_alpha: f64, alpha: f64) -> f64 {
    if alpha > 0.0 { ms_alpha / alpha } else { 1.0 }
}

impl Atmosphere {
    /// The mean optics over the bin `(r_a, r_b)` of range whose ends are at altitudes
    /// `(z_a, z_b)` (either order), along a beam whose path spans the altitudes `span`
    /// (`BeamPath::altitude_span`) and whose range at altitude z is `range_at(z)`. The
    /// slabs are those of `slabs_iter(span)` that meet the bin: the grid cells around the
    /// bin, cut at the span's ends, the layers' edges and the profiles' tops, so that each
    /// has the mid-altitude (and optics) of the path's own slab.
    pub fn bin_mean(
        &self,
        span: (f64, f64),
        (r_a, r_b): (f64, f64),
        (z_a, z_b): (f64, f64),
        range_at: impl Fn(f64) -> f64,
    ) -> BinMean {
        let (z_lo, z_hi) = (z_a.min(z_b), z_a.max(z_b));
        let g = self.grid_m;
        let lo = span.0.max((z_lo / g).floor() as i64 as f64 * g);
        let hi = span.1.min((z_hi / g).ceil() as i64 as f64 * g);
        let width = (r_b - r_a).abs();
        let mut mean = BinMean::default();
        if hi <= lo || width <= 0.0 {
            return mean;
        }
        for s in self.slabs_iter(lo, hi) {
            let (a, b) = (s.z_lo.max(z_lo), s.z_hi.min(z_hi));
            if b > a {
                mean.add((range_at(b) - range_at(a)).abs() / width, &s);
            }
        }
        mean
    }
}
