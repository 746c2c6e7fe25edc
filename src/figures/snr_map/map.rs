//! The S/N map a caller hands to the figure: its values, the figure's size and scale,
//! and what a valid map is.

/// S/N against altitude and accumulation time, ready to be drawn.
#[derive(Debug, Clone)]
pub struct SnrMap {
    /// Bin-centre altitudes (km), any order, distinct and finite.
    pub altitude_km: Vec<f64>,
    /// Accumulation times TC (s), strictly increasing and > 0 (log-spaced, e.g. 1..1000 s).
    pub accumulation_time_s: Vec<f64>,
    /// `snr[i_alt][j_tc]`, finite and >= 0 (0 where there is no signal).
    pub snr: Vec<Vec<f64>>,
    /// Figure title, e.g. "Scenario 1 — cirrus 10–12 km + polluted aerosol".
    pub title: String,
    /// Instrument summary, e.g. "E0 = 1 J, fL = 10 Hz, A = 0.1 m², 532 nm, night".
    pub subtitle: String,
}

/// Width of the written PNG in pixels.
pub const WIDTH: u32 = 1000;
/// Height of the written PNG in pixels.
pub const HEIGHT: u32 = 700;
/// S/N levels drawn as labelled contours.
pub const CONTOUR_LEVELS: [f64; 3] = [1.0, 3.0, 10.0];
/// Lower end of the colour scale: smaller S/N (including 0) get the bottom colour.
pub const SNR_COLOUR_MIN: f64 = 0.1;
/// Default upper end of the colour scale; raised to the next decade when the data go higher.
pub const SNR_COLOUR_MAX: f64 = 1000.0;
/// The colour scale never extends past this.
pub(super) const SNR_COLOUR_CAP: f64 = 1e6;

/// Why `map` cannot be drawn, if it cannot (shapes, finite values, increasing TC).
pub(super) fn check(map: &SnrMap) -> std::result::Result<(), String> {
    let (n_alt, n_tc) = (map.altitude_km.len(), map.accumulation_time_s.len());
    if n_alt < 2 || n_tc < 2 {
        return Err(format!(
            "S/N map needs at least 2 altitudes and 2 accumulation times, got {n_alt} × {n_tc}"
        ));
    }
    if map.snr.len() != n_alt {
        return Err(format!(
            "snr has {} rows but there are {n_alt} altitudes",
            map.snr.len()
        ));
    }
    for (i, row) in map.snr.iter().enumerate() {
        if row.len() != n_tc {
            return Err(format!(
                "snr[{i}] has {} values but there are {n_tc} accumulation times",
                row.len()
            ));
        }
        if let Some((j, v)) = row
            .iter()
            .enumerate()
            .find(|(_, v)| !(v.is_finite() && **v >= 0.0))
        {
            return Err(format!("snr[{i}][{j}] = {v}: S/N must be finite and >= 0"));
        }
    }
    if let Some((i, z)) = map
        .altitude_km
        .iter()
        .enumerate()
        .find(|(_, z)| !z.is_finite())
    {
        return Err(format!("altitude_km[{i}] = {z} is not finite"));
    }
    for (j, &t) in map.accumulation_time_s.iter().enumerate() {
        if !t.is_finite() || t <= 0.0 {
            return Err(format!(
                "accumulation_time_s[{j}] = {t}: must be finite and > 0"
            ));
        }
        if j > 0 && t <= map.accumulation_time_s[j - 1] {
            return Err(format!(
                "accumulation_time_s must be strictly increasing (index {j})"
            ));
        }
    }
    Ok(())
}
