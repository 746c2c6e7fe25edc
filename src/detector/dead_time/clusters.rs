//! The photon path of the dead time at the ideal detector's cost ([`ClusterShots`]): the
//! shot's photons go straight into the record, as without dead time, and only the
//! *clusters* (runs of adjacent bins hit in the same shot, or a bin hit more than once)
//! are corrected afterwards, in time order, the dead time carried from bin to bin.
//!
//! # Method
//!
//! The photons of a shot are the shot path's ([`ShotSampler::sample_shot`], the same
//! draws), reported to a [`CountSink`] that adds each to the record at once and stamps its
//! bin with the shot's number. A photon can lose (or cost) a count only within τ of
//! another; with Δt ≥ 2τ that needs a second photon in its bin or in a neighbouring one.
//! The sink flags a bin when its photon lands next to (or in) a bin already hit in the
//! shot; after the shot each flagged cluster is recorded exactly, in time order, from its
//! first bin (entered live: the bin before it is empty and at least τ long), and the record
//! corrected by the difference. Per bin of a cluster, entered dead for `r ∈ [0, τ)`:
//!
//! * **one photon**: its time `t = Δt·U` (one `u64`), drawn only when it matters (`r > 0`
//!   or the next bin hit): lost if `t < r`, else recorded and leaving `max(0, t + τ − Δt)`;
//!   both models alike (a paralyzable detector's lost photon at `t < r < τ` leaves nothing
//!   past `Δt ≥ 2τ`);
//! * **two photons, alone** (no residual in, none needed out): one `u64` against
//!   `P(|U₁ − U₂| < τ/Δt) = 1 − (1 − τ/Δt)²`: one count lost, else none; both models;
//! * **more photons**, non-paralyzable: the counting tables given the photons
//!   ([`counting::Family::record_bin`], exact, residual in and out); paralyzable (or more
//!   than [`counting::MAX_PHOTONS`]): the bin's arrival times, sorted, swept with the
//!   detector live from `r` on, every photon restarting the dead time.
//!
//! Exact: each photon's time is uniform in its bin and independent of the others' (the
//! rate constant within a bin), drawn lazily, and a time is left undrawn only where no
//! outcome depends on it. The photons drawn, shot for shot, are the shot path's.
//!
//! # Cost
//!
//! Per photon, next to the ideal detector's own draw: a read of its bin's and neighbours'
//! stamps and a write; per cluster bin one `u64` (or the bin's tables or sweep). Measured
//! by `benches/dead_time_rates.rs` (`validation/reports/dead_time_cost.md`).
//!
//! [`ShotSampler::sample_shot`]: crate::sampling::ShotSampler::sample_shot

use rand::Rng;

use super::model::{DeadTime, DeadTimeModel};
use super::record::{ARRIVAL_STREAM, sorted_uniform_times};
use crate::detector::counting::{self, Family};
use crate::sampling::{CountSink, SHOT_BLOCK, ShotSampler, add_block_sums, stream_rng};

/// The shot number's place in a bin's state (the count this shot below it).
const STAMP_SHIFT: u32 = 32;
/// The state's count bits.
const COUNT_MASK: u64 = (1 << 31) - 1;
/// A bin whose cluster is recorded.
const DONE: u64 = 1 << 31;

const TWO_POW_64: f64 = 18_446_744_073_709_551_616.0;

/// Shots of fixed means through a dead time by their photons, the clusters corrected (see
/// the module docs): bins at least 2τ wide, either model.
#[derive(Debug)]
pub(super) struct ClusterShots<'a> {
    pub(super) photons: &'a ShotSampler,
    pub(super) dead: &'a DeadTime,
}

/// Per block of shots: the bins' states (padded by one bin each side), the flagged bins,
/// the counting tables, a buffer of arrival times.
struct Block {
    state: Vec<u64>,
    flagged: Vec<u32>,
    /// The hit bins, where more were flagged than `flagged` holds.
    all: Vec<u32>,
    family: Option<std::sync::Arc<Family>>,
    times: Vec<f64>,
    /// `⌊P(|U₁ − U₂| < τ/Δt)·2^64⌋`.
    pair_lost: u64,
}

/// The sink of one shot's photons: into the record at once, their bins stamped, the bins
/// flagged without a branch (`flagged[n]` written, `n` advanced by the flag; past the
/// buffer's end every hit bin is looked at instead).
struct StampSink<'b> {
    acc: &'b mut [u64],
    state: &'b mut [u64],
    stamp: u64,
    flagged: &'b mut [u32],
    n: usize,
}

impl CountSink for StampSink<'_> {
    #[inline(always)]
    fn add(&mut self, bin: usize, count: u32) {
        self.acc[bin] += u64::from(count);
        let w = &mut self.state[bin..bin + 3];
        // stamped this shot: the same shot number in the top 32 bits
        let hit = |s: u64| (s ^ self.stamp) >> STAMP_SHIFT == 0;
        let here = w[1];
        let again = hit(here);
        let near = hit(w[0]) | hit(w[2]);
        w[1] = if again { here } else { self.stamp } + u64::from(count);
        let last = self.flagged.len() - 1;
        self.flagged[self.n.min(last)] = bin as u32;
        self.n += usize::from(again | near | (count > 1));
    }
}

