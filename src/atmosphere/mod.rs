//! The atmosphere (model.md §4): molecules, a background aerosol profile (paper
//! Eq. 5–6) and any number of aerosol or cloud layers, as point optical properties and
//! as the piecewise-constant slabs on which the bin integral is exact. Here: the whole
//! [`Atmosphere`] of a scenario built from its config, and a Raman channel's return.

pub mod aerosol_optics_table;
pub mod aerosol_profile;
pub mod aerosol_species;
pub mod bin_mean;
pub mod cabannes_line;
pub mod cloud_optics;
mod molecules;
pub mod multiple_scattering;
mod optics;
pub mod ozone;
mod particles;
pub mod profile_file;
pub mod raman;
pub mod rayleigh;
pub mod rotational_raman;
pub mod us76;
pub mod water_vapour;
pub mod wide_angle;

pub use molecules::{LinePart, MolecularSource, MolecularState, Molecules};
pub use optics::{Optics, Slab};
pub use particles::{BackgroundAerosol, Layer};

use crate::config::{Channel, LayerKind, MolecularLine, MolecularModel};
use crate::error::Result;
use crate::loaded::LoadedConfig;
use crate::receiver::{ChannelKind, LineTransmission, PolarizationOptics, RamanSpecies};
use optics::perpendicular;
use particles::{background_aerosol, layers};
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
            MolecularModel::Table {
                altitude_km,
                pressure_hpa,
                temperature_k,
            } => MolecularSource::Profile(MolecularProfile::from_table(
                altitude_km,
                pressure_hpa,
                temperature_k,
                &loaded.file_label(),
            )?),
        };
        let rho_n = m
            .depolarization
            .unwrap_or_else(|| rayleigh::depolarization_rho_n(wl));
        let channel = loaded.channels.first();
        let hsrl = channel.is_some_and(|c| c.kind == ChannelKind::HsrlMolecular);
        let width_nm = cfg.instrument.filter_width_nm;
        let cabannes = || rotational_raman::seen_line(rho_n, 0.0);
        let seen = match m.line {
            // an HSRL filter is far narrower than the rotational Raman wings
            _ if hsrl => cabannes(),
            MolecularLine::Cabannes => cabannes(),
            MolecularLine::Rayleigh => rotational_raman::seen_line(rho_n, 1.0),
            MolecularLine::Auto if width_nm < rayleigh::CABANNES_FILTER_MAX_NM => cabannes(),
            MolecularLine::Auto => rotational_raman::seen_line(rho_n, 1.0),
            MolecularLine::Filter => rotational_raman::through_top_hat(rho_n, wl, width_nm),
        };
        let part = if seen.rr_passed == 0.0 {
            LinePart::Cabannes
        } else if seen.rr_passed == 1.0 {
            LinePart::Whole
        } else {
            LinePart::CabannesAndSomeRotationalRaman
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
            part,
            us76_above_scale,
            source,
            cross_section_m2: rayleigh::cross_section_m2(wl),
            // the filter keeps all of the extinction and a share of the backscatter
            lidar_ratio_sr: rayleigh::lidar_ratio_sr(rho_n) / seen.share,
            depolarization: seen.depolarization,
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

    /// The CAMS species (0-based, increasing) the layers at the line the channel
    /// detects carry (none but in a model-field scene with aerosol).
    pub fn aerosol_species(&self) -> Vec<usize> {
        let mut present: Vec<usize> = (self.detected_line().layers.iter())
            .flat_map(|l| l.species.iter().map(|s| s.0))
            .collect();
        present.sort_unstable();
        present.dedup();
        present
    }

    /// Adds the aerosol extinction by CAMS species at `z_m` at the line the channel
    /// detects (the parts of `optics_at`'s `alpha_aer`), m⁻¹, into `out` (indexed by
    /// species, 0-based, longer than [`Self::aerosol_species`]'s last).
    pub fn add_aerosol_species_extinction(&self, z_m: f64, out: &mut [f64]) {
        particles::add_species_extinction(&self.detected_line().layers, z_m, out);
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

    /// The name of what the channel's `beta_mol` is: `cabannes`, `cabannes+partial_rr` or
    /// `whole` (the part of the elastic molecular line its filter passes), `raman_N2`.
    pub fn molecular_line_name(&self) -> String {
        match &self.raman {
            Some(r) => format!("raman_{}", r.species.name()),
            None => self.molecules.part.name().into(),
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
    /// beam path from them without a second copy of every slab's optics. From the bottom
    /// up, or from the top down (`rev`), so that a path looking down is laid in range
    /// order too.
    pub fn slabs_iter(&self, z_lo: f64, z_hi: f64) -> impl DoubleEndedIterator<Item = Slab> + '_ {
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
