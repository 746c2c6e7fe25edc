//! The atmosphere (model.md §4): molecules, a background aerosol profile (paper
//! Eq. 5–6) and any number of aerosol or cloud layers, as point optical properties and
//! as the piecewise-constant slabs on which the bin integral is exact.

pub mod aerosol_profile;
pub mod cabannes_line;
pub mod multiple_scattering;
pub mod ozone;
pub mod profile_file;
pub mod raman;
pub mod rayleigh;
pub mod us76;
pub mod water_vapour;
pub mod wide_angle;

use crate::config::{
    Channel, ExtinctionSource, LayerKind, MolecularLine, MolecularModel, MultipleScatteringModel,
    ScenarioConfig, StratosphericAerosol,
};
use crate::constants::BOLTZMANN_J_PER_K;
use crate::error::Result;
use crate::loaded::LoadedConfig;
use crate::receiver::{ChannelKind, LineTransmission, PolarizationOptics, RamanSpecies};
use profile_file::MolecularProfile;

/// Temperature at which a Raman channel's band cross-section is taken, K: the band
/// summed over its lines depends on T only through the vibrational ground state's
/// population, which differs from 1 by 9e-6 at 288 K and by < 2e-5 below 320 K
/// (`raman::n2_ground_state_fraction`).
pub const RAMAN_TEMPERATURE_K: f64 = 288.15;

/// What a Raman channel sees (docs/model.md §4h): the atmosphere at its detected line,
/// which attenuates the return on its way back, and the species' band.
#[derive(Debug, Clone)]
pub struct RamanReturn {
    /// The species (`N2`, `H2O`).
    pub species: RamanSpecies,
    /// The detected line, nm.
    pub line_nm: f64,
    /// The atmosphere at the detected line (its elastic optics give the extinction back;
    /// it carries the water-vapour profile).
    pub line: Box<Atmosphere>,
    /// The species' band backscatter cross-section at the laser line times the share of
    /// the band the filter passes, m² sr⁻¹ (`raman::n2_backscatter_cross_section_m2_sr`,
    /// `raman::h2o_…`).
    pub cross_section_m2_sr: f64,
}

impl RamanReturn {
    /// The species' molecules per air molecule at `z_m`: N₂'s share of dry air, or the
    /// water-vapour profile's `w·M_d/M_w`.
    pub fn molecules_per_air_molecule(&self, z_m: f64) -> f64 {
        match (self.species, &self.line.water_vapour) {
            (RamanSpecies::N2, _) => raman::N2_FRACTION_OF_AIR,
            (RamanSpecies::H2O, Some(w)) => w.molecules_per_air_molecule(z_m),
            (RamanSpecies::H2O, None) => 0.0,
        }
    }

    /// The optics a Raman channel sees at `z_m`, from the elastic optics `up` at the laser
    /// line: extinction by species at the detected line (the truth of the channel), the
    /// Raman backscatter as the molecular one (particles scatter no Raman light), and
    /// the attenuation of the way up and back, `α_eff = (α_eff(λ₀) + α_eff(λ_R))/2`, so
    /// that `T² = T_λ₀·T_λR` (model.md §8).
    fn optics(&self, up: &Optics, z_m: f64) -> Optics {
        let down = self.line.elastic_optics_at(z_m);
        // β_R = N_X·σ_R from the Rayleigh extinction N·σ(λ_R) already computed: the
        // number density is evaluated once per point
        let beta_r = down.alpha_mol
            * self.molecules_per_air_molecule(z_m)
            * (self.cross_section_m2_sr / self.line.molecules.cross_section_m2);
        Optics {
            beta_mol: beta_r,
            beta_aer: 0.0,
            beta_cld: 0.0,
            beta_perp_aer: 0.0,
            beta_perp_cld: 0.0,
            depol_mol: 0.0,
            beta_channel: beta_r,
            alpha_effective: 0.5 * (up.alpha_effective + down.alpha_effective),
            ..down
        }
    }
}

