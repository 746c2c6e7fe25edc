//! Statistical and determinism tests of the samplers.
//!
//! Over 700 lines on purpose: one file of tests, read test by test (each states its
//! false-alarm rate and the wrong sampler it rejects), sharing the reference PMFs and
//! goodness-of-fit helpers at its top; cutting it would split those helpers from their users.
//!
//! Every statistical check uses a fixed seed, so the suite is deterministic;
//! the false-alarm rate stated beside each check is the probability that a
//! *correct* sampler fails it for a random seed (normal approximation for the
//! z-tests: P(|z| > 5) = 5.7e-7; chi-square p-value threshold 1e-6). Beside it each
//! check shows its power on the same draws: the same statistic rejects a model whose
//! mean is off by 1 % (or the 10–15 standard errors the draws resolve, stated) and whose
//! variance is off by 10 % (`assert_poisson_moments`, `assert_poisson_fit`).

use rand_pcg::Pcg64Mcg;
use statrs::distribution::{ChiSquared, ContinuousCDF, Discrete, Poisson as PoissonPmf};

use super::alias::AliasTable;
use super::table::{poisson_pmf, tail_thresholds};
use super::*;

/// |z| above this fails a z-test: false alarm 5.7e-7 per check.
const Z_MAX: f64 = 5.0;
/// Chi-square p-value below this fails: false alarm 1e-6 per check.
const P_MIN: f64 = 1e-6;

/// Every λ the brief lists, through each path.
const LAMBDAS: [f64; 9] = [0.0, 1e-300, 1e-4, 0.01, 0.5, 3.0, 10.0, 30.0, 100.0];

/// Histogram of single-shot per-bin counts (`hist[k]` = number of (shot, bin)
/// samples with count k), drawn with `for_each_shot` so zero bins cost nothing.
fn shot_histogram(sampler: &ShotSampler, rng: &mut Pcg64Mcg, shots: u64) -> Vec<u64> {
    let mut hist = vec![0u64; 8];
    let mut nonzero = 0u64;
    sampler.for_each_shot(rng, shots, |s| {
        for (_, c) in s.nonzero() {
            let c = c as usize;
            if c >= hist.len() {
                hist.resize(c + 1, 0);
            }
            hist[c] += 1;
            nonzero += 1;
        }
    });
    hist[0] = shots * sampler.bins() as u64 - nonzero;
    hist
}

/// z-scores of the sample mean and variance against Poisson(λ) (n samples).
fn moment_z(hist: &[u64], lambda: f64) -> (f64, f64) {
    let n: f64 = hist.iter().sum::<u64>() as f64;
    let (mut s1, mut s2) = (0.0f64, 0.0f64);
    for (k, &h) in hist.iter().enumerate() {
        let k = k as f64;
        s1 += h as f64 * k;
        s2 += h as f64 * k * k;
    }
    let mean = s1 / n;
    let var = s2 / n - mean * mean;
    let z_mean = (mean - lambda) / (lambda / n).sqrt();
    // Var of the sample variance of a Poisson: (μ4 - σ⁴)/n = (λ + 2λ²)/n.
    let z_var = (var - lambda) / ((lambda + 2.0 * lambda * lambda) / n).sqrt();
    (z_mean, z_var)
}

/// Chi-square goodness of fit of a histogram to Poisson(λ), cells with an
/// expected count < 5 pooled with their neighbours (left to right; the last
/// cell is the upper tail P(K ≥ k)). Returns (statistic, degrees of freedom, p-value).
fn chi_square_poisson(hist: &[u64], lambda: f64) -> (f64, usize, f64) {
    let n: f64 = hist.iter().sum::<u64>() as f64;
    let pois = PoissonPmf::new(lambda).unwrap();
    // Cells 0..kmax-1 and the tail K >= kmax, kmax past both the data and the bulk.
    let kmax = hist
        .len()
        .max((lambda + 12.0 * lambda.sqrt() + 12.0) as usize);
    let mut exp: Vec<f64> = (0..kmax).map(|k| n * pois.pmf(k as u64)).collect();
    let head: f64 = exp.iter().sum();
    exp.push((n - head).max(0.0));
    let mut obs: Vec<f64> = (0..=kmax)
        .map(|k| *hist.get(k).unwrap_or(&0) as f64)
        .collect();
    obs[kmax] += hist.iter().skip(kmax + 1).sum::<u64>() as f64;
    let (mut cells_o, mut cells_e) = (Vec::new(), Vec::new());
    let (mut o, mut e) = (0.0, 0.0);
    for k in 0..=kmax {
        o += obs[k];
        e += exp[k];
        if e >= 5.0 {
            cells_o.push(o);
            cells_e.push(e);
            o = 0.0;
            e = 0.0;
        }
    }
    if let (Some(lo), Some(le)) = (cells_o.last_mut(), cells_e.last_mut()) {
        *lo += o;
        *le += e;
    }
    let stat: f64 = cells_o
        .iter()
        .zip(&cells_e)
        .map(|(o, e)| (o - e) * (o - e) / e)
        .sum();
    let df = cells_o.len() - 1;
    let p = ChiSquared::new(df as f64).unwrap().sf(stat);
    (stat, df, p)
}

