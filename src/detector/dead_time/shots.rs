//! Shots of fixed means through the dead time ([`DeadTimedShots`]): the bins of many
//! photons drawn from their counting law, the others given their photons; what they cost.

use super::clusters::ClusterShots;
use super::columns::ColumnShots;
use super::model::{DeadTime, DeadTimeModel};
use super::record::{ARRIVAL_STREAM, LawBins, Scratch};
use super::walk::WalkShots;
use crate::detector::counting::{self, RateLaw};
use crate::detector::recorder::recorded_profile;
use crate::sampling::{SHOT_BLOCK, ShotSampler, add_block_sums, stream_rng};

/// Cost of recording one photon through the arrival-time path (the paralyzable
/// detector, bins narrower than 2τ), ns, for the duration estimate a run announces
/// ([`DeadTime::ns_per_shot`]): measured at 13–21 ns (one thread; 2,631 and 26,309 true
/// photons per shot: `configs/ground/ground_532_depol.toml` with
/// `--set instrument.pulse_energy_j=4e-4` and `4e-3`, `--profiles 1 --threads 1`, the
/// drawing time over shots × photons, on a machine shared with another build). Lone
/// photons cost less (recorded without drawing a time): the estimate errs long.
pub const NS_PER_PHOTON: f64 = 20.0;

/// Cost of one photon recorded given its bin's photons by the counting tables
/// ([`counting::Family`]), and of one bin drawn from its counting law ([`RateLaw`],
/// below and above 64 MHz at τ = 3.5 ns), ns, for the same estimate: measured by
/// `benches/dead_time_rates.rs` (one thread; 0.2 photons per bin: 3.3 ns a bin; 1–20
/// photons: 3.8–6.6 ns a bin on a quiet machine, 2026-12-05; 100–600: 18–22 ns), the
/// ideal detector's share included.
pub const NS_PER_GIVEN_PHOTON: f64 = 16.0;
/// See [`NS_PER_GIVEN_PHOTON`].
pub const NS_PER_LAW_BIN: f64 = 5.0;
/// See [`NS_PER_GIVEN_PHOTON`].
pub const NS_PER_DENSE_LAW_BIN: f64 = 22.0;

impl DeadTime {
    /// Estimated cost of recording one shot of true means `lambda` per bin, ns (for the
    /// duration a run announces): per photon on the arrival-time path, per bin or photon
    /// by the counting distributions ([`NS_PER_GIVEN_PHOTON`]).
    pub fn ns_per_shot(&self, lambda: &[f64]) -> f64 {
        if !self.by_counts() {
            return lambda.iter().sum::<f64>() * NS_PER_PHOTON;
        }
        lambda
            .iter()
            .map(|&l| {
                if l < LAW_FROM_PHOTONS {
                    l * NS_PER_GIVEN_PHOTON
                } else if counting::is_dense(l / self.bin_width_s, self.tau_s) {
                    NS_PER_DENSE_LAW_BIN
                } else {
                    NS_PER_LAW_BIN
                }
            })
            .sum()
    }
}

/// Fewest expected photons per shot for a bin to be drawn from its counting law
/// ([`RateLaw`], its photons not drawn) rather than given its photons: measured
/// (`benches/dead_time_rates.rs`), the photon path costs more from about here on.
pub const LAW_FROM_PHOTONS: f64 = 0.5;

/// Most bytes of [`RateLaw`] tables one run keeps; bins past it are recorded given
/// their photons.
pub const LAW_BUDGET_BYTES: usize = 32 << 20;

