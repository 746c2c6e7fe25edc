//! Analog detection (docs/model.md §4b, "Analog detection"): the photomultiplier's anode
//! current through a load resistance, a first-order low-pass, Gaussian electronic noise,
//! an offset and an ADC; what the file holds is the sum over a profile's shots of each
//! bin's ADC code, as a Licel transient recorder's analog memory does.
//!
//! **Law of one shot and bin.** `N ~ Poisson(λ)` photoelectrons (signal, background and
//! dark: the shot path's own draw), each with a gain g of mean G and excess noise factor
//! `F = 1 + Var(g)/G²`, Gamma-distributed with shape `k = 1/(F−1)` (a standard model of a
//! photomultiplier's pulse-height spread; F = 1 is a noiseless gain). The sum of N
//! Gamma(k, G/k) gains is Gamma(Nk, G/k), one draw whatever N. The charge `q·G·e` of a
//! bin, spread evenly over its width Δt, gives the mean current `q·G·e/Δt` and the voltage
//! `q·u` with `u = G·e·R/Δt` volts per photoelectron. The electronics' low-pass
//! (bandwidth B, time constant `τ_e = 1/(2πB)`) moves a share `h_j` of a bin's charge into
//! the bin j later ([`impulse_response`]); Gaussian noise of rms σ_e is added to every
//! sample, then the offset V₀, and the ADC of `bits` bits over `[0, range]` rounds to the
//! nearest code `round(V/LSB)`, `LSB = range/2^bits`, clipped to `[0, 2^bits − 1]`.
//!
//! **Expectation** (the file's `expected_counts`, codes per shot):
//! `E[code_b] = V₀/LSB + c·Σ_j h_j λ_{b−j}`, `c = u/LSB` codes per photoelectron, and
//! **variance** `Var[code_b] = c²·F·Σ_j h_j² λ_{b−j} + (σ_e/LSB)² + 1/12`. The rounding is
//! taken as an independent uniform error (mean 0, variance 1/12 LSB²): with σ_e ≥ LSB its
//! bias is below `e^{−2π²}/π ≈ 9e-10` LSB (the Gaussian part alone smooths the
//! quantiser; Widrow & Kollár 2008, *Quantization Noise*, ch. 4), 2e-3 LSB at σ_e =
//! LSB/2. Clipping is not in the law: `simulate` warns where a bin's codes leave the
//! ADC's range with a probability above 1e-6 a shot (bounded from the law of the code,
//! `analog_range`).
//!
//! **Shot path** ([`Analog::record_shot`], through [`super::recorder::recorded_profile`]: its gains
//! and noise from `stream_rng(seed ^ ANALOG_STREAM, profile, block)`, the photons the
//! photon-counting draw's own): exact, per shot and bin, as above.
//! **Aggregate path** ([`Analog::record_profile`]): the photoelectrons of the M shots
//! summed (one Poisson draw per bin, as the photon-counting aggregate path), their
//! charge one Gamma(N_tot·k, 1/k) draw (exact), the low-pass applied to the sum (exact:
//! it is linear), and the M shots' noise and rounding as one Gaussian of variance
//! `M·((σ_e/LSB)² + 1/12) − 1/12` around `M·V₀/LSB + c·Σ h q`, rounded (the rounding of
//! the sum adds the last 1/12: [`aggregate_noise_variance`]) and clipped to
//! `[0, M·(2^bits − 1)]`. This approximates the per-shot quantisation (exact in mean and
//! variance where the law above holds: `M·κ2`, as M shots each rounded) and ignores
//! per-shot clipping.

use rand::Rng;
use rand_distr::{Distribution, Gamma, StandardNormal};

use crate::config::DetectorConfig;
use crate::sampling::{AGGREGATE_STREAM, ShotCounts, stream_rng};

/// The nearest code to `v` (halves up), clipped to `[0, full]`: a cast, not a call to
/// the C library's `round`.
#[inline]
fn quantize(v: f64, full: f64) -> u64 {
    if v <= 0.0 {
        0
    } else {
        (v + 0.5).min(full + 0.5) as u64
    }
}

