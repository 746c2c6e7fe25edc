//! The photon path of the dead time at the ideal detector's cost ([`ClusterShots`]): the
//! shot's photons go straight into the record, as without dead time, each with its time
//! within its bin handed over by the shot path's own placement draw; only the photons
//! that can meet another within τ are looked at again, in time order, the dead time
//! carried from bin to bin.
//!
//! # Method
//!
//! The photons of a shot are the shot path's ([`ShotSampler::sample_shot`], the same
//! draws), reported to a [`CountSink`] that adds each to the record at once. A sparse
//! photon arrives with `(offset, width)` ([`CountSink::add_placed`]): its time within its
//! bin is `t = Δt·(offset + V)/width`, `V` uniform on `[0, 1)`, drawn only if needed (the
//! offset is the alias draw's leftover bits, uniform given the bin: issue 41's first
//! fact made free). A dense-path count has no offset: `width = 1`, its time all `V`.
//!
//! With Δt ≥ 2τ, a photon alone in its bin whose whole cell `[offset, offset + 1)/width`
//! lies in `[τ/Δt, 1 − τ/Δt]` has no other photon within τ, in either model: it is
//! recorded and leaves the detector live at its bin's end. Per photon the sink does one
//! read and write of its own bin's state (this shot's stamp, whether the bin is
//! flagged, its latest photon), appends `(offset, width)` to the shot's log (each bin's
//! photons chained), and flags the bin when the photon is its second or lies within τ of
//! an edge (a 64×64-bit multiply and a compare: `min(offset, width − 1 − offset) <
//! ⌊width·p⌋ + 1`, `p ≥ τ/Δt`), branch-free. After the shot each run of adjacent flagged
//! bins is recorded exactly: entered live (the bin before it is empty or holds one photon
//! at least τ before its end), its photons' times taken from the log (`V` drawn from the
//! arrival stream where `width < 2^53`, else the cell's middle, finer than an `f64`
//! time), each bin's sorted and swept in time order, the dead time carried into the next,
//! every photon restarting it (paralyzable) or only a recorded one (non-paralyzable);
//! it leaves nothing the bin after it feels (empty, or one photon at least τ after its
//! start). The record is corrected by the counts lost.
//!
//! Exact: each photon's time is uniform in its bin and independent of the others' (the
//! rate constant within a bin); where a decision used only the offset, the time given
//! it is the offset's cell with `V` uniform in it, and `V` is drawn where a decision needs
//! it. The photons drawn, shot for shot, are the shot path's; a time is never drawn
//! twice.
//!
//! # Cost
//!
//! Per photon, next to the ideal detector's own draw: the state read and write, the log
//! entry and the edge test; per flagged photon (a bin hit twice, or within τ of an edge:
//! probability `2τ/Δt`, 0.35 % at τ = 3.5 ns, Δt = 2 µs) its time and its bin's sort and
//! sweep. Measured by `benches/dead_time_rates.rs` (`validation/reports/dead_time_cost.md`).
//!
//! [`ShotSampler::sample_shot`]: crate::sampling::ShotSampler::sample_shot

use rand::Rng;

use super::model::{DeadTime, DeadTimeModel};
use super::record::ARRIVAL_STREAM;
use crate::sampling::{CountSink, SHOT_BLOCK, ShotSampler, add_block_sums, stream_rng};

/// The shot number's place in a bin's state.
const STAMP_SHIFT: u32 = 32;
/// A bin flagged this shot.
const FLAG: u64 = 1 << 31;
/// The bin's first photon came without a draw (dense path): its time is all `V`.
const NO_DRAW: u64 = 1 << 30;
/// The state's count bits.
const COUNT_MASK: u64 = NO_DRAW - 1;
/// Widths from here on hold the time to an `f64`'s precision without a `V`.
const FINE_WIDTH: u64 = 1 << 53;

const TWO_POW_64: f64 = 18_446_744_073_709_551_616.0;

/// Shots of fixed means through a dead time by their photons, the clusters corrected (see
/// the module docs): bins at least 2τ wide, either model.
#[derive(Debug)]
pub(super) struct ClusterShots<'a> {
    pub(super) photons: &'a ShotSampler,
    pub(super) dead: &'a DeadTime,
}

/// A bin's state: `[stamp | FLAG | NO_DRAW | count, draw of its first photon]`.
type State = [u64; 2];

/// Per block of shots: the bins' states (padded by one bin each side), the flagged bins,
/// a buffer of times.
struct Block {
    state: Vec<State>,
    flagged: Vec<u32>,
    /// The flagged bins, where more were flagged than `flagged` holds.
    all: Vec<u32>,
    times: Vec<f64>,
    /// `⌈(τ/Δt)·2^64⌉`: a photon's cell within `⌊width·edge/2^64⌋ + 1` of an edge is
    /// flagged.
    edge: u64,
}

