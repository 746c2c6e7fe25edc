//! The embedded font, text drawing and PNG encoding.
//!
//! Text is drawn with DejaVu Sans embedded in the binary (`assets/fonts/`, licence
//! beside it) through plotters' `ab_glyph` feature, so no system font or fontconfig is
//! needed.

use std::sync::OnceLock;

use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use plotters::style::{FontStyle, register_font};

/// Font family name under which the embedded font is registered with plotters.
pub const FONT: &str = "sans-serif";
static FONT_BYTES: &[u8] = include_bytes!(concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/assets/fonts/DejaVuSans.ttf"
));

/// Registers the embedded font once; an error if it cannot be parsed.
pub fn ensure_font() -> std::result::Result<(), String> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let ok = *REGISTERED.get_or_init(|| register_font(FONT, FontStyle::Normal, FONT_BYTES).is_ok());
    if ok {
        Ok(())
    } else {
        Err("embedded font DejaVuSans.ttf could not be parsed".into())
    }
}

/// The PNG of an RGB buffer of `w`×`h` pixels, encoded in memory.
pub fn encode_png(rgb: &[u8], w: u32, h: u32) -> std::result::Result<Vec<u8>, png::EncodingError> {
    let mut out = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut out, w, h);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let mut writer = enc.write_header()?;
        writer.write_image_data(rgb)?;
        writer.finish()?;
    }
    Ok(out)
}

/// The embedded font at `size` pixels, black.
pub fn font(size: f64) -> TextStyle<'static> {
    TextStyle::from((FONT, size).into_font()).color(&BLACK)
}

/// Draws unrotated text anchored at `(x, y)` on any drawing area. plotters' `ab_glyph`
/// renderer puts glyphs lower than its layout box says; shift so that `VPos::Center`
/// centres the capitals on `y` and `VPos::Top` puts their tops at about `y`.
pub fn label<DB: DrawingBackend>(
    root: &DrawingArea<DB, plotters::coord::Shift>,
    text: &str,
    (x, y): (i32, i32),
    style: &TextStyle<'_>,
    h: HPos,
    v: VPos,
) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let size = style.font.get_size();
    let dy = match v {
        VPos::Center => (0.22 * size).round() as i32,
        VPos::Top => (0.13 * size).round() as i32,
        VPos::Bottom => 0,
    };
    root.draw(&Text::new(
        text.to_string(),
        (x, y + dy),
        style.pos(Pos::new(h, v)),
    ))
}
