//! The instrument: the signal constant of Eq. 2, the sky background of Eq. 3 and the
//! dark counts, all as expected counts per shot per bin (model.md §1).

use crate::atmosphere::Atmosphere;
use crate::config::{BackgroundEfficiency, Channel, ScenarioConfig};
use crate::constants::{PLANCK_J_S, SPEED_OF_LIGHT_M_PER_S};

/// Instrument figures derived from a validated config.
#[derive(Debug, Clone)]
pub struct Instrument {
    /// Laser wavelength λ0, nm.
    pub wavelength_nm: f64,
    /// Time bin width Δt, s.
    pub bin_width_s: f64,
    /// Pulse repetition frequency fL, Hz.
    pub rep_rate_hz: f64,
    /// Relative rms shot-to-shot pulse-energy jitter.
    pub pulse_energy_jitter: f64,
    /// Receiver channel.
    pub channel: Channel,
    /// `C = K·E0·(λ0/(h·c))·A·TR·TF·Qλ` (Eq. 2 without the atmosphere), counts·m³·sr per
    /// shot: the signal of a bin is `C·∫ η β T²/r² dr`.
    pub signal_constant: f64,
    /// Expected sky-background counts per shot per bin, `λ_bkg` (Eq. 3).
    pub background_per_bin: f64,
    /// Background counts per shot per bin per unit of radiance (photons m⁻² s⁻¹ sr⁻¹
    /// nm⁻¹): `A·Ω·Δλ·TF·Δt·ε_bkg`, halved for a polarization channel (Eq. 3).
    pub background_per_radiance: f64,
    /// Expected dark counts per shot per bin, `λ_dc = R_dc·Δt`.
    pub dark_per_bin: f64,
    /// The detector's dead time; `None` for an ideal linear detector (τ = 0) and for
    /// an analog record.
    pub dead_time: Option<crate::detector::DeadTime>,
    /// The analog chain of a channel that records analog codes; `None` for a photon
    /// counter.
    pub analog: Option<crate::detector::Analog>,
    /// The photon counter's afterpulsing (set with the window's bins by the scenario);
    /// `None` without, and for an analog record.
    pub afterpulsing: Option<crate::detector::afterpulse::Afterpulsing>,
    /// One half of a `both` pair: its photons are drawn as the other half's, shot for
    /// shot (no dead-time bin drawn from its counting law alone).
    pub glued: bool,
}

/// The sky radiance the instrument sees, photons m⁻² s⁻¹ sr⁻¹ nm⁻¹: the fixed
/// `background.radiance`; with the solar model and a fixed `solar_zenith_deg` also the
/// sunlight reflected below and the air's scattered sunlight (at 1 AU,
/// `crate::scene::sun::SunlightPath::radiance`, through `atmosphere`). Along an orbit the solar part changes from
/// profile to profile and is added by the scene (`src/simulate/scene.rs`), not here.
pub fn sky_radiance(cfg: &ScenarioConfig, atmosphere: &Atmosphere) -> f64 {
    let b = &cfg.background;
    let floor = b.radiance.unwrap_or(0.0);
    match (b.model, b.solar_zenith_deg) {
        (crate::config::BackgroundModel::Solar, Some(zenith)) => {
            use crate::scene::sun;
            let f = sun::solar_spectral_irradiance_photons(cfg.instrument.wavelength_nm);
            let reflector = crate::surface::reflector_below(cfg);
            let sun = sun::SunlightPath::of(cfg, atmosphere, reflector.altitude_m)
                .radiance(
                    reflector.albedo,
                    if f.is_finite() { f } else { 0.0 },
                    zenith,
                )
                .total();
            floor + sun
        }
        _ => floor,
    }
}

/// Photons per joule at `wavelength_nm`: `λ0/(h·c)`.
pub fn photons_per_joule(wavelength_nm: f64) -> f64 {
    wavelength_nm * 1e-9 / (PLANCK_J_S * SPEED_OF_LIGHT_M_PER_S)
}

/// Receiver solid angle `Ω = (π/4)·θ²` for a full field-of-view angle θ (rad), sr.
pub fn solid_angle_sr(fov_rad: f64) -> f64 {
    std::f64::consts::FRAC_PI_4 * fov_rad * fov_rad
}

