//! The exact per-shot sampler: dense table inversion, dense alias tables and
//! step-envelope rejection over the PMF, dense Ahrens–Dieter,
//! and the sparse "Poisson total + alias placement" path, mixed per bin by a
//! cost model.

use std::fmt;

use rand::Rng;
use rand_distr::{Distribution, Poisson};

use super::alias::AliasTable;
use super::pmf_alias::{PmfAlias, pmf_alias_columns};
use super::pmf_cells::{PmfCells, pmf_cells_bytes};
use super::sink::CountSink;
use super::table::{count_above, tail_thresholds};

/// Largest per-bin mean drawn densely by table inversion (one compare when the
/// count is 0, a count of the thresholds otherwise); above it an alias table over
/// the PMF ([`PmfAlias`]: one `u64` and one column whatever the count), which is
/// the cheaper of the two from here on (measured, see [`cost`]).
pub const DENSE_TABLE_MAX: f64 = 0.07;

/// Largest per-bin mean drawn densely by an alias table over the PMF (tables of at
/// most 1024 columns, 16 KiB); above it rejection from a step envelope over the PMF
/// ([`PmfCells`]: 7–27 KiB up to λ = 10^6) within the sampler's table budget, and a
/// prebuilt [`rand_distr::Poisson`] (Ahrens–Dieter 1982) per bin past it. Where the
/// cost model's alias cost (growing with the table, [`cost::alias`]) passes
/// [`cost::CELLS`]; a whole scenario-1 aggregate run measured 14 % less drawing time
/// with this switch at 10^3 than at 4·10^4 (`validation/reports/throughput.md`).
pub const DENSE_ALIAS_MAX: f64 = 1.0e3;

/// Most bytes of tables over PMFs (alias, [`PmfAlias`], and step envelope, [`PmfCells`])
/// that one sampler keeps. A dense bin whose table would pass 1 KiB (λ ≳ 10) once this
/// is spent is drawn by Ahrens–Dieter instead (out of the caches a large table is no
/// faster); tables of at most 1 KiB are always built. So a sampler's tables take at most
/// [`table_bytes_bound`] whatever its bins.
pub const ALIAS_BUDGET_BYTES: usize = 4 << 20;

/// Alias-table bytes a bin may always take, whatever the budget.
const SMALL_TABLE_BYTES: usize = 1024;

/// An upper bound of the memory of a [`ShotSampler`]'s tables over `bins` bins, bytes:
/// per bin a small alias table or inversion thresholds (≤ 1 KiB), plus the budget of the
/// larger alias tables, plus the sparse set's alias table (16 bytes per bin, rounded up
/// to a power of two).
pub fn table_bytes_bound(bins: usize) -> f64 {
    (SMALL_TABLE_BYTES + 32) as f64 * bins as f64 + ALIAS_BUDGET_BYTES as f64
}

/// Largest sparse-set total `Σλ` whose shot total `N` is drawn from an alias
/// table over the (truncated at `2^-72`) Poisson PMF; above it a prebuilt
/// [`rand_distr::Poisson`] is used.
pub const TOTAL_TABLE_MAX: f64 = 512.0;