/// The sink of one shot's photons: into the record at once, their bins' states updated
/// and flagged without a branch (`flagged[n]` written, `n` advanced by the flag; past the
/// buffer's end every flagged bin is looked up instead).
struct PlacedSink<'b> {
    acc: &'b mut [u64],
    state: &'b mut [State],
    stamp: u64,
    edge: u64,
    flagged: &'b mut [u32],
    n: usize,
}

impl CountSink for PlacedSink<'_> {
    /// Dense-path counts: photons without a draw, their bin flagged (their times drawn).
    #[inline(always)]
    fn add(&mut self, bin: usize, count: u32) {
        self.acc[bin] += u64::from(count);
        let st = &mut self.state[bin + 1];
        let again = (st[0] ^ self.stamp) >> STAMP_SHIFT == 0;
        st[0] = if again {
            st[0] + u64::from(count)
        } else {
            self.stamp | NO_DRAW | u64::from(count)
        } | FLAG;
        let last = self.flagged.len() - 1;
        self.flagged[self.n.min(last)] = bin as u32;
        self.n += 1;
    }

    #[inline(always)]
    fn add_placed(&mut self, bin: usize, draw: u64, offset: u64, width: u64) {
        self.acc[bin] += 1;
        let st = &mut self.state[bin + 1];
        let again = (st[0] ^ self.stamp) >> STAMP_SHIFT == 0;
        let e = ((u128::from(width) * u128::from(self.edge)) >> 64) as u64 + 1;
        let near = offset.min(width - 1 - offset) < e;
        let flag = u64::from(again | near) << 31;
        // branch-free (a second photon in a bin is not rare enough to predict)
        let keep = u64::from(again).wrapping_neg();
        st[0] = (((st[0] & keep) | (self.stamp & !keep)) + 1) | flag;
        st[1] = (st[1] & keep) | (draw & !keep);
        let last = self.flagged.len() - 1;
        self.flagged[self.n.min(last)] = bin as u32;
        self.n += (flag >> 31) as usize;
    }
}

/// Cost of the clusters path per bin and shot of mean λ (paralyzable), ns:
/// `CLUSTER_NS_PER_BIN + λ·(CLUSTER_NS_PER_PHOTON + CLUSTER_NS_PER_PAIR·min(λ, 1))`, the
/// last term the bins hit twice (sorted and swept); fitted to `benches/dead_time_rates.rs`
/// (`validation/reports/dead_time_cost.md`; 2026-12-05, a quiet machine, profiles of 100
/// shots: 0.16 ns a bin at 0.01 photons, 0.74 at 0.1, 1.7 at 0.2, 5.9 at 0.48).
const CLUSTER_NS_PER_BIN: f64 = 0.1;
/// See [`CLUSTER_NS_PER_BIN`].
const CLUSTER_NS_PER_PHOTON: f64 = 6.5;
/// See [`CLUSTER_NS_PER_BIN`].
const CLUSTER_NS_PER_PAIR: f64 = 10.0;

