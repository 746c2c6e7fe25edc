//! What the validation programs' figures share: the embedded font and writing an RGB
//! buffer as a PNG. Included by each program with `#[path = "figure.rs"] mod figure;`
//! (the library's own figures are in `src/output/`).

use plotters::style::{FontStyle, register_font};

/// The font family the figures name; [`register`] binds it to the embedded DejaVu Sans.
pub const FONT: &str = "sans-serif";
static FONT_BYTES: &[u8] = include_bytes!(concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/assets/fonts/DejaVuSans.ttf"
));

/// Registers the embedded font as [`FONT`].
pub fn register() {
    register_font(FONT, FontStyle::Normal, FONT_BYTES)
        .map_err(|_| "font")
        .expect("embedded font");
}

/// Writes the `width × height` RGB buffer `rgb` to `path` as a PNG.
pub fn write_png(rgb: &[u8], width: u32, height: u32, path: &std::path::Path) {
    let mut bytes = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut bytes, width, height);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let mut wr = enc.write_header().expect("png header");
        wr.write_image_data(rgb).expect("png data");
        wr.finish().expect("png finish");
    }
    std::fs::write(path, bytes).expect("write the PNG");
}
