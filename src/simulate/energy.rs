//! The emitted energies of a run: their law, seed and envelope over the run.

use crate::error::{Error, Result};
use crate::laser::PulseEnergy;
use crate::scenario::Lidar;

/// The emitted energies of a run: their law, the run's seed (every channel sees the
/// same pulses) and the envelope bounding every factor of the run.
#[derive(Debug, Clone, Copy)]
pub struct RunEnergy {
    /// Jitter and drift.
    pub law: PulseEnergy,
    /// The seed the factors are drawn from (`None`: each stream's own seed).
    pub seed: Option<u64>,
    /// Upper bound of every factor of the run.
    pub envelope: f64,
}

impl RunEnergy {
    /// Energies that vary with relative jitter `jitter` only, drawn from each stream's
    /// own seed (a single stream, as in tests and benches).
    pub fn jitter(jitter: f64) -> Self {
        let law = PulseEnergy {
            jitter,
            drift: None,
            rep_rate_hz: 1.0,
        };
        RunEnergy {
            law,
            seed: None,
            envelope: law.jitter_envelope(),
        }
    }
}

/// The run's energies: the laser of the first channel (shared by all), its envelope over
/// the run's `duration_s`; refuses a drift that would leave the laser dark.
pub fn run_energy(lidar: &Lidar, seed: u64, duration_s: f64) -> Result<RunEnergy> {
    let sc = lidar.first();
    let law = PulseEnergy::from_config(&sc.loaded.config.instrument);
    let lowest = law.lowest_drift(duration_s);
    if lowest < 0.05 {
        return Err(Error::config(
            sc.loaded.file_label(),
            "instrument.energy_drift",
            format!(
                "drifts to {:.1} % of the pulse energy within the run ({}); a laser \
                 below 5 % is off: shorten the run or the drift",
                100.0 * lowest,
                crate::resources::human_duration(duration_s)
            ),
        ));
    }
    Ok(RunEnergy {
        law,
        seed: Some(seed),
        envelope: law.envelope(duration_s),
    })
}