/// Cost model, in ns, measured on the development machine (2-core AMD EPYC
/// VM under load, `Pcg64Mcg`, accumulation into `[u64]`, 1000 bins unless
/// said, each path forced alone with [`PathChoice`]; `cargo run --release
/// --example sampler_costs`, best of 15 runs). Only the ratios matter; a
/// wrong estimate costs speed, never correctness.
///
/// * dense inversion bin of mean λ, `q = P(K ≥ 1)`, `L` thresholds after the
///   first: `DENSE_BASE + DENSE_MISS·min(q, 1-q) + q·DENSE_PER_THRESHOLD·L`
///   (one `u64` and a compare; a mispredicted branch; a branch-free count);
///   measured 1.4 ns (λ ≤ 0.01), 2.1 (0.05), 3.0 (0.1), 8.6 (0.5), 9.9 (1), 16 (10);
/// * dense alias bin over the PMF ([`PmfAlias`]): [`cost::alias`] of its
///   columns, measured 2.4 ns up to 64 columns (λ ≲ 10, whatever the count),
///   3.9 (λ = 30), 4.8–5.3 (100), 7.0 (10^3), 8–14 (10^4), 19–20 (10^5: 8192 columns,
///   128 MiB for the 1000 bins, out of the caches);
/// * dense step-envelope rejection bin ([`PmfCells`]): `CELLS`, measured 6.0–8.3 ns for
///   100 bins from λ = 30 to 10^6 (two `u64` per draw, tables in the caches), 10.3 ns at
///   10^7, 12.5–25 ns for 1000 bins of 10^3–10^6 (7–26 MiB, out of the caches, which
///   the table budget prevents), hence [`DENSE_ALIAS_MAX`];
/// * dense Ahrens–Dieter bin: `DENSE_PD` (measured 21 ns for λ ≥ 30);
/// * sparse set of `n` bins and total mean `Λ`: the alias draw of its total
///   (`DENSE_PD` above [`TOTAL_TABLE_MAX`]) per shot plus `Λ·sparse_place(n)`,
///   the cost of one count (one `u64`, an alias column, an increment), which
///   grows once the alias table and accumulator leave the caches: measured
///   2.0 ns (1000 bins), 2.9 (10^4), 4.8 (3·10^4), 5.8 (10^5), ~40 (3·10^5).
///
/// A bin costs about `λ·sparse_place` in the sparse set and at least
/// `DENSE_BASE` in the dense set, the ratio falling with λ, so the sparse set
/// is a prefix of the bins sorted by λ: [`ShotSampler::new`] evaluates every
/// prefix (O(n log n)) and keeps the cheapest. On 1000 equal bins this puts
/// λ ≲ 1 on the sparse path.
pub mod cost {
    /// Per dense inversion bin: one `u64` and a compare.
    pub const DENSE_BASE: f64 = 1.55;
    /// Per mispredicted branch in a dense inversion bin.
    pub const DENSE_MISS: f64 = 8.0;
    /// Per threshold counted after a hit in a dense inversion bin.
    pub const DENSE_PER_THRESHOLD: f64 = 0.35;
    /// Per dense Ahrens–Dieter bin (`rand_distr::Poisson`).
    pub const DENSE_PD: f64 = 21.0;
    /// Per draw by rejection from a step envelope ([`super::pmf_cells::PmfCells`]).
    pub const CELLS: f64 = 7.5;
    /// Per draw from an alias table over a PMF of at most 64 columns (1 KiB).
    pub const ALIAS_BASE: f64 = 2.4;
    /// Extra per draw for each doubling of the table past 64 columns (cache).
    pub const ALIAS_PER_DOUBLING: f64 = 1.4;

    /// Cost of one draw from an alias table of `columns` columns.
    pub fn alias(columns: usize) -> f64 {
        ALIAS_BASE + ALIAS_PER_DOUBLING * (columns as f64 / 64.0).max(1.0).log2()
    }
    /// Per sparse count while alias table + accumulator fit in L1/L2 (≤ 64 KiB).
    pub const SPARSE_PLACE: f64 = 2.2;
    /// Extra per sparse count for each doubling of that working set past 64 KiB.
    pub const SPARSE_PLACE_PER_DOUBLING: f64 = 0.7;
    /// Factor on the placement cost once the working set passes 8 MiB (TLB/DRAM).
    pub const SPARSE_PLACE_DRAM_FACTOR: f64 = 5.0;

    /// Cost of one sparse count with `n` sparse bins.
    pub fn sparse_place(n: usize) -> f64 {
        let cols = n.next_power_of_two().max(2) as f64;
        let bytes = 16.0 * cols + 8.0 * n as f64;
        let c = SPARSE_PLACE + SPARSE_PLACE_PER_DOUBLING * (bytes / 65536.0).max(1.0).log2();
        if bytes > 8.0 * 1024.0 * 1024.0 {
            c * SPARSE_PLACE_DRAM_FACTOR
        } else {
            c
        }
    }
}

