//! The scenes at each (fL, TC) and the methods compared.

use crate::report::sci;

/// Tolerances (KS distance) offered to the normal approximation.
pub(crate) const TOLERANCES: [f64; 4] = [1e-1, 1e-2, 1e-3, 1e-4];

/// One scene at one (fL, TC).
pub(crate) struct Case {
    pub(crate) label: &'static str,
    pub(crate) file: &'static str,
    pub(crate) overrides: Vec<String>,
    pub(crate) rep_rate_hz: f64,
    pub(crate) accumulation_s: f64,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Method {
    ShotDense,
    ShotSparse,
    ShotAuto,
    Aggregate,
    /// Normal approximation above `normal_threshold(tolerance)`.
    AggregateNormal(f64),
}

impl Method {
    pub(crate) fn all() -> Vec<Method> {
        let mut v = vec![
            Method::ShotDense,
            Method::ShotSparse,
            Method::ShotAuto,
            Method::Aggregate,
        ];
        v.extend(TOLERANCES.iter().map(|&t| Method::AggregateNormal(t)));
        v
    }

    pub(crate) fn name(self) -> String {
        match self {
            Method::ShotDense => "shot-dense".into(),
            Method::ShotSparse => "shot-sparse".into(),
            Method::ShotAuto => "shot-auto".into(),
            Method::Aggregate => "aggregate".into(),
            Method::AggregateNormal(t) => format!("aggregate-normal {}", sci(t, 0)),
        }
    }

    pub(crate) fn is_exact(self) -> bool {
        !matches!(self, Method::AggregateNormal(_))
    }
}

pub(crate) fn cases() -> Vec<Case> {
    let configs = [(10.0, 1.0), (10.0, 100.0), (250.0, 10.0)];
    let scenes: [(&str, &str, &[&str]); 5] = [
        ("S1 night", "scenario1.toml", &[]),
        ("S1 day", "scenario1.toml", &["background.radiance=1.1e15"]),
        ("S3 night", "scenario3.toml", &[]),
        ("S4 night", "scenario4.toml", &[]),
        (
            "S1 night 1 mJ",
            "scenario1.toml",
            &["instrument.pulse_energy_j=0.001"],
        ),
    ];
    let mut v = Vec::new();
    for (label, file, extra) in scenes {
        for (fl, tc) in configs {
            let mut overrides = vec![
                format!("instrument.rep_rate_hz={fl}"),
                format!("acquisition.accumulation_time_s={tc}"),
            ];
            overrides.extend(extra.iter().map(|s| s.to_string()));
            v.push(Case {
                label,
                file,
                overrides,
                rep_rate_hz: fl,
                accumulation_s: tc,
            });
        }
    }
    v
}