/// Shots of fixed means recorded through a dead-time detector: what `simulate --method
/// shot` draws for a channel with dead time and without jitter.
///
/// A non-paralyzable detector ([`DeadTime::by_counts`]) draws each bin of at least
/// [`LAW_FROM_PHOTONS`] photons per shot from its counting law ([`RateLaw`], built once
/// for the run) without drawing its photons, and the other bins' photons by a
/// [`ShotSampler`] over them, recorded given those photons; otherwise
/// ([`recorded_profile`]) every photon is drawn and recorded.
#[derive(Debug, Clone)]
pub struct DeadTimedShots {
    photons: ShotSampler,
    dead: DeadTime,
    split: std::sync::OnceLock<Split>,
    /// Every bin's photons drawn by `photons` and recorded given them, none from its law:
    /// the photons are then the shot path's own, shot for shot (a `both` detector's
    /// photon-counting half records the analog half's photons).
    every_photon: bool,
    /// Which path draws the shots ([`DeadTimePath`]).
    path: DeadTimePath,
    walk: std::sync::OnceLock<Option<WalkShots>>,
    /// The column path and the other path's cost estimate per shot, ns.
    columns: std::sync::OnceLock<(ColumnShots, f64)>,
}

/// Which of [`DeadTimedShots`]' paths draws a profile's shots.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum DeadTimePath {
    /// The cheaper by the cost estimates: the arrival walk (`walk.rs`) where
    /// [`WalkShots`]' estimate is below the other path's (the clusters' for a paralyzable
    /// detector on bins of 2τ or more, [`DeadTime::ns_per_shot`] on narrower bins; never
    /// for a non-paralyzable one on bins of 2τ or more, whose clusters path and counting
    /// law cost less at every rate, measured), else as [`Photons`](Self::Photons).
    #[default]
    Auto,
    /// The shot path's photons (the clusters path, the counting laws).
    Photons,
    /// The arrival walk, whatever it costs (benches and tests).
    Walk,
    /// The column path (`columns.rs`) for profiles on bins of 2τ or more, whatever it
    /// costs (benches and tests); per-shot consumers as [`Auto`](Self::Auto).
    Columns,
}

/// The bins drawn by their law and the sampler of the others.
#[derive(Debug, Clone)]
struct Split {
    others: ShotSampler,
    laws: LawBins,
}

impl DeadTimedShots {
    /// The shots of `photons` through `dead`.
    pub fn new(photons: ShotSampler, dead: DeadTime) -> Self {
        DeadTimedShots {
            photons,
            dead,
            split: std::sync::OnceLock::new(),
            every_photon: false,
            path: DeadTimePath::Auto,
            walk: std::sync::OnceLock::new(),
            columns: std::sync::OnceLock::new(),
        }
    }

    /// The same shots drawn by `path` (the default [`DeadTimePath::Auto`]); ignored, the
    /// photons drawn, where [`drawing_every_photon`](Self::drawing_every_photon) is set.
    pub fn with_path(mut self, path: DeadTimePath) -> Self {
        self.path = path;
        self.walk = std::sync::OnceLock::new();
        self.columns = std::sync::OnceLock::new();
        self
    }

    /// The arrival walk, where it draws this profile's shots (see [`DeadTimePath`]).
    fn by_walk(&self) -> Option<&WalkShots> {
        self.walk
            .get_or_init(|| {
                let means = self.photons.means();
                let walk = match self.path {
                    _ if self.every_photon => false,
                    DeadTimePath::Walk => true,
                    DeadTimePath::Photons | DeadTimePath::Columns => false,
                    DeadTimePath::Auto => {
                        let other = match self.dead.model {
                            DeadTimeModel::Paralyzable if ClusterShots::serves(&self.dead) => {
                                ClusterShots::ns_per_shot(means)
                            }
                            // on bins of 2τ or more the clusters path and the counting
                            // law cost less than the walk at every rate (measured)
                            DeadTimeModel::Nonparalyzable if ClusterShots::serves(&self.dead) => {
                                0.0
                            }
                            _ => self.dead.ns_per_shot(means),
                        };
                        WalkShots::ns_per_shot(means, &self.dead) < other
                    }
                };
                walk.then(|| WalkShots::new(means, &self.dead))
            })
            .as_ref()
    }

