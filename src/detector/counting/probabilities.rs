//! Binomial and Poisson probabilities and tails by Loader's saddle-point form (Loader 2000,
//! "Fast and accurate computation of binomial probabilities"; `stirlerr` and `bd0` as R's).

/// `P(Pois(μ) = x)` by Loader's saddle-point form.
pub(crate) fn pois_pmf(x: u32, mu: f64) -> f64 {
    if mu <= 0.0 {
        return if x == 0 { 1.0 } else { 0.0 };
    }
    if x == 0 {
        return (-mu).exp();
    }
    let x = f64::from(x);
    (-stirlerr(x) - bd0(x, mu)).exp() / (2.0 * std::f64::consts::PI * x).sqrt()
}

/// `(P(Pois(μ) ≥ k), P(Pois(μ) < k))`, the smaller summed from `k` outwards.
pub(crate) fn pois_tails(k: u32, mu: f64) -> (f64, f64) {
    if k == 0 {
        return (1.0, 0.0);
    }
    if mu <= 0.0 {
        return (0.0, 1.0);
    }
    if f64::from(k) > mu {
        let mut term = pois_pmf(k, mu);
        let (mut sum, mut j) = (0.0, k);
        loop {
            sum += term;
            if term < sum * 1e-18 || term == 0.0 {
                break;
            }
            j += 1;
            term *= mu / f64::from(j);
        }
        (sum, 1.0 - sum)
    } else {
        let mut j = k - 1;
        let mut term = pois_pmf(j, mu);
        let mut sum = 0.0;
        loop {
            sum += term;
            if j == 0 || term < sum * 1e-18 {
                break;
            }
            term *= f64::from(j) / mu;
            j -= 1;
        }
        (1.0 - sum, sum)
    }
}

const LN_SQRT_2PI: f64 = 0.918_938_533_204_672_8;

/// `ln n! − ln(√(2πn)·(n/e)^n)` for an integer n ≥ 1: directly below 16, else its
/// asymptotic series (as R's `stirlerr`).
fn stirlerr(n: f64) -> f64 {
    const S0: f64 = 1.0 / 12.0;
    const S1: f64 = 1.0 / 360.0;
    const S2: f64 = 1.0 / 1260.0;
    const S3: f64 = 1.0 / 1680.0;
    const S4: f64 = 1.0 / 1188.0;
    if n <= 15.0 {
        let fact: f64 = (1..=n as u64).map(|i| i as f64).product();
        return fact.ln() - (n + 0.5) * n.ln() + n - LN_SQRT_2PI;
    }
    let nn = n * n;
    if n > 500.0 {
        (S0 - S1 / nn) / n
    } else if n > 80.0 {
        (S0 - (S1 - S2 / nn) / nn) / n
    } else if n > 35.0 {
        (S0 - (S1 - (S2 - S3 / nn) / nn) / nn) / n
    } else {
        (S0 - (S1 - (S2 - (S3 - S4 / nn) / nn) / nn) / nn) / n
    }
}

/// `x·ln(x/np) + np − x`, accurately where x ≈ np (Loader 2000).
fn bd0(x: f64, np: f64) -> f64 {
    if (x - np).abs() < 0.1 * (x + np) {
        let mut v = (x - np) / (x + np);
        let mut s = (x - np) * v;
        let mut ej = 2.0 * x * v;
        v *= v;
        for j in 1..1000 {
            ej *= v;
            let s1 = s + ej / f64::from(2 * j + 1);
            if s1 == s {
                return s1;
            }
            s = s1;
        }
        return s;
    }
    x * (x / np).ln() + np - x
}