/// How [`ShotSampler::with_choice`] splits the bins between the dense and the
/// sparse path.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PathChoice {
    /// The cheapest split by the cost model ([`cost`]); what [`ShotSampler::new`] uses.
    Auto,
    /// Every bin on the dense path, each by [`DenseMethod::for_mean`].
    AllDense,
    /// Every bin on the dense path by the one method given (tests and benchmarks:
    /// `Inversion` needs λ ≤ 600, `Alias` λ < 4·10^9).
    Dense(DenseMethod),
    /// Every bin (with λ > 0) on the sparse path.
    AllSparse,
    /// Bins with `0 < λ < threshold` sparse, the rest dense.
    SparseBelow(f64),
}

/// Which path [`ShotSampler`] picked, for reports.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StrategyKind {
    /// No bin can ever count (all λ = 0 or below `2^-64`).
    Empty,
    /// Every active bin dense.
    Dense,
    /// Every active bin through the sparse path.
    Sparse,
    /// Large-λ bins dense, the rest sparse.
    Hybrid,
}

/// Summary of the split chosen by [`ShotSampler`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShotStrategy {
    pub kind: StrategyKind,
    /// Length of the λ vector.
    pub bins: usize,
    /// Dense bins drawn by table inversion.
    pub dense_table_bins: usize,
    /// Dense bins drawn by an alias table over their PMF.
    pub dense_alias_bins: usize,
    /// Dense bins drawn by rejection from a step envelope over their PMF.
    pub dense_cells_bins: usize,
    /// Dense bins drawn by a prebuilt `rand_distr::Poisson`.
    pub dense_pd_bins: usize,
    /// Bins on the sparse path.
    pub sparse_bins: usize,
    /// `Σλ` over the sparse bins (mean number of sparse counts per shot).
    pub sparse_mean: f64,
    /// Bins that can never count (λ = 0, or dense with `P(K ≥ 1) < 2^-64`).
    pub idle_bins: usize,
    /// Cost-model estimate of one shot, in ns.
    pub est_ns_per_shot: f64,
}

impl fmt::Display for ShotStrategy {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{:?}: {} bins = {} dense-table + {} dense-alias + {} dense-cells + {} dense-PD + {} sparse (Σλ = {:.4}) + {} idle; ~{:.1} ns/shot",
            self.kind,
            self.bins,
            self.dense_table_bins,
            self.dense_alias_bins,
            self.dense_cells_bins,
            self.dense_pd_bins,
            self.sparse_bins,
            self.sparse_mean,
            self.idle_bins,
            self.est_ns_per_shot
        )
    }
}

#[derive(Clone, Debug)]
enum TotalSampler {
    /// Alias table over the Poisson PMF.
    Table(PmfAlias),
    Pd(Poisson<f64>),
}

#[derive(Clone, Debug)]
struct SparseSet {
    total: TotalSampler,
    alias: AliasTable,
}

