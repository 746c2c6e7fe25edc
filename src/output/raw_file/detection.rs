//! The analog chain's variables (docs/file-format.md, "Analog and photon-counting
//! channels"), written when a channel records analog: the ADC's conversion, the chain's
//! parameters (NaN for photon-counting channels), the gluing constant and which bins each
//! record is linear in.

//! It imports nothing of the raw file's own modules (they import it): its variables are
//! plain [`DetectionVariable`]s, made into the file's by `content`.

use crate::detector::Analog;
use crate::scenario::{ExpectedProfile, Lidar};

/// One variable of this module: (channel), or (channel, bin) with `per_bin`; NaN-filled
/// (`_FillValue` NaN) where a channel has no value.
#[derive(Debug, Clone)]
pub struct DetectionVariable {
    /// Name in the file.
    pub name: &'static str,
    /// (channel, bin) rather than (channel).
    pub per_bin: bool,
    /// CF `long_name`.
    pub long_name: &'static str,
    /// CF `units`.
    pub units: &'static str,
    /// The values, channel-major.
    pub data: Vec<f64>,
}

/// The detector's variables: those of the analog chain ([`analog_variables`]) and the
/// expected signal-induced counts, each only when some channel has it.
pub fn detection_variables(lidar: &Lidar, expected: &[ExpectedProfile]) -> Vec<DetectionVariable> {
    let mut vars = analog_variables(lidar, expected);
    if expected.iter().any(|e| !e.induced.is_empty()) {
        vars.push(DetectionVariable {
            name: "expected_induced",
            per_bin: true,
            long_name: "expected signal-induced counts per shot (included in expected_counts; 0 for a channel without): the expected signal convolved with the detector's decay law",
            units: "count",
            data: expected
                .iter()
                .flat_map(|e| {
                    if e.induced.is_empty() {
                        vec![0.0; e.n_bins()]
                    } else {
                        e.induced.clone()
                    }
                })
                .collect(),
        });
    }
    if lidar
        .channels
        .iter()
        .any(|c| c.instrument.afterpulsing.is_some())
    {
        vars.extend(afterpulse_variables(lidar, expected));
    }
    vars
}

/// `expected_afterpulse` and `afterpulse_calibration` (channel, bin); 0 for a channel
/// without afterpulsing.
fn afterpulse_variables(lidar: &Lidar, expected: &[ExpectedProfile]) -> Vec<DetectionVariable> {
    let ran: Vec<f64> = expected
        .iter()
        .flat_map(|e| {
            if e.afterpulse.is_empty() {
                vec![0.0; e.n_bins()]
            } else {
                e.afterpulse.clone()
            }
        })
        .collect();
    let calibration: Vec<f64> = lidar
        .channels
        .iter()
        .zip(expected)
        .flat_map(|(c, e)| match &c.instrument.afterpulsing {
            Some(ap) => {
                // a closed telescope: dark counts only, through the dead time
                let dark = vec![e.dark; e.n_bins()];
                let recorded = match &c.instrument.dead_time {
                    Some(d) => d.recorded_means(&dark),
                    None => dark,
                };
                ap.expected(&recorded)
            }
            None => vec![0.0; e.n_bins()],
        })
        .collect();
    vec![
        DetectionVariable {
            name: "expected_afterpulse",
            per_bin: true,
            long_name: "expected afterpulses per shot (included in expected_counts): the recorded counts' afterpulses, p times the delay law's share of each earlier bin",
            units: "count",
            data: ran,
        },
        DetectionVariable {
            name: "afterpulse_calibration",
            per_bin: true,
            long_name: "expected afterpulses per shot of a closed-telescope (dark) run, as an MPL afterpulse calibration measures them: the dark counts' afterpulses",
            units: "count",
            data: calibration,
        },
    ]
}

/// One (channel) value of the analog chain: name, long name, units and how to read it.
type ChainValue = (&'static str, &'static str, &'static str, fn(&Analog) -> f64);

/// The variables of a run with an analog channel; none without.
pub fn analog_variables(lidar: &Lidar, expected: &[ExpectedProfile]) -> Vec<DetectionVariable> {
    if lidar.channels.iter().all(|c| c.instrument.analog.is_none()) {
        return Vec::new();
    }
    let per = |f: fn(&Analog) -> f64| {
        lidar
            .channels
            .iter()
            .map(|c| c.instrument.analog.as_ref().map_or(f64::NAN, f))
            .collect::<Vec<f64>>()
    };
    let scalars: [ChainValue; 10] = [
        (
            "adc_volts_per_count",
            "voltage of one ADC code (LSB = adc_range / 2^adc_bits): volts = counts / n_shots x this, per shot",
            "V",
            Analog::volts_per_code,
        ),
        ("adc_bits", "ADC resolution", "1", |a| f64::from(a.adc_bits)),
        ("adc_range", "ADC input range (full scale)", "V", |a| {
            a.adc_range_v
        }),
        (
            "analog_offset",
            "baseline offset added before the ADC",
            "V",
            |a| a.offset_v,
        ),
        (
            "electronic_noise",
            "rms Gaussian electronic noise of one sample (one bin, one shot)",
            "V",
            |a| a.electronic_noise_v,
        ),
        ("pmt_gain", "mean gain G of the photomultiplier", "1", |a| {
            a.gain
        }),
        (
            "excess_noise_factor",
            "excess noise factor F = 1 + Var(g)/G^2 of the gain (Gamma-distributed)",
            "1",
            |a| a.excess_noise_factor,
        ),
        (
            "load_resistance",
            "load resistance the anode current flows through",
            "ohm",
            |a| a.load_resistance_ohm,
        ),
        (
            "analog_bandwidth",
            "-3 dB bandwidth of the first-order low-pass (0 = none)",
            "Hz",
            |a| a.bandwidth_hz,
        ),
        (
            "analog_counts_per_photoelectron",
            "gluing constant: mean ADC codes per photoelectron per shot, so that expected_counts = analog_offset/adc_volts_per_count + this x low-passed (expected_signal + expected_background + expected_dark)",
            "count",
            Analog::codes_per_photoelectron,
        ),
    ];
    let mut vars: Vec<DetectionVariable> = scalars
        .into_iter()
        .map(|(name, long_name, units, f)| DetectionVariable {
            name,
            per_bin: false,
            long_name,
            units,
            data: per(f),
        })
        .collect();
    let linear: Vec<f64> = lidar
        .channels
        .iter()
        .zip(expected)
        .flat_map(|(c, e)| {
            crate::detector::linear_bins(
                c.instrument.analog.as_ref(),
                &e.total_per_shot(),
                &e.recorded,
            )
        })
        .map(|l| if l { 1.0 } else { 0.0 })
        .collect();
    vars.push(DetectionVariable {
        name: "linear_range",
        per_bin: true,
        long_name: "1 where the channel's record is linear in the photons (photon counting: dead time loses at most 1 %; analog: mean above one shot's noise rms, codes inside the ADC range but with probability at most 1e-6 a shot, and the low-passed photons within 1 % of the bin's own), else 0; a both pair glues where both are 1",
        units: "1",
        data: linear,
    });
    vars
}
