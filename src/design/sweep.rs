//! Design sweeps (`lidarsim sweep`, docs/config.md): a grid over any config keys, and per
//! grid point metrics of the deterministic model (Eq. 2–4), no Monte Carlo.
//!
//! * `snr_at:Zkm` — Eq. 4 S/N of the bin nearest altitude Z at the config's accumulation
//!   time (first channel);
//! * `max_altitude:snr=X` — the highest bin-centre altitude with S/N ≥ X, km (NaN when
//!   none);
//! * `time_to_snr:X@Zkm` — the accumulation time for S/N ≥ X at Z: Eq. 4 grows as √M,
//!   so `M = X²·(λ_sig+λ_bkg+λ_dc)/λ_sig²` shots, `t = M/fL` (s; ∞ without signal);
//! * `mean_laser_power_w` — `E0·fL`, W;
//! * `pulses_in_flight` — pulses emitted while one travels to the ground and back,
//!   `⌈2·r_ground/c · fL⌉` (space-borne; 1 for a ground lidar).

use rayon::prelude::*;

use crate::constants::SPEED_OF_LIGHT_M_PER_S;
use crate::error::{Error, Result, compact};
use crate::scenario::{ExpectedProfile, Scenario};
use crate::snr;

/// Most grid points a sweep computes.
pub const MAX_POINTS: usize = 1_000_000;

/// The valid forms of `--vary`, for messages.
pub const VARY_FORMS: &str = "KEY=START..STOP:N or KEY=START..STOP:log:N (N from 1 to 1e6; \
     e.g. instrument.pulse_energy_j=0.01..0.1:log:10)";

/// The valid forms of `--metric`, for messages.
pub const METRIC_FORMS: &str = "snr_at:Zkm, max_altitude:snr=X, time_to_snr:X@Zkm (X > 0, \
     Z inside the acquisition window), mean_laser_power_w or pulses_in_flight";

/// One varied key: its values.
#[derive(Debug, Clone, PartialEq)]
pub struct Axis {
    /// The dotted config key.
    pub key: String,
    /// Its values, in order.
    pub values: Vec<f64>,
}

/// A parsed `--vary` before its values are laid out: key, bounds, count, spacing.
struct AxisSpec {
    key: String,
    start: f64,
    stop: f64,
    n: usize,
    log: bool,
}

impl AxisSpec {
    fn parse(spec: &str) -> Result<AxisSpec> {
        let fail =
            |why: &str| Error::Unsupported(format!("--vary {spec}: {why}; expected {VARY_FORMS}"));
        let (key, range) = spec.split_once('=').ok_or_else(|| fail("no `=`"))?;
        let key = key.trim();
        if key.is_empty() || key.split('.').any(|part| part.trim().is_empty()) {
            return Err(fail("the key is empty or has an empty part"));
        }
        let (bounds, rest) = range
            .split_once(':')
            .ok_or_else(|| fail("missing :N (the number of values)"))?;
        let (log, n) = match rest.split_once(':') {
            Some(("log", n)) => (true, n),
            Some(_) => return Err(fail("expected :N or :log:N after the range")),
            None => (false, rest),
        };
        if bounds.matches("..").count() != 1 || bounds.contains("...") {
            return Err(fail("START and STOP are separated by exactly two dots"));
        }
        let (start, stop) = bounds
            .split_once("..")
            .ok_or_else(|| fail("expected START..STOP"))?;
        let number = |s: &str| {
            s.trim()
                .parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| fail(&format!("`{s}` is not a finite number")))
        };
        let (start, stop) = (number(start)?, number(stop)?);
        let n: usize = n
            .trim()
            .parse()
            .ok()
            .filter(|&n| (1..=MAX_POINTS).contains(&n))
            .ok_or_else(|| fail("N must be a whole number from 1 to 1e6"))?;
        if log && (start <= 0.0 || stop <= 0.0) {
            return Err(fail("a log range needs positive bounds"));
        }
        if start == stop && n > 1 {
            return Err(fail(&format!(
                "START equals STOP, so the {n} values would all be {}; give N = 1 or two \
                 different bounds",
                compact(start)
            )));
        }
        Ok(AxisSpec {
            key: key.to_string(),
            start,
            stop,
            n,
            log,
        })
    }

    fn axis(&self) -> Axis {
        let (a, b, n) = (self.start, self.stop, self.n);
        let values = (0..n)
            .map(|i| {
                let t = if n == 1 {
                    0.0
                } else {
                    i as f64 / (n - 1) as f64
                };
                if self.log {
                    (a.ln() + t * (b.ln() - a.ln())).exp()
                } else {
                    a + t * (b - a)
                }
            })
            .collect();
        Axis {
            key: self.key.clone(),
            values,
        }
    }
}