/// Variance, codes², of the one Gaussian the aggregate path draws for the noise and
/// rounding of `shots` shots of electronic noise `sigma_codes` per shot:
/// `M·(σ² + 1/12) − 1/12`, since rounding that Gaussian's sum adds the last 1/12 itself
/// (Sheppard's correction, exact to `e^{−2π²s²}` for a Gaussian of sd s ≥ σ; Widrow &
/// Kollár 2008, ch. 4), so that the profile's code has the variance `M·κ2` of M shots
/// each rounded (module docs). At M = 1 it is σ², the shot path's own draw.
pub fn aggregate_noise_variance(shots: f64, sigma_codes: f64) -> f64 {
    shots * (sigma_codes * sigma_codes + 1.0 / 12.0) - 1.0 / 12.0
}

/// One standard normal variate (rand_distr's ziggurat).
fn normal<R: Rng + ?Sized>(rng: &mut R) -> f64 {
    StandardNormal.sample(rng)
}

/// Elementary charge, C (SI 2019, exact).
pub const ELEMENTARY_CHARGE_C: f64 = 1.602_176_634e-19;

/// Cost of one bin of one shot recorded by the analog chain ([`Analog::ns_per_shot`]), ns.
/// Measured on 2026-12-02 (one thread, an idle 2-core machine): `lidarsim simulate
/// configs/ground/pollyxt_like_glued.toml --profiles 30 --threads 1` draws in 17.4 s
/// (97 µs a shot), of which the three analog halves of 2,925 bins take 85 µs (the rest
/// as the photon-counting estimate says): 9.7 ns a bin; the time does not change with the
/// photoelectrons a bin holds (the same run at a hundredth of the 355 nm energy: 16.7 s).
pub const NS_PER_ANALOG_BIN: f64 = 10.0;

/// Seed offset of the gain and noise streams of an analog record (the photons are the
/// photon-counting draw's own, stream for stream).
pub const ANALOG_STREAM: u64 = 0xA7A1_06AD_C000_0001;

/// The analog chain's defaults: a photomultiplier of gain 10⁶ and F = 1.2 (a first dynode
/// gain of ~6) into 50 Ω, no bandwidth limit, 50 µV of noise, a 2 mV offset and a 12-bit
/// ADC over 100 mV (one of a Licel TR's ranges; LSB 24.4 µV).
pub mod defaults {
    /// Mean gain G.
    pub const GAIN: f64 = 1e6;
    /// Excess noise factor F.
    pub const EXCESS_NOISE_FACTOR: f64 = 1.2;
    /// Load resistance, Ω.
    pub const LOAD_RESISTANCE_OHM: f64 = 50.0;
    /// −3 dB bandwidth, Hz (0 = none).
    pub const BANDWIDTH_HZ: f64 = 0.0;
    /// Electronic noise rms, V.
    pub const ELECTRONIC_NOISE_V: f64 = 5e-5;
    /// Offset, V.
    pub const OFFSET_V: f64 = 2e-3;
    /// ADC bits.
    pub const ADC_BITS: u32 = 12;
    /// ADC input range, V.
    pub const ADC_RANGE_V: f64 = 0.1;
}

/// An analog recorder on a window of bins of equal width.
#[derive(Debug, Clone, PartialEq)]
pub struct Analog {
    /// Mean gain G, electrons per photoelectron.
    pub gain: f64,
    /// Excess noise factor F ≥ 1.
    pub excess_noise_factor: f64,
    /// Load resistance R, Ω.
    pub load_resistance_ohm: f64,
    /// −3 dB bandwidth B of the low-pass, Hz (0 = none).
    pub bandwidth_hz: f64,
    /// Electronic noise σ_e per sample, V.
    pub electronic_noise_v: f64,
    /// Offset V₀, V.
    pub offset_v: f64,
    /// ADC bits.
    pub adc_bits: u32,
    /// ADC input range, V.
    pub adc_range_v: f64,
    /// Bin width Δt, s.
    pub bin_width_s: f64,
    /// The low-pass's shares as `(h_0, h_1, a)`, `h_j = h_1·a^{j−1}` for j ≥ 1
    /// ([`super::delay::exponential_law`] of τ_e); `None` without a low-pass.
    low_pass: Option<(f64, f64, f64)>,
}

