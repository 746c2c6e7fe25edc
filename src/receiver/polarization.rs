//! The receiver's polarization optics (model.md §4 "Channels and polarization", §8
//! "Depolarization calibration"; docs/model.md §4c): what share of a species'
//! backscatter each channel sees.
//!
//! **Light.** A species of linear depolarization δ returns `β_∥ = β/(1+δ)` polarized
//! parallel to the laser and `β_⊥ = β·δ/(1+δ)` perpendicular (an incoherent sum: no
//! circular part, `U = 0` in the laser's frame).
//!
//! **Optics**, in the order the light meets them:
//!
//! 1. the receiving optics' **diattenuation** D (`instrument.diattenuation`; telescope,
//!    mirrors, dichroics in front of the calibrator): they pass `(1+D)` of the parallel
//!    and `(1−D)` of the perpendicular light, relative to their mean transmission (which
//!    is in `receiver_efficiency`): `A = (1+D)·β_∥`, `B = (1−D)·β_⊥`;
//! 2. a **rotation** φ of the polarization plane (`instrument.receiver_rotation_deg`;
//!    0 in measurements, ±45° in the calibration runs of the Δ90 method, Freudenthaler
//!    2016, Atmos. Meas. Tech. 9, 4181): the beam splitter's parallel axis then receives
//!    `p = A·cos²φ + B·sin²φ` and its perpendicular axis `s = A·sin²φ + B·cos²φ`;
//! 3. the **polarizing beam splitter** with cross-talk x (`instrument.crosstalk`): the
//!    parallel channel sees `(1−x)·p + x·s`, the perpendicular one `(1−x)·s + x·p`; a
//!    total channel (no splitter) sees `A + B`.
//!
//! The channel's lidar constant (its efficiencies) multiplies this share; the ratio of a
//! perpendicular to a parallel channel's constants is the **calibration constant** η*.
//! At φ = ±45° both splitter axes receive `(A + B)/2` whatever D and δ, and the two
//! channels see it alike whatever x: the ratio of their signals is η* in each run, and
//! the geometric mean of the two runs (the Δ90 method) cancels to first order a rotation
//! a little off 45°. With D = 0, φ = 0 this is the model of every earlier version.

use crate::config::{Channel, InstrumentConfig};

/// The receiver's polarization optics in front of a channel's detector.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PolarizationOptics {
    /// The beam splitter's cross-talk x.
    pub crosstalk: f64,
    /// The receiving optics' diattenuation D.
    pub diattenuation: f64,
    /// The rotation φ of the polarization plane in front of the splitter, rad.
    pub rotation_rad: f64,
}

impl PolarizationOptics {
    /// The optics of a (channel's) `[instrument]`.
    pub fn from_config(i: &InstrumentConfig) -> Self {
        PolarizationOptics {
            crosstalk: i.crosstalk,
            diattenuation: i.diattenuation,
            rotation_rad: i.receiver_rotation_deg.to_radians(),
        }
    }

    /// The share of a species' backscatter of linear depolarization `depolarization`
    /// that `channel` sees (steps 1–3 of the module's doc).
    pub fn share(&self, channel: Channel, depolarization: f64) -> f64 {
        let d = self.diattenuation;
        let a = (1.0 + d) / (1.0 + depolarization);
        let b = (1.0 - d) * depolarization / (1.0 + depolarization);
        // no trigonometry on the model's hot path in a measurement (φ = 0)
        let (sin, cos) = if self.rotation_rad == 0.0 {
            (0.0, 1.0)
        } else {
            self.rotation_rad.sin_cos()
        };
        let p = a * cos * cos + b * sin * sin;
        let s = a * sin * sin + b * cos * cos;
        let x = self.crosstalk;
        match channel {
            Channel::Total => a + b,
            Channel::Parallel => (1.0 - x) * p + x * s,
            Channel::Perpendicular => (1.0 - x) * s + x * p,
        }
    }
}

/// The mean transmission `T_S` of a channel's analyser (Freudenthaler 2016, Atmos. Meas.
/// Tech. 9, 4181: the intensity transmittance for unpolarized light,
/// `T_S = (T_S,p + T_S,s)/2`): the channel's share of light half parallel, half
/// perpendicular to the laser (δ = 1) without diattenuation or rotation, i.e. the mean of
/// its transmissions `(1−x, x)` of the two polarizations: 1/2 for a parallel or a
/// perpendicular channel behind the splitter whatever its cross-talk x, 1 for a total
/// channel.
pub fn analyser_transmission(channel: Channel, crosstalk: f64) -> f64 {
    let ideal = PolarizationOptics {
        crosstalk,
        diattenuation: 0.0,
        rotation_rad: 0.0,
    };
    ideal.share(channel, 1.0)
}