impl Axis {
    /// Parses `KEY=START..STOP:N` (linear) or `KEY=START..STOP:log:N`.
    pub fn parse(spec: &str) -> Result<Axis> {
        AxisSpec::parse(spec).map(|s| s.axis())
    }

    /// Parses every `--vary`: each key at most once, at most [`MAX_POINTS`] grid points,
    /// checked before any value is laid out.
    pub fn parse_all(specs: &[String]) -> Result<Vec<Axis>> {
        let parsed = specs
            .iter()
            .map(|s| AxisSpec::parse(s))
            .collect::<Result<Vec<_>>>()?;
        for (i, a) in parsed.iter().enumerate() {
            if parsed[..i].iter().any(|b| b.key == a.key) {
                return Err(Error::Unsupported(format!(
                    "--vary {}: the key `{}` is given twice; vary each key once ({VARY_FORMS})",
                    specs[i], a.key
                )));
            }
        }
        let n: f64 = parsed.iter().map(|a| a.n as f64).product();
        if n > MAX_POINTS as f64 {
            return Err(Error::Unsupported(format!(
                "--vary: the sweep has {} grid points, at most {} (the product of the N's)",
                compact(n),
                compact(MAX_POINTS as f64)
            )));
        }
        Ok(parsed.iter().map(AxisSpec::axis).collect())
    }
}

/// A metric of the deterministic model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Metric {
    /// Eq. 4 S/N at an altitude (m).
    SnrAt(f64),
    /// The highest altitude with S/N ≥ a threshold.
    MaxAltitude(f64),
    /// Accumulation time for S/N ≥ a threshold at an altitude (m).
    TimeToSnr(f64, f64),
    /// `E0·fL`.
    MeanLaserPower,
    /// Pulses in flight.
    PulsesInFlight,
}

impl std::fmt::Display for Metric {
    /// The metric as `--metric` takes it.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Metric::SnrAt(z) => write!(f, "snr_at:{}km", z / 1e3),
            Metric::MaxAltitude(x) => write!(f, "max_altitude:snr={x}"),
            Metric::TimeToSnr(x, z) => write!(f, "time_to_snr:{x}@{}km", z / 1e3),
            Metric::MeanLaserPower => write!(f, "mean_laser_power_w"),
            Metric::PulsesInFlight => write!(f, "pulses_in_flight"),
        }
    }
}

