//! The wide-angle part of multiple scattering (docs/model.md §4j): Hogan & Battaglia's
//! (2008, J. Atmos. Sci. 65, 3636) time-dependent two-stream (TDTS) method, for
//! optically thick cloud whose photons scatter many times through wide angles and still
//! reach the field of view.
//!
//! **Physics.** The small-angle model ([`super::multiple_scattering`]) follows the
//! photons that stay in the narrow forward lobe of large particles. Photons scattered
//! outside it (the other half of the particles' extinction, and all of the air's) spread
//! through the cloud by diffusion; a wide field of view, or a cloud many mean free paths
//! deep, sees them come back late (the pulse stretches below a cloud's base). Two
//! streams carry this light, one away from the instrument and one back, each with its
//! energy `I` and its lateral spread `V = I·⟨x²⟩`.
//!
//! **Algorithm (HB08 §2–3).** On gates of equal width Δ, time advances in steps of Δ/c.
//! - *Sources.* The quasi-direct beam (the unscattered photons and the forward lobe's,
//!   attenuated by the air and half the particles' extinction) loses to the wide-angle
//!   streams, in each gate, the scattering outside the lobe: `½α_p + σ_air` times the
//!   gate's mean transmission. The two-stream phase function splits it into
//!   `½(1 ∓ 3g_w μ₁)` (back, on), with `g_w` the asymmetry of the phase function
//!   without its forward peak; the source's spread is the quasi-direct beam's there
//!   (its second moments, stepped as in the small-angle model with half the lobe term:
//!   the way out only).
//! - *Medium.* Delta-scaled ("δ-Eddington"): the particles' forward peak `g²` counts as
//!   unscattered, `α' = α_air + α_p(1 − g²)`, `g' = g/(1 + g)`; the air scatters
//!   isotropically.
//! - *Transfer.* Each step moves a stream's energy within its gate, into the other
//!   stream, or one gate on or back, with the six coefficients of HB08's upwind scheme
//!   made stable for gates of any optical depth: transport over a mean free path
//!   `l_t = 1/(α'(1 − ϖ'g'))`, absorption, and a diffusion term for photons that cross
//!   a gate faster than the two-stream speed μ₁c. They sum to the gate's absorption
//!   factor, so energy is conserved without absorbers ([`Transfer::new`]).
//! - *Spread.* Each step adds to `V` the lateral expansion of diffusion theory started
//!   ballistically (HB08 Eq. 18–20 in the form accurate to 1.5 %, [`expansion_m2`]).
//! - *Return.* In each step each gate backscatters toward the receiver
//!   `ϖ'α'(1 ± 3g'μ₁)/(4π)` of each stream, the share inside the field of view
//!   (`1 − e^{−W/⟨x²⟩}` for a top-hat of radius² `W`, capped at what light could have
//!   reached by then), attenuated on the way back by the delta-scaled optical depth. A
//!   photon in gate `i` at step `t` is seen at apparent gate `⌊(t + i)/2⌋`.
//!
//! Hogan's own C implementation (the `multiscatter` package, LGPL) is the reference the
//! tests compare with (tests/wide_angle.rs: within 1e-7 where its inputs are this
//! model's); this is written from the method. It departs in one place: the source's
//! asymmetry `g_w` leaves the air isotropic (his gives the air the particles' g),
//! which moves clear-air gates near a cloud by a few per cent of a return far below
//! single scattering. The source's spread follows his implementation, not the exact
//! moment integral ([`SourceBeam`]).
//!
//! **Not modelled.** The surface (light reaching it is lost), absorbing particles
//! (ϖ = 1), the depolarization of the diffuse light below a water cloud (it keeps the
//! air's), and the anisotropic phase function near 180°.
//!
//! **Cost.** O(n²) in the gates from the first particles with a forward lobe to the
//! window's end; past [`MAX_GATES`] the gates are widened (`benches/multiple_scattering.rs`).

use super::multiple_scattering::{Footprint, mean_exp};

