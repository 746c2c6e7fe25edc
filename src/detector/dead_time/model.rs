//! A photon counter's dead time ([`DeadTime`]) and its model: the mean recorded counts
//! per bin by Müller's equations on a grid, the stationary rates, the renewal variance.

/// Most grid steps of the mean-rate solver; beyond, the stationary formulas per bin.
pub const MAX_GRID_STEPS: f64 = 5e7;
/// Grid steps per dead time (and at least per bin).
const STEPS_PER_TAU: f64 = 64.0;

/// How the dead period behaves (a config key's type, so it lives in the config).
pub use crate::config::DeadTimeModel;

/// A photon counter's dead time on a window of bins of equal width.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DeadTime {
    /// τ, s (> 0).
    pub tau_s: f64,
    /// Non-paralyzable or paralyzable.
    pub model: DeadTimeModel,
    /// Δt of a bin, s.
    pub bin_width_s: f64,
    /// Pixels k ≥ 1 sharing the photons evenly, each with this dead time of its own
    /// (`instrument.detector.pixels`): each sees the rate n/k, independently (a Poisson
    /// stream split at random is k independent Poisson streams), and the channel
    /// records their sum, so every law here is k times one pixel's at n/k.
    pub pixels: u32,
}

impl DeadTime {
    /// One pixel of the detector (the same dead time, `pixels = 1`).
    pub fn pixel(&self) -> DeadTime {
        DeadTime { pixels: 1, ..*self }
    }

    /// `k·f(one pixel, λ/k)` for the detector's k pixels (f itself for one pixel).
    fn summed_over_pixels(
        &self,
        lambda: &[f64],
        f: impl Fn(&DeadTime, &[f64]) -> Vec<f64>,
    ) -> Vec<f64> {
        if self.pixels <= 1 {
            return f(self, lambda);
        }
        let k = self.pixels as f64;
        let share: Vec<f64> = lambda.iter().map(|l| l / k).collect();
        f(&self.pixel(), &share)
            .into_iter()
            .map(|x| k * x)
            .collect()
    }

    /// Stationary recorded rate for a true rate `n` (s⁻¹): `n/(1+nτ)` or `n·e^{−nτ}`
    /// (k pixels: k times that at n/k).
    pub fn stationary_rate(&self, n: f64) -> f64 {
        if self.pixels > 1 {
            let k = self.pixels as f64;
            return k * self.pixel().stationary_rate(n / k);
        }
        match self.model {
            DeadTimeModel::Nonparalyzable => n / (1.0 + n * self.tau_s),
            DeadTimeModel::Paralyzable => n * (-n * self.tau_s).exp(),
        }
    }

    /// Mean recorded counts per shot per bin for true means `lambda` per bin (see the
    /// module docs).
    pub fn recorded_means(&self, lambda: &[f64]) -> Vec<f64> {
        self.summed_over_pixels(lambda, |d, l| d.solve(l, |_, _| {}))
    }

    /// The mean-rate solver of [`recorded_means`](Self::recorded_means); before each bin
    /// of the grid it hands `entering(bin, last)` the recorded counts of the last steps
    /// before the bin, newest first, each `m·h` of a step of `h` (non-paralyzable: the
    /// detector's dead state entering the bin, `detector::dead_time_variance`), or `None`
    /// where the grid is too long and the stationary formulas are used.
    pub(crate) fn solve(
        &self,
        lambda: &[f64],
        mut entering: impl FnMut(usize, Option<(&[f64], f64)>),
    ) -> Vec<f64> {
        let dt = self.bin_width_s;
        let h = self.tau_s.min(dt) / STEPS_PER_TAU;
        let per_bin = (dt / h).ceil().max(1.0);
        if per_bin * lambda.len() as f64 > MAX_GRID_STEPS {
            return lambda
                .iter()
                .enumerate()
                .map(|(b, &l)| {
                    entering(b, None);
                    self.stationary_rate(l / dt) * dt
                })
                .collect();
        }
        let per_bin = per_bin as usize;
        let h = dt / per_bin as f64;
        // each step is evaluated at its midpoint t: the last τ before t is half of the
        // step itself and `past` = τ/h − 1/2 earlier steps, the oldest of them in part
        let past = self.tau_s / h - 0.5;
        let lag = past.ceil().max(1.0) as usize;
        let oldest_share = past - (lag as f64 - 1.0);
        // ring buffer of the last `lag` steps: m·h (non-paralyzable) or n·h (paralyzable)
        let mut ring = vec![0.0f64; lag];
        let mut newest_first = Vec::new();
        let (mut pos, mut window) = (0usize, 0.0f64);
        lambda
            .iter()
            .enumerate()
            .map(|(b, &l)| {
                newest_first.clear();
                newest_first.extend((1..=lag).map(|k| ring[(pos + lag - k) % lag]));
                entering(b, Some((&newest_first, h)));
                let n = l / dt;
                let mut recorded = 0.0;
                for _ in 0..per_bin {
                    let before = window - (1.0 - oldest_share) * ring[pos];
                    let (m, pushed) = match self.model {
                        // m = n·(1 − before − m·h/2)
                        DeadTimeModel::Nonparalyzable => {
                            let m = n * (1.0 - before).max(0.0) / (1.0 + 0.5 * n * h);
                            (m, m * h)
                        }
                        DeadTimeModel::Paralyzable => (n * (-(before + 0.5 * n * h)).exp(), n * h),
                    };
                    recorded += m * h;
                    window += pushed - ring[pos];
                    ring[pos] = pushed;
                    pos = (pos + 1) % lag;
                }
                recorded
            })
            .collect()
    }

