//! The quicklook's title: the instrument (the `name` of the file's resolved config,
//! its root attribute `config`), the date and the UTC times of the first and last
//! profile, and the place: a ground station's `platform.latitude_deg`/`longitude_deg`
//! and altitude from the config, or an orbit's track from its first to its last
//! sub-satellite point.

use super::axis::{latitude_text, longitude_text, utc};

/// A text attribute of `g` (variable-length UTF-8 or ASCII).
pub(super) fn text_attr(g: &hdf5::Group, name: &str) -> Option<String> {
    attr_text(&g.attr(name).ok()?)
}

/// The text of a variable-length UTF-8 or ASCII attribute.
pub(super) fn attr_text(a: &hdf5::Attribute) -> Option<String> {
    a.read_scalar::<hdf5::types::VarLenUnicode>()
        .map(|s| s.as_str().to_string())
        .or_else(|_| {
            a.read_scalar::<hdf5::types::VarLenAscii>()
                .map(|s| s.as_str().to_string())
        })
        .ok()
}

/// What the title says of the file's instrument and station, from its resolved config.
#[derive(Debug, Clone, Default)]
pub struct Source {
    /// The config's `name`.
    pub instrument: Option<String>,
    /// A ground station's latitude and longitude, degrees.
    pub station: Option<(f64, f64)>,
    /// The platform's altitude, km.
    pub altitude_km: Option<f64>,
    /// The config's `platform.kind` (`ground`, `space`).
    pub kind: Option<String>,
}

impl Source {
    /// From the root attribute `config` of `root` (a raw file or a product); the root
    /// attribute `title` after its colon when the config cannot be read.
    pub fn of(root: &hdf5::Group) -> Source {
        let config: Option<toml::Table> =
            text_attr(root, "config").and_then(|t| t.parse::<toml::Table>().ok());
        let number = |t: &toml::Value| t.as_float().or_else(|| t.as_integer().map(|i| i as f64));
        let platform = config
            .as_ref()
            .and_then(|c| c.get("platform"))
            .and_then(|p| p.as_table());
        let get = |k: &str| platform.and_then(|p| p.get(k)).and_then(number);
        let instrument = config
            .as_ref()
            .and_then(|c| c.get("name"))
            .and_then(|n| n.as_str())
            .map(str::to_string)
            .or_else(|| {
                text_attr(root, "title")
                    .and_then(|t| t.split_once(": ").map(|(_, n)| n.trim().to_string()))
            })
            .filter(|n| !n.is_empty());
        Source {
            instrument,
            station: get("latitude_deg").zip(get("longitude_deg")),
            altitude_km: get("altitude_km"),
            kind: platform
                .and_then(|p| p.get("kind"))
                .and_then(|k| k.as_str())
                .map(str::to_string),
        }
    }
}

/// The start of the first and the end of the last of `n` evenly spaced profiles whose
/// centres are at `first` and `last` (half a spacing beyond each; one profile: itself).
pub fn span_edges(first: f64, last: f64, n: usize) -> (f64, f64) {
    let half = if n > 1 {
        0.5 * (last - first) / (n - 1) as f64
    } else {
        0.0
    };
    (first - half, last + half)
}

/// `HH:MM` of a UTC time `YYYY-MM-DDTHH:MM:SSZ`.
fn hh_mm(t: &str) -> &str {
    t.get(11..16).unwrap_or("")
}

/// The title's line: instrument — date and times — place. `times` are the Unix times of
/// the first and last profile (when the start is known); `track` the first and last
/// sub-satellite points `(lat, lon)` of an orbit.
pub fn title_line(
    source: &Source,
    times: Option<(f64, f64)>,
    track: Option<((f64, f64), (f64, f64))>,
) -> String {
    let mut parts = vec![
        source
            .instrument
            .clone()
            .unwrap_or_else(|| "lidarsim file".into()),
    ];
    if let Some((a, b)) = times.and_then(|(a, b)| utc(a).zip(utc(b))) {
        parts.push(if a[..10] == b[..10] {
            format!("{} {}–{} UTC", &a[..10], hh_mm(&a), hh_mm(&b))
        } else {
            format!(
                "{} {} – {} {} UTC",
                &a[..10],
                hh_mm(&a),
                &b[..10],
                hh_mm(&b)
            )
        });
    }
    let place = |(la, lo): (f64, f64)| format!("{} {}", latitude_text(la, 2), longitude_text(lo));
    match (track, source.station) {
        (Some((a, b)), _) => parts.push(format!("track {} to {}", place(a), place(b))),
        (None, Some(s)) => parts.push(format!(
            "station {}{}",
            place(s),
            source
                .altitude_km
                .map_or(String::new(), |z| format!(", {z} km a.s.l."))
        )),
        (None, None) if source.kind.as_deref().is_some_and(|k| k != "ground") => {
            parts.push(format!(
                "{} platform{} (no [orbit]: no track)",
                source.kind.as_deref().unwrap_or(""),
                source
                    .altitude_km
                    .map_or(String::new(), |z| format!(" at {z} km"))
            ))
        }
        (None, None) => parts.push(format!(
            "ground station{} (no latitude, longitude in the config)",
            source
                .altitude_km
                .map_or(String::new(), |z| format!(" at {z} km a.s.l."))
        )),
    }
    parts.join(" — ")
}
