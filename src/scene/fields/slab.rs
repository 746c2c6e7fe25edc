//! The box of the grid read at once and a profile sampled from it: the profiles are
//! read in runs of consecutive profiles whose box (times × levels × latitudes ×
//! longitudes) stays under [`MAX_SLAB_CELLS`], so that memory does not grow with the
//! track (a day through global 0.25° fields would be ~21 GB read at once); within a
//! run each profile's levels are mixed from the box by its weights ([`super::grid`]).

use super::column::{Level, STANDARD_GRAVITY};
use super::grid::Weight;

/// Most grid cells (times × levels × latitudes × longitudes) read at once: the
/// profiles are read in runs of consecutive profiles whose box stays within it (a run
/// of one profile may exceed it), so that a day through global fields holds one part of
/// them at a time. 2^20 cells are ~120 MB for the ~14 arrays read, a box of ~30° at 37
/// levels and two times (a run of ~600 profiles along an orbit; at the seam of a global
/// grid, whose box spans every longitude, a few tens).
pub const MAX_SLAB_CELLS: usize = 1 << 20;

/// A box of the grid: the times, latitudes and longitudes from `t0`, `y0`, `x0` on, `ct`,
/// `cy`, `cx` of them (every level).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Slab {
    /// First time index and count.
    pub t0: usize,
    /// Time count.
    pub ct: usize,
    /// First latitude index.
    pub y0: usize,
    /// Latitude count.
    pub cy: usize,
    /// First longitude index.
    pub x0: usize,
    /// Longitude count.
    pub cx: usize,
}

impl Slab {
    /// The smallest box holding every point of `weights`; `None` for no point.
    pub fn spanning<'a>(weights: impl IntoIterator<Item = &'a Weight>) -> Option<Slab> {
        let mut lo = [usize::MAX; 3];
        let mut hi = [0; 3];
        let mut any = false;
        for w in weights {
            any = true;
            for (k, i) in [w.t, w.y, w.x].into_iter().enumerate() {
                lo[k] = lo[k].min(i);
                hi[k] = hi[k].max(i);
            }
        }
        any.then(|| Slab {
            t0: lo[0],
            ct: hi[0] - lo[0] + 1,
            y0: lo[1],
            cy: hi[1] - lo[1] + 1,
            x0: lo[2],
            cx: hi[2] - lo[2] + 1,
        })
    }

    /// The smallest box holding both.
    pub fn union(&self, o: &Slab) -> Slab {
        let span = |a0: usize, ca: usize, b0: usize, cb: usize| {
            let lo = a0.min(b0);
            (lo, (a0 + ca).max(b0 + cb) - lo)
        };
        let (t0, ct) = span(self.t0, self.ct, o.t0, o.ct);
        let (y0, cy) = span(self.y0, self.cy, o.y0, o.cy);
        let (x0, cx) = span(self.x0, self.cx, o.x0, o.cx);
        Slab {
            t0,
            ct,
            y0,
            cy,
            x0,
            cx,
        }
    }

    /// Cells of the box at `levels` levels.
    pub fn cells(&self, levels: usize) -> usize {
        self.ct * levels * self.cy * self.cx
    }

    /// Index of the point `w` at level `k` of `levels` in the box's (t, level, y, x) array.
    pub fn index(&self, levels: usize, w: &Weight, k: usize) -> usize {
        (((w.t - self.t0) * levels + k) * self.cy + (w.y - self.y0)) * self.cx + (w.x - self.x0)
    }
}

/// The runs of consecutive samples (each sample its grid points `weights[p]`) read as
/// one box of at most `max_cells` cells at `levels` levels: each run as long as its
/// box allows, at least one sample.
pub fn runs(
    weights: &[Vec<Weight>],
    levels: usize,
    max_cells: usize,
) -> Vec<std::ops::Range<usize>> {
    let mut out = Vec::new();
    let mut run: Option<(usize, Slab)> = None;
    for (p, w) in weights.iter().enumerate() {
        let Some(own) = Slab::spanning(w) else {
            continue;
        };
        run = match run {
            Some((start, b)) => {
                let grown = b.union(&own);
                if grown.cells(levels) <= max_cells {
                    Some((start, grown))
                } else {
                    out.push(start..p);
                    Some((p, own))
                }
            }
            None => Some((0, own)),
        };
    }
    if let Some((start, _)) = run {
        out.push(start..weights.len());
    }
    out
}