/// The shares `h_0, h_1, …` (the first `n`) of a bin's charge (spread evenly over the
/// bin) that a first-order low-pass of time constant τ_e moves into the bin j later,
/// for bin width Δt: `h_0 = 1 − r(1−a)`, `h_j = r(1−a)²a^{j−1}`, with `r = τ_e/Δt`,
/// `a = e^{−Δt/τ_e}` (the step response `1 − e^{−t/τ_e}` averaged over each bin: the
/// exponential delay law of mean τ_e, [`super::delay::exponential_law`]). The shares sum
/// to 1. `τ_e = 0`: `[1, 0, …]`.
pub fn impulse_response(tau_e_s: f64, bin_width_s: f64, n: usize) -> Vec<f64> {
    if tau_e_s <= 0.0 {
        return (0..n).map(|j| if j == 0 { 1.0 } else { 0.0 }).collect();
    }
    let (h0, h1, a) = super::delay::exponential_law(tau_e_s, bin_width_s);
    (0..n)
        .map(|j| {
            if j == 0 {
                h0
            } else {
                h1 * a.powi(j as i32 - 1)
            }
        })
        .collect()
}

/// Reusable buffer of [`Analog::record_shot`]: the smeared charge of every bin.
#[derive(Debug, Default, Clone)]
pub struct AnalogScratch {
    charge: Vec<f64>,
}

impl Analog {
    /// The recorder of `[instrument.detector]` (its analog keys, defaults where absent) on
    /// bins of `bin_width_s`.
    pub fn from_config(d: &DetectorConfig, bin_width_s: f64) -> Self {
        let mut a = Analog {
            gain: d.gain.unwrap_or(defaults::GAIN),
            excess_noise_factor: d
                .excess_noise_factor
                .unwrap_or(defaults::EXCESS_NOISE_FACTOR),
            load_resistance_ohm: d
                .load_resistance_ohm
                .unwrap_or(defaults::LOAD_RESISTANCE_OHM),
            bandwidth_hz: d.bandwidth_hz.unwrap_or(defaults::BANDWIDTH_HZ),
            electronic_noise_v: d.electronic_noise_v.unwrap_or(defaults::ELECTRONIC_NOISE_V),
            offset_v: d.offset_v.unwrap_or(defaults::OFFSET_V),
            adc_bits: d.adc_bits.unwrap_or(defaults::ADC_BITS),
            adc_range_v: d.adc_range_v.unwrap_or(defaults::ADC_RANGE_V),
            bin_width_s,
            low_pass: None,
        };
        let tau_e = a.time_constant_s();
        a.low_pass = (tau_e > 0.0).then(|| super::delay::exponential_law(tau_e, bin_width_s));
        a
    }

    /// The low-pass's time constant τ_e = 1/(2πB), s (0 without a low-pass).
    pub fn time_constant_s(&self) -> f64 {
        if self.bandwidth_hz > 0.0 {
            1.0 / (2.0 * std::f64::consts::PI * self.bandwidth_hz)
        } else {
            0.0
        }
    }

    /// Cost of recording one shot of `bins` bins through the chain (the charge, the
    /// low-pass, the noise and the ADC of every bin), ns, for the duration a run
    /// announces: `bins` × [`NS_PER_ANALOG_BIN`].
    pub fn ns_per_shot(&self, bins: usize) -> f64 {
        bins as f64 * NS_PER_ANALOG_BIN
    }

    /// The low-pass's first `n` shares `h_j` ([`impulse_response`]).
    pub fn kernel(&self, n: usize) -> Vec<f64> {
        impulse_response(self.time_constant_s(), self.bin_width_s, n)
    }

    /// One ADC code (LSB), V: `range/2^bits`.
    pub fn volts_per_code(&self) -> f64 {
        self.adc_range_v / 2f64.powi(self.adc_bits as i32)
    }

    /// The largest code of one shot, `2^bits − 1`.
    pub fn full_scale_code(&self) -> u64 {
        (1u64 << self.adc_bits) - 1
    }