/// z-scores of the sample mean and variance of `hist` against a model of mean `mean`
/// and variance `var`, their standard errors those of Poisson(λ) draws.
fn moment_z_against(hist: &[u64], lambda: f64, mean: f64, var: f64) -> (f64, f64) {
    let (zm, zv) = moment_z(hist, lambda);
    let n: f64 = hist.iter().sum::<u64>() as f64;
    let sd_mean = (lambda / n).sqrt();
    let sd_var = ((lambda + 2.0 * lambda * lambda) / n).sqrt();
    (zm - (mean - lambda) / sd_mean, zv - (var - lambda) / sd_var)
}

/// The moment z-tests pass on `hist` (false alarm 5.7e-7 each) and have power: the same
/// statistics reject, on the same draws, a model whose mean is off by
/// `δm = max(1 %, 10/√(nλ))` and one whose variance is off by
/// `δv = max(10 %, 10·sd(s²)/λ)`, either way (with |z| < 5 on the right model, a shift
/// of 10 standard errors always rejects; a sampler off by that much fails with
/// probability > 1 − 1e-6). Returns (δm, δv), the sizes it is shown to catch.
fn assert_poisson_moments(hist: &[u64], lambda: f64, what: &str) -> (f64, f64) {
    let (zm, zv) = moment_z(hist, lambda);
    assert!(
        zm.abs() < Z_MAX && zv.abs() < Z_MAX,
        "{what}: λ={lambda}: z_mean={zm:.2}, z_var={zv:.2}"
    );
    let n: f64 = hist.iter().sum::<u64>() as f64;
    let dm = (10.0 / (n * lambda).sqrt()).max(0.01);
    let dv = (10.0 * ((lambda + 2.0 * lambda * lambda) / n).sqrt() / lambda).max(0.1);
    for sign in [-1.0, 1.0] {
        let (zm, _) = moment_z_against(hist, lambda, lambda * (1.0 + sign * dm), lambda);
        let (_, zv) = moment_z_against(hist, lambda, lambda, lambda * (1.0 + sign * dv));
        assert!(
            zm.abs() > Z_MAX && zv.abs() > Z_MAX,
            "{what}: λ={lambda}: no power at a mean off by {dm:.3} (z {zm:.1}) or a variance off by {dv:.3} (z {zv:.1})"
        );
    }
    (dm, dv)
}

/// The chi-square test passes on `hist` (false alarm 1e-6) and has power: on the same
/// draws it rejects Poisson(λ·(1 ± δ)), `δ = max(1 %, 15/√(nλ))` (noncentrality ≈
/// nλδ² ≥ 225). Returns δ.
fn assert_poisson_fit(hist: &[u64], lambda: f64, what: &str) -> f64 {
    let (stat, df, p) = chi_square_poisson(hist, lambda);
    assert!(
        p > P_MIN,
        "{what}: λ={lambda}: chi2={stat:.1}, df={df}, p={p:.2e}"
    );
    let n: f64 = hist.iter().sum::<u64>() as f64;
    let d = (15.0 / (n * lambda).sqrt()).max(0.01);
    for sign in [-1.0, 1.0] {
        let (stat, df, p) = chi_square_poisson(hist, lambda * (1.0 + sign * d));
        assert!(
            p < P_MIN,
            "{what}: λ={lambda}: no power at a mean off by {d:.3}: chi2={stat:.1}, df={df}, p={p:.2e}"
        );
    }
    d
}

/// Shots so that a λ gets ≥ ~2e6 (shot, bin) samples and ≥ ~2e4 counts.
fn shots_for(lambda: f64, bins: usize) -> u64 {
    let samples = (2e6f64).max(2e4 / lambda.max(1e-300)).min(2e8);
    (samples / bins as f64).ceil() as u64
}

// ---------------------------------------------------------------- building blocks

#[test]
fn tail_thresholds_edge_cases() {
    // Deterministic checks (no false alarm).
    assert!(tail_thresholds(0.0).is_empty());
    assert!(tail_thresholds(1e-300).is_empty());
    assert!(tail_thresholds(5e-20).is_empty()); // P(K>=1) < 2^-64
    let t = tail_thresholds(1e-4);
    let q1 = -(-1e-4f64).exp_m1();
    assert!(((t[0] as f64) / 2f64.powi(64) - q1).abs() < 1e-19);
    for l in [0.3, 3.0, 16.0, 100.0, 600.0] {
        let t = tail_thresholds(l);
        assert!(
            t.windows(2).all(|w| w[0] >= w[1]),
            "non-increasing for λ={l}"
        );
        // E[K] = Σ_j P(K >= j)
        let mean: f64 = t.iter().map(|&x| x as f64 / 2f64.powi(64)).sum();
        assert!(
            (mean - l).abs() < 1e-12 * l.max(1.0),
            "λ={l}: table mean {mean}"
        );
    }
}

