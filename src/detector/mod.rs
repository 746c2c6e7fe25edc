//! What the detector records of the photons that reach it (architecture: sampler →
//! detector → output). Absent for an ideal linear detector: a scene without dead time
//! has no detector stage and keeps every exact fast path. A photon counter records
//! through its dead time ([`dead_time`]); an analog channel records ADC codes
//! ([`analog`]).

pub mod afterpulse;
pub mod analog;
pub mod analog_range;
pub mod counting;
pub mod dead_time;
pub mod dead_time_variance;
pub mod delay;
pub mod induced;
pub mod modulated;
mod recorder;

pub use analog::Analog;
pub use dead_time::{DeadTime, DeadTimeModel};
pub use modulated::DetectedShots;
pub use recorder::{ShotRecorder, recorded_profile};

use crate::config::{Checker, DetectionMode, DetectorConfig, ScenarioConfig};
use crate::error::Result;

/// Longest dead time a photon counter may have, s.
pub const MAX_DEAD_TIME_S: f64 = 1e-6;

/// Most pixels of a photon counter (`instrument.detector.pixels`).
pub const MAX_PIXELS: u32 = 1024;

/// Checks `[instrument.detector]`: a dead time from 0 to [`MAX_DEAD_TIME_S`] (none in
/// analog mode), and the analog keys where the mode records analog (refused elsewhere).
pub fn validate(config: &ScenarioConfig, c: &Checker) -> Result<()> {
    if let Some(d) = &config.instrument.detector {
        c.range(
            "instrument.detector.dead_time_s",
            d.dead_time_s,
            0.0,
            MAX_DEAD_TIME_S,
        )?;
        validate_pixels(d, config, c)?;
        validate_analog(d, config.instrument.bin_width_s, c)?;
        if let Some(sin) = &d.signal_induced_noise {
            validate_induced(sin, c)?;
        }
        if let Some(ap) = &d.afterpulsing {
            validate_afterpulsing(ap, d.mode, c)?;
        }
    }
    Ok(())
}

/// `pixels`: 1 to [`MAX_PIXELS`], on a photon counter with dead time (each pixel's own
/// dead time is what makes them differ from one pixel; an analog record sums them).
fn validate_pixels(d: &DetectorConfig, config: &ScenarioConfig, c: &Checker) -> Result<()> {
    let Some(p) = d.pixels else { return Ok(()) };
    let key = "instrument.detector.pixels";
    if p == 0 || p > MAX_PIXELS {
        return Err(c.fail(key, format!("must be from 1 to {MAX_PIXELS}, got {p}")));
    }
    if p > 1 && d.mode != DetectionMode::PhotonCounting {
        return Err(c.fail(
            key,
            "splits a photon counter's dead time over pixels; this detector records analog \
             (mode = \"analog\" or \"both\"): leave pixels out",
        ));
    }
    let i = &config.instrument;
    if p > 1 && (i.pulse_energy_jitter > 0.0 || i.energy_drift.is_some()) {
        return Err(c.fail(
            key,
            "with a pulse energy that varies (instrument.pulse_energy_jitter or energy_drift) \
             is not drawn by this version: set pixels = 1 or a constant pulse energy",
        ));
    }
    if p > 1 && d.dead_time_s == 0.0 {
        return Err(c.fail(
            key,
            "splits the dead time over pixels, and instrument.detector.dead_time_s is 0 \
             (an ideal detector's pixels record what one would): set a dead time or leave \
             pixels out",
        ));
    }
    Ok(())
}

/// Most exponential components of an afterpulse delay law.
pub const MAX_AFTERPULSE_COMPONENTS: usize = 8;