    /// Mean and variance of each bin's recorded count per shot when the signal varies
    /// from shot to shot with the laser's jitter (`energy`, drift excluded): by the law
    /// of total variance over the shot's energy factor f,
    /// `E[m(f)]` and `E[v(f)] + Var[m(f)]`, with m from [`recorded_means`](Self::recorded_means)
    /// and v from [`recorded_mean_and_variance`](Self::recorded_mean_and_variance) at
    /// `f·signal + rest`.
    pub fn recorded_moments(
        &self,
        signal: &[f64],
        rest: f64,
        energy: &crate::laser::PulseEnergy,
    ) -> (Vec<f64>, Vec<f64>) {
        let n = signal.len();
        let m = energy.jitter_expectation(|f| {
            let lambda: Vec<f64> = signal.iter().map(|s| f * s + rest).collect();
            let (mean, var) = self.recorded_mean_and_variance(&lambda);
            let square = mean.iter().map(|x| x * x).collect::<Vec<f64>>();
            mean.iter().copied().chain(var).chain(square).collect()
        });
        let mean = m[..n].to_vec();
        let var = (0..n)
            .map(|i| m[n + i] + (m[2 * n + i] - m[i] * m[i]).max(0.0))
            .collect();
        (mean, var)
    }

    /// Variance of a bin's recorded count per shot (renewal theory, module docs), for the
    /// bin's true mean `lambda` per shot.
    pub fn recorded_variance(&self, lambda: f64) -> f64 {
        if self.pixels > 1 {
            let k = self.pixels as f64;
            return k * self.pixel().recorded_variance(lambda / k);
        }
        let dt = self.bin_width_s;
        let n = lambda / dt;
        let x = n * self.tau_s;
        match self.model {
            DeadTimeModel::Nonparalyzable => lambda / (1.0 + x).powi(3),
            DeadTimeModel::Paralyzable => {
                let m = lambda * (-x).exp();
                m * (1.0 - 2.0 * x * (-x).exp())
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dead(model: DeadTimeModel) -> DeadTime {
        DeadTime {
            tau_s: 3.5e-9,
            model,
            bin_width_s: 2e-6,
            pixels: 1,
        }
    }

    #[test]
    fn the_solver_meets_the_stationary_formulas() {
        for model in [DeadTimeModel::Nonparalyzable, DeadTimeModel::Paralyzable] {
            let d = dead(model);
            for n in [1e3, 1e6, 5e7, 2e8] {
                let lambda = vec![n * d.bin_width_s; 40];
                let m = d.recorded_means(&lambda);
                let want = d.stationary_rate(n) * d.bin_width_s;
                // past the first bin the rate is stationary
                assert!(
                    (m[20] / want - 1.0).abs() < 1e-3,
                    "{model:?} n={n}: {} vs {want}",
                    m[20]
                );
                // the first bin starts live: at least the stationary count
                assert!(m[0] >= want * (1.0 - 1e-9));
            }
        }
    }

    #[test]
    fn no_rate_no_count_and_low_rates_are_poisson() {
        let d = dead(DeadTimeModel::Nonparalyzable);
        assert_eq!(d.recorded_means(&[0.0, 0.0]), vec![0.0, 0.0]);
        let m = d.recorded_means(&[1e-3; 3]);
        // n = 500 Hz: m/n = 1/(1 + nτ) = 1 − 1.75e-6
        assert!((m[1] / 1e-3 - 1.0 + 1.75e-6).abs() < 1e-8);
        // variance 1/(1 + nτ)³ = 1 − 5.25e-6 of the Poisson value
        assert!((d.recorded_variance(1e-3) / 1e-3 - 1.0 + 5.25e-6).abs() < 1e-8);
    }
}
