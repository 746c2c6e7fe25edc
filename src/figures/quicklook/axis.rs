//! The quicklook's horizontal axis (`quicklook --x-axis time|latitude|along-track|profile`):
//! what places the profiles along x, its unit and label, and its tick labels — the UTC
//! clock, or the track's latitude and longitude at round latitudes.

use crate::figures::plot::panel::Clock;
use crate::figures::plot::ticks;

/// What the quicklook's x axis shows.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum XAxis {
    /// Time for a ground file, latitude and longitude for an orbit's.
    #[default]
    Auto,
    /// The profiles' `time`, labelled by the UTC clock when the start is known.
    Time,
    /// The along-track distance, labelled by the track's latitude and longitude at round
    /// latitudes (an orbit's file only).
    Latitude,
    /// The along-track distance, km (an orbit's file only).
    AlongTrack,
    /// The profile index (a raw file only).
    Profile,
}

impl XAxis {
    /// The names `--x-axis` takes, in order.
    pub const NAMES: [&'static str; 5] = ["auto", "time", "latitude", "along-track", "profile"];

    /// The axis of `--x-axis NAME`.
    pub fn parse(name: &str) -> Option<XAxis> {
        match name.trim() {
            "auto" => Some(XAxis::Auto),
            "time" => Some(XAxis::Time),
            "latitude" => Some(XAxis::Latitude),
            "along-track" => Some(XAxis::AlongTrack),
            "profile" => Some(XAxis::Profile),
            _ => None,
        }
    }

    /// The name `--x-axis` knows it by.
    pub fn name(self) -> &'static str {
        match self {
            XAxis::Auto => "auto",
            XAxis::Time => "time",
            XAxis::Latitude => "latitude",
            XAxis::AlongTrack => "along-track",
            XAxis::Profile => "profile",
        }
    }

    /// [`XAxis::Auto`] made definite: latitude for an orbit (`along_track`), time otherwise.
    pub fn resolve(self, along_track: bool) -> XAxis {
        match self {
            XAxis::Auto if along_track => XAxis::Latitude,
            XAxis::Auto => XAxis::Time,
            x => x,
        }
    }

    /// The file variable that places the profiles along x (`None`: the profile index).
    pub fn variable(self) -> Option<&'static str> {
        match self {
            XAxis::Time | XAxis::Auto => Some("time"),
            XAxis::Latitude | XAxis::AlongTrack => Some("along_track_distance"),
            XAxis::Profile => None,
        }
    }

    /// Why a file cannot be drawn against this axis: `along_track` (an orbit's file) and
    /// `product` (an onboard product) say what it is.
    pub fn refusal(self, along_track: bool, product: bool) -> Option<String> {
        match self {
            XAxis::Latitude | XAxis::AlongTrack if !along_track => Some(format!(
                "--x-axis {}: the file has no `along_track_distance`, `latitude` and \
                 `longitude` (its run had no [orbit]); use time or profile",
                self.name()
            )),
            XAxis::Profile if product => Some(
                "--x-axis profile: an onboard product's regions number their profiles each \
                 at its own resolution; use time, latitude or along-track"
                    .into(),
            ),
            _ => None,
        }
    }
}

/// The x axis: the factor from the file's values to the shown unit, the label, and for
/// a time axis whose start is known (`start_unix_s`, the Unix time of `time` 0) the UTC
/// clock that labels it, with the date of `first_s` (the first profile's time) in the
/// label. `span` is the file's values' span (seconds of a time axis without a start).
pub fn x_axis(
    kind: XAxis,
    span: f64,
    start_unix_s: Option<f64>,
    first_s: f64,
) -> (f64, String, Option<Clock>) {
    match kind {
        XAxis::AlongTrack => return (1e-3, "along-track distance (km)".into(), None),
        XAxis::Latitude => {
            return (
                1e-3,
                "latitude, longitude of the sub-satellite point".into(),
                None,
            );
        }
        XAxis::Profile => return (1.0, "profile".into(), None),
        XAxis::Time | XAxis::Auto => {}
    }
    if let Some(date) = start_unix_s.and_then(|t0| utc_date(t0 + first_s)) {
        let clock = Clock {
            origin_unix_s: start_unix_s.unwrap_or(0.0),
            seconds_per_unit: 1.0,
        };
        return (1.0, format!("time (UTC, {date})"), Some(clock));
    }
    let (scale, label) = x_scale(span);
    (scale, label, None)
}

/// The UTC date `YYYY-MM-DD` of Unix time `t_s` (None outside years 1970–9999).
pub fn utc_date(t_s: f64) -> Option<String> {
    utc(t_s).and_then(|t| t.get(..10).map(str::to_string))
}

/// The UTC time `YYYY-MM-DDTHH:MM:SSZ` of Unix time `t_s` (None outside 1970–9999).
pub fn utc(t_s: f64) -> Option<String> {
    if !(0.0..2.5e11).contains(&t_s) {
        return None;
    }
    let t = std::time::UNIX_EPOCH.checked_add(std::time::Duration::from_secs_f64(t_s))?;
    Some(humantime::format_rfc3339_seconds(t).to_string())
}

