//! Point optical properties by species ([`Optics`]) and the slabs of constant optics
//! ([`Slab`]) on which the bin integral is exact.

/// Point optical properties at one altitude, by species (model.md §4 and §8): what the
/// model integrates and what a retrieval compares with.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Optics {
    /// Molecular backscatter of the part of the line the channel sees, m⁻¹ sr⁻¹.
    pub beta_mol: f64,
    /// Aerosol backscatter (profile and aerosol layers), m⁻¹ sr⁻¹.
    pub beta_aer: f64,
    /// Cloud backscatter, m⁻¹ sr⁻¹.
    pub beta_cld: f64,
    /// Molecular (Rayleigh) extinction, m⁻¹.
    pub alpha_mol: f64,
    /// Aerosol extinction (profile and aerosol layers), m⁻¹.
    pub alpha_aer: f64,
    /// Cloud extinction, m⁻¹.
    pub alpha_cld: f64,
    /// Ozone absorption, m⁻¹.
    pub alpha_o3: f64,
    /// Total extinction, `α_mol + α_o3 + α_aer + α_cld`, m⁻¹.
    pub alpha_total: f64,
    /// Aerosol extinction weighted by each contribution's multiple-scattering factor,
    /// `Σ η·α` (the background profile has η = 1), m⁻¹.
    pub ms_alpha_aer: f64,
    /// Cloud extinction weighted by each layer's multiple-scattering factor, m⁻¹.
    pub ms_alpha_cld: f64,
    /// Extinction that attenuates the signal, `α_mol + α_o3 + Σ η·α`, m⁻¹.
    pub alpha_effective: f64,
    /// Extinction of water-droplet clouds, m⁻¹ (their multiply scattered return
    /// depolarizes, `multiple_scattering::water_cloud_depolarization`).
    pub alpha_water: f64,
    /// Extinction of the particles whose forward lobe is narrow enough for the
    /// small-angle model (`multiple_scattering.wide_angle_cutoff_rad`), m⁻¹.
    pub alpha_lobe: f64,
    /// The same weighted by each species' squared forward-lobe width, `Σ α·Θ²`,
    /// m⁻¹ rad².
    pub alpha_theta2: f64,
    /// The same weighted by each species' asymmetry factor, `Σ α·g`, m⁻¹.
    pub alpha_lobe_g: f64,
    /// Cross-polarized part of the aerosol backscatter, `Σ β·δ/(1+δ)`, m⁻¹ sr⁻¹.
    pub beta_perp_aer: f64,
    /// Cross-polarized part of the cloud backscatter, m⁻¹ sr⁻¹.
    pub beta_perp_cld: f64,
    /// Linear depolarization ratio of the molecular backscatter the channel sees.
    pub depol_mol: f64,
    /// Backscatter seen by the receiver channel, m⁻¹ sr⁻¹.
    pub beta_channel: f64,
    /// The share of the Cabannes line the channel's filter passes here, `f_m`: 1 but in
    /// an HSRL molecular channel, where a filter table makes it follow the temperature.
    pub molecular_transmission: f64,
}

impl Optics {
    /// Adds particles of extinction `alpha`, forward-lobe half-width `theta_rad` and
    /// asymmetry factor `g` to the multiple-scattering models' sums, if their lobe is not
    /// wider than `cutoff_rad`.
    pub(super) fn add_forward_lobe(&mut self, alpha: f64, theta_rad: f64, g: f64, cutoff_rad: f64) {
        if theta_rad <= cutoff_rad {
            self.alpha_lobe += alpha;
            self.alpha_theta2 += alpha * theta_rad * theta_rad;
            self.alpha_lobe_g += alpha * g;
        }
    }
}

/// `a/b`, or `absent` where `b` is 0 (the species is not there).
fn ratio_or(a: f64, b: f64, absent: f64) -> f64 {
    if b > 0.0 { a / b } else { absent }
}

/// Linear depolarization ratio `δ = β⊥/β∥` of a backscatter `beta` whose
/// cross-polarized part is `perp`; 0 where there is no backscatter.
fn depolarization(perp: f64, beta: f64) -> f64 {
    ratio_or(perp, beta - perp, 0.0)
}

/// The cross-polarized part `β·δ/(1+δ)` of a backscatter `beta` of depolarization `delta`.
pub(super) fn perpendicular(beta: f64, delta: f64) -> f64 {
    beta * delta / (1.0 + delta)
}

impl Optics {
    /// Aerosol extinction-to-backscatter ratio `α_aer/β_aer`, sr (0 without aerosol).
    pub fn lidar_ratio_aer(&self) -> f64 {
        ratio_or(self.alpha_aer, self.beta_aer, 0.0)
    }

    /// Cloud extinction-to-backscatter ratio, sr (0 without cloud).
    pub fn lidar_ratio_cld(&self) -> f64 {
        ratio_or(self.alpha_cld, self.beta_cld, 0.0)
    }

    /// Effective multiple-scattering factor of the aerosol, `Σηα/Σα` (1 without aerosol).
    pub fn ms_factor_aer(&self) -> f64 {
        ratio_or(self.ms_alpha_aer, self.alpha_aer, 1.0)
    }

    /// Effective multiple-scattering factor of the cloud (1 without cloud).
    pub fn ms_factor_cld(&self) -> f64 {
        ratio_or(self.ms_alpha_cld, self.alpha_cld, 1.0)
    }

    /// Particle linear depolarization ratio of the aerosol, `β⊥/β∥` (0 without aerosol).
    pub fn depol_aer(&self) -> f64 {
        depolarization(self.beta_perp_aer, self.beta_aer)
    }

    /// Particle linear depolarization ratio of the cloud (0 without cloud).
    pub fn depol_cld(&self) -> f64 {
        depolarization(self.beta_perp_cld, self.beta_cld)
    }

    /// Volume linear depolarization ratio, `Σβ⊥/Σβ∥` over molecules (the line the
    /// channel sees), aerosol and cloud: what an ideal ∥/⊥ pair of channels measures.
    pub fn depol_volume(&self) -> f64 {
        let beta = self.beta_mol + self.beta_aer + self.beta_cld;
        let perp =
            perpendicular(self.beta_mol, self.depol_mol) + self.beta_perp_aer + self.beta_perp_cld;
        depolarization(perp, beta)
    }
}

/// A slab `[z_lo, z_hi)` of constant optical properties.
#[derive(Debug, Clone, Copy)]
pub struct Slab {
    /// Lower altitude, m.
    pub z_lo: f64,
    /// Upper altitude, m.
    pub z_hi: f64,
    /// Optical properties (evaluated at the slab's mid-altitude).
    pub optics: Optics,
}