/// The two streams' direction cosine μ₁ (HB08 §2a).
const MU1: f64 = 0.5;
/// Diffusion theory's factor between the transport mean free path and the lateral
/// spread (HB08 Eq. 18).
const DIFFUSION_FACTOR: f64 = 4.0 / 3.0;
/// The most gates the calculation runs on; a longer stretch gets wider gates. The cost is
/// O(gates²) (`benches/multiple_scattering.rs`: 2,000 gates take ~0.3 s); widening the
/// gates blurs the return where it changes within a gate, behind a cloud's far edge most
/// (docs/model.md §4j).
pub const MAX_GATES: usize = 2000;

/// One gate's optics, each a mean over the gate.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Gate {
    /// Extinction of the particles with a narrow forward lobe, m⁻¹ (non-absorbing).
    pub alpha_particle_per_m: f64,
    /// The same weighted by their asymmetry factor, `Σ α·g`, m⁻¹.
    pub alpha_g_per_m: f64,
    /// The same weighted by their squared forward-lobe width, `Σ α·Θ²`, m⁻¹ rad².
    pub alpha_theta2_per_m: f64,
    /// The rest of the extinction (molecules, absorbing gases, particles with a wide
    /// lobe), m⁻¹.
    pub alpha_air_per_m: f64,
    /// The scattering part of it (isotropic here), m⁻¹.
    pub scattering_air_per_m: f64,
}

impl Gate {
    /// The particles' mean asymmetry factor (0 without particles).
    fn asymmetry(&self) -> f64 {
        if self.alpha_particle_per_m > 0.0 {
            self.alpha_g_per_m / self.alpha_particle_per_m
        } else {
            0.0
        }
    }

    /// Extinction of the quasi-direct beam on its way out, m⁻¹: the air's and the half
    /// of the particles' that leaves the forward lobe.
    pub fn outward_extinction_per_m(&self) -> f64 {
        self.alpha_air_per_m + 0.5 * self.alpha_particle_per_m
    }

    /// Extinction of the light on its way back, m⁻¹: the delta-scaled medium's.
    pub fn inward_extinction_per_m(&self) -> f64 {
        self.scaled().0
    }

    /// The delta-scaled medium the wide-angle streams cross: extinction, single-scattering
    /// albedo and asymmetry factor.
    fn scaled(&self) -> (f64, f64, f64) {
        let g = self.asymmetry();
        let particles = self.alpha_particle_per_m * (1.0 - g * g);
        let extinction = self.alpha_air_per_m + particles;
        let scattering = self.scattering_air_per_m + particles;
        if extinction <= 0.0 {
            return (0.0, 0.0, 0.0);
        }
        let g_scaled = if scattering > 0.0 {
            particles * g / (1.0 + g) / scattering
        } else {
            0.0
        };
        (extinction, scattering / extinction, g_scaled)
    }

    /// The power one unit of quasi-direct beam gives the wide-angle streams per metre,
    /// and the asymmetry of the phase function without its forward peak.
    fn source(&self) -> (f64, f64) {
        let alpha_p = self.alpha_particle_per_m;
        let power = 0.5 * alpha_p + self.scattering_air_per_m;
        let g_wide = if power > 0.0 {
            alpha_p * (self.asymmetry() - 0.5) / power
        } else {
            0.0
        };
        (power, g_wide)
    }
}

/// The shares of a stream's energy in a gate that, after one step, are (HB08 §3a):
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Transfer {
    /// in the same gate and stream,
    pub stay: f64,
    /// in the same gate, the other stream,
    pub turn: f64,
    /// one gate on in its direction, same stream,
    pub advance: f64,
    /// one gate on, the other stream (also one gate back, the other stream),
    pub advance_turned: f64,
    /// one gate back against its direction, same stream (diffusion).
    pub retreat: f64,
}

