//! The entropy of a Poisson count: what a compressed count takes, for the file-size
//! estimates.

/// Entropy of a Poisson(μ) count, bits: exact sum over the PMF below μ = 50, the
/// normal-limit `½·log2(2πeμ)` with its `1/(12μ)`-order correction above.
pub fn poisson_entropy_bits(mu: f64) -> f64 {
    if mu.is_nan() || mu <= 0.0 {
        return 0.0;
    }
    if mu >= 50.0 {
        let e = std::f64::consts::E;
        return 0.5 * (2.0 * std::f64::consts::PI * e * mu).log2()
            - 1.0 / (12.0 * mu * std::f64::consts::LN_2);
    }
    let mut p = (-mu).exp();
    let mut h = 0.0;
    let kmax = (mu + 12.0 * mu.sqrt() + 30.0) as u64;
    for k in 0..=kmax {
        if p > 0.0 {
            h -= p * p.log2();
        }
        p *= mu / (k + 1) as f64;
    }
    h
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn poisson_entropy_matches_known_values() {
        // H(Poisson(1)) = 1.8825 bits (direct sum); continuity at the switch
        assert!((poisson_entropy_bits(1.0) - 1.882_5).abs() < 1e-3);
        let (a, b) = (poisson_entropy_bits(49.999), poisson_entropy_bits(50.0));
        assert!((a - b).abs() < 1e-3, "{a} {b}");
        assert_eq!(poisson_entropy_bits(0.0), 0.0);
        assert!(poisson_entropy_bits(1e15).is_finite());
    }
}
