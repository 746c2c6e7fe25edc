//! The scene along the track (docs/model.md §4f): segments of given length, each with its own
//! layers, aerosol and surface, and broken layers cut into cells. Each shot sees the
//! column at its own along-track position `x = v_g·t` (v_g the ground-track speed,
//! model.md §3; t from the first shot).
//!
//! **Columns.** The scene is piecewise constant along the track: a *column* is a
//! segment with a subset of its broken layers present. The simulation builds each
//! column's model and samplers once, and a profile is drawn as runs of consecutive
//! shots that see one column (cost per column change, not per shot).
//!
//! **Broken cloud.** A layer with `cloud_fraction = f` and `cell_length_km = L` covers
//! alternating cloudy and clear stretches with exponential lengths of means `L`
//! (cloudy) and `L·(1−f)/f` (clear): a two-state Markov renewal process whose long-run
//! cloudy fraction is f (Cox 1962, *Renewal Theory*, §7.2), started in its stationary
//! state (cloudy with probability f) at the segment's start. The cells are drawn from
//! `stream_rng(seed ^ CELL_STREAM, segment, layer)`: the same seed gives the same clouds
//! whatever else the run does.

use rand::Rng;

use crate::config::{LayerConfig, ScenarioConfig, SegmentAerosol};
use crate::error::{Error, Result, compact};
use crate::sampling::stream_rng;
use crate::scene::orbit::Orbit;

/// How far along the track a time is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum AlongTrack {
    /// `x = v·t` at a constant ground speed, m s⁻¹ (a run without an orbit).
    Speed(f64),
    /// The length of the orbit's Earth-fixed ground track ([`Orbit::along_track_m`]).
    Orbit(Orbit),
}

impl AlongTrack {
    /// Distance from the first shot at `t_s` seconds after it, m.
    pub fn at(&self, t_s: f64) -> f64 {
        match self {
            AlongTrack::Speed(v) => v * t_s,
            AlongTrack::Orbit(o) => o.along_track_m(t_s),
        }
    }
}

/// Seed offset of the cloud-cell streams.
const CELL_STREAM: u64 = 0xC311_5EED_0000_0001;
/// Most columns a scene may have (segments × their broken-layer subsets). Columns are
/// built when first drawn and dropped after their last profile, their truth streamed
/// (issue 39), so the bound is on the per-column indices held for the whole run
/// (a few tens of bytes each); a day of 5 km profiles through model fields has ~1.3e5.
pub const MAX_COLUMNS: usize = 1 << 20;

/// One column: a segment and which of its broken layers are present (bit k: the k-th
/// broken layer of the segment).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Column {
    /// Index of the segment (0 for a scene without segments).
    pub segment: usize,
    /// Present broken layers, one bit each.
    pub present: u8,
}

/// A stretch of the track with its broken layers' cloudy cells.
#[derive(Debug, Clone)]
struct Stretch {
    start_m: f64,
    /// Cloudy intervals `[a, b)` of each broken layer, in order.
    cells: Vec<Vec<(f64, f64)>>,
}

/// The track of a run: where each shot is and which column it sees.
#[derive(Debug, Clone)]
pub struct Track {
    along: AlongTrack,
    rep_rate_hz: f64,
    shots_per_profile: u64,
    stretches: Vec<Stretch>,
}

/// Whether a layer is broken (covers less than the whole track).
fn is_broken(l: &LayerConfig) -> bool {
    l.cloud_fraction.is_some_and(|f| f < 1.0)
}

/// The layers of segment `i` of `cfg` (its own, or the atmosphere's).
fn segment_layers(cfg: &ScenarioConfig, i: usize) -> &[LayerConfig] {
    cfg.scene
        .as_ref()
        .and_then(|s| s.segments.get(i))
        .and_then(|s| s.layers.as_deref())
        .unwrap_or(&cfg.atmosphere.layers)
}

/// Number of segments (1 without `[scene]`).
fn n_segments(cfg: &ScenarioConfig) -> usize {
    cfg.scene.as_ref().map_or(0, |s| s.segments.len()).max(1)
}

impl Track {
    /// Whether `cfg` describes a scene that changes along the track.
    pub fn is_changing(cfg: &ScenarioConfig) -> bool {
        cfg.scene
            .as_ref()
            .is_some_and(|s| s.curtain.is_some() || s.model_fields.is_some())
            || (0..n_segments(cfg)).any(|i| i > 0 || segment_layers(cfg, i).iter().any(is_broken))
    }