/// Deterministic: [`PmfAlias`] (the dense alias path and the sparse path's shot total)
/// realises P(K = k) to within 1e-15 absolute of the forward-recurrence PMF up to
/// λ = 512; up to λ = 10^6, to within 1e-8 relative plus 2^-60 absolute (the table's
/// integer weights are units of 2^-64) of statrs' PMF (whose log-gamma form is itself
/// off by ~1e-10 relative at λ = 4·10^4, against mpmath), and with successive cells
/// above 1e-6 in the ratio λ/(k+1) to 1e-11; mean λ and variance λ; a table built for 1.001·λ is told
/// apart (its mean is off by 0.1 %).
#[test]
fn pmf_alias_realises_poisson() {
    for l in [
        1e-6,
        0.07,
        0.7,
        11.48,
        100.0,
        TOTAL_TABLE_MAX,
        1e4,
        4e4,
        1e6,
    ] {
        let (k0, w) = super::pmf_alias::pmf_window(l);
        let len = k0 as usize + w.len();
        let p = PmfAlias::new(l).probabilities(len);
        let exact = PoissonPmf::new(l).unwrap();
        let small = (l <= 600.0).then(|| poisson_pmf(l));
        let (mut mean, mut second) = (0.0, 0.0);
        for (k, &pk) in p.iter().enumerate() {
            match &small {
                Some(pmf) => {
                    let want = pmf.get(k).copied().unwrap_or(0.0);
                    assert!((pk - want).abs() < 1e-15, "λ={l}, k={k}: {pk} vs {want}");
                }
                None => {
                    let want = exact.pmf(k as u64);
                    let tol = 1e-8 * want + (2.0f64).powi(-60);
                    assert!((pk - want).abs() < tol, "λ={l}, k={k}: {pk} vs {want}");
                    if pk > 1e-6 && p[k + 1] > 1e-6 {
                        let ratio = p[k + 1] / pk * (k + 1) as f64 / l;
                        assert!((ratio - 1.0).abs() < 1e-11, "λ={l}, k={k}: ratio {ratio}");
                    }
                }
            }
            mean += k as f64 * pk;
            second += (k as f64 - l).powi(2) * pk;
        }
        assert!((mean - l).abs() < 1e-12 * l.max(1.0), "λ={l}: mean {mean}");
        assert!(
            (second - l).abs() < 1e-9 * l.max(1.0),
            "λ={l}: variance {second}"
        );
        // power: the table of a 0.1 % larger mean has a visibly larger mean
        if l >= 0.07 {
            let (q0, qw) = super::pmf_alias::pmf_window(l * 1.001);
            let q = PmfAlias::new(l * 1.001).probabilities(q0 as usize + qw.len());
            let wrong: f64 = q.iter().enumerate().map(|(k, &x)| k as f64 * x).sum();
            assert!(wrong - l > 0.5e-3 * l, "λ={l}: {wrong}");
        }
    }
}

/// Deterministic: [`PmfCells`] (rejection from a step envelope) realises the PMF window
/// of [`PmfAlias`] (the same recurrence, normalised) to within 1e-12 relative plus
/// 2^-60 absolute, from a mean whose cells are single counts (λ = 30) to cells of 2^11
/// counts (λ = 10^8); a sampler built for 1.001·λ is told apart by its mean.
#[test]
fn pmf_cells_realise_the_pmf_window() {
    for l in [30.0, 1e3, 4e4, 1e6, 1e8] {
        let (k0, w) = super::pmf_alias::pmf_window(l);
        let len = k0 as usize + w.len();
        let total: f64 = w.iter().sum();
        let p = PmfCells::new(l).probabilities(len);
        let mut mean = 0.0;
        for (k, &pk) in p.iter().enumerate() {
            let want = if k < k0 as usize {
                0.0
            } else {
                w[k - k0 as usize] / total
            };
            let tol = 1e-12 * want + (2.0f64).powi(-60);
            assert!((pk - want).abs() < tol, "λ={l}, k={k}: {pk} vs {want}");
            mean += k as f64 * pk;
        }
        assert!((mean - l).abs() < 1e-11 * l, "λ={l}: mean {mean}");
        let q = PmfCells::new(l * 1.001).probabilities(len + len / 50);
        let wrong: f64 = q.iter().enumerate().map(|(k, &x)| k as f64 * x).sum();
        assert!(wrong - l > 0.5e-3 * l, "λ={l}: {wrong}");
    }
}