impl Transfer {
    /// The coefficients of a gate of width `width_m` in a medium of extinction
    /// `extinction`, albedo `ssa` and asymmetry `g` (delta-scaled), stable for any
    /// optical depth of the gate. They sum to the gate's absorption factor
    /// `e^{−α(1−ϖ)Δ}` (with the "turned" share counted twice, on and back).
    pub fn new(width_m: f64, extinction: f64, ssa: f64, g: f64) -> (Transfer, f64) {
        if extinction <= 0.0 {
            let empty = Transfer {
                stay: 1.0 - MU1,
                advance: MU1,
                ..Default::default()
            };
            return (empty, f64::INFINITY);
        }
        let mfp_transport = 1.0 / (extinction * (1.0 - ssa * g));
        let x = width_m / mfp_transport;
        let f_transport = (-x).exp();
        let f_absorb = (-extinction * (1.0 - ssa) * width_m).exp();
        // the share of scattered photons that leave the gate: μ₁(l_t/Δ − f/(1−f))
        let f = MU1 * (1.0 / x + f_transport / (-x).exp_m1());
        let diffusion = MU1 * ssa * f_absorb * (1.0 / (3.0 * x)).sqrt();
        let d1 = diffusion * (-3.7 * x.powf(-0.75)).exp();
        let d2 = diffusion * (-3.7 / x).exp();
        let scattered = f_absorb - f_transport;
        let mut t = Transfer {
            stay: f_transport * (1.0 - MU1) + scattered * (0.5 - f) - d1,
            turn: scattered * (1.0 - f) * 0.5 - d2,
            advance: MU1 * f_transport + scattered * f + 0.5 * d1,
            advance_turned: 0.25 * scattered * f + 0.5 * d2,
            retreat: 0.5 * d1,
        };
        // the diffusion terms can exceed the transport terms: move the excess, keeping
        // the energy
        if t.stay < 0.0 {
            t.advance -= 0.5 * t.stay;
            t.retreat -= 0.5 * t.stay;
            t.stay = 0.0;
        }
        if t.turn < 0.0 {
            t.advance_turned -= 0.5 * t.turn;
            t.turn = 0.0;
        }
        (t, mfp_transport)
    }

    /// The sum of the shares: the energy a stream keeps over a step.
    pub fn total(&self) -> f64 {
        self.stay + self.turn + self.advance + 2.0 * self.advance_turned + self.retreat
    }
}

/// The lateral spread a stream's photons add over one step, m² per unit energy: diffusion
/// started ballistically, given the spread `varw0` they had at their source and `var`
/// they have now, in a medium of transport mean free path `lt` (HB08 Eq. 18–20, the
/// fast form: `n` solves `(4/3)(n + e^{−n} − 1) = (var − varw0)/lt²` within 1.5 %).
pub fn expansion_m2(width_m: f64, lt: f64, varw0: f64, var: f64) -> f64 {
    expansion_with_decay(width_m, lt, (-width_m / lt).exp_m1(), varw0, var)
}

/// [`expansion_m2`] given `e^{−Δ/l_t} − 1` (one per gate, not per step).
fn expansion_with_decay(width_m: f64, lt: f64, decay_m1: f64, varw0: f64, var: f64) -> f64 {
    let n = if var <= varw0 {
        0.0
    } else {
        let norm = (var - varw0) / (lt * lt);
        if norm < 1.0 {
            let s = (2.0 * norm / DIFFUSION_FACTOR).sqrt();
            s * (1.0 + 0.2 * s)
        } else {
            norm / DIFFUSION_FACTOR + 1.0 - 0.24 / (norm * norm)
        }
    };
    DIFFUSION_FACTOR * lt * (width_m + lt * (-n).exp() * decay_m1)
}

/// The quasi-direct beam's second moments at the gates' centres, as the source of the
/// wide-angle streams: stepped once per gate as HB08's implementation does, the position
/// variance growing by `⟨θ²⟩Δ² + ⟨xθ⟩Δ` and the forward lobe widening the direction
/// (`½αΘ²Δ`: the way out only) after the step. This grows the width more slowly than the
/// exact moment integral (half the covariance term, the lobe a gate late); it is kept
/// because the published TDTS results, checked against Monte Carlo, use it, and the
/// exact integral gives up to half their wide-angle return below a cloud seen through a
/// narrow footprint (docs/model.md §4j).
struct SourceBeam {
    width2: f64,
    cov: f64,
    zeta2: f64,
}

impl SourceBeam {
    /// The unscattered beam of 1/e angular half-width² `rho_t2` at range `r`.
    fn new(r: f64, rho_t2: f64) -> Self {
        SourceBeam {
            width2: r * r * rho_t2,
            cov: r * rho_t2,
            zeta2: rho_t2,
        }
    }