    /// The track of a run of `profiles` profiles of `shots_per_profile` shots laid
    /// along `along`; broken layers' cells are drawn from `seed`.
    pub fn new(
        cfg: &ScenarioConfig,
        seed: u64,
        along: AlongTrack,
        shots_per_profile: u64,
        profiles: u64,
    ) -> Result<Track> {
        let rep_rate_hz = cfg.instrument.rep_rate_hz;
        let run_length_m = along.at((profiles as f64 * shots_per_profile as f64) / rep_rate_hz);
        let lengths: Vec<f64> = match &cfg.scene {
            Some(s) if !s.segments.is_empty() => {
                s.segments.iter().map(|g| g.length_km * 1e3).collect()
            }
            _ => vec![f64::INFINITY],
        };
        let mut start_m = 0.0;
        let stretches = lengths
            .iter()
            .enumerate()
            .map(|(i, &len)| {
                let last = i + 1 == lengths.len();
                // the last stretch runs to the end of the run (cells are drawn that far)
                let end_m = if last {
                    (start_m + if len.is_finite() { len } else { 0.0 }).max(run_length_m)
                } else {
                    start_m + len
                };
                let cells = segment_layers(cfg, i)
                    .iter()
                    .filter(|l| is_broken(l))
                    .enumerate()
                    .map(|(k, l)| {
                        check_cell_count(l, end_m - start_m)?;
                        Ok(draw_cells(l, seed, i, k, start_m, end_m))
                    })
                    .collect::<Result<_>>()?;
                let s = Stretch { start_m, cells };
                start_m = end_m;
                Ok(s)
            })
            .collect::<Result<_>>()?;
        Ok(Track {
            along,
            rep_rate_hz,
            shots_per_profile,
            stretches,
        })
    }

    /// Every column the scene can show, in order (segment, then subset).
    pub fn columns(&self) -> Vec<Column> {
        self.stretches
            .iter()
            .enumerate()
            .flat_map(|(segment, s)| {
                (0..1u16 << s.cells.len()).map(move |present| Column {
                    segment,
                    present: present as u8,
                })
            })
            .collect()
    }

    /// Along-track distance of shot `shot` of profile `profile` from the first shot, m.
    pub fn position_m(&self, profile: u64, shot: u64) -> f64 {
        let n = profile as f64 * self.shots_per_profile as f64 + shot as f64;
        self.along.at(n / self.rep_rate_hz)
    }

    /// The column seen at along-track position `x_m`.
    pub fn column_at(&self, x_m: f64) -> Column {
        let segment = self
            .stretches
            .partition_point(|s| s.start_m <= x_m)
            .saturating_sub(1);
        let present = self.stretches[segment]
            .cells
            .iter()
            .enumerate()
            .filter(|(_, cells)| {
                let k = cells.partition_point(|c| c.0 <= x_m);
                k > 0 && x_m < cells[k - 1].1
            })
            .fold(0u8, |m, (k, _)| m | (1 << k));
        Column { segment, present }
    }

    /// The runs of profile `profile`: consecutive shots that see one column, with their
    /// shot counts, in shot order.
    pub fn runs(&self, profile: u64) -> Vec<(Column, u64)> {
        let mut runs: Vec<(Column, u64)> = Vec::new();
        for s in 0..self.shots_per_profile {
            let c = self.column_at(self.position_m(profile, s));
            match runs.last_mut() {
                Some((last, n)) if *last == c => *n += 1,
                _ => runs.push((c, 1)),
            }
        }
        runs
    }