impl Metric {
    /// Parses a metric name of docs/config.md, e.g. `snr_at:10km`, `time_to_snr:10@15km`;
    /// an S/N target must be positive (`time_to_snr:0` is no target, a negative one no
    /// S/N). Altitudes are checked against each grid point's window ([`Metric::check`]).
    pub fn parse(spec: &str) -> Result<Metric> {
        let fail = |why: &str| {
            Error::Unsupported(format!("--metric {spec}: {why}expected {METRIC_FORMS}"))
        };
        let km = |s: &str| -> Result<f64> {
            let v: f64 = s
                .strip_suffix("km")
                .ok_or_else(|| fail("an altitude is written in km, e.g. 10km; "))?
                .parse()
                .map_err(|_| fail(""))?;
            v.is_finite().then_some(v * 1e3).ok_or_else(|| fail(""))
        };
        let target = |s: &str| {
            let x = s
                .parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| fail(""))?;
            if x > 0.0 {
                Ok(x)
            } else {
                Err(fail(&format!(
                    "the S/N target {} is not positive (an S/N is ≥ 0 and every bin reaches 0); ",
                    compact(x)
                )))
            }
        };
        match spec.split_once(':') {
            Some(("snr_at", z)) => Ok(Metric::SnrAt(km(z)?)),
            Some(("max_altitude", x)) => Ok(Metric::MaxAltitude(target(
                x.strip_prefix("snr=").ok_or_else(|| fail(""))?,
            )?)),
            Some(("time_to_snr", rest)) => {
                let (x, z) = rest.split_once('@').ok_or_else(|| fail(""))?;
                Ok(Metric::TimeToSnr(target(x)?, km(z)?))
            }
            None if spec == "mean_laser_power_w" => Ok(Metric::MeanLaserPower),
            None if spec == "pulses_in_flight" => Ok(Metric::PulsesInFlight),
            _ => Err(fail("")),
        }
    }

    /// Parses every `--metric`, each at most once.
    pub fn parse_all(specs: &[String]) -> Result<Vec<Metric>> {
        let parsed = specs
            .iter()
            .map(|s| Metric::parse(s))
            .collect::<Result<Vec<_>>>()?;
        for (i, m) in parsed.iter().enumerate() {
            if parsed[..i].contains(m) {
                return Err(Error::Unsupported(format!(
                    "--metric {}: given twice; name each metric once ({METRIC_FORMS})",
                    specs[i]
                )));
            }
        }
        Ok(parsed)
    }

    /// The altitude the metric is taken at, m, if any.
    fn altitude_m(self) -> Option<f64> {
        match self {
            Metric::SnrAt(z) | Metric::TimeToSnr(_, z) => Some(z),
            _ => None,
        }
    }

    /// Refuses an altitude outside the scenario's acquisition window (the nearest bin
    /// would be a bin far from the one asked for).
    pub fn check(self, sc: &Scenario) -> Result<()> {
        let a = &sc.loaded.config.acquisition;
        match self.altitude_m() {
            Some(z) if z < a.bottom_altitude_km * 1e3 || z > a.top_altitude_km * 1e3 => {
                Err(Error::Unsupported(format!(
                    "--metric {self}: {} km is outside the acquisition window ({} to {} km); \
                     give an altitude inside it ({METRIC_FORMS})",
                    compact(z / 1e3),
                    compact(a.bottom_altitude_km),
                    compact(a.top_altitude_km)
                )))
            }
            _ => Ok(()),
        }
    }

    /// The metric of a scenario and its model.
    pub fn of(self, sc: &Scenario, e: &ExpectedProfile) -> f64 {
        let shots = sc.instrument.rep_rate_hz * sc.accumulation_time_s();
        let bin_at = |z: f64| {
            (0..e.n_bins()).min_by(|&a, &b| {
                (e.altitude_m[a] - z)
                    .abs()
                    .total_cmp(&(e.altitude_m[b] - z).abs())
            })
        };
        match self {
            Metric::SnrAt(z) => bin_at(z).map_or(f64::NAN, |i| {
                snr::eq4(e.signal[i], e.background, e.dark, shots)
            }),
            Metric::MaxAltitude(x) => (0..e.n_bins())
                .filter(|&i| snr::eq4(e.signal[i], e.background, e.dark, shots) >= x)
                .map(|i| e.altitude_m[i] / 1e3)
                .fold(f64::NAN, f64::max),
            Metric::TimeToSnr(x, z) => bin_at(z).map_or(f64::NAN, |i| {
                let s = e.signal[i];
                if s > 0.0 {
                    x * x * (s + e.background + e.dark) / (s * s) / sc.instrument.rep_rate_hz
                } else {
                    f64::INFINITY
                }
            }),
            Metric::MeanLaserPower => {
                sc.loaded.config.instrument.pulse_energy_j * sc.instrument.rep_rate_hz
            }
            Metric::PulsesInFlight => {
                let g = &sc.geometry;
                if g.kind == crate::config::PlatformKind::Ground {
                    return 1.0;
                }
                let ground = g.range_at_altitude(0.0);
                (2.0 * ground / SPEED_OF_LIGHT_M_PER_S * sc.instrument.rep_rate_hz).ceil()
            }
        }
    }
}

/// The grid's points: every combination of the axes' values, the last axis fastest.
pub fn grid(axes: &[Axis]) -> Result<Vec<Vec<f64>>> {
    let n: f64 = axes.iter().map(|a| a.values.len() as f64).product();
    if n > MAX_POINTS as f64 {
        return Err(Error::Unsupported(format!(
            "the sweep has {n} grid points, at most {MAX_POINTS}"
        )));
    }
    Ok(axes.iter().fold(vec![vec![]], |points, axis| {
        points
            .iter()
            .flat_map(|p| {
                axis.values.iter().map(move |&v| {
                    let mut q = p.clone();
                    q.push(v);
                    q
                })
            })
            .collect()
    }))
}

