//! One plotting module for every figure lidarsim draws (`snr-map`, `sweep`, `curtain`,
//! `quicklook`): the embedded font and text, nice ticks, human labels with units for
//! config keys and metrics, colour scales with colour bars (viridis from `colorous`),
//! isolines from `contour`, and an image panel that draws a field pixel by pixel with
//! its axes and colour bar. Figures are drawn into an RGB buffer with `plotters` and
//! encoded in memory ([`text::encode_png`]); the caller writes the bytes through
//! `safe_file` (complete or not at all).

pub mod colour;
pub mod isolines;
pub mod labels;
pub mod panel;
mod result;
pub mod text;
pub mod ticks;

pub use colour::ColourScale;
pub use labels::{Label, describe};
pub use panel::{Axis, ImagePanel};
pub use result::DrawResult;
pub use text::{FONT, encode_png, ensure_font};
