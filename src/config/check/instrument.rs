//! The checks of `[instrument]`: its ranges, the crosstalk's channel, the energy drift
//! and the overlap, with the laser's and the detector's own checks in their places.

use crate::config::instrument::{Channel, EnergyDriftConfig, OverlapConfig, WAVELENGTH_RANGE_NM};
use crate::config::scenario::ScenarioConfig;
use crate::error::Result;

use super::{Checker, OwnerChecks};

impl ScenarioConfig {
    pub(super) fn validate_instrument(&self, c: &Checker, owners: &OwnerChecks) -> Result<()> {
        let i = &self.instrument;
        let (shortest, longest) = WAVELENGTH_RANGE_NM;
        c.range(
            "instrument.wavelength_nm",
            i.wavelength_nm,
            shortest,
            longest,
        )?;
        c.positive("instrument.pulse_energy_j", i.pulse_energy_j, 1e3)?;
        (owners.laser)(self, c)?;
        c.positive("instrument.rep_rate_hz", i.rep_rate_hz, 1e7)?;
        if let Some(w) = i.pulse_fwhm_s {
            c.positive("instrument.pulse_fwhm_s", w, 1e-3)?;
        }
        c.positive("instrument.telescope_area_m2", i.telescope_area_m2, 1e3)?;
        c.efficiency("instrument.optical_efficiency", i.optical_efficiency)?;
        c.efficiency("instrument.receiver_efficiency", i.receiver_efficiency)?;
        c.efficiency("instrument.filter_transmission", i.filter_transmission)?;
        c.efficiency("instrument.quantum_efficiency", i.quantum_efficiency)?;
        c.positive("instrument.fov_rad", i.fov_rad, 0.1)?;
        c.positive("instrument.filter_width_nm", i.filter_width_nm, 100.0)?;
        c.range(
            "instrument.dark_count_rate_hz",
            i.dark_count_rate_hz,
            0.0,
            1e9,
        )?;
        c.range("instrument.bin_width_s", i.bin_width_s, 1e-10, 1e-3)?;
        c.range("instrument.crosstalk", i.crosstalk, 0.0, 0.5)?;
        c.range("instrument.diattenuation", i.diattenuation, -0.99, 0.99)?;
        c.range(
            "instrument.receiver_rotation_deg",
            i.receiver_rotation_deg,
            -90.0,
            90.0,
        )?;
        if i.crosstalk > 0.0 && i.channel == Channel::Total {
            return Err(c.fail(
                "instrument.crosstalk",
                "applies to a parallel or perpendicular channel; a total channel sees both",
            ));
        }
        match i.energy_drift {
            None => {}
            Some(EnergyDriftConfig::Linear { per_hour }) => {
                c.range("instrument.energy_drift.per_hour", per_hour, -0.5, 0.5)?;
            }
            Some(EnergyDriftConfig::Periodic {
                amplitude,
                period_s,
                phase_deg,
            }) => {
                c.range("instrument.energy_drift.amplitude", amplitude, 0.0, 0.5)?;
                c.positive("instrument.energy_drift.period_s", period_s, 1e9)?;
                c.range(
                    "instrument.energy_drift.phase_deg",
                    phase_deg,
                    -360.0,
                    360.0,
                )?;
            }
        }
        (owners.detector)(self, c)?;
        match &i.overlap {
            None | Some(OverlapConfig::None) => {}
            Some(OverlapConfig::FullRange { full_overlap_m }) => {
                c.positive("instrument.overlap.full_overlap_m", *full_overlap_m, 1e6)?;
            }
            Some(OverlapConfig::Geometric {
                beam_radius_m,
                beam_divergence_rad,
                axis_offset_m,
            }) => {
                c.positive("instrument.overlap.beam_radius_m", *beam_radius_m, 10.0)?;
                c.range(
                    "instrument.overlap.beam_divergence_rad",
                    *beam_divergence_rad,
                    0.0,
                    0.1,
                )?;
                c.range(
                    "instrument.overlap.axis_offset_m",
                    *axis_offset_m,
                    0.0,
                    100.0,
                )?;
            }
        }
        Ok(())
    }
}