    /// One gate of width `d` and forward-lobe source `Σ α·Θ²` = `alpha_theta2`.
    fn step(&mut self, d: f64, alpha_theta2: f64) {
        self.width2 += self.zeta2 * d * d + self.cov * d;
        self.cov += self.zeta2 * d;
        self.zeta2 += 0.5 * alpha_theta2 * d;
    }
}

/// Two streams of wide-angle light along the gates (index 1..=n; 0 and n+1 stay empty:
/// light leaving the gates is lost).
#[derive(Clone)]
struct Streams {
    energy_back: Vec<f64>,
    energy_on: Vec<f64>,
    spread_back: Vec<f64>,
    spread_on: Vec<f64>,
}

impl Streams {
    fn new(n: usize) -> Self {
        Streams {
            energy_back: vec![0.0; n + 2],
            energy_on: vec![0.0; n + 2],
            spread_back: vec![0.0; n + 2],
            spread_on: vec![0.0; n + 2],
        }
    }
}

/// One stream's transfer into gate `k` (padded index) from itself and its neighbours:
/// `same` is the stream arriving in its own direction from `k − dir`, `other` the other
/// stream. `ahead`/`behind` are the neighbours in the stream's direction of travel.
#[inline]
fn gather(
    t: &[Transfer],
    same: &[f64],
    other: &[f64],
    k: usize,
    from_behind: usize,
    from_ahead: usize,
) -> f64 {
    same[k] * t[k].stay
        + other[k] * t[k].turn
        + same[from_behind] * t[from_behind].advance
        + other[from_ahead] * t[from_ahead].advance_turned
        + same[from_ahead] * t[from_ahead].retreat
        + other[from_behind] * t[from_behind].advance_turned
}

/// What the quasi-direct beam gives the two streams in each gate: power (relative to
/// the pulse, calibrated) and the spread it starts with.
struct Sources {
    back: Vec<f64>,
    on: Vec<f64>,
    spread: Vec<f64>,
}

impl Sources {
    /// The sources of `gates`, the first gate's centre at `first_range_m`, for a beam of
    /// 1/e half-width² `rho_t2`; `calibration` scales the power.
    fn new(
        gates: &[Gate],
        width_m: f64,
        first_range_m: f64,
        rho_t2: f64,
        calibration: f64,
    ) -> Self {
        let n = gates.len();
        let mut out = Sources {
            back: vec![0.0; n],
            on: vec![0.0; n],
            spread: vec![0.0; n],
        };
        let mut beam = SourceBeam::new(first_range_m, rho_t2);
        let mut tau_out = 0.0_f64;
        for (i, gate) in gates.iter().enumerate() {
            if i > 0 {
                beam.step(width_m, gates[i - 1].alpha_theta2_per_m);
            }
            out.spread[i] = beam.width2;
            let od = gate.outward_extinction_per_m() * width_m;
            let mean_transmission = (-tau_out).exp() * mean_exp(od);
            tau_out += od;
            let (power, g_wide) = gate.source();
            let power = calibration * mean_transmission * power * width_m;
            let back_share = (0.5 * (1.0 - 3.0 * g_wide * MU1)).clamp(0.0, 1.0);
            out.back[i] = power * back_share;
            out.on[i] = power * (1.0 - back_share);
        }
        out
    }
}

/// The delta-scaled medium of each gate as the streams see it (padded index 1..=n):
/// transfer shares, transport mean free path, and the return toward the receiver.
struct Medium {
    transfer: Vec<Transfer>,
    mfp: Vec<f64>,
    /// `e^{−Δ/l_t} − 1`
    decay: Vec<f64>,
    /// `ϖ'α'·T_back/(4π)`, unpadded
    ret: Vec<f64>,
    /// the backscatter phase of the back and on streams, `1 ± 3g'μ₁`, unpadded
    phase: Vec<(f64, f64)>,
}