    /// An upper bound of the distinct columns one of the run's `profiles` profiles
    /// sees: one more than the column boundaries (segment starts, cloudy cells' edges)
    /// between its first and last shot, at most `n_columns` and the shots per profile.
    /// O(profiles × broken layers × log cells): no shot is placed.
    pub fn columns_per_profile_bound(&self, profiles: u64, n_columns: usize) -> usize {
        let cap = n_columns.min(self.shots_per_profile as usize).max(1);
        let last_shot = self.shots_per_profile.saturating_sub(1);
        let mut most = 1;
        for p in 0..profiles {
            if most >= cap {
                break;
            }
            let (a, b) = (self.position_m(p, 0), self.position_m(p, last_shot));
            let starts_before = |x: f64| self.stretches.partition_point(|s| s.start_m <= x);
            let (first, last) = (starts_before(a).saturating_sub(1), starts_before(b));
            let mut edges = last.saturating_sub(first + 1);
            for s in &self.stretches[first..last] {
                for cells in &s.cells {
                    let at_most = |x: f64, end: bool| {
                        cells.partition_point(|c| if end { c.1 <= x } else { c.0 <= x })
                    };
                    edges += at_most(b, false) - at_most(a, false);
                    edges += at_most(b, true) - at_most(a, true);
                }
            }
            most = most.max(1 + edges);
        }
        most.min(cap)
    }

    /// The config of one column: the segment's layers, aerosol, surface, water vapour and molecules in place of
    /// the atmosphere's, its absent broken layers removed and its present ones whole.
    pub fn column_config(&self, base: &ScenarioConfig, c: Column) -> ScenarioConfig {
        let mut cfg = base.clone_without_scene();
        let segment = base.scene.as_ref().and_then(|s| s.segments.get(c.segment));
        if let Some(seg) = segment {
            match &seg.aerosol {
                Some(SegmentAerosol::Named(_)) => cfg.atmosphere.aerosol = None,
                Some(SegmentAerosol::Given(a)) => cfg.atmosphere.aerosol = Some(a.clone()),
                None => {}
            }
            if let Some(s) = &seg.surface {
                cfg.surface = Some(s.clone());
            }
            if let Some(w) = &seg.water_vapour {
                cfg.atmosphere.water_vapour = Some(w.clone());
            }
            if let Some(m) = &seg.molecular {
                cfg.atmosphere.molecular.model = m.clone();
            }
        }
        let mut k = 0;
        cfg.atmosphere.layers = segment_layers(base, c.segment)
            .iter()
            .filter(|l| {
                if !is_broken(l) {
                    return true;
                }
                let present = c.present & (1 << k) != 0;
                k += 1;
                present
            })
            .map(|l| LayerConfig {
                cloud_fraction: None,
                cell_length_km: None,
                ..l.clone()
            })
            .collect();
        cfg
    }
}

/// Most cloudy cells a broken layer may have over the run (memory: 16 bytes each).
pub const MAX_CELLS: f64 = 1e7;

/// Refuses a broken layer whose cells over `length_m` would not fit in memory.
fn check_cell_count(l: &LayerConfig, length_m: f64) -> Result<()> {
    let f = l.cloud_fraction.unwrap_or(1.0);
    let cell_m = l.cell_length_km.unwrap_or(1.0) * 1e3;
    let cells = length_m * f / cell_m;
    if cells > MAX_CELLS {
        return Err(Error::Unsupported(format!(
            "a broken layer with cells of {} km would need ~{cells:.1e} cells over the run's \
             {:.3e} km (at most {}): use longer cells or fewer profiles",
            compact(cell_m / 1e3),
            length_m / 1e3,
            compact(MAX_CELLS)
        )));
    }
    Ok(())
}