/// Exact sampler of one shot's photon counts for fixed per-bin means `λ_i`;
/// built once per profile (O(n log n)), reused for every shot, allocation-free
/// per shot.
///
/// Each bin's count is Poisson(λ_i), independent across bins and shots. Exact
/// paths, chosen per bin by a cost model ([`cost`], [`PathChoice`]):
///
/// * **Dense inversion** (`λ ≤` [`DENSE_TABLE_MAX`]): per bin a table of
///   64-bit tail thresholds `⌊P(K ≥ j)·2^64⌋`; one `u64` per draw and, when
///   the count is 0, one compare (else a branch-free count of the thresholds
///   above the draw). Inversion by sequential search, Devroye (1986),
///   *Non-Uniform Random Variate Generation*, §X.3.3.
/// * **Dense alias** (`λ ≤` [`DENSE_ALIAS_MAX`]): an alias table over the PMF
///   ([`PmfAlias`]), one `u64` per draw.
/// * **Dense step-envelope rejection** (above): [`PmfCells`], about two `u64`
///   per draw from tables of `O(√λ)` bytes.
/// * **Dense rejection** (past the table budget, [`ALIAS_BUDGET_BYTES`]): a prebuilt
///   [`rand_distr::Poisson`] per bin, Ahrens & Dieter (1982), "Computer
///   generation of Poisson deviates from modified normal distributions",
///   ACM TOMS 8(2), 163–179.
/// * **Sparse** (bins whose λ are small next to their number): the shot's
///   total `N ~ Poisson(Λ)`, `Λ = Σ λ_i` over these bins (an alias table
///   over the Poisson PMF, or Ahrens–Dieter above [`TOTAL_TABLE_MAX`]), then each of the `N` counts
///   placed in bin `i` with probability `λ_i/Λ` by an integer alias table
///   (Walker 1977; Vose 1991). Exact because a multinomial split of a
///   Poisson total gives independent Poissons (e.g. Kingman 1993, *Poisson
///   Processes*, §1.2 "colouring"). Cost O(N + 1) instead of O(bins).
///
/// Precision: every cell probability is realised to within a few `2^-64`
/// absolute (plus f64 rounding of the PMF, relative ~1e-15); λ = 0 and
/// λ = 1e-300 give zero counts.
#[derive(Clone, Debug)]
pub struct ShotSampler {
    bins: usize,
    /// The means it was built from (a detector stage may draw some bins otherwise).
    means: Box<[f64]>,
    /// Dense inversion bins, structure of arrays in bin order.
    d_first: Box<[u64]>,
    d_bin: Box<[u32]>,
    /// `d_rest[d_off[i]..d_off[i+1]]` are bin `i`'s `T_2, …, T_kmax` (`len + 1` offsets).
    d_off: Box<[u32]>,
    d_rest: Box<[u64]>,
    /// Dense bins drawn by an alias table over their PMF.
    d_alias: Box<[(u32, PmfAlias)]>,
    /// Dense bins drawn by rejection from a step envelope over their PMF.
    d_cells: Box<[(u32, PmfCells)]>,
    /// Dense Ahrens–Dieter bins.
    d_pd: Box<[(u32, Poisson<f64>)]>,
    sparse: Option<SparseSet>,
    strategy: ShotStrategy,
}

/// How one dense bin is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DenseMethod {
    /// Table inversion (`sampling::table`), `λ ≤` [`DENSE_TABLE_MAX`].
    Inversion,
    /// Alias table over the PMF ([`PmfAlias`]), `λ ≤` [`DENSE_ALIAS_MAX`].
    Alias,
    /// Rejection from a step envelope over the PMF ([`PmfCells`]), `λ >`
    /// [`DENSE_ALIAS_MAX`].
    Cells,
    /// A prebuilt `rand_distr::Poisson` (Ahrens–Dieter), past the table budget.
    Rejection,
}

impl DenseMethod {
    /// The method for a dense bin of mean `lambda`.
    pub fn for_mean(lambda: f64) -> DenseMethod {
        if lambda <= DENSE_TABLE_MAX {
            DenseMethod::Inversion
        } else if lambda <= DENSE_ALIAS_MAX {
            DenseMethod::Alias
        } else {
            DenseMethod::Cells
        }
    }
}

/// `method` for a dense bin of mean `lambda`, or Ahrens–Dieter when its table (past
/// [`SMALL_TABLE_BYTES`]) would take the sampler's tables past [`ALIAS_BUDGET_BYTES`];
/// `spent` counts the bytes of those larger tables.
fn within_budget(method: DenseMethod, lambda: f64, spent: &mut usize) -> DenseMethod {
    let bytes = match method {
        DenseMethod::Alias => 16 * pmf_alias_columns(lambda),
        DenseMethod::Cells => pmf_cells_bytes(lambda),
        _ => return method,
    };
    if bytes > SMALL_TABLE_BYTES && *spent + bytes > ALIAS_BUDGET_BYTES {
        DenseMethod::Rejection
    } else {
        *spent += bytes;
        method
    }
}

