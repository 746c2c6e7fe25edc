//! Delayed counts spread over later bins (signal-induced noise, afterpulses): the
//! share of a count, uniform within its bin, whose delay lands in each later bin.

/// Relative tail below which an exponential law's shares are no longer listed.
const TAIL: f64 = 1e-15;

/// The shares `w_j`, j = 0, 1, …, of an exponential delay of mean `tau_s` for a source
/// uniform within its bin of `bin_width_s`: with `r = Δt/τ`,
/// `w_0 = 1 − (1 − e^{−r})/r` and `w_j = e^{−jr}·(2 sinh(r/2))²/r` for j ≥ 1 (the
/// bin-averaged delay CDF; closed form, free of the second difference's cancellation
/// far out). At most `bins` shares, none once below 1e-15 of `w_0`; they sum to 1 less
/// what falls beyond.
pub fn exponential_shares(tau_s: f64, bin_width_s: f64, bins: usize) -> Vec<f64> {
    let r = bin_width_s / tau_s;
    let mut w = Vec::with_capacity(bins.min(64));
    if bins == 0 {
        return w;
    }
    w.push(1.0 + (-r).exp_m1() / r);
    let s = 2.0 * (0.5 * r).sinh();
    let first = s * s / r;
    for j in 1..bins {
        let x = first * (-(j as f64) * r).exp();
        if x < TAIL * w[0].max(TAIL) {
            break;
        }
        w.push(x);
    }
    w
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exponential_shares_sum_to_one_and_follow_the_law() {
        for (tau, dt) in [(3e-6, 2e-7), (1e-8, 2e-7), (2e-7, 2e-7)] {
            let w = exponential_shares(tau, dt, 10_000);
            assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-12, "{tau} {dt}");
            assert!((w[2] / w[1] - (-dt / tau).exp()).abs() < 1e-12);
        }
    }
}