/// The draws of [`PmfCells`] fit Poisson(λ) (chi-square and moments, 2·10^5 draws at
/// λ = 30, 10^3, 10^5), and a sampler of 1.001·λ fails the same checks at 10^3 and 10^5
/// (its mean is off by 14 and 141 standard errors). False alarm: 9 checks at ≤ 1e-6 →
/// 5e-6.
#[test]
fn pmf_cells_draws_fit_poisson() {
    let draws = |l: f64, seed: u64| {
        let s = PmfCells::new(l);
        let mut rng = stream_rng(6000, seed, 0);
        let mut hist = vec![0u64; (l + 12.0 * l.sqrt() + 12.0) as usize];
        for _ in 0..200_000 {
            let k = s.sample(&mut rng) as usize;
            if k >= hist.len() {
                hist.resize(k + 1, 0);
            }
            hist[k] += 1;
        }
        hist
    };
    for (j, l) in [30.0, 1e3, 1e5].into_iter().enumerate() {
        let hist = draws(l, j as u64);
        assert_poisson_moments(&hist, l, "PmfCells");
        assert_poisson_fit(&hist, l, "PmfCells");
        if l >= 1e3 {
            let wrong = draws(l * 1.001, j as u64);
            let (zm, _) = moment_z(&wrong, l);
            assert!(zm > Z_MAX, "λ={l}: a 0.1 % mean error gave z = {zm:.1}");
        }
    }
}

#[test]
fn alias_table_realises_weights() {
    // Deterministic: integer construction, probabilities within (n+1)·2^-64.
    let w = [3.0, 0.0, 1e-12, 7.5, 0.25, 1e-3];
    let ids: Vec<u32> = (0..w.len() as u32).collect();
    let t = AliasTable::new(&w, &ids);
    let p = t.probabilities(w.len());
    let total: f64 = w.iter().sum();
    for i in 0..w.len() {
        assert!(
            (p[i] - w[i] / total).abs() < 1e-15,
            "bin {i}: {} vs {}",
            p[i],
            w[i] / total
        );
    }
    // One bin: every draw lands on it.
    let t = AliasTable::new(&[0.5], &[42]);
    for x in [0, 1, u64::MAX, 1 << 63] {
        assert_eq!(t.bin_for(x), 42);
    }
}

// ---------------------------------------------------------------- shot sampler

/// Mean and variance of single-shot per-bin counts against Poisson, for every
/// λ in LAMBDAS, through the dense and the sparse path (and Auto).
/// False alarm: 2 z-tests × 7 non-trivial λ × 3 paths = 42 checks at 5.7e-7 → 2.4e-5.
/// Power (`assert_poisson_moments`, on the same draws): a 10 % variance change at every
/// λ, a 1 % mean bias from λ = 0.5 up (below, 10/√(nλ): 7 % at λ = 1e-4 and 0.01).
#[test]
fn shot_moments_all_paths() {
    const BINS: usize = 100;
    for (pi, choice) in [
        PathChoice::AllDense,
        PathChoice::AllSparse,
        PathChoice::Auto,
    ]
    .into_iter()
    .enumerate()
    {
        for (li, &l) in LAMBDAS.iter().enumerate() {
            let s = ShotSampler::with_choice(&[l; BINS], choice);
            let mut rng = stream_rng(1000 + pi as u64, li as u64, 0);
            let shots = if l == 0.0 || l < 1e-200 {
                10_000
            } else {
                shots_for(l, BINS)
            };
            let hist = shot_histogram(&s, &mut rng, shots);
            let what = format!("{choice:?} ({})", s.strategy());
            if l < 1e-200 {
                // Exact: zero counts, never NaN (deterministic, no false alarm).
                assert_eq!(hist[0], shots * BINS as u64, "{what}");
                assert_eq!(s.strategy().kind, StrategyKind::Empty);
                continue;
            }
            let (dm, dv) = assert_poisson_moments(&hist, l, &what);
            assert!(dv <= 0.1 + 1e-12, "{what}: λ={l}: resolves only {dv:.3}");
            if l >= 0.5 {
                assert!(dm <= 0.01 + 1e-12, "{what}: λ={l}: resolves only {dm:.3}");
            }
        }
    }
}

/// Chi-square goodness of fit of single-shot counts, both paths, a few λ
/// (incl. the sparse total drawn by Ahrens–Dieter: 100 bins × 3 = 300 > TOTAL_TABLE_MAX).
/// False alarm: 12 tests at 1e-6 → 1.2e-5. Power (`assert_poisson_fit`): each rejects
/// a mean 1 % off from λ = 3 up (below, 15/√(nλ): 1.5 % at λ = 0.5, 2.7 % at 0.15,
/// 11 % at 0.01).
#[test]
fn shot_chi_square() {
    const BINS: usize = 100;
    for (pi, choice) in [PathChoice::AllDense, PathChoice::AllSparse]
        .into_iter()
        .enumerate()
    {
        for (li, &l) in [0.01, 0.15, 0.5, 3.0, 10.0, 30.0].iter().enumerate() {
            let s = ShotSampler::with_choice(&[l; BINS], choice);
            let mut rng = stream_rng(2000 + pi as u64, li as u64, 0);
            let hist = shot_histogram(&s, &mut rng, shots_for(l, BINS));
            assert_poisson_fit(&hist, l, &format!("{choice:?} ({})", s.strategy()));
        }
    }
}

