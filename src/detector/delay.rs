//! Delayed counts spread over later bins (signal-induced noise, afterpulses): the
//! share of a count, uniform within its bin, whose delay lands in each later bin.

/// Relative tail below which an exponential law's shares are no longer listed.
const TAIL: f64 = 1e-15;

/// The shares `w_j`, j = 0, 1, …, of an exponential delay of mean `tau_s` for a source
/// uniform within its bin of `bin_width_s`: with `r = Δt/τ`,
/// `w_0 = 1 − (1 − e^{−r})/r` and `w_j = e^{−jr}·(2 sinh(r/2))²/r` for j ≥ 1 (the
/// bin-averaged delay CDF; closed form, free of the second difference's cancellation
/// far out: `(2 sinh(r/2))²e^{−jr}/r = expm1(−r)²e^{−(j−1)r}/r`). At most `bins` shares,
/// none once below 1e-15 of `w_0`; they sum to 1 less what falls beyond.
pub fn exponential_shares(tau_s: f64, bin_width_s: f64, bins: usize) -> Vec<f64> {
    let (w0, w1, a) = exponential_law(tau_s, bin_width_s);
    let mut w = Vec::with_capacity(bins.min(64));
    if bins == 0 {
        return w;
    }
    w.push(w0);
    let mut x = w1;
    for _ in 1..bins {
        if x < TAIL * w0.max(TAIL) {
            break;
        }
        w.push(x);
        x *= a;
    }
    w
}

/// The exponential tail of a convolution, `z_b = Σ_{j≥1} a^{j−1}·x_{b−j}`, by the
/// recursion `z_b = x_{b−1} + a·z_{b−1}`: O(bins) whatever the decay's length (a
/// first-order recursive filter), where the direct sum costs O(bins × taps).
pub fn exponential_tail(x: &[f64], a: f64) -> Vec<f64> {
    let mut z = vec![0.0; x.len()];
    for b in 1..x.len() {
        z[b] = x[b - 1] + a * z[b - 1];
    }
    z
}

/// An exponential delay of mean `tau_s` on bins of `bin_width_s` as the three numbers
/// of its shares: `w_0`, `w_1` and the ratio `a = e^{−r}` with `w_j = w_1·a^{j−1}`
/// (j ≥ 1), `r = Δt/τ`: `w_0 = 1 + expm1(−r)/r`, `w_1 = expm1(−r)²/r` (no overflow
/// however short τ is).
pub fn exponential_law(tau_s: f64, bin_width_s: f64) -> (f64, f64, f64) {
    let r = bin_width_s / tau_s;
    let e = (-r).exp_m1();
    (1.0 + e / r, e * e / r, (-r).exp())
}

/// `Σ_j w_j·x_{b−j}` for the exponential law `(w_0, w_1, a)` ([`exponential_law`]).
pub fn exponential_convolve(x: &[f64], (w0, w1, a): (f64, f64, f64)) -> Vec<f64> {
    exponential_tail(x, a)
        .iter()
        .zip(x)
        .map(|(z, v)| w0 * v + w1 * z)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_recursion_is_the_direct_convolution() {
        let x: Vec<f64> = (0..50).map(|i| ((i * 7) % 11) as f64).collect();
        let law = exponential_law(3e-7, 2e-7);
        let w = exponential_shares(3e-7, 2e-7, 50);
        let fast = exponential_convolve(&x, law);
        for b in 0..50 {
            let direct: f64 = (0..=b)
                .map(|j| w.get(j).copied().unwrap_or(0.0) * x[b - j])
                .sum();
            assert!((fast[b] - direct).abs() < 1e-12 * direct.max(1.0), "{b}");
        }
        // a delay far shorter than a bin: everything in the bin, no overflow
        let (w0, w1, _) = exponential_law(1e-15, 2e-7);
        assert!((w0 - 1.0).abs() < 1e-6 && w1.is_finite() && w1 >= 0.0);
    }

    #[test]
    fn exponential_shares_sum_to_one_and_follow_the_law() {
        for (tau, dt) in [(3e-6, 2e-7), (1e-8, 2e-7), (2e-7, 2e-7)] {
            let w = exponential_shares(tau, dt, 10_000);
            assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-12, "{tau} {dt}");
            assert!((w[2] / w[1] - (-dt / tau).exp()).abs() < 1e-12);
        }
    }
}
