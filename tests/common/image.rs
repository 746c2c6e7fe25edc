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