/// Where the molecular number density comes from.
#[derive(Debug, Clone)]
pub enum MolecularSource {
    /// No molecules.
    None,
    /// U.S. Standard Atmosphere 1976 (embedded, up to 86 km).
    Us76,
    /// A tabulated profile read from a file.
    Profile(MolecularProfile),
}

/// Molecular scattering: Bucholtz (1995) cross-section and lidar ratio at the laser wavelength.
#[derive(Debug, Clone)]
pub struct Molecules {
    /// Number density source.
    pub source: MolecularSource,
    /// Rayleigh cross-section per molecule σ(λ), m².
    pub cross_section_m2: f64,
    /// Molecular lidar ratio of the part of the line the filter passes, sr:
    /// `S_mol = (8π/3)(1+2γ)/(1+γ)` for the whole line, divided by the Cabannes fraction
    /// for the Cabannes line.
    pub lidar_ratio_sr: f64,
    /// Linear depolarization ratio of that part's backscatter: `γ = ρn/(2−ρn)` for the
    /// whole line, `3ε/(180+4ε)` for the Cabannes line.
    pub depolarization: f64,
    /// Whether the channel's filter passes the Cabannes line only (else the whole
    /// Rayleigh line, rotational Raman wings included).
    pub cabannes: bool,
    /// For a profile file that ends below the US76 top (86 km): the factor by which US76
    /// continues it above its top row, `N_file(top)/N_US76(top)`, so that the density is
    /// continuous there.
    pub us76_above_scale: Option<f64>,
}

impl Molecules {
    /// Number density at altitude `z_m`, m⁻³.
    pub fn number_density_m3(&self, z_m: f64) -> f64 {
        match &self.source {
            MolecularSource::None => 0.0,
            MolecularSource::Us76 => us76::number_density_m3(z_m),
            MolecularSource::Profile(p) => match self.us76_above_scale {
                Some(scale) if z_m > p.top_altitude_m() => scale * us76::number_density_m3(z_m),
                _ => p.number_density_m3(z_m),
            },
        }
    }

    /// A note for the run summary when a profile file is continued with US76 above its
    /// top.
    pub fn continuation_note(&self) -> Option<String> {
        let (MolecularSource::Profile(p), Some(scale)) = (&self.source, self.us76_above_scale)
        else {
            return None;
        };
        Some(format!(
            "lidarsim: note: the molecular profile ends at {:.1} km; above it the US Standard \
             Atmosphere 1976 continues it (to 86 km), scaled by {scale:.4} to match at the junction",
            p.top_altitude_m() / 1e3
        ))
    }

    /// Altitude above which there are no molecules, m.
    pub fn top_m(&self) -> f64 {
        match &self.source {
            MolecularSource::None => f64::NEG_INFINITY,
            MolecularSource::Us76 => us76::TOP_ALTITUDE_M,
            MolecularSource::Profile(p) => match self.us76_above_scale {
                Some(_) => us76::TOP_ALTITUDE_M,
                None => p.top_altitude_m(),
            },
        }
    }

    /// The molecular state at altitude `z_m`: US76's pressure and temperature, a
    /// profile file's (interpolated log-linearly in p, `T = p/(k_B·N)`), or scaled US76
    /// above a profile's top (p scaled as N is, US76's T).
    pub fn state_at(&self, z_m: f64) -> MolecularState {
        let n = self.number_density_m3(z_m);
        // US76 has a state up to its top (where its N > 0), none above
        let us76 = |z: f64, scale: f64| match us76::state(z.max(us76::BOTTOM_ALTITUDE_M)) {
            Some(s) => (scale * s.pressure_pa, s.temperature_k),
            None => (f64::NAN, f64::NAN),
        };
        let (pressure_pa, temperature_k) = match &self.source {
            MolecularSource::None => (f64::NAN, f64::NAN),
            MolecularSource::Us76 => us76(z_m, 1.0),
            MolecularSource::Profile(p) => match self.us76_above_scale {
                Some(scale) if z_m > p.top_altitude_m() => us76(z_m, scale),
                _ => match p.pressure_pa(z_m) {
                    Some(pa) if n > 0.0 => (pa, pa / (BOLTZMANN_J_PER_K * n)),
                    _ => (f64::NAN, f64::NAN),
                },
            },
        };
        MolecularState {
            pressure_pa,
            temperature_k,
            number_density_m3: n,
            water_vapour_mixing_ratio: f64::NAN,
        }
    }