/// The cloudy cells of broken layer `k` of segment `i` over `[start_m, end_m)`.
fn draw_cells(
    l: &LayerConfig,
    seed: u64,
    i: usize,
    k: usize,
    start_m: f64,
    end_m: f64,
) -> Vec<(f64, f64)> {
    let f = l.cloud_fraction.unwrap_or(1.0);
    let cloudy_mean = l.cell_length_km.unwrap_or(1.0) * 1e3;
    let clear_mean = cloudy_mean * (1.0 - f) / f;
    let mut rng = stream_rng(seed ^ CELL_STREAM, i as u64, k as u64);
    let mut uniform = || (rng.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64);
    let mut cloudy = uniform() < f;
    let mut exp = |mean: f64| -mean * (1.0 - uniform()).ln();
    let mut x = start_m;
    let mut cells = Vec::new();
    while x < end_m {
        let len = exp(if cloudy { cloudy_mean } else { clear_mean });
        if cloudy {
            cells.push((x, (x + len).min(end_m)));
        }
        x += len;
        cloudy = !cloudy;
    }
    cells
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cfg(extra: &[&str]) -> ScenarioConfig {
        let mut ov: Vec<String> = vec![
            "atmosphere.layers.0.cloud_fraction=0.3".into(),
            "atmosphere.layers.0.cell_length_km=5".into(),
        ];
        ov.extend(extra.iter().map(|s| s.to_string()));
        let path = std::path::Path::new(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/configs/paper/scenario1.toml"
        ));
        crate::loaded::load(path, &ov).unwrap().config
    }

    /// Over 200,000 km of a layer with f = 0.3 and 5 km cells (cloudy and clear lengths
    /// exponential, means L = 5 km and L(1−f)/f = 11.67 km; ~12,000 cycles) the cloudy
    /// fraction is 0.3 within 5 sd, sd = sqrt(Var(C(1−f) − fG)/n)/E[C+G] with the
    /// exponentials' variances (≈ 0.0027), and the mean cloudy cell is 5 km within 5 sd
    /// (sd = 5 km/√n, n cells). False alarm: 2 × 5.7e-7 (normal approximation to sums
    /// of ~12,000 cycles). Power, on the same draws: a fraction 10 % off (0.33 or 0.27) and
    /// a mean cell 10 % off are rejected; and the same seed gives the same cells.
    #[test]
    fn broken_cloud_has_its_fraction_and_cell_length() {
        let c = cfg(&[]);
        let len = 200_000e3;
        let cells = draw_cells(&c.atmosphere.layers[0], 7, 0, 0, 0.0, len);
        let covered: f64 = cells.iter().map(|(a, b)| b - a).sum();
        let (f, cell, gap) = (0.3, 5e3, 5e3 * 0.7 / 0.3);
        let cycles = len / (cell + gap);
        let sd_f = ((1.0 - f) * (1.0 - f) * cell * cell + f * f * gap * gap).sqrt()
            / (cell + gap)
            / cycles.sqrt();
        let fraction_ok = |want: f64| (covered / len - want).abs() < 5.0 * sd_f;
        assert!(fraction_ok(f), "{} (sd {sd_f})", covered / len);
        assert!(
            !fraction_ok(1.1 * f) && !fraction_ok(0.9 * f),
            "no power (sd {sd_f})"
        );
        let mean = covered / cells.len() as f64;
        let sd_m = cell / (cells.len() as f64).sqrt();
        let cell_ok = |want: f64| (mean - want).abs() < 5.0 * sd_m;
        assert!(cell_ok(cell), "{mean} (sd {sd_m})");
        assert!(
            !cell_ok(1.1 * cell) && !cell_ok(0.9 * cell),
            "no power (sd {sd_m})"
        );
        assert_eq!(
            cells,
            draw_cells(&c.atmosphere.layers[0], 7, 0, 0, 0.0, len)
        );
        assert_ne!(
            cells,
            draw_cells(&c.atmosphere.layers[0], 8, 0, 0, 0.0, len)
        );
    }

    #[test]
    fn runs_follow_the_cells_and_columns_drop_absent_layers() {
        let c = cfg(&[]);
        let track = Track::new(&c, 3, AlongTrack::Speed(7000.0), 100, 50).unwrap();
        assert!(Track::is_changing(&c));
        assert_eq!(track.columns().len(), 2);
        let mut seen = [0u64; 2];
        for p in 0..50 {
            let runs = track.runs(p);
            assert_eq!(runs.iter().map(|r| r.1).sum::<u64>(), 100);
            for (col, n) in runs {
                seen[col.present as usize] += n;
            }
        }
        assert!(seen[0] > 0 && seen[1] > 0, "{seen:?}");
        let clear = track.column_config(
            &c,
            Column {
                segment: 0,
                present: 0,
            },
        );
        let cloudy = track.column_config(
            &c,
            Column {
                segment: 0,
                present: 1,
            },
        );
        assert_eq!(clear.atmosphere.layers.len(), c.atmosphere.layers.len() - 1);
        assert_eq!(cloudy.atmosphere.layers.len(), c.atmosphere.layers.len());
        assert!(
            cloudy
                .atmosphere
                .layers
                .iter()
                .all(|l| l.cloud_fraction.is_none())
        );
        assert!(!Track::is_changing(&cfg(&[
            "atmosphere.layers.0.cloud_fraction=1"
        ])));
    }
}