/// The unit of a time axis of `span` seconds without a known start: its scale and label.
fn x_scale(span: f64) -> (f64, String) {
    if span < 600.0 {
        (1.0, "time since start (s)".into())
    } else if span < 6.0 * 3600.0 {
        (1.0 / 60.0, "time since start (min)".into())
    } else {
        (1.0 / 3600.0, "time since start (h)".into())
    }
}

/// A latitude as a tick writes it: `30°N`, `62°S`, `0°`; with `decimals` after the point
/// when the ticks are closer than a degree (`12.5°N`).
pub fn latitude_text(lat: f64, decimals: usize) -> String {
    let v = format!("{:.*}", decimals, lat.abs());
    if v.trim_start_matches(['0', '.']).is_empty() {
        return format!("{v}°");
    }
    format!("{v}°{}", if lat > 0.0 { 'N' } else { 'S' })
}

/// A longitude as a tick writes it, to 0.1°: `12.3°E`, `170.0°W` (from −180 to 180).
pub fn longitude_text(lon: f64) -> String {
    let l = (lon + 180.0).rem_euclid(360.0) - 180.0;
    let v = format!("{:.1}", l.abs());
    if v == "0.0" || v == "180.0" {
        return format!("{v}°");
    }
    format!("{v}°{}", if l > 0.0 { 'E' } else { 'W' })
}

/// The ticks of a latitude axis: where the track (`x` along it, ascending, and the
/// sub-satellite `lat`, `lon` at each x) crosses the multiples of a 1-2-5 step of
/// latitude that give about `target` ticks over its path in latitude, each labelled
/// `<latitude> <longitude>` (`30°N 12.3°E`), the longitude interpolated linearly
/// between the profiles around the crossing (across ±180° the short way). A track that
/// crosses no multiple is labelled at its ends.
pub fn latitude_marks(x: &[f64], lat: &[f64], lon: &[f64], target: f64) -> Vec<(f64, String)> {
    let n = x.len().min(lat.len()).min(lon.len());
    if n == 0 {
        return vec![];
    }
    let path: f64 = lat[..n].windows(2).map(|w| (w[1] - w[0]).abs()).sum();
    let step = ticks::nice_step(path, target).max(0.01);
    let decimals = if step >= 1.0 {
        0
    } else {
        (-step.log10().floor()) as usize
    };
    let mark = |x: f64, la: f64, lo: f64| {
        (
            x,
            format!("{} {}", latitude_text(la, decimals), longitude_text(lo)),
        )
    };
    let mut out = Vec::new();
    for k in 0..n.saturating_sub(1) {
        let (a, b) = (lat[k], lat[k + 1]);
        if a == b {
            continue;
        }
        let (lo, hi) = (a.min(b), a.max(b));
        // multiples m·step in (lo, hi], each crossing once
        let (m0, m1) = (
            (lo / step + 1e-9).floor() as i64 + 1,
            (hi / step + 1e-9).floor() as i64,
        );
        let dlon = (lon[k + 1] - lon[k] + 180.0).rem_euclid(360.0) - 180.0;
        let mut here: Vec<(f64, String)> = (m0..=m1)
            .map(|m| {
                let v = m as f64 * step;
                let f = (v - a) / (b - a);
                mark(x[k] + f * (x[k + 1] - x[k]), v, lon[k] + f * dlon)
            })
            .collect();
        if b < a {
            here.reverse();
        }
        out.extend(here);
    }
    if out.is_empty() {
        let d = decimals.max(2);
        let end = |k: usize| {
            (
                x[k],
                format!("{} {}", latitude_text(lat[k], d), longitude_text(lon[k])),
            )
        };
        out.push(end(0));
        if n > 1 {
            out.push(end(n - 1));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn latitude_ticks_fall_on_round_latitudes() {
        // a track from 62°S northwards, 1 km a profile, a degree of latitude every 111 km
        let x: Vec<f64> = (0..1000).map(|k| k as f64).collect();
        let lat: Vec<f64> = x.iter().map(|k| -62.0 + k / 111.0).collect();
        let lon: Vec<f64> = x.iter().map(|k| 178.0 + k / 100.0).collect();
        let m = latitude_marks(&x, &lat, &lon, 5.0);
        let labels: Vec<&str> = m.iter().map(|(_, s)| s.as_str()).collect();
        assert_eq!(labels[0], "60°S 179.8°W");
        assert!((m[0].0 - 222.0).abs() < 1e-6);
        assert_eq!(labels.last(), Some(&"54°S 173.1°W"));
        assert_eq!(latitude_text(0.0, 0), "0°");
        assert_eq!(latitude_text(12.5, 1), "12.5°N");
        assert_eq!(longitude_text(-0.04), "0.0°");
        assert_eq!(XAxis::parse("along-track"), Some(XAxis::AlongTrack));
        assert_eq!(XAxis::parse("lat"), None);
    }
}