    /// Mean voltage of one photoelectron in its bin, `u = G·e·R/Δt`, V.
    pub fn volts_per_photoelectron(&self) -> f64 {
        self.gain * ELEMENTARY_CHARGE_C * self.load_resistance_ohm / self.bin_width_s
    }

    /// Mean codes per photoelectron, `c = u/LSB`: the gluing constant (analog over
    /// photon counting in their common linear range, with the offset taken off).
    pub fn codes_per_photoelectron(&self) -> f64 {
        self.volts_per_photoelectron() / self.volts_per_code()
    }

    /// The offset in codes, `V₀/LSB`.
    pub fn offset_codes(&self) -> f64 {
        self.offset_v / self.volts_per_code()
    }

    /// The electronic noise in codes, `σ_e/LSB`.
    pub fn noise_codes(&self) -> f64 {
        self.electronic_noise_v / self.volts_per_code()
    }

    /// `Σ_j h_j^power x_{b−j}` for every bin b (the low-pass applied to `x`; its squares
    /// etc. for the cumulants), by the recursion of [`super::delay::exponential_tail`]
    /// (`h_j^p = h_1^p·(a^p)^{j−1}`): O(bins).
    pub fn smear(&self, x: &[f64], power: i32) -> Vec<f64> {
        let Some((h0, h1, a)) = self.low_pass else {
            return x.to_vec();
        };
        let (h0, h1) = (h0.powi(power), h1.powi(power));
        super::delay::exponential_tail(x, a.powi(power))
            .iter()
            .zip(x)
            .map(|(z, v)| h0 * v + h1 * z)
            .collect()
    }

    /// Expected code per shot of each bin for photoelectron means `lambda` per shot.
    pub fn expected_codes(&self, lambda: &[f64]) -> Vec<f64> {
        let (c, v0) = (self.codes_per_photoelectron(), self.offset_codes());
        self.smear(lambda, 1).iter().map(|y| v0 + c * y).collect()
    }

    /// The first four cumulants of one shot's code of each bin (module docs): the
    /// compound Poisson–Gamma charge (`κ_j = c^j·E[g^j]/G^j·Σ h^j λ`), the Gaussian noise
    /// and the uniform rounding error (κ2 = 1/12, κ4 = −1/120).
    pub fn shot_cumulants(&self, lambda: &[f64]) -> Vec<[f64; 4]> {
        let c = self.codes_per_photoelectron();
        let moments = self.gain_moments();
        let s: Vec<Vec<f64>> = (1..=4).map(|p| self.smear(lambda, p)).collect();
        let noise = self.noise_codes().powi(2);
        (0..lambda.len())
            .map(|b| {
                let k = |p: usize| c.powi(p as i32) * moments[p - 1] * s[p - 1][b];
                [
                    self.offset_codes() + k(1),
                    k(2) + noise + 1.0 / 12.0,
                    k(3),
                    k(4) - 1.0 / 120.0,
                ]
            })
            .collect()
    }

    /// Raw moments `E[g^p]/G^p`, p = 1..4, of the Gamma gain (all 1 when F = 1).
    fn gain_moments(&self) -> [f64; 4] {
        let f = self.excess_noise_factor - 1.0;
        // Gamma(k, 1/k): E[x^p] = Π_{i<p} (k+i)/k = Π (1 + i·(F−1))
        let mut m = [1.0; 4];
        for p in 1..4 {
            m[p] = m[p - 1] * (1.0 + p as f64 * f);
        }
        m
    }

    /// The charge of `n` photoelectrons in units of G: Gamma(n·k, 1/k), or n when F = 1.
    fn charge<R: Rng + ?Sized>(&self, rng: &mut R, n: f64) -> f64 {
        let f = self.excess_noise_factor - 1.0;
        if n <= 0.0 {
            return 0.0;
        }
        if f <= 0.0 {
            return n;
        }
        match Gamma::new(n / f, f) {
            Ok(g) => g.sample(rng),
            Err(_) => n,
        }
    }

