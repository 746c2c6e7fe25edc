//! exploration
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.get(1).map(|s| s.as_str()) == Some("explore") {
        for e in [
            -6.0f64, -3.0, -1.0, -0.5, -0.3, 0.0, 0.3, 0.5, 1.0, 1.5, 2.0, 3.0, 4.0, 5.0, 6.0,
        ] {
            let mu = 10f64.powf(e);
            let t = Instant::now();
            let (ks, k) = approx::ks_sum(mu);
            println!(
                "sum   mu={mu:.3e} ks={ks:.6e} s={:.6} z*={:.3} k*={k} {:?}",
                ks * mu.sqrt(),
                (k + 0.5 - mu) / mu.sqrt(),
                t.elapsed()
            );
        }
        for e in [4.0f64, 5.0, 6.0, 7.0, 9.0, 12.0, 15.0] {
            let mu = 10f64.powf(e);
            let t = Instant::now();
            let (ks, k) = approx::ks_smooth(mu);
            println!(
                "smooth mu={mu:.3e} ks={ks:.9e} s={:.9} z*={:.4} {:?}",
                ks * mu.sqrt(),
                (k + 0.5 - mu) / mu.sqrt(),
                t.elapsed()
            );
        }
        println!("c = {:.9}", approx::KS_ASYMPTOTE);
    }
    if args.get(1).map(|s| s.as_str()) == Some("sweep") {
        let c = approx::KS_ASYMPTOTE;
        let t = Instant::now();
        let mut pts: Vec<(f64, f64)> = Vec::new();
        let segs = [(-3.0, -1.0, 2000), (-1.0, 2.0, 20000), (2.0, 4.0, 2000), (4.0, 6.0, 200)];
        for (a, b, per) in segs {
            let n = ((b - a) * per as f64) as usize;
            for i in 0..n {
                let mu = 10f64.powf(a + (b - a) * i as f64 / n as f64);
                pts.push((mu, approx::ks_sum(mu).0));
            }
        }
        eprintln!("sum part {:?}", t.elapsed());
        for i in 0..=180 {
            let mu = 10f64.powf(6.0 + 9.0 * i as f64 / 180.0);
            pts.push((mu, approx::ks_smooth(mu).0));
        }
        eprintln!("all {:?}", t.elapsed());
        // last mu where s > c
        let mut last = 0.0;
        let mut maxks: f64 = 0.0;
        for &(mu, ks) in &pts { if ks * mu.sqrt() > c { last = mu; } maxks = maxks.max(ks); }
        println!("last crossing mu = {last:.6}, max ks = {maxks:.6}");
        for &(lo, hi) in &[(1.0, 10.0), (10.0, 100.0), (100.0, 1e4), (1e4, 1e6), (1e6, 1e9), (1e9, 1e12), (1e12, 1.01e15)] {
            let m = pts.iter().filter(|p| p.0 >= lo && p.0 < hi).map(|p| p.1 * p.0.sqrt() / c).fold(0.0f64, f64::max);
            let mn = pts.iter().filter(|p| p.0 >= lo && p.0 < hi).map(|p| p.1 * p.0.sqrt() / c).fold(9.0f64, f64::min);
            println!("[{lo:e},{hi:e}) s/c in [{mn:.9}, {m:.9}]");
        }
        for &(mu, ks) in pts.iter().filter(|p| p.0 > 0.3 && p.0 < 1.5).step_by(300) { println!("{mu:.4} {ks:.5} {:.5}", ks*mu.sqrt()/c); }
        for &(mu, ks) in pts.iter().filter(|p| p.0 >= 1e6).step_by(10) { println!("{mu:.3e} {:.4e} s/c-1 = {:.3e}", ks, ks*mu.sqrt()/c - 1.0); }
    }
}

#[allow(dead_code)]
mod approx {
    use std::f64::consts::{PI, SQRT_2};

    use statrs::function::erf::erfc;
    use statrs::function::gamma::ln_gamma;

    pub const KS_SUM_MAX: f64 = 1e6;
    const SQRT_2PI: f64 = 2.506_628_274_631_000_5;
    pub const KS_ASYMPTOTE: f64 = 1.0 / (6.0 * SQRT_2PI);

    fn stirlerr(n: f64) -> f64 {
        if n <= 15.0 {
            ln_gamma(n + 1.0) - (n + 0.5) * n.ln() + n - 0.5 * (2.0 * PI).ln()
        } else {
            const S0: f64 = 1.0 / 12.0;
            const S1: f64 = 1.0 / 360.0;
            const S2: f64 = 1.0 / 1260.0;
            const S3: f64 = 1.0 / 1680.0;
            const S4: f64 = 1.0 / 1188.0;
            let nn = n * n;
            (S0 - (S1 - (S2 - (S3 - S4 / nn) / nn) / nn) / nn) / n
        }
    }

    fn bd0(x: f64, np: f64) -> f64 {
        if (x - np).abs() < 0.1 * (x + np) {
            let v = (x - np) / (x + np);
            let mut s = (x - np) * v;
            let mut ej = 2.0 * x * v;
            let v2 = v * v;
            for j in 1..200 {
                ej *= v2;
                let s1 = s + ej / (2 * j + 1) as f64;
                if s1 == s {
                    return s1;
                }
                s = s1;
            }
            s
        } else {
            x * (x / np).ln() + np - x
        }
    }

    pub fn pmf(k: f64, mu: f64) -> f64 {
        if k == 0.0 {
            (-mu).exp()
        } else {
            (-stirlerr(k) - bd0(k, mu)).exp() / (2.0 * PI * k).sqrt()
        }
    }