/// A non-uniform λ vector (lidar-like, a few strong bins): every bin's total
/// over many shots against its Poisson mean, through Auto (hybrid), dense and
/// sparse. Checks that placement puts each count in the right bin.
/// False alarm: 3 paths × 64 bins z-tests at 5.7e-7 → 1.1e-4. Power: the strong bins'
/// totals (1.25e6 counts) reject a mean 1 % off either way (z ≈ 11) and the
/// neighbouring bin's mean (a count put in the wrong bin).
#[test]
fn shot_per_bin_means_nonuniform() {
    let lambda: Vec<f64> = (0..64)
        .map(|i| {
            if i % 16 == 3 {
                25.0
            } else {
                0.15 * (-(i as f64) / 10.0).exp() + 1e-3
            }
        })
        .collect();
    let shots = 50_000u64;
    for (pi, choice) in [
        PathChoice::Auto,
        PathChoice::AllDense,
        PathChoice::AllSparse,
    ]
    .into_iter()
    .enumerate()
    {
        let s = ShotSampler::with_choice(&lambda, choice);
        let mut acc = vec![0u64; lambda.len()];
        s.add_shots(&mut stream_rng(3000 + pi as u64, 0, 0), shots, &mut acc);
        for (i, (&a, &l)) in acc.iter().zip(&lambda).enumerate() {
            let mu = l * shots as f64;
            let z = (a as f64 - mu) / mu.sqrt();
            assert!(
                z.abs() < Z_MAX,
                "{choice:?} bin {i}: λ={l}, got {a}, expected {mu:.1} (z={z:.2})"
            );
            // power: a strong bin 1 % off, or a count in the neighbouring bin's place
            if l >= 25.0 {
                for wrong in [1.01 * mu, 0.99 * mu, lambda[i + 1] * shots as f64] {
                    let z = (a as f64 - wrong) / wrong.sqrt();
                    assert!(z.abs() > Z_MAX, "{choice:?} bin {i}: no power (z={z:.2})");
                }
            }
        }
    }
    assert_eq!(
        ShotSampler::new(&lambda).strategy().kind,
        StrategyKind::Hybrid
    );
}

/// The test statistics have power: a sampler whose mean is 1 % too high is
/// rejected by the chi-square test (same n and threshold as `shot_chi_square`
/// at λ = 3: noncentrality ≈ n·(0.01λ)²/λ ≈ 600, so a miss has probability
/// < 1e-12), and by the mean z-test (expected z ≈ 24).
/// False alarm (the correct sampler failing the control check): 1e-6 + 5.7e-7.
#[test]
fn wrong_sampler_is_rejected() {
    const BINS: usize = 100;
    let l = 3.0;
    for (pi, choice) in [PathChoice::AllDense, PathChoice::AllSparse]
        .into_iter()
        .enumerate()
    {
        let shots = shots_for(l, BINS);
        let wrong = ShotSampler::with_choice(&[l * 1.01; BINS], choice);
        let hist = shot_histogram(&wrong, &mut stream_rng(4000 + pi as u64, 0, 0), shots);
        let (_, _, p) = chi_square_poisson(&hist, l);
        assert!(
            p < P_MIN,
            "{choice:?}: a 1 % mean error was not detected (p = {p:.2e})"
        );
        let (zm, _) = moment_z(&hist, l);
        assert!(zm > Z_MAX, "{choice:?}: z_mean = {zm:.2}");
        // Control: the right sampler with the same stream passes.
        let right = ShotSampler::with_choice(&[l; BINS], choice);
        let hist = shot_histogram(&right, &mut stream_rng(4000 + pi as u64, 0, 0), shots);
        assert_poisson_fit(&hist, l, "control");
    }
}