impl ClusterShots<'_> {
    /// Estimated cost of one shot of means `lambda` on this path, ns
    /// ([`CLUSTER_NS_PER_BIN`]).
    pub(super) fn ns_per_shot(lambda: &[f64]) -> f64 {
        lambda
            .iter()
            .map(|&l| {
                CLUSTER_NS_PER_BIN + l * (CLUSTER_NS_PER_PHOTON + CLUSTER_NS_PER_PAIR * l.min(1.0))
            })
            .sum()
    }

    /// Whether this path serves `dead`: bins at least 2τ wide.
    pub(super) fn serves(dead: &DeadTime) -> bool {
        dead.bin_width_s >= 2.0 * dead.tau_s
    }

    fn block(&self) -> Block {
        let p = self.dead.tau_s / self.dead.bin_width_s;
        Block {
            state: vec![[0; 2]; self.photons.bins() + 2],
            flagged: vec![0; self.photons.bins().max(64)],
            all: Vec::new(),
            times: Vec::new(),
            // p ≤ ½; rounded up, so that no cell within τ of an edge goes unflagged
            edge: ((p * TWO_POW_64) as u64).saturating_add(1),
        }
    }

    /// Draws `shots` shots (`stream_rng(seed, profile, block)` for the photons, its
    /// arrival stream for the detector, blocks of [`SHOT_BLOCK`] summed in integers) into
    /// `acc`.
    pub(super) fn profile(&self, seed: u64, profile: u64, shots: u64, acc: &mut [u64]) {
        let bins = acc.len();
        add_block_sums(acc, shots.div_ceil(SHOT_BLOCK), |b| {
            let mut part = vec![0u64; bins];
            let n = SHOT_BLOCK.min(shots - b * SHOT_BLOCK);
            let mut rng = stream_rng(seed, profile, b);
            let mut arrivals = stream_rng(seed ^ ARRIVAL_STREAM, profile, b);
            let mut block = self.block();
            for shot in 0..n {
                self.shot(&mut rng, &mut arrivals, shot, &mut block, &mut part);
            }
            part
        });
    }

    /// [`profile`](Self::profile)'s draws, each shot's recorded counts handed to `f`.
    pub(super) fn for_each_shot(
        &self,
        seed: u64,
        profile: u64,
        shots: u64,
        mut f: impl FnMut(&[u64]),
    ) {
        let mut acc = vec![0u64; self.photons.bins()];
        let mut rng = stream_rng(seed, profile, 0);
        let mut arrivals = stream_rng(seed ^ ARRIVAL_STREAM, profile, 0);
        let mut block = self.block();
        for shot in 0..shots {
            acc.iter_mut().for_each(|a| *a = 0);
            if shot > 0 && shot % (1 << 31) == 0 {
                block.state.iter_mut().for_each(|s| *s = [0; 2]);
            }
            self.shot(
                &mut rng,
                &mut arrivals,
                shot % (1 << 31),
                &mut block,
                &mut acc,
            );
            f(&acc);
        }
    }

    /// One shot (number `shot` < 2³¹ of its block): the photons into `acc`, then the
    /// flagged clusters corrected.
    #[inline(always)]
    fn shot<R: Rng + Clone, A: Rng + ?Sized>(
        &self,
        rng: &mut R,
        arrivals: &mut A,
        shot: u64,
        block: &mut Block,
        acc: &mut [u64],
    ) {
        let stamp = (shot + 1) << STAMP_SHIFT;
        let n = draw_photons(
            self.photons,
            rng,
            acc,
            &mut block.state,
            &mut block.flagged,
            stamp,
            block.edge,
        );
        if n > 0 {
            self.correct(arrivals, stamp, n, block, acc);
        }
    }

    /// The flagged clusters of the shot stamped `stamp` (`n` flagged) recorded exactly,
    /// `acc` corrected (apart from the shot's loop, so that the photons' loop stays small).
    #[inline(never)]
    fn correct<A: Rng + ?Sized>(
        &self,
        arrivals: &mut A,
        stamp: u64,
        n: usize,
        block: &mut Block,
        acc: &mut [u64],
    ) {
        let Block {
            state,
            flagged,
            all,
            times,
            ..
        } = block;
        let flagged_now = |s: &State| (s[0] ^ stamp) >> STAMP_SHIFT == 0 && s[0] & FLAG != 0;
        let starts: &[u32] = if n < flagged.len() {
            &flagged[..n]
        } else {
            // more flagged than the buffer holds: every flagged bin
            all.clear();
            all.extend(
                (0..state.len() as u32 - 2).filter(|&b| flagged_now(&state[b as usize + 1])),
            );
            all
        };
        let tau = self.dead.tau_s / self.dead.bin_width_s;
        let paralyzable = self.dead.model == DeadTimeModel::Paralyzable;
        for &b in starts {
            let mut j = b as usize + 1;
            if !flagged_now(&state[j]) {
                continue; // its cluster is recorded
            }
            while flagged_now(&state[j - 1]) {
                j -= 1;
            }
            // the cluster from bin j − 1 on, entered live; times in bins from its start
            let mut live_at = 0.0f64;
            while flagged_now(&state[j]) {
                let c = state[j][0] & COUNT_MASK;
                times.clear();
                // the first photon at its draw's place (its cell consulted), the others
                // anywhere (their draws decided nothing: the bin was flagged by them)
                let first = (state[j][0] & NO_DRAW == 0)
                    .then(|| self.photons.placement(state[j][1]))
                    .flatten();
                if let Some((_, offset, width)) = first {
                    let v = if width >= FINE_WIDTH {
                        0.5
                    } else {
                        unit_f64(arrivals.next_u64())
                    };
                    times.push((offset as f64 + v) / width as f64);
                }
                while (times.len() as u64) < c {
                    times.push(unit_f64(arrivals.next_u64()));
                }
                times.sort_unstable_by(f64::total_cmp);
                let mut k = 0u64;
                for &t in times.iter() {
                    let live = t >= live_at;
                    k += u64::from(live);
                    if live | paralyzable {
                        live_at = t + tau;
                    }
                }
                acc[j - 1] -= c - k;
                state[j][0] &= !FLAG;
                live_at = (live_at - 1.0).max(0.0);
                j += 1;
            }
        }
    }
}

/// The shot's photons into the record, the bins' states and the flagged list (returns
/// how many were flagged); the generator a local copy and the buffers arguments of their
/// own: behind references in a struct, the generator's state went through memory on
/// every photon (the sink's stores might alias it), which made the photons' loop 2–3×
/// the ideal detector's (measured, perf).
#[inline(never)]
fn draw_photons<R: Rng + Clone>(
    photons: &ShotSampler,
    rng: &mut R,
    acc: &mut [u64],
    state: &mut [State],
    flagged: &mut [u32],
    stamp: u64,
    edge: u64,
) -> usize {
    let mut local = rng.clone();
    let mut sink = PlacedSink {
        acc,
        state,
        stamp,
        edge,
        flagged,
        n: 0,
    };
    photons.sample_shot(&mut local, &mut sink);
    *rng = local;
    sink.n
}

/// A uniform in [0, 1) from the top 53 bits of `x`.
#[inline(always)]
fn unit_f64(x: u64) -> f64 {
    (x >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}