    /// Records one shot whose photoelectrons per bin are `photons`, adding each bin's
    /// code into `acc`.
    pub fn record_shot<R: Rng + ?Sized>(
        &self,
        rng: &mut R,
        photons: &ShotCounts,
        scratch: &mut AnalogScratch,
        acc: &mut [u64],
    ) {
        let bins = acc.len();
        scratch.charge.resize(bins, 0.0);
        let q = &mut scratch.charge;
        for (b, n) in photons.nonzero() {
            q[b] = self.charge(rng, f64::from(n));
        }
        let (c, v0, sigma) = (
            self.codes_per_photoelectron(),
            self.offset_codes(),
            self.noise_codes(),
        );
        let full = self.full_scale_code() as f64;
        let (h0, h1, a) = self.low_pass.unwrap_or((1.0, 0.0, 0.0));
        // z = Σ_{j≥1} a^{j−1}·q_{b−j}: the charge the low-pass carries into bin b
        let mut z = 0.0;
        for (acc_b, q_b) in acc.iter_mut().zip(q.iter_mut()) {
            let noise = if sigma > 0.0 {
                sigma * normal(rng)
            } else {
                0.0
            };
            *acc_b += quantize(v0 + c * (h0 * *q_b + h1 * z) + noise, full);
            z = *q_b + a * z;
            *q_b = 0.0;
        }
    }

    /// Records a whole profile of `shots` shots from the summed photoelectrons of each
    /// bin `photoelectrons` (aggregate path, module docs), adding the code sums into `acc`.
    pub fn record_profile<R: Rng + ?Sized>(
        &self,
        rng: &mut R,
        photoelectrons: &[u64],
        shots: u64,
        acc: &mut [u64],
    ) {
        let m = shots as f64;
        let (c, v0) = (self.codes_per_photoelectron(), self.offset_codes());
        let sd = aggregate_noise_variance(m, self.noise_codes()).sqrt();
        let full = m * self.full_scale_code() as f64;
        let (h0, h1, a) = self.low_pass.unwrap_or((1.0, 0.0, 0.0));
        // one pass: each bin's charge, the low-pass's carry z (as in `record_shot`)
        let mut z = 0.0;
        for (acc_b, &n) in acc.iter_mut().zip(photoelectrons) {
            let q = self.charge(rng, n as f64);
            *acc_b += quantize(m * v0 + c * (h0 * q + h1 * z) + sd * normal(rng), full);
            z = q + a * z;
        }
    }
}

impl super::recorder::ShotRecorder for Analog {
    type Scratch = AnalogScratch;
    const STREAM: u64 = ANALOG_STREAM;

    fn record_shot<R: Rng + ?Sized>(
        &self,
        rng: &mut R,
        photons: &ShotCounts,
        scratch: &mut AnalogScratch,
        acc: &mut [u64],
    ) {
        Analog::record_shot(self, rng, photons, scratch, acc)
    }
}

/// The generator of an aggregate analog profile's gains and noise.
pub fn aggregate_rng(seed: u64, profile: u64) -> rand_pcg::Pcg64Mcg {
    stream_rng(seed ^ ANALOG_STREAM, profile, AGGREGATE_STREAM)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_impulse_response_sums_to_one_and_matches_the_rc_step() {
        let h = impulse_response(16e-9, 50e-9, 200);
        assert!((h.iter().sum::<f64>() - 1.0).abs() < 1e-15);
        // first bin: 1 − (τ/Δt)(1 − e^{−Δt/τ})
        let (r, a) = (16.0 / 50.0, (-50.0f64 / 16.0).exp());
        assert!((h[0] - (1.0 - r * (1.0 - a))).abs() < 1e-15);
        assert!((h[2] / h[1] - a).abs() < 1e-12);
        assert_eq!(impulse_response(0.0, 50e-9, 2), vec![1.0, 0.0]);
    }

    #[test]
    fn gain_moments_are_those_of_a_unit_mean_gamma() {
        let d = DetectorConfig {
            excess_noise_factor: Some(1.5),
            ..serde_default()
        };
        let a = Analog::from_config(&d, 5e-8);
        // k = 2: E[x²] = (k+1)/k = 1.5, E[x³] = 1.5·2 = 3, E[x⁴] = 3·2.5 = 7.5
        assert_eq!(a.gain_moments(), [1.0, 1.5, 3.0, 7.5]);
    }

    fn serde_default() -> DetectorConfig {
        toml::from_str("").expect("every key has a default")
    }
}
