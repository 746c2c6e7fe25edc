//! The figure's grid: values of any resolution averaged into pixel-sized cells, each
//! weighted by the share of the cell it covers, so that profiles and bins finer than a
//! pixel are averaged and coarser ones (an onboard product's upper regions) fill every
//! cell they cover. Memory is the grid's, whatever the file.

/// Sums over the cells of a `cols`×`rows` grid spanning `x` and `z` (ascending).
#[derive(Debug, Clone)]
pub struct Grid {
    pub cols: usize,
    pub rows: usize,
    pub x: (f64, f64),
    pub z: (f64, f64),
    sum: Vec<f64>,
    weight: Vec<f64>,
}

impl Grid {
    /// An empty grid (`x` and `z` finite, lo < hi).
    pub fn new(cols: usize, rows: usize, x: (f64, f64), z: (f64, f64)) -> Self {
        Grid {
            cols,
            rows,
            x,
            z,
            sum: vec![0.0; cols * rows],
            weight: vec![0.0; cols * rows],
        }
    }

    /// The cells `[lo, hi)` covers along an axis of `n` cells spanning `span`, each with
    /// the share of it covered.
    fn cover(lo: f64, hi: f64, span: (f64, f64), n: usize) -> impl Iterator<Item = (usize, f64)> {
        let w = (span.1 - span.0) / n as f64;
        let (a, b) = ((lo.min(hi) - span.0) / w, (lo.max(hi) - span.0) / w);
        let (first, last) = (a.floor().max(0.0), b.ceil().min(n as f64));
        let (first, last) = if last > first {
            (first as usize, last as usize)
        } else {
            (0, 0)
        };
        (first..last).filter_map(move |k| {
            let share = (b.min(k as f64 + 1.0) - a.max(k as f64)).max(0.0);
            // a point (zero extent) counts fully in its cell
            let share = if b == a { 1.0 } else { share };
            (share > 0.0).then_some((k, share))
        })
    }

    /// The columns `[x0, x1)` covers, with their shares.
    pub fn columns(&self, x0: f64, x1: f64) -> Vec<(usize, f64)> {
        Self::cover(x0, x1, self.x, self.cols).collect()
    }

    /// The rows `[z0, z1)` covers (row 0 at the top), with their shares.
    pub fn rows_of(&self, z0: f64, z1: f64) -> Vec<(usize, f64)> {
        let rows = self.rows;
        Self::cover(z0, z1, self.z, rows)
            .map(|(r, w)| (rows - 1 - r, w))
            .collect()
    }

    /// Adds the value `v` over the cells of `columns` × `rows` (from [`Grid::columns`],
    /// [`Grid::rows_of`]); NaN adds nothing.
    pub fn add_covered(&mut self, columns: &[(usize, f64)], rows: &[(usize, f64)], v: f64) {
        if v.is_nan() {
            return;
        }
        for &(row, wz) in rows {
            for &(c, wx) in columns {
                let k = row * self.cols + c;
                self.sum[k] += wx * wz * v;
                self.weight[k] += wx * wz;
            }
        }
    }

    /// Adds one profile: `values` of its bins, bin `i` over `bin_rows[i]`, the profile
    /// over `columns`; NaN adds nothing. The bins are summed into rows first, then the
    /// rows into the columns: the cost is the bins' plus the rows', not their product.
    pub fn add_profile(
        &mut self,
        columns: &[(usize, f64)],
        bin_rows: &[Vec<(usize, f64)>],
        values: impl Iterator<Item = f64>,
    ) {
        if columns.is_empty() {
            return;
        }
        let mut s = vec![0.0; self.rows];
        let mut w = vec![0.0; self.rows];
        for (v, rows) in values.zip(bin_rows) {
            if v.is_nan() {
                continue;
            }
            for &(r, wz) in rows {
                s[r] += wz * v;
                w[r] += wz;
            }
        }
        for (r, (&sr, &wr)) in s.iter().zip(&w).enumerate() {
            if wr > 0.0 {
                for &(c, wx) in columns {
                    let k = r * self.cols + c;
                    self.sum[k] += wx * sr;
                    self.weight[k] += wx * wr;
                }
            }
        }
    }

    /// Adds the value `v` of the region `[x0, x1)` × `[z0, z1)`; NaN adds nothing.
    pub fn add(&mut self, (x0, x1): (f64, f64), (z0, z1): (f64, f64), v: f64) {
        let (c, r) = (self.columns(x0, x1), self.rows_of(z0, z1));
        self.add_covered(&c, &r, v);
    }

    /// The cells' means, row 0 at the top; NaN where nothing fell.
    pub fn means(&self) -> Vec<f64> {
        self.sum
            .iter()
            .zip(&self.weight)
            .map(|(s, w)| if *w > 0.0 { s / w } else { f64::NAN })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fine_values_average_and_coarse_ones_fill() {
        let mut g = Grid::new(4, 2, (0.0, 4.0), (0.0, 2.0));
        // two half-cell values in cell (0, bottom)
        g.add((0.0, 0.5), (0.0, 1.0), 1.0);
        g.add((0.5, 1.0), (0.0, 1.0), 3.0);
        // one value over the whole top row
        g.add((0.0, 4.0), (1.0, 2.0), 7.0);
        let m = g.means();
        assert_eq!(&m[0..4], &[7.0; 4]);
        assert_eq!(m[4], 2.0);
        assert!(m[5].is_nan());
        // a profile: bins into rows, then into columns, as the cell by cell sum
        let mut h = Grid::new(4, 2, (0.0, 4.0), (0.0, 2.0));
        let rows = vec![
            h.rows_of(0.0, 1.0),
            h.rows_of(1.0, 2.0),
            h.rows_of(0.5, 1.5),
        ];
        h.add_profile(
            &h.columns(0.0, 2.0),
            &rows,
            [1.0, 3.0, f64::NAN].into_iter(),
        );
        let mut k = Grid::new(4, 2, (0.0, 4.0), (0.0, 2.0));
        k.add((0.0, 2.0), (0.0, 1.0), 1.0);
        k.add((0.0, 2.0), (1.0, 2.0), 3.0);
        let same = |a: f64, b: f64| a == b || (a.is_nan() && b.is_nan());
        assert!(h.means().iter().zip(k.means()).all(|(&a, b)| same(a, b)));
        // outside adds nothing, NaN adds nothing
        g.add((10.0, 11.0), (0.0, 1.0), 5.0);
        g.add((1.0, 2.0), (0.0, 1.0), f64::NAN);
        assert!(g.means()[5].is_nan());
    }
}
