//! The S/N map's layout in pixels and the style of each contour level.

use plotters::prelude::*;

use super::map::CONTOUR_LEVELS;

// Layout (pixels).
pub(super) const PLOT_L: i32 = 92;
pub(super) const PLOT_R: i32 = 812;
pub(super) const PLOT_T: i32 = 84;
pub(super) const PLOT_B: i32 = 592;
pub(super) const CBAR_L: i32 = 846;
pub(super) const CBAR_R: i32 = 870;

pub(super) type Area<'a> = DrawingArea<BitMapBackend<'a>, plotters::coord::Shift>;

/// How one contour level is drawn.
pub(super) struct LevelStyle {
    pub(super) level: f64,
    pub(super) colour: RGBColor,
    pub(super) halo: RGBColor,
    pub(super) dashed: bool,
}

/// S/N = 1 dashed white, 3 white, 10 black, each on a contrasting halo.
pub(super) fn level_styles() -> [LevelStyle; 3] {
    let style = |k: usize, colour, halo, dashed| LevelStyle {
        level: CONTOUR_LEVELS[k],
        colour,
        halo,
        dashed,
    };
    [
        style(0, WHITE, BLACK, true),
        style(1, WHITE, BLACK, false),
        style(2, BLACK, WHITE, false),
    ]
}