    pub fn phi(z: f64) -> f64 {
        0.5 * erfc(-z / SQRT_2)
    }

    pub fn ks_sum(mu: f64) -> (f64, f64) {
        let s = mu.sqrt();
        let k_lo = (mu - 40.0 * s - 5.0).floor().max(0.0);
        let k_hi = (mu + 40.0 * s + 40.0).ceil();
        let (mut sum, mut comp) = (0.0f64, 0.0f64);
        let mut best = (0.0, k_lo);
        let mut k = k_lo;
        while k <= k_hi {
            let p = pmf(k, mu);
            let t = sum + p;
            if sum.abs() >= p.abs() {
                comp += (sum - t) + p;
            } else {
                comp += (p - t) + sum;
            }
            sum = t;
            let d = (sum + comp - phi((k + 0.5 - mu) / s)).abs();
            if d > best.0 {
                best = (d, k);
            }
            k += 1.0;
        }
        best
    }

    fn gl16() -> &'static [(f64, f64)] {
        static NODES: std::sync::OnceLock<Vec<(f64, f64)>> = std::sync::OnceLock::new();
        NODES.get_or_init(|| gauss_legendre(16))
    }

    fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
        let mut out = Vec::with_capacity(n);
        for i in 1..=n {
            let mut x = (PI * (i as f64 - 0.25) / (n as f64 + 0.5)).cos();
            let mut dp = 1.0;
            for _ in 0..100 {
                let (mut p0, mut p1) = (1.0, x);
                for j in 2..=n {
                    let p2 = ((2 * j - 1) as f64 * x * p1 - (j - 1) as f64 * p0) / j as f64;
                    p0 = p1;
                    p1 = p2;
                }
                dp = n as f64 * (x * p1 - p0) / (x * x - 1.0);
                let dx = p1 / dp;
                x -= dx;
                if dx.abs() < 1e-16 {
                    break;
                }
            }
            out.push((x, 2.0 / ((1.0 - x * x) * dp * dp)));
        }
        out
    }

    /// `κ·(−ln(1−y) − y)`, `y = d/κ`: minus the log of `t^κ e^{-t}/(κ^κ e^{-κ})` at `t = κ − d`.
    fn bd0_shift(kappa: f64, d: f64) -> f64 {
        let y = d / kappa;
        if y.abs() < 0.1 {
            let mut term = y * y;
            let mut s = 0.5 * term;
            for j in 3..100 {
                term *= y;
                let s1 = s + term / j as f64;
                if s1 == s {
                    break;
                }
                s = s1;
            }
            kappa * s
        } else {
            kappa * (-(-y).ln_1p() - y)
        }
    }

    /// Q(κ+1, x) = P(Poisson(x) ≤ κ) = ∫_x^∞ t^κ e^{-t}/Γ(κ+1) dt, κ > 15.
    pub fn gamma_q_int(kappa: f64, x: f64) -> f64 {
        let sk = kappa.sqrt();
        let h = 0.5 * sk;
        let d0 = kappa - x; // t = x + u  ⇒  κ − t = d0 − u
        let top = d0.max(0.0) + 14.0 * sk;
        let panels = (top / h).ceil().max(1.0) as usize;
        let nodes = gl16();
        let norm = -stirlerr(kappa);
        let pre = 1.0 / (2.0 * PI * kappa).sqrt();
        let mut sum = 0.0;
        for p in 0..panels {
            let mid = (p as f64 + 0.5) * h;
            let mut part = 0.0;
            for &(v, w) in nodes {
                let u = mid + 0.5 * h * v;
                part += w * (norm - bd0_shift(kappa, d0 - u)).exp();
            }
            sum += 0.5 * h * part;
        }
        sum * pre
    }

    pub fn ks_smooth(mu: f64) -> (f64, f64) {
        let s = mu.sqrt();
        let dreal = |k: f64| (gamma_q_int(k, mu) - phi((k + 0.5 - mu) / s)).abs();
        let n = 320usize;
        let ks: Vec<f64> = (0..=n)
            .map(|j| (mu - 0.5 + (-8.0 + 16.0 * j as f64 / n as f64) * s).round())
            .collect();
        let vals: Vec<f64> = ks.iter().map(|&k| dreal(k)).collect();
        let mut best = (0.0, ks[0]);
        for j in 0..=n {
            if vals[j] > best.0 {
                best = (vals[j], ks[j]);
            }
        }
        let mut peaks: Vec<usize> = (1..n)
            .filter(|&j| vals[j] >= vals[j - 1] && vals[j] >= vals[j + 1])
            .collect();
        peaks.sort_by(|&a, &b| vals[b].total_cmp(&vals[a]));
        for &j in peaks.iter().take(3) {
            let (mut a, mut b) = (ks[j - 1], ks[j + 1]);
            let g = 0.5 * (5f64.sqrt() - 1.0);
            let mut c = b - g * (b - a);
            let mut d = a + g * (b - a);
            let (mut fc, mut fd) = (dreal(c), dreal(d));
            for _ in 0..60 {
                if fc > fd {
                    b = d;
                    d = c;
                    fd = fc;
                    c = b - g * (b - a);
                    fc = dreal(c);
                } else {
                    a = c;
                    c = d;
                    fc = fd;
                    d = a + g * (b - a);
                    fd = dreal(d);
                }
                if b - a < 0.5 {
                    break;
                }
            }
            let m = 0.5 * (a + b);
            for k in [m.floor() - 1.0, m.floor(), m.ceil(), m.ceil() + 1.0] {
                let v = dreal(k);
                if v > best.0 {
                    best = (v, k);
                }
            }
        }
        best
    }
}
