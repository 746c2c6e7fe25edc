//! False-colour S/N map PNG, after Figs. 2–3 of Fochesatto et al. (2004):
//! log10(S/N) in false colour (viridis) against accumulation time TC (log
//! horizontal axis) and altitude (vertical axis), with labelled contours at
//! S/N = 1, 3 and 10 and a labelled colour bar.
//!
//! The shared pieces (embedded font and text, PNG encoding, ticks, viridis,
//! isolines) come from [`super::plot`]; this file holds the figure's layout. The
//! PNG is encoded in memory and written by the caller through
//! [`crate::safe_file`] (complete or not at all).

use super::plot::text::{encode_png, ensure_font};

mod contours;
mod draw;
mod grid;

use draw::render;
use grid::Grid;

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
const SNR_COLOUR_CAP: f64 = 1e6;

/// Renders `map` as a `WIDTH`×`HEIGHT` PNG, encoded in memory.
///
/// Invalid input (empty grid, fewer than 2 altitudes or times, ragged rows, NaN,
/// infinite or negative S/N, non-increasing or non-positive TC, duplicate
/// altitudes) is an error message; the caller writes the bytes through
/// [`crate::safe_file`].
pub fn png_bytes(map: &SnrMap) -> std::result::Result<Vec<u8>, String> {
    let grid = Grid::new(map)?;
    ensure_font()?;
    let mut rgb = vec![0u8; (WIDTH * HEIGHT * 3) as usize];
    render(&grid, map, &mut rgb).map_err(|e| format!("drawing failed: {e}"))?;
    encode_png(&rgb, WIDTH, HEIGHT).map_err(|e| format!("PNG encoding failed: {e}"))
}

// ---------------------------------------------------------------------------
// Validated grid
// ---------------------------------------------------------------------------

/// Why `map` cannot be drawn, if it cannot (shapes, finite values, increasing TC).
fn check(map: &SnrMap) -> std::result::Result<(), String> {
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

#[cfg(test)]
mod tests;