/// Continuity across every switch point: λ just below and just above each
/// threshold gives the Poisson law (chi-square against Poisson at the
/// threshold; the laws differ by 2e-9 relative, far below resolution).
/// Switch points: dense table ↔ alias over the PMF (DENSE_TABLE_MAX), alias ↔
/// step-envelope rejection (DENSE_ALIAS_MAX), sparse total table ↔ Ahrens–Dieter
/// (TOTAL_TABLE_MAX), and the Auto dense ↔ sparse split (found from the sampler
/// itself).
/// False alarm: 8 tests at 1e-6 → 8e-6. Power (`assert_poisson_fit`, on the same
/// draws): each rejects a mean off by max(1 %, 15/√(nλ)) either way: 1 % at the
/// DENSE_ALIAS_MAX and TOTAL_TABLE_MAX switches, 13 % at DENSE_TABLE_MAX = 0.07 (4000
/// shots of 50 bins).
#[test]
fn continuity_at_switch_points() {
    let eps = 1e-9;
    let dense = |s: &ShotSampler| {
        let st = s.strategy();
        [
            st.dense_table_bins,
            st.dense_alias_bins,
            st.dense_cells_bins,
            st.dense_pd_bins,
        ]
    };
    for (switch, lo_side) in [(DENSE_TABLE_MAX, 0), (DENSE_ALIAS_MAX, 1)] {
        for (j, l) in [switch * (1.0 - eps), switch * (1.0 + eps)]
            .into_iter()
            .enumerate()
        {
            let s = ShotSampler::with_choice(&[l; 50], PathChoice::AllDense);
            let mut want = [0; 4];
            want[lo_side + j] = 50;
            assert_eq!(dense(&s), want, "{}", s.strategy());
            let hist = shot_histogram(&s, &mut stream_rng(5000, j as u64, lo_side as u64), 4000);
            assert_poisson_fit(&hist, switch, &format!("dense switch {}", s.strategy()));
        }
    }
    // Sparse total table ↔ rand_distr::Poisson: 64 bins with Σλ just around TOTAL_TABLE_MAX.
    for (j, f) in [1.0 - eps, 1.0 + eps].into_iter().enumerate() {
        let l = TOTAL_TABLE_MAX / 64.0 * f;
        let s = ShotSampler::with_choice(&[l; 64], PathChoice::AllSparse);
        let hist = shot_histogram(&s, &mut stream_rng(5001, j as u64, 0), 40_000);
        assert_poisson_fit(
            &hist,
            TOTAL_TABLE_MAX / 64.0,
            &format!("total switch {}", s.strategy()),
        );
    }
    // Auto split: find the λ where a uniform vector of 100 bins flips from sparse to dense.
    let kind = |l: f64| ShotSampler::new(&[l; 100]).strategy().kind;
    let (mut lo, mut hi) = (1e-3, 30.0);
    assert_eq!(kind(lo), StrategyKind::Sparse);
    assert_ne!(kind(hi), StrategyKind::Sparse);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if kind(mid) == StrategyKind::Sparse {
            lo = mid
        } else {
            hi = mid
        }
    }
    for (j, l) in [lo, hi].into_iter().enumerate() {
        let s = ShotSampler::new(&[l; 100]);
        let hist = shot_histogram(&s, &mut stream_rng(5002, j as u64, 0), shots_for(l, 100));
        assert_poisson_fit(
            &hist,
            0.5 * (lo + hi),
            &format!("auto switch {}", s.strategy()),
        );
    }
}

/// `add_shots`, `add_shot` and `for_each_shot` consume the same stream and
/// give the same totals (deterministic).
#[test]
fn shot_forms_agree() {
    let lambda: Vec<f64> = (0..300)
        .map(|i| if i == 7 { 40.0 } else { 0.3 / (1.0 + i as f64) })
        .collect();
    let s = ShotSampler::new(&lambda);
    let mut a = vec![0u64; 300];
    s.add_shots(&mut stream_rng(9, 9, 9), 500, &mut a);
    let mut b = vec![0u64; 300];
    let mut rng = stream_rng(9, 9, 9);
    for _ in 0..500 {
        s.add_shot(&mut rng, &mut b);
    }
    let mut c = vec![0u64; 300];
    s.for_each_shot(&mut stream_rng(9, 9, 9), 500, |shot| {
        assert_eq!(
            shot.total(),
            shot.counts().iter().map(|&x| x as u64).sum::<u64>()
        );
        for (bin, k) in shot.nonzero() {
            c[bin] += k as u64;
        }
    });
    assert_eq!(a, b);
    assert_eq!(a, c);
}

// ---------------------------------------------------------------- determinism

/// shot_profile is identical with 1 and 2 rayon threads, equals the sum of
/// its blocks regenerated alone, and changes with the seed and the profile.
/// Deterministic (the "differs" checks fail with probability ~0).
#[test]
fn shot_profile_deterministic() {
    let lambda: Vec<f64> = (0..500)
        .map(|i| 0.149 * (1.0 + i as f64 / 50.0).powi(-2) + 1e-3)
        .collect();
    let s = ShotSampler::new(&lambda);
    let shots = 3 * SHOT_BLOCK + 1234;
    let run = |threads: usize, seed: u64, profile: u64| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let mut acc = vec![0u64; lambda.len()];
            shot_profile(&s, seed, profile, shots, &mut acc);
            acc
        })
    };
    let one = run(1, 42, 3);
    let two = run(2, 42, 3);
    assert_eq!(one, two);
    // Regenerate each block alone.
    let mut blocks = vec![0u64; lambda.len()];
    for b in 0..shots.div_ceil(SHOT_BLOCK) {
        let n = SHOT_BLOCK.min(shots - b * SHOT_BLOCK);
        s.add_shots(&mut stream_rng(42, 3, b), n, &mut blocks);
    }
    assert_eq!(one, blocks);
    assert_ne!(one, run(2, 43, 3));
    assert_ne!(one, run(2, 42, 4));
    // Accumulates (adds), does not overwrite.
    let mut acc = one.clone();
    shot_profile(&s, 42, 3, shots, &mut acc);
    assert!(acc.iter().zip(&one).all(|(a, b)| *a == 2 * b));
}