/// `afterpulsing`: a probability in [0, 0.5], 1 to [`MAX_AFTERPULSE_COMPONENTS`] time
/// constants in (0, 1 ms], as many weights ≥ 0 with a positive sum; a photon counter's.
fn validate_afterpulsing(
    ap: &crate::config::AfterpulsingConfig,
    mode: DetectionMode,
    c: &Checker,
) -> Result<()> {
    let key = |k: &str| format!("instrument.detector.afterpulsing.{k}");
    if mode == DetectionMode::Analog {
        return Err(c.fail(
            &key("probability"),
            "afterpulsing is a photon counter's and this detector records analog only; use \
             mode = \"both\" for a photon-counting record that afterpulses",
        ));
    }
    c.range(&key("probability"), ap.probability, 0.0, 0.5)?;
    let n = ap.time_constants_s.len();
    if n == 0 || n > MAX_AFTERPULSE_COMPONENTS {
        return Err(c.fail(
            &key("time_constants_s"),
            format!("lists {n} delays; give 1 to {MAX_AFTERPULSE_COMPONENTS}"),
        ));
    }
    for (i, &t) in ap.time_constants_s.iter().enumerate() {
        c.positive(&format!("{}[{i}]", key("time_constants_s")), t, 1e-3)?;
    }
    let w = ap.weights();
    if w.len() != n {
        return Err(c.fail(
            &key("weights"),
            format!(
                "lists {} weights for {n} time constants; give one each",
                w.len()
            ),
        ));
    }
    for (i, &x) in w.iter().enumerate() {
        c.range(&format!("{}[{i}]", key("weights")), x, 0.0, 1e6)?;
    }
    if w.iter().sum::<f64>() <= 0.0 {
        return Err(c.fail(
            &key("weights"),
            "sum to 0; give at least one positive weight",
        ));
    }
    Ok(())
}

/// `signal_induced_noise`: a fraction in [0, 0.1], a time constant in (0, 10 ms], a
/// power law's exponent in (1, 10].
fn validate_induced(sin: &crate::config::SignalInducedNoiseConfig, c: &Checker) -> Result<()> {
    use crate::config::SignalInducedNoiseConfig as Sin;
    let key = |k: &str| format!("instrument.detector.signal_induced_noise.{k}");
    let (Sin::Exponential {
        fraction,
        time_constant_s,
    }
    | Sin::PowerLaw {
        fraction,
        time_constant_s,
        ..
    }) = *sin;
    c.range(&key("fraction"), fraction, 0.0, 0.1)?;
    c.positive(&key("time_constant_s"), time_constant_s, 1e-2)?;
    if let Sin::PowerLaw { exponent, .. } = *sin {
        c.range(&key("exponent"), exponent, 1.0, 10.0)?;
        if exponent <= 1.0 {
            return Err(c.fail(
                &key("exponent"),
                "must be greater than 1 (the decay's integral is finite only then)",
            ));
        }
    }
    Ok(())
}