/// Cost-model estimate of one dense draw of mean `lambda` by `method`, ns.
fn dense_cost_by(lambda: f64, method: DenseMethod) -> f64 {
    match method {
        DenseMethod::Inversion => {
            let q = -(-lambda).exp_m1();
            // Thresholds after the first: j >= 2 with P(K >= j) >= 2^-64, estimated
            // allocation-free by the PMF terms (the tail is within a small factor of them).
            let mut p = (-lambda).exp() * lambda; // p_1
            let mut j = 1.0;
            let mut rest = 0.0;
            loop {
                j += 1.0;
                p *= lambda / j;
                if j > lambda && p < 5.421e-20 {
                    break;
                }
                rest += 1.0;
            }
            cost::DENSE_BASE
                + cost::DENSE_MISS * q.min(1.0 - q)
                + q * cost::DENSE_PER_THRESHOLD * rest
        }
        DenseMethod::Alias => cost::alias(pmf_alias_columns(lambda)),
        DenseMethod::Cells => cost::CELLS,
        DenseMethod::Rejection => cost::DENSE_PD,
    }
}

fn dense_cost(lambda: f64) -> f64 {
    dense_cost_by(lambda, DenseMethod::for_mean(lambda))
}

fn sparse_cost(n: usize, mean: f64) -> f64 {
    if n == 0 {
        0.0
    } else if mean <= TOTAL_TABLE_MAX {
        cost::alias(pmf_alias_columns(mean)) + mean * cost::sparse_place(n)
    } else {
        cost::DENSE_PD + mean * cost::sparse_place(n)
    }
}

impl ShotSampler {
    /// Build with the cost-model split ([`PathChoice::Auto`]).
    ///
    /// `lambda_per_bin[i]` is the mean count of bin `i` per shot: finite and
    /// `>= 0` (the caller validates; checked by `debug_assert`).
    pub fn new(lambda_per_bin: &[f64]) -> ShotSampler {
        Self::with_choice(lambda_per_bin, PathChoice::Auto)
    }

