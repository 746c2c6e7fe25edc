//! Multiple scattering on the beam path's bins (docs/model.md §4j): the small-angle
//! model ([`ms::small_angle_ratios`]) on steps cut at the bins, and the wide-angle
//! diffuse return ([`wide_angle::wide_angle_backscatter`]) on gates of the bins' width,
//! each bin's apparent over its single-scattering signal.

use super::beam_path::BeamPath;
use crate::atmosphere::multiple_scattering as ms;
use crate::atmosphere::wide_angle::{self, Gate};

/// One-way optical depth beyond which `e^{−2τ}` underflows to 0 (e^{−800}): the
/// multiple-scattering steps stop there, so that an opaque scene costs no more steps
/// than its first 400 optical depths.
const OPAQUE_OPTICAL_DEPTH: f64 = 400.0;

/// A bin's multiple scattering (the `small_angle` and `small_and_wide_angle` models).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BinMultipleScattering {
    /// Apparent over single-scattering signal of the bin (≥ 1; 1 without particles),
    /// its steps weighted by the channel's own single scattering.
    pub ratio: f64,
    /// The same in every polarization (steps weighted by the single scattering of
    /// every species), alike for every channel.
    pub total_ratio: f64,
    /// The clouds' single-scattering attenuated backscatter in every polarization,
    /// averaged over the bin (`Σ β_cld·T²·Δ/r² / Σ Δ/r²` over its steps), m⁻¹ sr⁻¹.
    pub cloud_single: f64,
    /// The same with each step's multiple scattering (and the bin's wide-angle return):
    /// the clouds' apparent return in every polarization, which a water cloud's
    /// depolarization splits between the channels.
    pub cloud_apparent: f64,
    /// One-way particle optical depth from the instrument to the bin centre.
    pub particle_optical_depth: f64,
    /// Linear depolarization of a water cloud's apparent return in the bin (Hu et al.
    /// 2006, `multiple_scattering::water_cloud_depolarization`); 0 outside water cloud.
    pub water_depolarization: f64,
    /// What that depolarization changes of the channel's share of the bin's return
    /// (1 outside water cloud and for a channel that sees every polarization alike).
    pub polarization_factor: f64,
}

impl BinMultipleScattering {
    /// The channel's apparent over its single-scattering signal in the bin: the ratio
    /// times the polarization factor.
    pub fn channel_ratio(&self) -> f64 {
        self.ratio * self.polarization_factor
    }

    /// A bin without multiple scattering (the `constant` model, pre-trigger bins).
    pub const NONE: BinMultipleScattering = BinMultipleScattering {
        ratio: 1.0,
        total_ratio: 1.0,
        cloud_single: 0.0,
        cloud_apparent: 0.0,
        particle_optical_depth: 0.0,
        water_depolarization: 0.0,
        polarization_factor: 1.0,
    };

    /// The effective multiple-scattering factor η of the particle optical depth above
    /// the bin centre: the constant η that would give the same signal,
    /// `ratio = e^{2(1−η)τ_p}`; 1 where there are no particles above.
    pub fn effective_factor(&self) -> f64 {
        if self.particle_optical_depth > 1e-9 {
            1.0 - self.ratio.ln() / (2.0 * self.particle_optical_depth)
        } else {
            1.0
        }
    }
}

/// One step's share of its bin (`BeamSteps::weights`).
struct StepWeight {
    bin: usize,
    channel: f64,
    total: f64,
    cloud: f64,
    range: f64,
}

/// The small-angle model's steps along the beam and what each bin needs of them.
#[derive(Default)]
struct BeamSteps {
    steps: Vec<ms::Step>,
    /// (step end range, particle optical depth there)
    ends: Vec<(f64, f64)>,
    /// per step: its bin, the single-scattering weights `β·T²·Δ/r²` of the channel,
    /// of every species in every polarization and of the clouds, and `Δ/r²`
    weights: Vec<StepWeight>,
}

