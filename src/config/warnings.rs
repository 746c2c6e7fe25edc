//! The plausibility warnings: values a config may hold that are almost surely a unit slip,
//! their thresholds, and the unambiguous range of a pulsed lidar.

use crate::error::compact;

use super::scenario::ScenarioConfig;
use super::scene::PlatformKind;

/// Pulse energy above which a config is warned of a unit slip, J
/// ([`ScenarioConfig::plausibility_warnings`]).
pub const PLAUSIBLE_PULSE_ENERGY_J: f64 = 10.0;

/// How much longer than the distance to the ground a window may be before a config is
/// warned of a unit slip, km ([`ScenarioConfig::plausibility_warnings`]).
pub const PLAUSIBLE_WINDOW_BEYOND_GROUND_KM: f64 = 100.0;

/// The unambiguous range of a pulsed lidar, `c/(2 fL)`, m: a return from farther
/// arrives after the next pulse has left.
pub fn unambiguous_range_m(rep_rate_hz: f64) -> f64 {
    crate::constants::SPEED_OF_LIGHT_M_PER_S / (2.0 * rep_rate_hz)
}

impl ScenarioConfig {
    /// Warnings for values that are legal but almost surely a unit slip, one line each
    /// (`lidarsim: warning: KEY ...`), in a fixed order: [`Self::pulse_energy_warning`],
    /// [`Self::window_length_warning`], [`Self::pulses_in_window_warning`]. The run goes
    /// on; a command prints them once, after it succeeds.
    pub fn plausibility_warnings(&self) -> Vec<String> {
        [
            self.pulse_energy_warning(),
            self.window_length_warning(),
            self.pulses_in_window_warning(),
        ]
        .into_iter()
        .flatten()
        .map(|w| format!("lidarsim: warning: {w}"))
        .collect()
    }

    /// A pulse energy above [`PLAUSIBLE_PULSE_ENERGY_J`]: no lidar laser in service
    /// gives more than about 1 J per pulse, so 110 (mJ) written for 0.110 (J) is likely.
    fn pulse_energy_warning(&self) -> Option<String> {
        let e = self.instrument.pulse_energy_j;
        (e > PLAUSIBLE_PULSE_ENERGY_J).then(|| {
            format!(
                "instrument.pulse_energy_j = {} J is above {} J, more than any lidar laser \
                 gives per pulse (a value in mJ written as J?); the run goes on",
                compact(e),
                compact(PLAUSIBLE_PULSE_ENERGY_J)
            )
        })
    }

    /// A window (along the beam, `(top − bottom)/cos θ`) longer than the distance from
    /// the lidar to the ground along the beam (`|h|/cos θ`) plus
    /// [`PLAUSIBLE_WINDOW_BEYOND_GROUND_KM`]: beyond the atmosphere's top (~100 km) there
    /// is nothing to see, so metres written as km (`top_altitude_km = 15000`) is likely.
    fn window_length_warning(&self) -> Option<String> {
        let a = &self.acquisition;
        let cos = self.platform.off_nadir_deg.to_radians().cos();
        let window_km = (a.top_altitude_km - a.bottom_altitude_km) / cos;
        let ground_km = self.platform.altitude_km.abs() / cos;
        (window_km > ground_km + PLAUSIBLE_WINDOW_BEYOND_GROUND_KM).then(|| {
            format!(
                "acquisition.top_altitude_km = {} and acquisition.bottom_altitude_km = {} make a \
                 window of {} km along the beam, longer than the {} km to the ground plus {} km \
                 (a value in m written as km?); the run goes on",
                compact(a.top_altitude_km),
                compact(a.bottom_altitude_km),
                format_args!("{window_km:.1}"),
                format_args!("{ground_km:.1}"),
                compact(PLAUSIBLE_WINDOW_BEYOND_GROUND_KM)
            )
        })
    }

    /// A ground lidar whose window reaches beyond the unambiguous range `c/(2 fL)`: the
    /// return from the window's far end arrives after the next pulse has left, so more
    /// than one pulse is in the window at once (second-trip echoes the model does not
    /// draw). A space-borne lidar has pulses in flight by design (the `pulses_in_flight`
    /// sweep metric) and its window is far from the platform, so it is not warned.
    fn pulses_in_window_warning(&self) -> Option<String> {
        if self.platform.kind != PlatformKind::Ground {
            return None;
        }
        let fl = self.instrument.rep_rate_hz;
        let cos = self.platform.off_nadir_deg.to_radians().cos();
        let far_m = (self.acquisition.top_altitude_km - self.platform.altitude_km) * 1e3 / cos;
        let unambiguous_m = unambiguous_range_m(fl);
        (far_m > unambiguous_m).then(|| {
            format!(
                "instrument.rep_rate_hz = {} Hz: the window's far end ({} km along the beam) is \
                 beyond c/(2 fL) = {} km, so more than one pulse is in the window at once \
                 (a rate in Hz written for kHz, or a window in m written as km?); the run goes on",
                compact(fl),
                format_args!("{:.1}", far_m / 1e3),
                format_args!("{:.1}", unambiguous_m / 1e3)
            )
        })
    }
}
