//! Decoded PNG figures, for tests that check what can be checked without eyes.

use std::collections::HashSet;
use std::path::Path;

/// A decoded RGB PNG: width, height, pixels.
pub struct Image {
    pub w: usize,
    pub h: usize,
    pub rgb: Vec<[u8; 3]>,
}

impl Image {
    pub fn read(path: &Path) -> Image {
        let file = std::io::BufReader::new(std::fs::File::open(path).unwrap());
        let mut reader = png::Decoder::new(file).read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size().unwrap()];
        let info = reader.next_frame(&mut buf).unwrap();
        assert_eq!(info.color_type, png::ColorType::Rgb);
        assert_eq!(info.bit_depth, png::BitDepth::Eight);
        buf.truncate(info.buffer_size());
        Image {
            w: info.width as usize,
            h: info.height as usize,
            rgb: buf.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
        }
    }

    /// The number of distinct colours.
    pub fn distinct(&self) -> usize {
        self.rgb.iter().collect::<HashSet<_>>().len()
    }

    /// Whether some pixel column in `x0..x1` (rows `y0..y1`) runs through at least `n`
    /// colours that are not grey, each once, one after the other: a colour bar (a field
    /// comes back to colours it had).
    pub fn has_colour_bar(&self, x0: usize, x1: usize, y0: usize, y1: usize, n: usize) -> bool {
        (x0..x1.min(self.w)).any(|x| {
            let mut runs: Vec<[u8; 3]> = (y0..y1.min(self.h))
                .map(|y| self.rgb[y * self.w + x])
                .filter(|c| !(c[0] == c[1] && c[1] == c[2]))
                .collect();
            runs.dedup();
            let distinct = runs.iter().collect::<HashSet<_>>().len();
            runs.len() >= n && distinct == runs.len()
        })
    }
}

/// `text` as the figures draw their tick labels (the embedded font, 13 px, black on
/// white): the dark pixels (any channel below 128) of its box, row by row.
pub fn rendered(text: &str) -> Vec<Vec<bool>> {
    rendered_at(text, 13)
}

/// `text` in the embedded font at `size` px, black on white: the dark pixels of its box.
pub fn rendered_at(text: &str, size: u32) -> Vec<Vec<bool>> {
    use lidarsim::figures::plot::{FONT, ensure_font};
    use plotters::prelude::*;
    ensure_font().unwrap();
    let (w, h) = (40 + size * text.chars().count() as u32, 20 + 3 * size);
    let mut rgb = vec![255u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
        root.draw(&Text::new(
            text.to_string(),
            (10, 10),
            (FONT, size).into_font(),
        ))
        .unwrap();
        root.present().unwrap();
    }
    let dark: Vec<bool> = rgb
        .chunks_exact(3)
        .map(|c| c.iter().any(|&v| v < 128))
        .collect();
    let (w, h) = (w as usize, h as usize);
    let rows: Vec<usize> = (0..h)
        .filter(|&y| (0..w).any(|x| dark[y * w + x]))
        .collect();
    let cols: Vec<usize> = (0..w)
        .filter(|&x| (0..h).any(|y| dark[y * w + x]))
        .collect();
    let (y0, y1, x0, x1) = (
        rows[0],
        *rows.last().unwrap(),
        cols[0],
        *cols.last().unwrap(),
    );
    (y0..=y1)
        .map(|y| (x0..=x1).map(|x| dark[y * w + x]).collect())
        .collect()
}

/// Where `img` shows `text` (its dark pixels exactly, the box's other pixels light), in
/// rows `y0..y1`: the left edges of every place found.
pub fn find_text(img: &Image, text: &str, y0: usize, y1: usize) -> Vec<usize> {
    find_text_at(img, text, 13, y0, y1)
        .into_iter()
        .map(|(x, _)| x)
        .collect()
}

/// Where `img` shows `text` drawn at `size` px, in rows `y0..y1`: the top left corner
/// `(x, y)` of every place found.
pub fn find_text_at(
    img: &Image,
    text: &str,
    size: u32,
    y0: usize,
    y1: usize,
) -> Vec<(usize, usize)> {
    let t = rendered_at(text, size);
    let (th, tw) = (t.len(), t[0].len());
    let dark: Vec<bool> = img.rgb.iter().map(|c| c.iter().any(|&v| v < 128)).collect();
    let mut found = Vec::new();
    for y in y0..y1.min(img.h).saturating_sub(th) {
        for x in 0..img.w.saturating_sub(tw) {
            if (0..th).all(|j| (0..tw).all(|i| dark[(y + j) * img.w + x + i] == t[j][i])) {
                found.push((x, y));
            }
        }
    }
    found
}

/// The panels of a figure: the rows where a dark line runs unbroken for at least
/// `min_len` pixels (a panel's x axis, its frame's foot), adjacent rows counted once.
pub fn axis_rows(img: &Image, min_len: usize) -> Vec<usize> {
    let dark = |x: usize, y: usize| img.rgb[y * img.w + x].iter().all(|&v| v < 80);
    let mut rows: Vec<usize> = Vec::new();
    for y in 0..img.h {
        let (mut run, mut best) = (0, 0);
        for x in 0..img.w {
            run = if dark(x, y) { run + 1 } else { 0 };
            best = best.max(run);
        }
        if best >= min_len && rows.last().is_none_or(|&r| r + 1 != y) {
            rows.push(y);
        } else if best >= min_len {
            *rows.last_mut().unwrap() = y;
        }
    }
    rows
}