impl BeamPath {
    /// The multiple scattering of each bin `(r_a, r_b)` (ascending, contiguous, of equal
    /// width): Hogan's PVC ([`ms::small_angle_ratios`]) along the beam in steps cut at
    /// the bins' edges and centres and no thicker than 0.05 in two-way optical depth,
    /// each step's ratio weighted in its bin by its single-scattering signal
    /// `β·T²·Δ/r²`; with `wide_angle`, plus the bin's wide-angle return over its
    /// single-scattering one ([`BeamPath::add_wide_angle`]).
    pub fn multiple_scattering_bins(
        &self,
        footprint: ms::Footprint,
        bins: &[(f64, f64)],
        wide_angle: bool,
    ) -> Vec<BinMultipleScattering> {
        let mut out = vec![BinMultipleScattering::NONE; bins.len()];
        let Some(first) = self.segments.first() else {
            return out;
        };
        let BeamSteps {
            steps,
            ends,
            weights,
        } = self.beam_steps(bins);
        let ratios = ms::small_angle_ratios(footprint, first.r_start, &steps);
        let n = bins.len();
        let mut sums = vec![(0.0, 0.0); n];
        let (mut single_total, mut apparent_total) = (vec![0.0; n], vec![0.0; n]);
        let mut range_sum = vec![0.0; n];
        for (w, ratio) in weights.into_iter().zip(ratios) {
            let i = w.bin;
            if let Some(s) = sums.get_mut(i) {
                s.0 += w.channel * ratio;
                s.1 += w.channel;
                single_total[i] += w.total;
                apparent_total[i] += w.total * ratio;
                out[i].cloud_single += w.cloud;
                out[i].cloud_apparent += w.cloud * ratio;
                range_sum[i] += w.range;
            }
        }
        for (i, (o, (num, den))) in out.iter_mut().zip(sums).enumerate() {
            if range_sum[i] > 0.0 {
                o.cloud_single /= range_sum[i];
                o.cloud_apparent /= range_sum[i];
            }
            if single_total[i] > 0.0 {
                o.total_ratio = apparent_total[i] / single_total[i];
            }
            o.ratio = if den > 0.0 {
                num / den
            } else {
                // the channel sees none of the bin's single scattering (a perpendicular
                // channel without cross-talk, every species of δ = 0): the ratio of
                // the return in every polarization, which a water cloud's
                // depolarization then gives the channel a share of
                o.total_ratio
            };
            let (a, b) = bins[i];
            let centre = 0.5 * (a + b);
            let k = ends.partition_point(|&(r, _)| r <= centre * (1.0 + 1e-12));
            o.particle_optical_depth = if k > 0 { ends[k - 1].1 } else { 0.0 };
        }
        if wide_angle {
            self.add_wide_angle(footprint, bins, &single_total, &range_sum, &mut out);
        }
        out
    }

    /// The beam path's slabs cut at every bin's edges and centre and into steps of at
    /// most 0.05 two-way optical depth, up to where T² underflows.
    fn beam_steps(&self, bins: &[(f64, f64)]) -> BeamSteps {
        let mut cuts: Vec<f64> = bins
            .iter()
            .flat_map(|&(a, b)| [a, 0.5 * (a + b), b])
            .collect();
        cuts.dedup();
        let mut out = BeamSteps::default();
        let mut tau_p = 0.0;
        debug_assert_eq!(self.lobes.len(), self.segments.len(), "PathExtent::Whole");
        for (s, l) in self.segments.iter().zip(&self.lobes) {
            if s.tau_start > OPAQUE_OPTICAL_DEPTH {
                break; // T² underflows to 0 here: these bins hold no signal to enhance
            }
            let lo = cuts.partition_point(|&c| c <= s.r_start);
            let hi = cuts.partition_point(|&c| c < s.r_end);
            let edges = std::iter::once(s.r_start)
                .chain(cuts[lo..hi].iter().copied())
                .chain(std::iter::once(s.r_end));
            let edges: Vec<f64> = edges.collect();
            for w in edges.windows(2) {
                let n = ms::pieces(w[1] - w[0], s.alpha);
                let d = (w[1] - w[0]) / n as f64;
                for k in 0..n {
                    let a = w[0] + k as f64 * d;
                    let tau = s.tau_start + s.alpha * (a - s.r_start);
                    let mid = a + 0.5 * d;
                    out.steps.push(ms::Step {
                        width_m: d,
                        alpha_particle_per_m: l.alpha_lobe,
                        alpha_theta2_per_m: l.alpha_theta2,
                        alpha_air_per_m: (s.alpha - l.alpha_lobe).max(0.0),
                    });
                    tau_p += l.alpha_particle * d;
                    out.ends.push((a + d, tau_p));
                    let bin = bins.partition_point(|&(_, b)| b <= mid);
                    let bin = match bins.get(bin) {
                        Some(&(a, _)) if a <= mid => bin,
                        _ => usize::MAX, // between the path's start and the first bin
                    };
                    let range = d / (mid * mid);
                    let t2 = (-2.0 * tau).exp() * range * ms::mean_exp(2.0 * s.alpha * d);
                    out.weights.push(StepWeight {
                        bin,
                        channel: s.beta * t2,
                        total: l.beta_total * t2,
                        cloud: l.beta_cloud * t2,
                        range,
                    });
                }
            }
        }
        out
    }