    /// `α_mol = N·σ`, m⁻¹.
    pub fn extinction_per_m(&self, z_m: f64) -> f64 {
        self.number_density_m3(z_m) * self.cross_section_m2
    }
}

/// The molecular state at one altitude (model.md §8): what the number density comes
/// from. Pressure and temperature are NaN where the source does not give them (a profile
/// file of number densities, no molecules, above the US76 top); the raw file marks them
/// missing there (`_FillValue`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MolecularState {
    /// Pressure, Pa.
    pub pressure_pa: f64,
    /// Temperature, K.
    pub temperature_k: f64,
    /// Number density, m⁻³: the one the model uses, `p/(k_B·T)` where p and T are known.
    pub number_density_m3: f64,
    /// Mass mixing ratio of water vapour to dry air, kg kg⁻¹ (NaN where the scene has no
    /// water-vapour profile; `Atmosphere::state_at` fills it).
    pub water_vapour_mixing_ratio: f64,
}

/// The background aerosol of Eq. 5–6: `α_aer(z) = α_aer(0)·Np(z)/Np(0)`.
#[derive(Debug, Clone)]
pub struct BackgroundAerosol {
    /// Near-surface extinction at the laser wavelength, m⁻¹.
    pub surface_extinction_per_m: f64,
    /// Lidar ratio, sr.
    pub lidar_ratio_sr: f64,
    /// Linear depolarization ratio.
    pub depolarization: f64,
    /// Its particles' forward-lobe 1/e half-width Θ, rad (`multiple_scattering`).
    pub forward_lobe_rad: f64,
    /// With a present-day background stratosphere, the laser wavelength, nm (the
    /// stratosphere's extinction is its own, not Elterman's scaled with the surface's).
    pub background_stratosphere_nm: Option<f64>,
}

impl BackgroundAerosol {
    /// Its particles' asymmetry factor (`wide_angle`).
    pub const ASYMMETRY: f64 = multiple_scattering::DEFAULT_AEROSOL_ASYMMETRY;

    /// `α_aer(z)`, m⁻¹ (Eq. 6; with a background stratosphere,
    /// `aerosol_profile::with_background_stratosphere_per_m`).
    pub fn extinction_per_m(&self, z_m: f64) -> f64 {
        match self.background_stratosphere_nm {
            None => self.surface_extinction_per_m * aerosol_profile::relative_concentration(z_m),
            Some(wl) => aerosol_profile::with_background_stratosphere_per_m(
                self.surface_extinction_per_m,
                z_m,
                wl,
            ),
        }
    }
}

/// A homogeneous aerosol or cloud layer.
#[derive(Debug, Clone)]
pub struct Layer {
    /// Cloud or aerosol.
    pub kind: LayerKind,
    /// Base altitude, m.
    pub base_m: f64,
    /// Top altitude, m.
    pub top_m: f64,
    /// Extinction, m⁻¹.
    pub extinction_per_m: f64,
    /// Lidar ratio, sr.
    pub lidar_ratio_sr: f64,
    /// Linear depolarization ratio.
    pub depolarization: f64,
    /// Multiple-scattering factor η_ms on the layer's optical depth (1 but in the
    /// `constant` model).
    pub multiple_scattering: f64,
    /// Its particles' forward-lobe 1/e half-width Θ, rad (`multiple_scattering`).
    pub forward_lobe_rad: f64,
    /// Its particles' asymmetry factor g (`wide_angle`).
    pub asymmetry_factor: f64,
    /// A cloud of liquid droplets (`multiple_scattering::phase`).
    pub water: bool,
}