    /// Build with an explicit dense/sparse split (tests, benchmarks, reports).
    pub fn with_choice(lambda_per_bin: &[f64], choice: PathChoice) -> ShotSampler {
        let bins = lambda_per_bin.len();
        assert!(bins <= u32::MAX as usize, "too many bins");
        debug_assert!(
            lambda_per_bin.iter().all(|l| l.is_finite() && *l >= 0.0),
            "every lambda must be finite and >= 0"
        );
        // Active bins sorted by (λ, index).
        let mut order: Vec<u32> = (0..bins as u32)
            .filter(|&i| lambda_per_bin[i as usize] > 0.0)
            .collect();
        order.sort_by(|&a, &b| {
            lambda_per_bin[a as usize]
                .total_cmp(&lambda_per_bin[b as usize])
                .then(a.cmp(&b))
        });
        let lam = |i: u32| lambda_per_bin[i as usize];

        let n_sparse = match choice {
            PathChoice::AllDense | PathChoice::Dense(_) => 0,
            PathChoice::AllSparse => order.len(),
            PathChoice::SparseBelow(t) => order.iter().take_while(|&&i| lam(i) < t).count(),
            PathChoice::Auto => {
                // cost(t) = sparse_cost(t, Λ_t) + Σ_{k≥t} dense_cost(λ_k)
                let mut suffix = vec![0.0f64; order.len() + 1];
                for k in (0..order.len()).rev() {
                    suffix[k] = suffix[k + 1] + dense_cost(lam(order[k]));
                }
                let (mut best_t, mut best) = (0usize, suffix[0]);
                let mut prefix = 0.0;
                for t in 1..=order.len() {
                    prefix += lam(order[t - 1]);
                    let c = sparse_cost(t, prefix) + suffix[t];
                    if c < best {
                        best = c;
                        best_t = t;
                    }
                }
                best_t
            }
        };

        let mut sparse_ids: Vec<u32> = order[..n_sparse].to_vec();
        let mut dense_ids: Vec<u32> = order[n_sparse..].to_vec();
        sparse_ids.sort_unstable();
        dense_ids.sort_unstable();

        // Dense bins.
        let mut d_first = Vec::new();
        let mut d_bin = Vec::new();
        let mut d_off = vec![0u32];
        let mut d_rest = Vec::new();
        let mut d_alias = Vec::new();
        let mut d_cells = Vec::new();
        let mut d_pd = Vec::new();
        let mut idle = bins - order.len();
        let mut est = 0.0;
        let mut alias_bytes = 0usize;
        for &i in &dense_ids {
            let l = lam(i);
            let method = match choice {
                PathChoice::Dense(m) => m,
                _ => within_budget(DenseMethod::for_mean(l), l, &mut alias_bytes),
            };
            match method {
                DenseMethod::Inversion => {
                    let thr = tail_thresholds(l);
                    if thr.is_empty() {
                        idle += 1; // P(K >= 1) < 2^-64: never counts
                        continue;
                    }
                    d_first.push(thr[0]);
                    d_bin.push(i);
                    d_rest.extend_from_slice(&thr[1..]);
                    d_off.push(u32::try_from(d_rest.len()).expect("dense table too large"));
                }
                DenseMethod::Alias => d_alias.push((i, PmfAlias::new(l))),
                DenseMethod::Cells => d_cells.push((i, PmfCells::new(l))),
                DenseMethod::Rejection => d_pd.push((
                    i,
                    Poisson::new(l).expect("lambda out of range for rand_distr::Poisson"),
                )),
            }
            est += dense_cost_by(l, method);
        }

        // Sparse bins.
        let mut sparse_mean: f64 = sparse_ids.iter().map(|&i| lam(i)).sum();
        if sparse_mean <= TOTAL_TABLE_MAX && tail_thresholds(sparse_mean).is_empty() {
            // P(N >= 1) < 2^-64: the sparse set can never count.
            idle += sparse_ids.len();
            sparse_ids.clear();
            sparse_mean = 0.0;
        }
        let sparse = if sparse_ids.is_empty() {
            None
        } else {
            let w: Vec<f64> = sparse_ids.iter().map(|&i| lam(i)).collect();
            let total = if sparse_mean <= TOTAL_TABLE_MAX {
                TotalSampler::Table(PmfAlias::new(sparse_mean))
            } else {
                TotalSampler::Pd(Poisson::new(sparse_mean).expect("sparse total out of range"))
            };
            est += sparse_cost(sparse_ids.len(), sparse_mean);
            Some(SparseSet {
                total,
                alias: AliasTable::new(&w, &sparse_ids),
            })
        };

        let n_dense = d_first.len() + d_alias.len() + d_cells.len() + d_pd.len();
        let kind = match (n_dense > 0, sparse.is_some()) {
            (false, false) => StrategyKind::Empty,
            (true, false) => StrategyKind::Dense,
            (false, true) => StrategyKind::Sparse,
            (true, true) => StrategyKind::Hybrid,
        };
        let strategy = ShotStrategy {
            kind,
            bins,
            dense_table_bins: d_first.len(),
            dense_alias_bins: d_alias.len(),
            dense_cells_bins: d_cells.len(),
            dense_pd_bins: d_pd.len(),
            sparse_bins: sparse_ids.len(),
            sparse_mean,
            idle_bins: idle,
            est_ns_per_shot: est,
        };
        ShotSampler {
            bins,
            means: lambda_per_bin.into(),
            d_first: d_first.into_boxed_slice(),
            d_bin: d_bin.into_boxed_slice(),
            d_off: d_off.into_boxed_slice(),
            d_rest: d_rest.into_boxed_slice(),
            d_alias: d_alias.into_boxed_slice(),
            d_cells: d_cells.into_boxed_slice(),
            d_pd: d_pd.into_boxed_slice(),
            sparse,
            strategy,
        }
    }

    /// The per-bin means it was built from.
    pub fn means(&self) -> &[f64] {
        &self.means
    }

    /// Number of bins (length of the λ vector it was built from).
    pub fn bins(&self) -> usize {
        self.bins
    }

    /// Which internal paths it picked.
    pub fn strategy(&self) -> ShotStrategy {
        self.strategy
    }