/// The Δ90 calibration constant η* of a cross-polarized channel R relative to a
/// reference channel T (a parallel or a total channel at the same laser line) with signal
/// constants `C_R`, `C_T` (everything but the analyser; `Instrument::signal_constant`):
///
/// ```text
/// η* = η · T_R/T_T,   η = C_R/C_T          (docs/model.md §4c, Eq. 4c.1)
/// ```
///
/// with `T_S` the analysers' mean transmissions ([`analyser_transmission`]): the gain
/// ratio η times the ratio of the channels' transmissions, Freudenthaler's (2016) "η
/// T_R/T_T", what the signal ratio `I_R/I_T` is at ±45° (both axes see `(A+B)/2`, a total
/// channel `A+B`, the module docs) and so what the Δ90 method
/// `sqrt([I_R/I_T](+45°)·[I_R/I_T](−45°))` recovers (with an ideal calibrator, K = 1).
/// For a parallel reference `T_R/T_T = 1` and η* = C_R/C_T; for a total reference
/// (PollyXT's total + cross layout) `T_R/T_T = 1/2`.
pub fn delta90_calibration_constant(
    cross_signal_constant: f64,
    cross: (Channel, f64),
    reference_signal_constant: f64,
    reference: (Channel, f64),
) -> f64 {
    let eta = cross_signal_constant / reference_signal_constant;
    eta * analyser_transmission(cross.0, cross.1) / analyser_transmission(reference.0, reference.1)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn optics(crosstalk: f64, diattenuation: f64, rotation_deg: f64) -> PolarizationOptics {
        PolarizationOptics {
            crosstalk,
            diattenuation,
            rotation_rad: f64::to_radians(rotation_deg),
        }
    }

    #[test]
    fn crosstalk_mixes_the_polarizations() {
        let d = 0.4;
        let (par, per) = (1.0 / 1.4, 0.4 / 1.4);
        let o = |x| optics(x, 0.0, 0.0);
        assert_eq!(o(0.1).share(Channel::Total, d), 1.0);
        assert!((o(0.0).share(Channel::Parallel, d) - par).abs() < 1e-15);
        assert!((o(0.1).share(Channel::Parallel, d) - (0.9 * par + 0.1 * per)).abs() < 1e-15);
        assert!((o(0.1).share(Channel::Perpendicular, d) - (0.9 * per + 0.1 * par)).abs() < 1e-15);
        // the two polarization channels together see all of it, whatever the cross-talk
        let sum = o(0.03).share(Channel::Parallel, d) + o(0.03).share(Channel::Perpendicular, d);
        assert!((sum - 1.0).abs() < 1e-15);
    }

    #[test]
    fn diattenuation_weights_the_two_polarizations() {
        // δ = 0.25: β_∥ = 0.8, β_⊥ = 0.2 of β; D = 0.1: 0.88 and 0.18
        let o = optics(0.0, 0.1, 0.0);
        assert!((o.share(Channel::Parallel, 0.25) - 0.88).abs() < 1e-15);
        assert!((o.share(Channel::Perpendicular, 0.25) - 0.18).abs() < 1e-15);
        assert!((o.share(Channel::Total, 0.25) - 1.06).abs() < 1e-15);
    }

    #[test]
    fn at_45_degrees_both_channels_see_half_whatever_the_light() {
        for (d, x, delta) in [(0.1, 0.02, 0.0), (-0.2, 0.05, 0.4), (0.3, 0.0, 1.0)] {
            for phi in [45.0, -45.0] {
                let o = optics(x, d, phi);
                let half = 0.5 * o.share(Channel::Total, delta);
                for c in [Channel::Parallel, Channel::Perpendicular] {
                    assert!((o.share(c, delta) - half).abs() < 1e-15, "{d} {x} {delta}");
                }
            }
        }
        // at 90° the channels swap
        let (o0, o90) = (optics(0.01, 0.1, 0.0), optics(0.01, 0.1, 90.0));
        let par0 = o0.share(Channel::Parallel, 0.3);
        assert!((o90.share(Channel::Perpendicular, 0.3) - par0).abs() < 1e-15);
    }
}