impl Layer {
    fn contains(&self, z_m: f64) -> bool {
        z_m >= self.base_m && z_m < self.top_m
    }
}

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
    fn add_forward_lobe(&mut self, alpha: f64, theta_rad: f64, g: f64, cutoff_rad: f64) {
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
fn perpendicular(beta: f64, delta: f64) -> f64 {
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

/// The whole atmosphere of a scenario.
#[derive(Debug, Clone)]
pub struct Atmosphere {
    /// Molecules.
    pub molecules: Molecules,
    /// Background aerosol profile, if any.
    pub aerosol: Option<BackgroundAerosol>,
    /// Layers, overlapping ones adding.
    pub layers: Vec<Layer>,
    /// Particles with a wider forward lobe only attenuate in the small-angle
    /// multiple-scattering model, rad.
    pub wide_angle_cutoff_rad: f64,
    /// Vertical resolution of the piecewise representation, m.
    pub grid_m: f64,
    /// Receiver channel (weights each species' backscatter by its depolarization).
    pub channel: Channel,
    /// The receiver's polarization optics (cross-talk, diattenuation, rotation).
    pub polarization: PolarizationOptics,
    /// Ozone absorption at this wavelength, if on: the Huggins- or Chappuis-band
    /// cross-section (`ozone::cross_section_m2`), m².
    pub ozone_cross_section_m2: Option<f64>,
    /// A Raman channel's return (None for an elastic channel).
    pub raman: Option<RamanReturn>,
    /// The water-vapour profile (`[atmosphere.water_vapour]`), if the scene has one.
    pub water_vapour: Option<water_vapour::WaterVapour>,
    /// What the channel's filter passes of the elastic molecular (Cabannes) and particle
    /// lines: 1 and 1 but in an HSRL molecular channel.
    pub lines: LineTransmission,
    /// An HSRL channel's filter table and the laser line, nm: then `f_m` is the share of
    /// the Doppler-broadened Cabannes line at the point's temperature it passes
    /// (`cabannes_line`, docs/model.md §4i), instead of `lines.molecular`.
    pub molecular_filter: Option<(cabannes_line::SpectralFilter, f64)>,
}

impl Atmosphere {
    /// Builds the atmosphere of a validated config (reads the molecular profile file if any).
    pub fn from_config(loaded: &LoadedConfig) -> Result<Self> {
        let cfg = &loaded.config;
        let wl = cfg.instrument.wavelength_nm;
        let m = &cfg.atmosphere.molecular;
        let source = match &m.model {
            MolecularModel::Named(n) if n == "none" => MolecularSource::None,
            MolecularModel::Named(_) => MolecularSource::Us76,
            MolecularModel::File { file } => {
                let resolved = loaded.resolve_path(file);
                // a file that cannot be read: name the key and where it was looked for
                let profile = MolecularProfile::from_file(&resolved).map_err(|e| match e {
                    crate::error::Error::Io { source, .. } => crate::error::Error::config(
                        loaded.file_label(),
                        "atmosphere.molecular.model.file",
                        if file.is_absolute() {
                            format!(
                                "{}: {}",
                                resolved.display(),
                                crate::error::describe_io(&source)
                            )
                        } else {
                            format!(
                                "\"{}\" resolves to {} (relative to the config's directory): {}",
                                file.display(),
                                resolved.display(),
                                crate::error::describe_io(&source)
                            )
                        },
                    ),
                    e => e,
                })?;
                MolecularSource::Profile(profile)
            }
        };
        let rho_n = m
            .depolarization
            .unwrap_or_else(|| rayleigh::depolarization_rho_n(wl));
        let channel = loaded.channels.first();
        let hsrl = channel.is_some_and(|c| c.kind == ChannelKind::HsrlMolecular);
        let cabannes = match m.line {
            // an HSRL filter is far narrower than the rotational Raman wings
            _ if hsrl => true,
            MolecularLine::Cabannes => true,
            MolecularLine::Rayleigh => false,
            MolecularLine::Auto => {
                cfg.instrument.filter_width_nm < rayleigh::CABANNES_FILTER_MAX_NM
            }
        };
        // the filter keeps all of the extinction and a share of the backscatter
        let (share, depolarization) = if cabannes {
            (
                rayleigh::cabannes_fraction(rho_n),
                rayleigh::cabannes_depolarization(rho_n),
            )
        } else {
            (1.0, rayleigh::gamma(rho_n))
        };
        let us76_above_scale = match &source {
            MolecularSource::Profile(p) if p.top_altitude_m() < us76::TOP_ALTITUDE_M => {
                let top = p.top_altitude_m();
                Some(p.number_density_m3(top) / us76::number_density_m3(top))
            }
            _ => None,
        };
        let molecular_filter = molecular_filter(loaded, &source)?;
        let molecules = Molecules {
            cabannes,
            us76_above_scale,
            source,
            cross_section_m2: rayleigh::cross_section_m2(wl),
            lidar_ratio_sr: rayleigh::lidar_ratio_sr(rho_n) / share,
            depolarization,
        };
        Ok(Atmosphere {
            molecules,
            aerosol: background_aerosol(cfg),
            layers: layers(cfg),
            wide_angle_cutoff_rad: cfg
                .multiple_scattering
                .wide_angle_cutoff_rad
                .unwrap_or(multiple_scattering::DEFAULT_WIDE_ANGLE_CUTOFF_RAD),
            grid_m: m.grid_m,
            channel: cfg.instrument.channel,
            polarization: PolarizationOptics::from_config(&cfg.instrument),
            ozone_cross_section_m2: cfg
                .atmosphere
                .ozone
                .then(|| ozone::cross_section_m2(wl))
                .filter(|s| *s > 0.0),
            raman: raman_return(loaded)?,
            water_vapour: cfg
                .atmosphere
                .water_vapour
                .as_ref()
                .map(water_vapour::WaterVapour::from_config),
            lines: channel.map_or(LineTransmission::ELASTIC, |c| c.lines),
            molecular_filter,
        })
    }

    /// The atmosphere at the line the channel detects: itself, or a Raman channel's
    /// atmosphere at the Raman line.
    pub fn detected_line(&self) -> &Atmosphere {
        self.raman.as_ref().map_or(self, |r| &r.line)
    }

    /// The share of the surface echo (an unbroadened line at the laser's wavelength) the
    /// channel sees: the particle line's share, and none for a Raman channel.
    pub fn surface_echo_share(&self) -> f64 {
        if self.raman.is_some() {
            0.0
        } else {
            self.lines.particle
        }
    }

    /// The name of what the channel's `beta_mol` is: `cabannes` or `whole` (the part of
    /// the elastic molecular line its filter passes), `raman_N2`.
    pub fn molecular_line_name(&self) -> String {
        match &self.raman {
            Some(r) => format!("raman_{}", r.species.name()),
            None if self.molecules.cabannes => "cabannes".into(),
            None => "whole".into(),
        }
    }

    /// `α_mol/β_mol` of what the channel sees, sr: the molecular lidar ratio of its part
    /// of the elastic line, or for an N₂ Raman channel the Rayleigh extinction at the
    /// Raman line over the Raman backscatter (both ∝ N: a constant); NaN for an H₂O one
    /// (its backscatter follows the mixing ratio, not the air).
    pub fn molecular_lidar_ratio_sr(&self) -> f64 {
        match &self.raman {
            Some(r) if r.species == RamanSpecies::N2 => {
                r.line.molecules.cross_section_m2
                    / (raman::N2_FRACTION_OF_AIR * r.cross_section_m2_sr)
            }
            Some(_) => f64::NAN,
            None => self.molecules.lidar_ratio_sr,
        }
    }

    /// The state at altitude `z_m`: the molecules' ([`Molecules::state_at`]) and the
    /// water-vapour mixing ratio (NaN without a profile).
    pub fn state_at(&self, z_m: f64) -> MolecularState {
        MolecularState {
            water_vapour_mixing_ratio: self
                .water_vapour
                .as_ref()
                .map_or(f64::NAN, |w| w.mixing_ratio_kg_per_kg(z_m)),
            ..self.molecules.state_at(z_m)
        }
    }

    /// `f_m` at `z_m`: the filter table's share of the Cabannes line at the air's
    /// temperature there (Eq. H2), or the channel's constant (also where the temperature
    /// is unknown: no molecules there).
    pub fn molecular_transmission_at(&self, z_m: f64) -> f64 {
        match &self.molecular_filter {
            None => self.lines.molecular,
            Some((filter, wavelength_nm)) => {
                let t = self.molecules.state_at(z_m).temperature_k;
                if t.is_finite() && t > 0.0 {
                    filter
                        .molecular_transmission(cabannes_line::doppler_sigma_hz(*wavelength_nm, t))
                } else {
                    self.lines.molecular
                }
            }
        }
    }

    /// The optics where the beam sees nothing (below the surface, before the pulse
    /// leaves): every extinction and backscatter 0, the molecular line's depolarization
    /// kept (it describes the channel's line, not the air).
    pub fn no_optics(&self) -> Optics {
        Optics {
            depol_mol: self.molecules.depolarization,
            ..Default::default()
        }
    }

    /// Optical properties the channel sees at altitude `z_m`: the elastic optics
    /// ([`Atmosphere::elastic_optics_at`]), or a Raman channel's ([`RamanReturn`]).
    pub fn optics_at(&self, z_m: f64) -> Optics {
        let up = self.elastic_optics_at(z_m);
        match &self.raman {
            None => up,
            Some(r) => r.optics(&up, z_m),
        }
    }

    /// Elastic optical properties at the laser line at altitude `z_m`:
    /// `β = β_mol + β_aer + β_cld`, `α = α_mol + α_aer + α_cld` (model.md §4).
    pub fn elastic_optics_at(&self, z_m: f64) -> Optics {
        let mut o = Optics {
            alpha_mol: self.molecules.extinction_per_m(z_m),
            depol_mol: self.molecules.depolarization,
            ..Default::default()
        };
        o.beta_mol = o.alpha_mol / self.molecules.lidar_ratio_sr;
        o.molecular_transmission = self.molecular_transmission_at(z_m);
        o.beta_channel = o.molecular_transmission
            * o.beta_mol
            * self.polarization.share(self.channel, o.depol_mol);
        if let Some(sigma) = self.ozone_cross_section_m2 {
            // absorption only: it attenuates, it does not backscatter
            o.alpha_o3 = sigma * ozone::number_density_m3(z_m);
        }
        if let Some(a) = &self.aerosol {
            let alpha = a.extinction_per_m(z_m);
            let beta = alpha / a.lidar_ratio_sr;
            o.alpha_aer += alpha;
            o.ms_alpha_aer += alpha;
            o.add_forward_lobe(
                alpha,
                a.forward_lobe_rad,
                BackgroundAerosol::ASYMMETRY,
                self.wide_angle_cutoff_rad,
            );
            o.beta_aer += beta;
            o.beta_perp_aer += perpendicular(beta, a.depolarization);
            o.beta_channel += self.lines.particle
                * beta
                * self.polarization.share(self.channel, a.depolarization);
        }
        for l in self.layers.iter().filter(|l| l.contains(z_m)) {
            let alpha = l.extinction_per_m;
            let beta = alpha / l.lidar_ratio_sr;
            let (a, ms, b, perp) = match l.kind {
                LayerKind::Cloud => (
                    &mut o.alpha_cld,
                    &mut o.ms_alpha_cld,
                    &mut o.beta_cld,
                    &mut o.beta_perp_cld,
                ),
                LayerKind::Aerosol => (
                    &mut o.alpha_aer,
                    &mut o.ms_alpha_aer,
                    &mut o.beta_aer,
                    &mut o.beta_perp_aer,
                ),
            };
            *a += alpha;
            *ms += alpha * l.multiple_scattering;
            *b += beta;
            *perp += perpendicular(beta, l.depolarization);
            o.add_forward_lobe(
                alpha,
                l.forward_lobe_rad,
                l.asymmetry_factor,
                self.wide_angle_cutoff_rad,
            );
            if l.water {
                o.alpha_water += alpha;
            }
            o.beta_channel += self.lines.particle
                * beta
                * self.polarization.share(self.channel, l.depolarization);
        }
        o.alpha_total = o.alpha_mol + o.alpha_o3 + o.alpha_aer + o.alpha_cld;
        o.alpha_effective = o.alpha_mol + o.alpha_o3 + o.ms_alpha_aer + o.ms_alpha_cld;
        o
    }

    /// Altitude above which the atmosphere is empty, m.
    pub fn top_m(&self) -> f64 {
        let mut top = self.molecules.top_m();
        if self.aerosol.is_some() {
            top = top.max(aerosol_profile::PROFILE_TOP_M);
        }
        for l in &self.layers {
            top = top.max(l.top_m);
        }
        top
    }

    /// The piecewise-constant representation of `[z_lo, z_hi)`: slabs split on the
    /// `grid_m` grid, at every layer edge and at the tops of the molecular and aerosol
    /// profiles, each with the optical properties of its mid-altitude. Inside a slab the
    /// bin integral is done exactly (see `signal`).
    pub fn slabs(&self, z_lo: f64, z_hi: f64) -> Vec<Slab> {
        self.slabs_iter(z_lo, z_hi).collect()
    }

    /// [`Self::slabs`] one at a time, none held: a window of millions of bins lays its
    /// beam path from them without a second copy of every slab's optics.
    pub fn slabs_iter(&self, z_lo: f64, z_hi: f64) -> impl Iterator<Item = Slab> + '_ {
        let first = (z_lo / self.grid_m).ceil() as i64;
        let last = (z_hi / self.grid_m).floor() as i64;
        let mut edges =
            Vec::with_capacity((last - first + 1).max(0) as usize + 5 + 2 * self.layers.len());
        edges.extend([z_lo, z_hi]);
        edges.extend((first..=last).map(|k| k as f64 * self.grid_m));
        edges.push(self.molecules.top_m());
        if self.ozone_cross_section_m2.is_some() {
            edges.push(ozone::TOP_ALTITUDE_M);
        }
        if self.aerosol.is_some() {
            edges.push(aerosol_profile::PROFILE_TOP_M);
        }
        for l in &self.layers {
            edges.push(l.base_m);
            edges.push(l.top_m);
        }
        edges.retain(|z| z.is_finite() && *z >= z_lo && *z <= z_hi);
        edges.sort_by(f64::total_cmp);
        edges.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
        (1..edges.len()).map(move |k| Slab {
            z_lo: edges[k - 1],
            z_hi: edges[k],
            optics: self.optics_at(0.5 * (edges[k - 1] + edges[k])),
        })
    }
}

/// A Raman channel's return: its atmosphere at the detected line (the layers' and the
/// aerosol's values carried there by their Ångström exponents, Rayleigh and ozone at that
/// line) and the species' band backscatter (docs/model.md §4h); None for another kind.
fn raman_return(loaded: &LoadedConfig) -> Result<Option<RamanReturn>> {
    let Some(channel) = loaded
        .channels
        .first()
        .filter(|c| c.kind == ChannelKind::Raman)
    else {
        return Ok(None);
    };
    let laser_nm = loaded.config.instrument.wavelength_nm;
    let line_nm = channel.detection_wavelength_nm();
    let mut down = loaded.clone();
    down.config.instrument.wavelength_nm = line_nm;
    down.channels[0].kind = ChannelKind::Elastic;
    down.channels[0].config.instrument.wavelength_nm = line_nm;
    let cross_section_m2_sr = match channel.species {
        RamanSpecies::N2 => {
            raman::n2_backscatter_cross_section_m2_sr(laser_nm, RAMAN_TEMPERATURE_K)
        }
        RamanSpecies::H2O => raman::h2o_backscatter_cross_section_m2_sr(laser_nm),
    };
    Ok(Some(RamanReturn {
        species: channel.species,
        line_nm,
        line: Box::new(Atmosphere::from_config(&down)?),
        cross_section_m2_sr: cross_section_m2_sr * channel.band_transmission,
    }))
}

/// An HSRL channel's filter table with its laser line, if it has one; a filter table
/// needs the air's temperature, which a profile file of number densities does not give.
fn molecular_filter(
    loaded: &LoadedConfig,
    source: &MolecularSource,
) -> Result<Option<(cabannes_line::SpectralFilter, f64)>> {
    let Some(filter) = loaded
        .channels
        .first()
        .and_then(|c| c.spectral_filter.clone())
    else {
        return Ok(None);
    };
    if let MolecularSource::Profile(profile) = source
        && profile.pressure_pa(profile.top_altitude_m()).is_none()
    {
        return Err(crate::error::Error::config(
            loaded.file_label(),
            "atmosphere.molecular.model.file",
            "gives number densities only: an HSRL channel's spectral_filter needs the \
                 air's temperature (a profile of altitude_km, pressure_hpa, temperature_k, or \
                 \"us76\")",
        ));
    }
    Ok(Some((filter, loaded.config.instrument.wavelength_nm)))
}

/// Eq. 5 near-surface extinction at the laser wavelength, from the visibility or from
/// the given surface extinction (scaled by the Ångström exponent), as the config selects.
fn background_aerosol(cfg: &ScenarioConfig) -> Option<BackgroundAerosol> {
    let a = cfg.atmosphere.aerosol.as_ref()?;
    let wl = cfg.instrument.wavelength_nm;
    let source = a
        .extinction_from
        .unwrap_or(if a.surface_extinction_per_km.is_some() {
            ExtinctionSource::SurfaceExtinction
        } else {
            ExtinctionSource::Visibility
        });
    let surface_extinction_per_m = match (source, a.surface_extinction_per_km) {
        (ExtinctionSource::SurfaceExtinction, Some(e)) => {
            let q = a
                .angstrom_exponent
                .unwrap_or_else(|| aerosol_profile::kruse_exponent(a.visibility_km));
            e * 1e-3 * (a.reference_wavelength_nm / wl).powf(q)
        }
        _ => aerosol_profile::surface_extinction_per_m(a.visibility_km, wl),
    };
    Some(BackgroundAerosol {
        surface_extinction_per_m,
        lidar_ratio_sr: a.lidar_ratio_sr,
        depolarization: a.depolarization,
        forward_lobe_rad: multiple_scattering::forward_lobe_half_width_rad(
            wl,
            a.effective_radius_um
                .unwrap_or(multiple_scattering::DEFAULT_AEROSOL_RADIUS_UM),
        ),
        background_stratosphere_nm: (a.stratosphere == StratosphericAerosol::Background)
            .then_some(wl),
    })
}

fn layers(cfg: &ScenarioConfig) -> Vec<Layer> {
    cfg.atmosphere
        .layers
        .iter()
        .map(|l| {
            let wl = cfg.instrument.wavelength_nm;
            let (extinction_per_km, lidar_ratio_sr) = l.at_wavelength(wl, wl);
            Layer {
                kind: l.kind,
                base_m: l.base_km * 1e3,
                top_m: l.top_km * 1e3,
                extinction_per_m: extinction_per_km * 1e-3,
                lidar_ratio_sr,
                depolarization: l.depolarization,
                // the other models compute the multiply scattered return instead
                multiple_scattering: match cfg.multiple_scattering.model {
                    MultipleScatteringModel::Constant => l.multiple_scattering,
                    _ => 1.0,
                },
                forward_lobe_rad: multiple_scattering::forward_lobe_half_width_rad(
                    wl,
                    multiple_scattering::effective_radius_um(l),
                ),
                asymmetry_factor: multiple_scattering::asymmetry_factor(l),
                water: l.kind == LayerKind::Cloud
                    && multiple_scattering::phase(l) == crate::config::CloudPhase::Water,
            }
        })
        .collect()
}