impl Medium {
    fn new(gates: &[Gate], width_m: f64) -> Self {
        let n = gates.len();
        let mut m = Medium {
            transfer: vec![Transfer::default(); n + 2],
            mfp: vec![1e6 * width_m; n + 2],
            decay: vec![0.0; n + 2],
            ret: vec![0.0; n],
            phase: vec![(0.0, 0.0); n],
        };
        let mut tau_back = 0.0_f64;
        for (i, gate) in gates.iter().enumerate() {
            let (extinction, ssa, g) = gate.scaled();
            let (t, lt) = Transfer::new(width_m, extinction, ssa, g);
            m.transfer[i + 1] = t;
            if lt.is_finite() {
                m.mfp[i + 1] = lt;
            }
            m.decay[i + 1] = (-width_m / m.mfp[i + 1]).exp_m1();
            let od = extinction * width_m;
            let t_back = (-tau_back).exp() * mean_exp(od);
            tau_back += od;
            m.ret[i] = ssa * extinction * t_back / (4.0 * std::f64::consts::PI);
            let back = (1.0 + 3.0 * g * MU1).min(2.0);
            m.phase[i] = (back, (2.0 - back).max(0.0));
        }
        m
    }
}

/// The wide-angle apparent backscatter (m⁻¹ sr⁻¹, in the units of single scattering's
/// `β·T²`) of each of `gates` (equal width `width_m`; the first gate's centre at range
/// `first_range_m` from the instrument), for a quasi-direct beam that reaches the first
/// gate with transmission `transmission_to_start` (out and back).
pub fn wide_angle_backscatter(
    footprint: Footprint,
    width_m: f64,
    first_range_m: f64,
    gates: &[Gate],
    transmission_to_start: f64,
) -> Vec<f64> {
    let n = gates.len();
    let mut out = vec![0.0; n];
    if n == 0 {
        return out;
    }
    let rho_t2 = footprint.divergence_rad.powi(2);
    let rho_r2 = footprint.fov_half_angle_rad.powi(2);
    // the unscattered beam's share in the field of view: single scattering is calibrated
    let calibration = transmission_to_start / -(-rho_r2 / rho_t2).exp_m1();
    let range = |i: usize| first_range_m + i as f64 * width_m;
    let src = Sources::new(gates, width_m, first_range_m, rho_t2, calibration);
    let Medium {
        transfer,
        mfp,
        decay,
        ret,
        phase,
    } = Medium::new(gates, width_m);

    let mut now = Streams::new(n);
    let mut next = Streams::new(n);
    let steps = 2 * n;
    for it in 0..steps {
        // gates the light has reached, and from which it can still return in time
        let last = it.min(n - 1).min(steps - it);
        for i in 0..=last {
            let k = i + 1;
            let (back, on) = (&now.energy_back, &now.energy_on);
            // "back" travels toward the instrument: it arrives from k + 1
            next.energy_back[k] = gather(&transfer, back, on, k, k + 1, k - 1);
            next.energy_on[k] = gather(&transfer, on, back, k, k - 1, k + 1);
            let (vb, vo) = (&now.spread_back, &now.spread_on);
            let grow = |e: f64, v: f64| {
                if e > 0.0 {
                    e * expansion_with_decay(width_m, mfp[k], decay[k], src.spread[i], v / e)
                } else {
                    0.0
                }
            };
            next.spread_back[k] = gather(&transfer, vb, vo, k, k + 1, k - 1) + grow(back[k], vb[k]);
            next.spread_on[k] = gather(&transfer, vo, vb, k, k - 1, k + 1) + grow(on[k], vo[k]);

            let j = (it + i) / 2;
            if j < n {
                let r = range(i);
                // light cannot have spread faster than it travelled
                let ballistic = ((it - i) as f64 * width_m).powi(2) + rho_t2 * r * r;
                let w = (rho_r2 * r * r).min(ballistic);
                let seen = |e: f64, v: f64| {
                    if e > 0.0 && v > 0.0 {
                        -(-w * e / v).exp_m1() * e
                    } else {
                        0.0
                    }
                };
                out[j] += ret[i]
                    * (phase[i].0 * seen(next.energy_back[k], next.spread_back[k])
                        + phase[i].1 * seen(next.energy_on[k], next.spread_on[k]));
            }
        }
        if it < n {
            let k = it + 1;
            next.energy_back[k] += src.back[it];
            next.energy_on[k] += src.on[it];
            next.spread_back[k] += src.back[it] * src.spread[it];
            next.spread_on[k] += src.on[it] * src.spread[it];
        }
        std::mem::swap(&mut now, &mut next);
    }
    out
}