#[test]
fn stream_rng_distinct_streams() {
    // Deterministic: nearby triples give unrelated first outputs.
    use rand::Rng;
    let mut seen = std::collections::HashSet::new();
    for seed in 0..4 {
        for profile in 0..16 {
            for block in 0..16 {
                assert!(seen.insert(stream_rng(seed, profile, block).next_u64()));
            }
        }
    }
}

// ---------------------------------------------------------------- aggregate

/// Mean and variance of poisson_u64 for means across every regime
/// (inversion, Ahrens–Dieter, the 2^50 chunking), 2·10⁶ draws below μ = 1, 3·10⁴ above.
/// False alarm: 2 × 15 z-tests at 5.7e-7 → 1.7e-5. Power, shown on the same draws
/// (rejected either way): a variance off by max(10 %, 10 sd) — 10 % from μ = 0.01 up,
/// 71 % at μ = 1e-4; a mean off by max(1 %, 10/√(nμ)) — 1 % at μ = 0.5 and from μ = 100
/// up, 3.3 % at μ = 3, 71 % at μ = 1e-4.
#[test]
fn aggregate_moments() {
    let mut rng = stream_rng(6000, 0, 0);
    assert_eq!(poisson_u64(&mut rng, 0.0), 0);
    assert_eq!(poisson_u64(&mut rng, 1e-300), 0);
    let means = [
        1e-4,
        0.01,
        0.5,
        3.0,
        11.999,
        12.001,
        30.0,
        100.0,
        1e4,
        1e6,
        1e9,
        1e12,
        1e15,
        AGGREGATE_CHUNK * 1.5,
        3e16,
    ];
    for (j, &mu) in means.iter().enumerate() {
        let n: usize = if mu < 1.0 { 2_000_000 } else { 30_000 };
        let mut rng = stream_rng(6001, j as u64, 0);
        let (mut s1, mut s2) = (0.0f64, 0.0f64);
        for _ in 0..n {
            // Center on the integer part of mu to keep f64 sums exact-ish at 3e16.
            let x = poisson_u64(&mut rng, mu) as f64 - mu.floor();
            s1 += x;
            s2 += x * x;
        }
        let nf = n as f64;
        let mean = s1 / nf + mu.floor();
        let var = s2 / nf - (s1 / nf) * (s1 / nf);
        let (sd_m, sd_v) = ((mu / nf).sqrt(), ((mu + 2.0 * mu * mu) / nf).sqrt());
        let zm = (mean - mu) / sd_m;
        let zv = (var - mu) / sd_v;
        assert!(
            zm.abs() < Z_MAX && zv.abs() < Z_MAX,
            "μ={mu:e}: mean {mean}, var {var} (z {zm:.2}, {zv:.2})"
        );
        // power on the same draws: a mean off by max(1 %, 10 sd) and a variance off by
        // max(10 %, 10 sd) are rejected either way
        let dm = (10.0 * sd_m / mu).max(0.01);
        let dv = (10.0 * sd_v / mu).max(0.1);
        for sign in [-1.0, 1.0] {
            let zm = (mean - mu * (1.0 + sign * dm)) / sd_m;
            let zv = (var - mu * (1.0 + sign * dv)) / sd_v;
            assert!(zm.abs() > Z_MAX && zv.abs() > Z_MAX, "μ={mu:e}: no power");
        }
        if mu >= 0.01 {
            assert!(
                dv <= 0.1 + 1e-12,
                "μ={mu:e}: the variance resolves only {dv:.3}"
            );
        }
        if mu >= 100.0 || mu == 0.5 {
            assert!(
                dm <= 0.01 + 1e-12,
                "μ={mu:e}: the mean resolves only {dm:.3}"
            );
        }
    }
}

/// Chi-square of poisson_u64 around its inversion ↔ Ahrens–Dieter switch and
/// for a few small means. False alarm: 5 tests at 1e-6 → 5e-6. Power
/// (`assert_poisson_fit`): a mean 1 % off is rejected at μ ≈ 12 and 50 (1.9 % at μ = 2,
/// 11 % at μ = 0.01).
#[test]
fn aggregate_chi_square() {
    let e = 1e-9;
    for (j, &mu) in [
        0.01,
        2.0,
        AGGREGATE_INVERSION_MAX * (1.0 - e),
        AGGREGATE_INVERSION_MAX * (1.0 + e),
        50.0,
    ]
    .iter()
    .enumerate()
    {
        let mut rng = stream_rng(6100, j as u64, 0);
        let mut hist = vec![0u64; 8];
        let n = if mu < 0.1 { 2_000_000 } else { 300_000 };
        for _ in 0..n {
            let k = poisson_u64(&mut rng, mu) as usize;
            if k >= hist.len() {
                hist.resize(k + 1, 0);
            }
            hist[k] += 1;
        }
        let target = if (mu - AGGREGATE_INVERSION_MAX).abs() < 1e-6 {
            AGGREGATE_INVERSION_MAX
        } else {
            mu
        };
        assert_poisson_fit(&hist, target, "poisson_u64");
    }
}

