//! The duration a run announces before it starts: the notice on stderr (or kept for the
//! Python module), and the cost of an afterpulse it counts.

use super::human::human_duration;

/// A run expected to take longer than this (s) says so before it starts.
pub const ANNOUNCE_AFTER_S: f64 = 60.0;

/// Says how long a run is expected to take when that is more than a minute: on stderr,
/// or kept for the caller once [`keep_duration_notices`] was called (the Python module,
/// which prints nothing and gives them as warnings, [`take_duration_notices`]).
pub fn announce_duration(what: &str, seconds: f64) {
    if let Some(notice) = duration_notice(what, seconds) {
        match KEPT_NOTICES.lock().as_deref_mut() {
            Ok(Some(kept)) => kept.push(notice),
            _ => crate::tell!("{notice}"),
        }
    }
}

/// The line [`announce_duration`] gives for a run of `what` expected to take `seconds`:
/// "lidarsim: WHAT: expected to take about 7 min (estimate)"; none at a minute or less.
pub fn duration_notice(what: &str, seconds: f64) -> Option<String> {
    (seconds > ANNOUNCE_AFTER_S).then(|| {
        format!(
            "lidarsim: {what}: expected to take about {} (estimate)",
            human_duration(seconds)
        )
    })
}

/// Duration notices kept for the caller instead of printed (`None`: printed on stderr).
static KEPT_NOTICES: std::sync::Mutex<Option<Vec<String>>> = std::sync::Mutex::new(None);

/// From now on this process keeps its duration notices for [`take_duration_notices`]
/// instead of printing them (a library that prints nothing: the Python module).
pub fn keep_duration_notices() {
    if let Ok(mut kept) = KEPT_NOTICES.lock() {
        kept.get_or_insert_with(Vec::new);
    }
}

/// The duration notices kept since the last call (empty when they are printed).
pub fn take_duration_notices() -> Vec<String> {
    KEPT_NOTICES
        .lock()
        .ok()
        .and_then(|mut kept| kept.as_mut().map(std::mem::take))
        .unwrap_or_default()
}

/// Cost of one afterpulse drawn (`detector::afterpulse`: its component, delay and bin),
/// ns, for the duration a run announces. Measured on 2026-12-01 (one thread, the machine
/// shared with two builds): `lidarsim simulate configs/ground/mpl_like.toml --profiles 1
/// --threads 1 --set instrument.detector.afterpulsing.probability=P`: drawing 14.0 s at
/// P = 5e-3 and 20.75 s at P = 0.5, whose 2.25e7 more counts are afterpulses: 300 ns each.
pub const AFTERPULSE_NS: f64 = 300.0;

/// Cost of drawing the afterpulses of one shot whose recorded counts sum to
/// `recorded_per_shot`, with afterpulse probability `probability`, ns: `p·R` afterpulses
/// at [`AFTERPULSE_NS`] each.
pub fn afterpulse_ns_per_shot(probability: f64, recorded_per_shot: f64) -> f64 {
    probability * recorded_per_shot * AFTERPULSE_NS
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The afterpulse cost model against the measurement it was made from (the constants
    /// of [`AFTERPULSE_NS`]'s comment): MPL-like at p = 0.5, 150,000 shots of 304 recorded
    /// counts (4.56e7 a profile at p = 5e-3) took 6.74 s more to draw: within 10 %, and a
    /// 10-profile run on two threads is announced (over a minute with the 14 s a profile
    /// of the rest of the draw).
    #[test]
    fn the_afterpulse_cost_model_matches_its_measurement() {
        let per_shot = 4.5624e7 / 150_000.0;
        let s = afterpulse_ns_per_shot(0.5, per_shot) * 150_000.0 * 1e-9;
        assert!((s / 6.74 - 1.0).abs() < 0.1, "{s} s");
        let run_s = 10.0 * (14.0 + s) / 2.0;
        assert!(duration_notice("run", run_s).is_some());
        assert!(duration_notice("run", 59.0).is_none());
    }
}