impl ClusterShots<'_> {
    /// Whether this path serves `dead`: bins at least 2τ wide.
    pub(super) fn serves(dead: &DeadTime) -> bool {
        dead.bin_width_s >= 2.0 * dead.tau_s
    }

    fn block(&self) -> Block {
        let (tau, dt) = (self.dead.tau_s, self.dead.bin_width_s);
        let p = tau / dt;
        // 1 − (1 − p)², without cancellation
        let lost = p * (2.0 - p);
        Block {
            state: vec![0; self.photons.bins() + 2],
            flagged: vec![0; self.photons.bins().max(64)],
            all: Vec::new(),
            family: (self.dead.model == DeadTimeModel::Nonparalyzable)
                .then(|| counting::family(tau, dt)),
            times: Vec::new(),
            pair_lost: (lost * TWO_POW_64) as u64,
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
                block.state.iter_mut().for_each(|s| *s = 0);
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
    fn shot<R: Rng + ?Sized, A: Rng + ?Sized>(
        &self,
        rng: &mut R,
        arrivals: &mut A,
        shot: u64,
        block: &mut Block,
        acc: &mut [u64],
    ) {
        let stamp = (shot + 1) << STAMP_SHIFT;
        let mut sink = StampSink {
            acc,
            state: &mut block.state,
            stamp,
            flagged: &mut block.flagged,
            n: 0,
        };
        self.photons.sample_shot(rng, &mut sink);
        let n = sink.n;
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
            family,
            times,
            pair_lost,
        } = block;
        let hit = |s: u64| (s ^ stamp) >> STAMP_SHIFT == 0;
        let starts: &[u32] = if n < flagged.len() {
            &flagged[..n]
        } else {
            // more flagged than the buffer holds: every hit bin
            all.clear();
            all.extend((0..state.len() as u32 - 2).filter(|&b| hit(state[b as usize + 1])));
            all
        };
        for &b in starts {
            let mut j = b as usize + 1;
            if state[j] & DONE != 0 {
                continue;
            }
            while hit(state[j - 1]) {
                j -= 1;
            }
            self.cluster(
                arrivals,
                j,
                state,
                family.as_deref(),
                times,
                *pair_lost,
                acc,
            );
        }
    }

    /// Records the cluster whose first bin has state index `j` (bin `j − 1`) exactly,
    /// entered live, correcting `acc`; marks its bins done.
    #[allow(clippy::too_many_arguments)]
    fn cluster<A: Rng + ?Sized>(
        &self,
        rng: &mut A,
        mut j: usize,
        state: &mut [u64],
        family: Option<&Family>,
        times: &mut Vec<f64>,
        pair_lost: u64,
        acc: &mut [u64],
    ) {
        let (tau, dt) = (self.dead.tau_s, self.dead.bin_width_s);
        let stamp = state[j] >> STAMP_SHIFT;
        let mut r = 0.0f64;
        loop {
            let c = (state[j] & COUNT_MASK) as u32;
            state[j] |= DONE;
            let next = state[j + 1] >> STAMP_SHIFT == stamp;
            let (k, left) = if c == 1 {
                if r == 0.0 && !next {
                    (1, 0.0)
                } else {
                    let t = dt * unit_f64(rng.next_u64());
                    if t < r {
                        (0, 0.0)
                    } else {
                        (1, (t + tau - dt).max(0.0))
                    }
                }
            } else if c == 2 && r == 0.0 && !next {
                (2 - u32::from(rng.next_u64() < pair_lost), 0.0)
            } else {
                match family {
                    Some(f) if c <= counting::MAX_PHOTONS => f.record_bin(rng, c, r, next),
                    _ => self.sweep_bin(rng, c, r, times),
                }
            };
            let i = j - 1;
            acc[i] = acc[i] + u64::from(k) - u64::from(c);
            if !next {
                return;
            }
            r = left;
            j += 1;
        }
    }

    /// One bin of `c` photons by their arrival times, entered dead for `r`: the recorded
    /// count and the dead time left at its end (paralyzable: every photon restarts it).
    fn sweep_bin<A: Rng + ?Sized>(
        &self,
        rng: &mut A,
        c: u32,
        r: f64,
        times: &mut Vec<f64>,
    ) -> (u32, f64) {
        let (tau, dt) = (self.dead.tau_s, self.dead.bin_width_s);
        let paralyzable = self.dead.model == DeadTimeModel::Paralyzable;
        sorted_uniform_times(rng, c, 0.0, dt, times);
        let (mut k, mut live_at) = (0u32, r);
        for &t in times.iter() {
            let live = t >= live_at;
            k += u32::from(live);
            if live | paralyzable {
                live_at = t + tau;
            }
        }
        (k, (live_at - dt).max(0.0))
    }
}

/// A uniform in [0, 1) from the top 53 bits of `x`.
#[inline(always)]
fn unit_f64(x: u64) -> f64 {
    (x >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}