/// `P(Bin(n, p) = x)` with `q = 1 − p` given apart (for p near 1), by Loader's
/// saddle-point form.
pub(crate) fn binom_pmf(n: u32, x: u32, p: f64, q: f64) -> f64 {
    if x > n {
        return 0.0;
    }
    if p <= 0.0 {
        return if x == 0 { 1.0 } else { 0.0 };
    }
    if q <= 0.0 {
        return if x == n { 1.0 } else { 0.0 };
    }
    let (n, x) = (f64::from(n), f64::from(x));
    if x == 0.0 {
        let lc = if p < 0.1 {
            -bd0(n, n * q) - n * p
        } else {
            n * q.ln()
        };
        return lc.exp();
    }
    if x == n {
        let lc = if q < 0.1 {
            -bd0(n, n * p) - n * q
        } else {
            n * p.ln()
        };
        return lc.exp();
    }
    let lc = stirlerr(n) - stirlerr(x) - stirlerr(n - x) - bd0(x, n * p) - bd0(n - x, n * q);
    let lf = 2.0 * LN_SQRT_2PI + x.ln() + (-x / n).ln_1p();
    (lc - 0.5 * lf).exp()
}

/// `(P(Bin(n, p) ≥ k), P(Bin(n, p) < k))`, the smaller summed term by term from `k`
/// outwards (relative precision ~1e-14), the other its complement.
pub(crate) fn binom_tails(n: u32, k: u32, p: f64, q: f64) -> (f64, f64) {
    if k == 0 {
        return (1.0, 0.0);
    }
    if k > n {
        return (0.0, 1.0);
    }
    if p <= 0.0 {
        return (0.0, 1.0);
    }
    if q <= 0.0 {
        return (1.0, 0.0);
    }
    let ratio = p / q;
    if f64::from(k) > f64::from(n) * p {
        // upper tail, terms decreasing from k
        let mut term = binom_pmf(n, k, p, q);
        let mut sum = 0.0;
        let mut j = k;
        loop {
            sum += term;
            if j == n || term < sum * 1e-18 {
                break;
            }
            term *= f64::from(n - j) / f64::from(j + 1) * ratio;
            j += 1;
        }
        (sum, 1.0 - sum)
    } else {
        // lower tail, terms decreasing from k − 1 down
        let mut j = k - 1;
        let mut term = binom_pmf(n, j, p, q);
        let mut sum = 0.0;
        loop {
            sum += term;
            if j == 0 || term < sum * 1e-18 {
                break;
            }
            term *= f64::from(j) / f64::from(n - j + 1) / ratio;
            j -= 1;
        }
        (1.0 - sum, sum)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Loader's binomial PMF against the direct product for small n (exact factorials)
    /// and against the recurrence from P(0) for n = 600: relative 1e-12.
    #[test]
    fn binomial_probabilities_are_accurate() {
        for (n, p) in [(10u32, 0.3f64), (17, 0.9), (40, 0.01)] {
            let mut c = 1.0f64;
            for x in 0..=n {
                if x > 0 {
                    c = c * f64::from(n - x + 1) / f64::from(x);
                }
                let want = c * p.powi(x as i32) * (1.0 - p).powi((n - x) as i32);
                let got = binom_pmf(n, x, p, 1.0 - p);
                assert!(
                    (got / want - 1.0).abs() < 1e-12,
                    "n {n} x {x}: {got} vs {want}"
                );
            }
        }
        let (n, p) = (600u32, 0.49f64);
        let mut want = (1.0 - p).powi(600);
        let mut total = 0.0f64;
        for x in 0..=n {
            if x > 0 {
                want *= f64::from(n - x + 1) / f64::from(x) * p / (1.0 - p);
            }
            total += want;
            if want > 1e-250 {
                let got = binom_pmf(n, x, p, 1.0 - p);
                assert!((got / want - 1.0).abs() < 1e-11, "x {x}: {got} vs {want}");
            }
        }
        assert!((total - 1.0).abs() < 1e-12);
        let (ge, lt) = binom_tails(n, 300, p, 1.0 - p);
        assert!((ge + lt - 1.0).abs() < 1e-15);
    }
}
