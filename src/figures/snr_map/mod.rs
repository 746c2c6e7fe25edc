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
mod layout;
mod map;

use draw::render;
use grid::Grid;
pub use map::{CONTOUR_LEVELS, HEIGHT, SNR_COLOUR_MAX, SNR_COLOUR_MIN, SnrMap, WIDTH};

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

#[cfg(test)]
mod tests;