impl Instrument {
    /// Derives the Eq. 2–3 figures from `cfg` (the sunlight through `atmosphere`).
    pub fn from_config(cfg: &ScenarioConfig, atmosphere: &Atmosphere) -> Self {
        let i = &cfg.instrument;
        let signal_constant = i.optical_efficiency
            * i.pulse_energy_j
            * photons_per_joule(i.wavelength_nm)
            * i.telescope_area_m2
            * i.receiver_efficiency
            * i.filter_transmission
            * i.quantum_efficiency;
        let efficiency = match cfg.background.efficiency {
            BackgroundEfficiency::Receiver => i.receiver_efficiency * i.quantum_efficiency,
            BackgroundEfficiency::Paper => 1.0,
        };
        // Sky light is unpolarized (δ = 1): a polarization channel receives half of it
        // (with diattenuation D, `(1 ± D)/2` at φ = 0)
        let polarization_share =
            crate::receiver::PolarizationOptics::from_config(i).share(i.channel, 1.0);
        // Eq. 3: N_bkg = Lλ·A·Ω·Δλ·TF (photons/s), then ·Δt·ε_bkg per bin.
        let background_per_radiance = i.telescope_area_m2
            * solid_angle_sr(i.fov_rad)
            * i.filter_width_nm
            * i.filter_transmission
            * i.bin_width_s
            * efficiency
            * polarization_share;
        Instrument {
            wavelength_nm: i.wavelength_nm,
            bin_width_s: i.bin_width_s,
            rep_rate_hz: i.rep_rate_hz,
            pulse_energy_jitter: i.pulse_energy_jitter,
            channel: i.channel,
            signal_constant,
            background_per_bin: sky_radiance(cfg, atmosphere) * background_per_radiance,
            background_per_radiance,
            dark_per_bin: i.dark_count_rate_hz * i.bin_width_s,
            dead_time: i
                .detector
                .as_ref()
                .filter(|d| d.dead_time_s > 0.0)
                .map(|d| crate::detector::DeadTime {
                    tau_s: d.dead_time_s,
                    model: d.dead_time_model,
                    bin_width_s: i.bin_width_s,
                    pixels: d.pixels.unwrap_or(1),
                }),
            analog: None,
            afterpulsing: None,
            glued: false,
        }
    }

    /// The instrument as the file channel that records `record` sees it: an analog
    /// record has the detector's analog chain and no dead time (a photon counter's).
    pub fn recording(
        mut self,
        record: crate::receiver::Record,
        detector: Option<&crate::config::DetectorConfig>,
    ) -> Self {
        self.glued = detector.is_some_and(|d| d.mode == crate::config::DetectionMode::Both);
        if let (crate::receiver::Record::Analog, Some(d)) = (record, detector) {
            self.dead_time = None;
            self.analog = Some(crate::detector::Analog::from_config(d, self.bin_width_s));
        }
        self
    }

    /// The instrument with its photon counter's afterpulsing (none for an analog record).
    pub fn with_afterpulsing(mut self, detector: Option<&crate::config::DetectorConfig>) -> Self {
        if self.analog.is_none() {
            self.afterpulsing = detector.and_then(|d| d.afterpulsing.as_ref()).map(|a| {
                crate::detector::afterpulse::Afterpulsing::from_config(a, self.bin_width_s)
            });
        }
        self
    }

    /// Shots accumulated in `accumulation_time_s`: `M = round(fL·TC)`.
    pub fn shots_per_profile(&self, accumulation_time_s: f64) -> u64 {
        (self.rep_rate_hz * accumulation_time_s).round() as u64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn photons_per_joule_at_532nm() {
        // E_photon = hc/λ = 3.734e-19 J at 532 nm
        assert!((photons_per_joule(532.0) - 2.678e18).abs() / 2.678e18 < 1e-3);
    }

    #[test]
    fn solid_angle_of_100_microrad() {
        assert!((solid_angle_sr(100e-6) - 7.853_981_6e-9).abs() < 1e-15);
    }
}