    /// Adds to each bin's ratio its wide-angle return (Hogan & Battaglia's TDTS,
    /// [`wide_angle::wide_angle_backscatter`]) over its single-scattering signal in all
    /// polarizations, `single_total` (`Σ β·T²·Δ/r²`). The calculation starts at the
    /// first bin with particles in the forward-lobe model (nearer, the air alone
    /// scatters too little to matter) and runs to the last, on gates of one bin or,
    /// past [`wide_angle::MAX_GATES`] bins, of several (each bin then gets its gate's
    /// backscatter).
    fn add_wide_angle(
        &self,
        footprint: ms::Footprint,
        bins: &[(f64, f64)],
        single_total: &[f64],
        range_sum: &[f64],
        out: &mut [BinMultipleScattering],
    ) {
        let (Some(path), Some(&(a0, b0))) = (self.segments.first(), bins.first()) else {
            return;
        };
        let width_m = b0 - a0;
        let Some(first) = bins
            .iter()
            .position(|&(a, b)| self.gate_over(a, b).alpha_particle_per_m > 0.0)
        else {
            return;
        };
        if first + 2 >= bins.len() {
            return;
        }
        let per_gate = (bins.len() - first).div_ceil(wide_angle::MAX_GATES);
        let gate_m = width_m * per_gate as f64;
        let start = bins[first].0;
        let gates: Vec<Gate> = (0..(bins.len() - first).div_ceil(per_gate))
            .map(|j| self.gate_over(start + j as f64 * gate_m, start + (j + 1) as f64 * gate_m))
            .collect();
        // out along the quasi-direct beam, back delta-scaled (HB08's code)
        let before = self.gate_over(path.r_start, start);
        let two_way = (before.outward_extinction_per_m() + before.inward_extinction_per_m())
            * (start - path.r_start).max(0.0);
        let wide = wide_angle::wide_angle_backscatter(
            footprint,
            gate_m,
            start + 0.5 * gate_m,
            &gates,
            (-two_way).exp(),
        );
        for (i, &(a, b)) in bins.iter().enumerate().skip(first) {
            if single_total[i] > 0.0 {
                let signal = wide[(i - first) / per_gate] * (1.0 / a - 1.0 / b);
                out[i].ratio += signal / single_total[i];
                out[i].total_ratio += signal / single_total[i];
                // the diffuse light is the clouds' (the air scatters too little)
                out[i].cloud_apparent += signal / range_sum[i];
            }
        }
    }

    /// The mean optics of the beam path over `[a, b]` as a wide-angle gate (the
    /// particles with a forward lobe apart, all else as air).
    fn gate_over(&self, a: f64, b: f64) -> Gate {
        let mut g = Gate::default();
        if b <= a {
            return g;
        }
        let k = self.segments.partition_point(|s| s.r_end <= a);
        let along = self.segments[k..]
            .iter()
            .zip(&self.lobes[k.min(self.lobes.len())..]);
        for (s, l) in along.take_while(|(s, _)| s.r_start < b) {
            let len = s.r_end.min(b) - s.r_start.max(a);
            if len <= 0.0 {
                continue;
            }
            let air = (s.alpha - l.alpha_lobe).max(0.0);
            g.alpha_particle_per_m += l.alpha_lobe * len;
            g.alpha_g_per_m += l.alpha_lobe_g * len;
            g.alpha_theta2_per_m += l.alpha_theta2 * len;
            g.alpha_air_per_m += air * len;
            g.scattering_air_per_m += (air - l.alpha_absorbing).max(0.0) * len;
        }
        let w = b - a;
        g.alpha_particle_per_m /= w;
        g.alpha_g_per_m /= w;
        g.alpha_theta2_per_m /= w;
        g.alpha_air_per_m /= w;
        g.scattering_air_per_m /= w;
        g
    }
}