/// The fields read over one box of the grid.
pub struct Boxed<'a> {
    /// The box.
    pub b: Slab,
    /// Levels.
    pub levels: usize,
    /// Each of the per-level roles' (`read::LEVEL_ROLES`)' values over the box, if in the files.
    pub fields: &'a [Option<Vec<f64>>],
    /// The CAMS species read: (index in `CAMS_SPECIES`, values over the box).
    pub species: &'a [(usize, Vec<f64>)],
}

impl Boxed<'_> {
    /// A per-level field `f` of the box at level `k`, mixed by the weights `ws`.
    pub fn mix(&self, f: &[f64], ws: &[Weight], k: usize) -> f64 {
        ws.iter()
            .map(|w| w.w * f[self.b.index(self.levels, w, k)])
            .sum()
    }

    /// A surface field `f` of the box (t, y, x), mixed by the weights `ws`.
    pub fn mix_surface(&self, f: &[f64], ws: &[Weight]) -> f64 {
        ws.iter().map(|w| w.w * f[self.b.index(1, w, 0)]).sum()
    }
}

/// Where the levels' pressure and height come from besides the fields: hybrid
/// coefficients (a, b) with the surface pressure, or the level coordinate's own units.
pub struct Vertical<'a> {
    /// Hybrid a (Pa) and b coefficients, one per level.
    pub hybrid: Option<&'a (Vec<f64>, Vec<f64>)>,
    /// The level coordinate as pressures, Pa.
    pub lev_p: Option<&'a [f64]>,
    /// The level coordinate as heights, m.
    pub lev_z: Option<&'a [f64]>,
}

impl Vertical<'_> {
    /// Level `k` of a profile whose grid points are `ws`, its surface pressure `sp`.
    pub fn level(&self, f: &Boxed, ws: &[Weight], k: usize, sp: Option<f64>) -> Level {
        let value = |i: usize| f.fields[i].as_ref().map(|x| f.mix(x, ws, k));
        let p_pa = value(5)
            .or_else(|| self.hybrid.zip(sp).map(|((a, b), s)| a[k] + b[k] * s))
            .or_else(|| self.lev_p.map(|l| l[k]))
            .unwrap_or(f64::NAN);
        let height_m = value(6)
            .or_else(|| value(7).map(|g| g / STANDARD_GRAVITY))
            .or_else(|| self.lev_z.map(|l| l[k]))
            .unwrap_or(f64::NAN);
        let mut aerosol_mmr = [0.0; 18];
        for (i, x) in f.species {
            aerosol_mmr[*i] = f.mix(x, ws, k).max(0.0);
        }
        Level {
            p_pa,
            t_k: value(0).unwrap_or(f64::NAN),
            q: value(1).unwrap_or(0.0).max(0.0),
            liquid: value(2).unwrap_or(0.0).max(0.0),
            ice: value(3).unwrap_or(0.0).max(0.0),
            cloud_fraction: value(4).unwrap_or(1.0),
            height_m,
            liquid_radius_um: value(8),
            ice_radius_um: value(9),
            aerosol_mmr,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The runs cover every sample once, in order; each run's box is within the bound
    /// unless the run is one sample; and a run ends only where the next sample would
    /// break the bound.
    #[test]
    fn runs_cover_the_samples_within_the_bound() {
        // a track walking east and south, a point every sample, with a jump back
        let weights: Vec<Vec<Weight>> = (0..200)
            .map(|i| {
                let (y, x) = (i / 7, (i * 3) % 170);
                vec![
                    Weight { t: 0, y, x, w: 0.5 },
                    Weight {
                        t: 1,
                        y: y + 1,
                        x: x + 1,
                        w: 0.5,
                    },
                ]
            })
            .collect();
        for cap in [1, 100, 1_000, 50_000, usize::MAX] {
            let runs = runs(&weights, 3, cap);
            assert_eq!(runs.first().map(|r| r.start), Some(0));
            assert_eq!(runs.last().map(|r| r.end), Some(weights.len()));
            for (a, b) in runs.iter().zip(runs.iter().skip(1)) {
                assert_eq!(a.end, b.start);
                let longer = Slab::spanning(weights[a.start..=b.start].iter().flatten()).unwrap();
                assert!(longer.cells(3) > cap, "run {a:?} could have grown");
            }
            for r in &runs {
                let b = Slab::spanning(weights[r.clone()].iter().flatten()).unwrap();
                assert!(
                    r.len() == 1 || b.cells(3) <= cap,
                    "{r:?}: {} cells",
                    b.cells(3)
                );
            }
        }
    }
}
