//! What `validate --file` adds up per bin over the judged profiles, and what the file
//! says of its channels.

use crate::detector::DeadTime;
use crate::validate::exact::ExactSum;

/// Per-bin sums over the judged profiles.
#[derive(Debug, Clone, Default)]
pub(super) struct Sums {
    pub(super) total: u128,
    pub(super) mu: ExactSum,
    pub(super) var: ExactSum,
    pub(super) v: ExactSum,
    pub(super) var_y: ExactSum,
    pub(super) k3: ExactSum,
    pub(super) k4: ExactSum,
}

impl Sums {
    /// A count `c` of mean `mu` and variance `var` (Poisson-shaped at that variance):
    /// `Y = (c − μ)²` has `E Y = var` and the cumulants of [`scene`](crate::validate::scene) at `var`.
    pub(super) fn push(&mut self, c: u64, mu: f64, var: f64) {
        let d = c as f64 - mu;
        self.total += u128::from(c);
        self.mu.add(mu);
        self.var.add(var);
        self.v.add(d * d);
        self.var_y.add(var + 2.0 * var * var);
        self.k3.add(var + 22.0 * var * var + 8.0 * var.powi(3));
        self.k4
            .add(var + 112.0 * var * var + 384.0 * var.powi(3) + 48.0 * var.powi(4));
    }
}

/// What the file says of its channels.
pub(super) struct Channels {
    pub(super) names: Vec<String>,
    /// `nominal_pulse_energy` of each channel: the energy its `pulse_energy` is relative to.
    pub(super) nominal_energy: Vec<f64>,
    /// Each channel's dead time, None for an ideal detector.
    pub(super) dead: Vec<Option<DeadTime>>,
}