    /// Estimated cost of a shot on the path [`for_each_shot`](Self::for_each_shot) takes,
    /// ns (the walk's, the clusters', or the counting laws' estimate).
    fn photon_paths_ns_per_shot(&self) -> f64 {
        let means = self.photons.means();
        if self.walks() {
            WalkShots::ns_per_shot(means, &self.dead)
        } else if self.by_clusters().is_some() {
            ClusterShots::ns_per_shot(means)
        } else {
            self.dead.ns_per_shot(means)
        }
    }

    /// The column path, where it draws a profile of `shots` shots: forced
    /// ([`DeadTimePath::Columns`]), or by [`DeadTimePath::Auto`] where its estimate is
    /// below the photon paths'; never where every photon is drawn or on bins under 2τ.
    fn by_columns(&self, shots: u64) -> Option<&ColumnShots> {
        let auto = match self.path {
            _ if self.every_photon || !ClusterShots::serves(&self.dead) => return None,
            DeadTimePath::Columns => false,
            DeadTimePath::Auto => true,
            DeadTimePath::Photons | DeadTimePath::Walk => return None,
        };
        let (columns, other) = self.columns.get_or_init(|| {
            (
                ColumnShots::new(self.photons.means(), &self.dead),
                self.photon_paths_ns_per_shot(),
            )
        });
        (!auto || columns.ns_per_profile(shots) < other * shots as f64).then_some(columns)
    }

    /// Where the arrival walk draws the shots: [`profile`](Self::profile)'s draws
    /// replayed, each recorded arrival handed to `f(shot, bin, place in the bin)` (their
    /// histogram is `profile`'s counts, bit for bit), and `true`; else `false`, nothing
    /// drawn.
    pub fn walk_registrations(
        &self,
        seed: u64,
        profile: u64,
        shots: u64,
        f: impl FnMut(u64, usize, f64),
    ) -> bool {
        if self.by_columns(shots).is_some() {
            return false; // `profile` takes the column path
        }
        match self.by_walk() {
            Some(w) => {
                w.registrations(seed, profile, shots, f);
                true
            }
            None => false,
        }
    }

    /// Whether the column path draws a profile of `shots` shots (see [`DeadTimePath`]).
    pub fn takes_columns(&self, shots: u64) -> bool {
        self.by_columns(shots).is_some()
    }

    /// Whether the arrival walk draws this profile's shots (see [`DeadTimePath`]).
    pub fn walks(&self) -> bool {
        self.by_walk().is_some()
    }

    /// The same shots with every bin's photons drawn (no bin from its counting law), so
    /// that they are the shot path's photons, shot for shot; slower at high rates.
    pub fn drawing_every_photon(mut self) -> Self {
        self.every_photon = true;
        self
    }

    /// The sampler of every bin's photons.
    pub fn photons(&self) -> &ShotSampler {
        &self.photons
    }

    /// The detector.
    pub fn dead(&self) -> &DeadTime {
        &self.dead
    }