/// aggregate_profile against the shot path: same law for the profile totals.
/// 64 bins × 2000 profiles of 1000 shots: per-bin mean and variance of the
/// aggregate totals vs Poisson(Mλ). False alarm: 2 × 64 × 2 z-tests and 2 × 2 pooled
/// ones (Σz/8) → 1.5e-4. Power: the pooled z-tests reject, on the same draws, every
/// bin's mean 1 % off and every bin's variance 10 % off, either way.
#[test]
fn aggregate_profile_law() {
    let lambda: Vec<f64> = (0..64)
        .map(|i| 0.2 * (-(i as f64) / 8.0).exp() + 1e-4)
        .collect();
    let shots = 1000u64;
    let profiles = 2000u64;
    let s = ShotSampler::new(&lambda);
    for path in 0..2 {
        let mut s1 = vec![0.0f64; 64];
        let mut s2 = vec![0.0f64; 64];
        for p in 0..profiles {
            let mut acc = vec![0u64; 64];
            if path == 0 {
                aggregate_profile(&lambda, 7000, p, shots, &mut acc);
            } else {
                shot_profile(&s, 7000, p, shots, &mut acc);
            }
            for i in 0..64 {
                s1[i] += acc[i] as f64;
                s2[i] += (acc[i] as f64).powi(2);
            }
        }
        let n = profiles as f64;
        // pooled over the bins: Σz/√64, for the right model and for models 1 % off in
        // the mean or 10 % off in the variance (the shift of each bin's z, pooled)
        let (mut pool_m, mut pool_v, mut shift_m, mut shift_v) = (0.0, 0.0, 0.0, 0.0);
        for i in 0..64 {
            let mu = lambda[i] * shots as f64;
            let mean = s1[i] / n;
            let var = s2[i] / n - mean * mean;
            let (sd_m, sd_v) = ((mu / n).sqrt(), ((mu + 2.0 * mu * mu) / n).sqrt());
            let zm = (mean - mu) / sd_m;
            let zv = (var - mu) / sd_v;
            assert!(
                zm.abs() < Z_MAX && zv.abs() < Z_MAX,
                "path {path} bin {i}: z {zm:.2} {zv:.2}"
            );
            pool_m += zm / 8.0;
            pool_v += zv / 8.0;
            shift_m += 0.01 * mu / sd_m / 8.0;
            shift_v += 0.1 * mu / sd_v / 8.0;
        }
        assert!(
            pool_m.abs() < Z_MAX && pool_v.abs() < Z_MAX,
            "path {path}: pooled z {pool_m:.2} {pool_v:.2}"
        );
        for sign in [-1.0, 1.0] {
            assert!(
                (pool_m - sign * shift_m).abs() > Z_MAX,
                "path {path}: no power at 1 % ({shift_m:.1})"
            );
            assert!(
                (pool_v - sign * shift_v).abs() > Z_MAX,
                "path {path}: no power at 10 % ({shift_v:.1})"
            );
        }
    }
    // Deterministic and seed-dependent.
    let mut a = vec![0u64; 64];
    let mut b = vec![0u64; 64];
    aggregate_profile(&lambda, 1, 2, 10_000, &mut a);
    aggregate_profile(&lambda, 1, 2, 10_000, &mut b);
    assert_eq!(a, b);
    let mut c = vec![0u64; 64];
    aggregate_profile(&lambda, 2, 2, 10_000, &mut c);
    assert_ne!(a, c);
}

/// The tables of one sampler stay within `ALIAS_BUDGET_BYTES`: 2000 bins at λ = 10^3
/// (16 KiB alias tables) keep 256 tables (4 MiB), 2000 bins at λ = 10^6 as many
/// step-envelope tables as fit, and both draw the rest by Ahrens–Dieter; small tables
/// (λ = 5, 1 KiB) are built for every bin whatever their number. Deterministic.
#[test]
fn alias_tables_stay_within_their_budget() {
    let st = ShotSampler::with_choice(&[1e3; 2000], PathChoice::AllDense).strategy();
    let per_table = 16 * pmf_alias_columns(1e3);
    assert_eq!(per_table, 16 * 1024);
    assert_eq!(st.dense_alias_bins, ALIAS_BUDGET_BYTES / per_table, "{st}");
    assert_eq!(st.dense_alias_bins + st.dense_pd_bins, 2000, "{st}");
    let st = ShotSampler::with_choice(&[1e6; 2000], PathChoice::AllDense).strategy();
    let per_table = pmf_cells_bytes(1e6);
    assert_eq!(st.dense_cells_bins, ALIAS_BUDGET_BYTES / per_table, "{st}");
    assert_eq!(st.dense_cells_bins + st.dense_pd_bins, 2000, "{st}");
    let st = ShotSampler::with_choice(&[5.0; 20_000], PathChoice::AllDense).strategy();
    assert_eq!(st.dense_alias_bins, 20_000, "{st}");
    assert!(table_bytes_bound(20_000) >= (20_000 * 16 * pmf_alias_columns(5.0)) as f64);
}