/// The analog keys of `d` with their limits: each a finite number in its range; the
/// offset and the noise within the ADC's range.
fn validate_analog(d: &DetectorConfig, bin_width_s: f64, c: &Checker) -> Result<()> {
    let key = |k: &str| format!("instrument.detector.{k}");
    let set: Vec<&str> = [
        ("gain", d.gain.is_some()),
        ("excess_noise_factor", d.excess_noise_factor.is_some()),
        ("load_resistance_ohm", d.load_resistance_ohm.is_some()),
        ("bandwidth_hz", d.bandwidth_hz.is_some()),
        ("electronic_noise_v", d.electronic_noise_v.is_some()),
        ("offset_v", d.offset_v.is_some()),
        ("adc_bits", d.adc_bits.is_some()),
        ("adc_range_v", d.adc_range_v.is_some()),
    ]
    .into_iter()
    .filter_map(|(k, is_set)| is_set.then_some(k))
    .collect();
    if d.mode == DetectionMode::PhotonCounting {
        return match set.first() {
            Some(k) => Err(c.fail(
                &key(k),
                "is an analog key and the detector counts photons; set \
                 instrument.detector.mode = \"analog\" or \"both\", or leave the key out",
            )),
            None => Ok(()),
        };
    }
    if d.mode == DetectionMode::Analog && d.dead_time_s > 0.0 {
        return Err(c.fail(
            &key("dead_time_s"),
            "is a photon counter's and this detector records analog only; use mode = \"both\" \
             for a photon-counting record beside the analog one",
        ));
    }
    let a = Analog::from_config(d, 1.0);
    c.positive(&key("gain"), a.gain, 1e9)?;
    c.range(
        &key("excess_noise_factor"),
        a.excess_noise_factor,
        1.0,
        10.0,
    )?;
    c.positive(&key("load_resistance_ohm"), a.load_resistance_ohm, 1e6)?;
    c.range(&key("bandwidth_hz"), a.bandwidth_hz, 0.0, 1e12)?;
    // a slower low-pass smears a bin over most of a window: taken for a unit error
    let slowest = 1.0 / (2.0 * std::f64::consts::PI * MAX_LOW_PASS_BINS * bin_width_s);
    if a.bandwidth_hz > 0.0 && a.bandwidth_hz < slowest {
        return Err(c.fail(
            &key("bandwidth_hz"),
            format!(
                "{} Hz smears a bin over more than {MAX_LOW_PASS_BINS} bins of {} s; give at \
                 least {slowest:.4e} Hz, or 0 for no low-pass",
                a.bandwidth_hz, bin_width_s
            ),
        ));
    }
    c.positive(&key("adc_range_v"), a.adc_range_v, 100.0)?;
    if !(1..=24).contains(&a.adc_bits) {
        return Err(c.fail(
            &key("adc_bits"),
            format!("must be within [1, 24], got {}", a.adc_bits),
        ));
    }
    c.range(
        &key("electronic_noise_v"),
        a.electronic_noise_v,
        0.0,
        a.adc_range_v,
    )?;
    c.range(&key("offset_v"), a.offset_v, 0.0, a.adc_range_v)?;
    Ok(())
}

/// Slowest low-pass of an analog chain: a time constant of this many bins.
pub const MAX_LOW_PASS_BINS: f64 = 1000.0;

/// Largest relative loss of a photon counter's record to its dead time in a bin the
/// file's `linear_range` still calls linear (where gluing may use it).
pub const GLUE_LOSS: f64 = 0.01;

/// Whether each bin of a channel's record is linear in the photons (the file's
/// `linear_range`): an analog record by [`Analog::linear_bins`]; a photon counter where
/// its dead time loses at most [`GLUE_LOSS`] of the photons `lambda` (per shot), i.e.
/// `recorded ≥ (1 − GLUE_LOSS)·lambda` (everywhere without dead time).
pub fn linear_bins(analog: Option<&Analog>, lambda: &[f64], recorded: &[f64]) -> Vec<bool> {
    match analog {
        Some(a) => a.linear_bins(lambda),
        None => lambda
            .iter()
            .zip(recorded)
            .map(|(&l, &r)| r >= (1.0 - GLUE_LOSS) * l)
            .collect(),
    }
}

/// Count rate above which a photon counter without a dead-time model is out of its
/// linear range (a non-paralyzable τ = 3.5 ns loses 15 % at 50 MHz; the
/// non-paralyzable correction is fitted below ~50 MHz).
pub const LINEAR_RANGE_HZ: f64 = 50e6;

/// The one-line warning for a scene without dead time whose brightest bin exceeds
/// [`LINEAR_RANGE_HZ`]: `lambda` are the expected counts per shot per bin, `altitude_m`
/// the bin centres. `None` when every bin is within the range.
pub fn linear_range_warning(
    lambda: &[f64],
    altitude_m: &[f64],
    bin_width_s: f64,
) -> Option<String> {
    let (bin, &peak) = lambda
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.total_cmp(b.1))?;
    let rate = peak / bin_width_s;
    (rate > LINEAR_RANGE_HZ).then(|| {
        format!(
            "lidarsim: warning: bin {bin} ({:.2} km) counts {:.0} MHz, beyond a photon counter's \
             linear range (~{:.0} MHz); set instrument.detector.dead_time_s to simulate its dead time",
            altitude_m[bin] / 1e3,
            rate / 1e6,
            LINEAR_RANGE_HZ / 1e6
        )
    })
}