/// The metrics at every grid point; `scenario` builds the scenario of one point's
/// overrides (`KEY=VALUE`, after the command's own `--set`); `tick` is called per point.
/// The first point is computed alone first, so that a metric or value the config
/// refuses fails fast; an error is the one of the first failing point in grid order.
pub fn run(
    axes: &[Axis],
    metrics: &[Metric],
    scenario: &(dyn Fn(&[String]) -> Result<Scenario> + Sync),
    tick: &(dyn Fn() + Sync),
    cancel: &std::sync::atomic::AtomicBool,
) -> Result<Vec<(Vec<f64>, Vec<f64>)>> {
    let point_metrics = |point: Vec<f64>| -> Result<(Vec<f64>, Vec<f64>)> {
        if cancel.load(std::sync::atomic::Ordering::Relaxed) {
            return Err(Error::Interrupted);
        }
        let overrides: Vec<String> = axes
            .iter()
            .zip(&point)
            .map(|(a, v)| format!("{}={v}", a.key))
            .collect();
        let at = || overrides.join(", ");
        let sc = scenario(&overrides).map_err(|e| match e {
            // a grid value the key does not take: name the --vary
            Error::Config { file, reason, .. }
                if overrides.iter().any(|o| file == format!("--set {o}")) =>
            {
                let key = file.trim_start_matches("--set ");
                let key = key.split_once('=').map_or(key, |(k, _)| k);
                Error::Unsupported(format!("--vary {key}: at {}: {reason}", at()))
            }
            e => e,
        })?;
        for m in metrics {
            m.check(&sc).map_err(|e| {
                if axes.is_empty() {
                    e
                } else {
                    Error::Unsupported(format!("{e} (at {})", at()))
                }
            })?;
        }
        let e = sc.expected()?;
        tick();
        let values = metrics.iter().map(|m| m.of(&sc, &e)).collect();
        Ok((point, values))
    };
    let mut points = grid(axes)?.into_iter();
    let Some(first) = points.next() else {
        return Ok(vec![]);
    };
    let first = point_metrics(first)?;
    let rest: Vec<Result<_>> = points
        .collect::<Vec<_>>()
        .into_par_iter()
        .map(point_metrics)
        .collect();
    std::iter::once(Ok(first)).chain(rest).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn axes_and_metrics_parse() {
        let a = Axis::parse("instrument.pulse_energy_j=1e-4..1e-1:log:4").unwrap();
        assert_eq!(a.key, "instrument.pulse_energy_j");
        let want = [1e-4, 1e-3, 1e-2, 1e-1];
        assert!(
            a.values
                .iter()
                .zip(want)
                .all(|(v, w)| (v / w - 1.0).abs() < 1e-12)
        );
        assert_eq!(
            Axis::parse("x=10..250:3").unwrap().values,
            vec![10.0, 130.0, 250.0]
        );
        for bad in [
            "x",
            "x=1..2",
            "x=1..2:0",
            "x=0..1:log:3",
            "x=a..2:3",
            "x=1..2:lin:3",
        ] {
            assert!(Axis::parse(bad).is_err(), "{bad}");
        }
        assert_eq!(Metric::parse("snr_at:10km").unwrap(), Metric::SnrAt(10e3));
        assert_eq!(
            Metric::parse("max_altitude:snr=3").unwrap(),
            Metric::MaxAltitude(3.0)
        );
        assert_eq!(
            Metric::parse("time_to_snr:10@15km").unwrap(),
            Metric::TimeToSnr(10.0, 15e3)
        );
        assert!(Metric::parse("snr_at:10").is_err() && Metric::parse("bogus").is_err());
        // issue 18: nonsense the grammar used to take is refused with the valid form
        for bad in [
            "x=0.1...1:5",
            "=1..2:3",
            "a..b=1..2:3",
            "x=1..1:3",
            "x=1..2:1000001",
        ] {
            let e = Axis::parse(bad).unwrap_err().to_string();
            assert!(e.contains("KEY=START..STOP:N"), "{bad}: {e}");
        }
        assert_eq!(Axis::parse("x=1..1:1").unwrap().values, vec![1.0]);
        let twice = ["x=1..2:2".to_string(), "x=3..4:2".to_string()];
        assert!(
            Axis::parse_all(&twice)
                .unwrap_err()
                .to_string()
                .contains("twice")
        );
        let big = ["a=1..2:1000".to_string(), "b=1..2:1001".to_string()];
        assert!(
            Axis::parse_all(&big)
                .unwrap_err()
                .to_string()
                .contains("grid points")
        );
        for bad in [
            "time_to_snr:0@5km",
            "time_to_snr:-3@5km",
            "max_altitude:snr=-1",
            "max_altitude:snr=0",
        ] {
            let e = Metric::parse(bad).unwrap_err().to_string();
            assert!(
                e.contains("not positive") && e.contains("X > 0"),
                "{bad}: {e}"
            );
        }
        let same = ["snr_at:5km".to_string(), "snr_at:5km".to_string()];
        assert!(
            Metric::parse_all(&same)
                .unwrap_err()
                .to_string()
                .contains("twice")
        );
        for m in [
            "snr_at:-5km",
            "time_to_snr:10@15km",
            "max_altitude:snr=3",
            "pulses_in_flight",
        ] {
            assert_eq!(Metric::parse(m).unwrap().to_string(), m);
        }
        let g = grid(&[
            Axis {
                key: "a".into(),
                values: vec![1.0, 2.0],
            },
            Axis {
                key: "b".into(),
                values: vec![3.0, 4.0, 5.0],
            },
        ])
        .unwrap();
        assert_eq!(g.len(), 6);
        assert_eq!(g[1], vec![1.0, 4.0]);
    }
}