    /// Draw one shot and report its counts to `sink` as `(bin, count ≥ 1)`
    /// events: dense-table bins, then dense-PD bins, each once and in bin
    /// order, then the sparse counts one at a time in random order, each by
    /// [`CountSink::add_placed`] with its place within its bin (a sparse
    /// bin may be reported several times in one shot). Per-shot counts are
    /// `u32`: λ must stay well below `4e9` per bin and shot.
    /// The random stream consumed depends only on the sampler and the rng.
    #[inline]
    pub fn sample_shot<R: Rng + ?Sized, S: CountSink + ?Sized>(&self, rng: &mut R, sink: &mut S) {
        // Dense inversion: one u64 per bin and a compare; on a count, a
        // branch-free count of the remaining thresholds above x.
        for ((&t1, &bin), off) in self
            .d_first
            .iter()
            .zip(self.d_bin.iter())
            .zip(self.d_off.windows(2))
        {
            let x = rng.next_u64();
            if x < t1 {
                let rest = &self.d_rest[off[0] as usize..off[1] as usize];
                let k = 1 + count_above(rest, x);
                sink.add(bin as usize, k);
            }
        }
        // Dense alias tables over the PMF: one u64 each.
        for (bin, table) in self.d_alias.iter() {
            sink.add_any(*bin as usize, table.count_for(rng.next_u64()));
        }
        // Dense rejection from a step envelope: about two u64 each.
        for (bin, cells) in self.d_cells.iter() {
            sink.add_any(*bin as usize, cells.sample(rng));
        }
        // Dense Ahrens–Dieter.
        for (bin, pd) in self.d_pd.iter() {
            let k: f64 = pd.sample(rng);
            if k > 0.0 {
                sink.add(*bin as usize, k as u32);
            }
        }
        // Sparse: total, then placement.
        if let Some(sp) = &self.sparse {
            let n = match &sp.total {
                TotalSampler::Table(t) => u64::from(t.count_for(rng.next_u64())),
                TotalSampler::Pd(p) => p.sample(rng) as u64,
            };
            for _ in 0..n {
                let x = rng.next_u64();
                let (bin, offset, width) = sp.alias.place(x);
                sink.add_placed(bin, x, offset, width);
            }
        }
    }

    /// `(bin, offset, width)` of a sparse count placed by `draw`, as
    /// [`CountSink::add_placed`] received it (`None` without a sparse set).
    pub(crate) fn placement(&self, draw: u64) -> Option<(usize, u64, u64)> {
        self.sparse.as_ref().map(|sp| sp.alias.place(draw))
    }

    /// Add one shot's counts into `acc` (`acc.len() == bins()`).
    #[inline]
    pub fn add_shot<R: Rng + ?Sized>(&self, rng: &mut R, acc: &mut [u64]) {
        assert_eq!(acc.len(), self.bins, "accumulator length != number of bins");
        self.sample_shot(rng, acc);
    }

    /// Add `shots` independent shots into `acc` (same stream as `shots` calls of [`add_shot`](Self::add_shot)).
    pub fn add_shots<R: Rng + ?Sized>(&self, rng: &mut R, shots: u64, acc: &mut [u64]) {
        assert_eq!(acc.len(), self.bins, "accumulator length != number of bins");
        for _ in 0..shots {
            self.sample_shot(rng, acc);
        }
    }

    /// Draw `shots` shots and hand each one, as a [`ShotCounts`](super::sink::ShotCounts), to `f`:
    /// the per-shot consumer form (onboard processing, detector models).
    /// Uses the same random stream as [`add_shots`](Self::add_shots); one buffer is
    /// allocated up front, none per shot.
    pub fn for_each_shot<R, F>(&self, rng: &mut R, shots: u64, mut f: F)
    where
        R: Rng + ?Sized,
        F: FnMut(&super::sink::ShotCounts),
    {
        let mut buf = super::sink::ShotCounts::new(self.bins);
        for _ in 0..shots {
            self.sample_shot(rng, &mut buf);
            f(&buf);
            buf.clear();
        }
    }
}