    /// The photon path with the clusters corrected ([`ClusterShots`]) where it serves:
    /// bins at least 2τ wide, and a paralyzable detector, or a non-paralyzable one with
    /// every bin's photons drawn (no bin of [`LAW_FROM_PHOTONS`] photons, or
    /// [`drawing_every_photon`](Self::drawing_every_photon)).
    fn by_clusters(&self) -> Option<ClusterShots<'_>> {
        let every = self.every_photon
            || self.dead.model == DeadTimeModel::Paralyzable
            || self.split().laws.laws.is_empty();
        (ClusterShots::serves(&self.dead) && every).then_some(ClusterShots {
            photons: &self.photons,
            dead: &self.dead,
        })
    }

    fn split(&self) -> &Split {
        self.split.get_or_init(|| {
            let (tau, dt) = (self.dead.tau_s, self.dead.bin_width_s);
            let means = self.photons.means();
            let mut spent = 0usize;
            let laws: Vec<Option<RateLaw>> = means
                .iter()
                .map(|&l| {
                    (l >= LAW_FROM_PHOTONS && spent < LAW_BUDGET_BYTES).then(|| {
                        let law = RateLaw::new(l / dt, tau, dt);
                        spent += counting::rate_law_bytes(&law);
                        law
                    })
                })
                .collect();
            let others: Vec<f64> = means
                .iter()
                .zip(&laws)
                .map(|(&l, law)| if law.is_some() { 0.0 } else { l })
                .collect();
            let starts: Vec<u32> = (0..laws.len())
                .filter(|&i| laws[i].is_some() && (i == 0 || laws[i - 1].is_none()))
                .map(|i| i as u32)
                .collect();
            let mut ends = vec![0u32; laws.len()];
            for &a in &starts {
                let mut e = a as usize;
                while e < laws.len() && laws[e].is_some() {
                    e += 1;
                }
                ends[a as usize] = e as u32;
            }
            let dense = (0..laws.len() as u32)
                .filter(|&i| laws[i as usize].as_ref().is_some_and(|l| l.dense))
                .collect();
            Split {
                others: ShotSampler::new(&others),
                laws: LawBins {
                    // without law bins, none to look up
                    laws: if starts.is_empty() { Vec::new() } else { laws },
                    starts,
                    ends,
                    dense,
                },
            }
        })
    }

    /// Draws `shots` shots from `stream_rng(seed, profile, 0)` and its arrival stream and
    /// hands each one's recorded counts to `f` (per-shot consumers: tests, onboard sums).
    pub fn for_each_shot(&self, seed: u64, profile: u64, shots: u64, mut f: impl FnMut(&[u64])) {
        if let Some(w) = self.by_walk() {
            return w.for_each_shot(seed, profile, shots, f);
        }
        if let Some(c) = self.by_clusters() {
            return c.for_each_shot(seed, profile, shots, f);
        }
        let bins = self.photons.bins();
        let mut acc = vec![0u64; bins];
        let mut scratch = Scratch::default();
        let mut arrivals = stream_rng(seed ^ ARRIVAL_STREAM, profile, 0);
        let mut rng = stream_rng(seed, profile, 0);
        if !self.dead.by_counts() || self.every_photon {
            return self.photons.for_each_shot(&mut rng, shots, |shot| {
                acc.iter_mut().for_each(|a| *a = 0);
                self.dead
                    .record_shot(&mut arrivals, shot, &mut scratch, &mut acc);
                f(&acc);
            });
        }
        let split = self.split();
        split.others.for_each_shot(&mut rng, shots, |shot| {
            acc.iter_mut().for_each(|a| *a = 0);
            self.dead
                .record_runs(&mut arrivals, shot, &split.laws, &mut scratch, &mut acc);
            f(&acc);
        });
    }

    /// Accumulates one profile of `shots` shots into `acc`, by blocks of [`SHOT_BLOCK`]
    /// shots from `stream_rng(seed, profile, block)` (photons) and its arrival stream
    /// (the detector's draws), summed in integers: independent of the thread count.
    pub fn profile(&self, seed: u64, profile: u64, shots: u64, acc: &mut [u64]) {
        if let Some(c) = self.by_columns(shots) {
            return c.profile(seed, profile, shots, acc);
        }
        if let Some(w) = self.by_walk() {
            return w.profile(seed, profile, shots, acc);
        }
        if let Some(c) = self.by_clusters() {
            return c.profile(seed, profile, shots, acc);
        }
        if !self.dead.by_counts() || self.every_photon {
            return recorded_profile(&self.photons, &self.dead, seed, profile, shots, acc);
        }
        let split = self.split();
        let bins = acc.len();
        add_block_sums(acc, shots.div_ceil(SHOT_BLOCK), |b| {
            let mut part = vec![0u64; bins];
            let mut scratch = Scratch::default();
            let n = SHOT_BLOCK.min(shots - b * SHOT_BLOCK);
            let mut arrivals = stream_rng(seed ^ ARRIVAL_STREAM, profile, b);
            split
                .others
                .for_each_shot(&mut stream_rng(seed, profile, b), n, |shot| {
                    self.dead
                        .record_runs(&mut arrivals, shot, &split.laws, &mut scratch, &mut part)
                });
            part
        });
    }
}
