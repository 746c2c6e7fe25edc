//! One region of a product shard (or of a whole product), read and checked as every
//! reader checks it: its counts, coordinates, calibration and truth.

use std::path::Path;

use hdf5::{Dataset, Group};
use ndarray::s;

use super::truth::{fixed_variables, per_profile_variables};
use crate::error::{Error, Result};

/// One region of a product shard.
pub(super) struct ShardRegion {
    /// Its profiles, and the shots summed in each.
    pub(super) rows: usize,
    pub(super) shots: u32,
    /// Channels × bins of a profile.
    pub(super) row_elems: usize,
    /// Its channels, the scene's columns and the `k` slots.
    pub(super) channels: usize,
    pub(super) columns: usize,
    pub(super) slots: usize,
    /// Whether it has the geolocation of an orbit.
    pub(super) geolocation: bool,
}

impl ShardRegion {
    /// Region group `g` of the shard at `path`, checked as a raw file's variables are
    /// ([`crate::output::raw_file::read`]): `counts` (profile, channel, bin) of unsigned
    /// integers holding the values it declares, `time` and `n_shots` (profile), `channel`
    /// (channel; numbered, named by `channel_name`, or the names in earlier products),
    /// `altitude` (bin), finite coordinates, `shots_averaged` ≥ 1.
    pub(super) fn of(g: &Group, path: &Path) -> Result<ShardRegion> {
        use crate::output::raw_file::integrity::{
            channel_labels, check_at_least_one, check_calibration,
        };
        use crate::output::raw_file::read::{check_finite, check_storage, is_float, is_unsigned};
        let region = g.name().trim_start_matches('/').to_string();
        let bad = |why: String| Error::output(path, format!("{region}: {why}"));
        let get = |name: &str| {
            g.dataset(name).map_err(|_| {
                Error::output(path, format!("{region} has no `{name}`: not a product"))
            })
        };
        // every variable holds what it declares before any is compared with another, so
        // that a crafted length is named where it is
        for d in g
            .datasets()
            .map_err(|_| bad("cannot list its variables".into()))?
        {
            let name = d.name();
            check_storage(path, name.trim_start_matches('/'), &d)?;
        }
        let counts = get("counts")?;
        let shape = counts.shape();
        let [rows, channels, bins] = shape[..] else {
            return Err(bad(format!(
                "`counts` has {} dimensions, not 3 (profile, channel, bin)",
                shape.len()
            )));
        };
        if !is_unsigned(&counts) || channels == 0 || bins == 0 {
            return Err(bad(
                "`counts` is not (profile, channel, bin) of unsigned integers with channels \
                 and bins"
                    .into(),
            ));
        }
        let shots = g
            .attr("shots_averaged")
            .and_then(|a| a.read_scalar::<u32>())
            .map_err(|_| bad("no whole-number attribute `shots_averaged`".into()))?;
        if shots == 0 {
            return Err(bad(
                "`shots_averaged` is 0; a profile sums at least one shot".into(),
            ));
        }
        for (name, len, float) in [
            ("time", rows, true),
            ("n_shots", rows, false),
            ("channel", channels, false),
            ("altitude", bins, true),
            ("profile", rows, false),
            ("bin", bins, false),
        ] {
            let d = get(name)?;
            if d.shape() != [len] || (float && !is_float(&d)) {
                return Err(bad(format!(
                    "`{name}` is {}, but `counts` (profile, channel, bin) = {rows} × \
                     {channels} × {bins} makes it {len}{}",
                    crate::output::raw_file::read::shape_text(&d.shape()),
                    if float { " floating-point numbers" } else { "" }
                )));
            }
        }
        for name in ["counts", "time", "n_shots", "channel", "altitude"] {
            check_storage(path, &format!("{region}/{name}"), &get(name)?)?;
        }
        for name in ["time", "altitude"] {
            check_finite(path, &format!("{region}/{name}"), &get(name)?)?;
        }
        check_at_least_one(path, &format!("{region}/n_shots"), &get("n_shots")?)?;
        let columns = get("column")?.shape().first().copied().unwrap_or(0);
        let slots = get("k")?.shape().first().copied().unwrap_or(0);
        let out = ShardRegion {
            rows,
            row_elems: channels * bins,
            shots,
            channels,
            columns,
            slots,
            geolocation: g.dataset("latitude").is_ok(),
        };
        out.check_fixed(g, path, &region)?;
        // the channels' names and numbers, and the calibration every reader divides by,
        // as a raw file's
        let prefix = format!("{region}/");
        let (names, _) = channel_labels(path, g, &prefix)?;
        let analog = vec![false; names.len()];
        check_calibration(path, g, &prefix, &names, &analog)?;
        out.check_truth(g, path, &region)?;
        Ok(out)
    }

    /// Refuses a region whose fixed truth variables (`range_weight`, `lidar_constant`,
    /// the truth per column, …) are missing, not floats, not (bin), (channel) or
    /// (column, channel, bin) of the region's lengths, or hold less than they declare (so
    /// that none is read at a size the file does not hold).
    fn check_fixed(&self, g: &Group, path: &Path, region: &str) -> Result<()> {
        use crate::output::product::RegionDims::{Bin, Channel, ColumnChannelBin};
        use crate::output::raw_file::read::{check_storage, is_float, shape_text};
        let bins = self.row_elems / self.channels.max(1);
        for v in fixed_variables(&[], |_| Ok(Vec::new()))? {
            let want = match v.dims {
                Bin => vec![bins],
                Channel => vec![self.channels],
                ColumnChannelBin => vec![self.columns, self.channels, bins],
                _ => vec![],
            };
            let name = format!("{region}/{}", v.name);
            let d = g.dataset(&v.name).map_err(|_| {
                Error::output(path, format!("no `{name}`: not a product of this version"))
            })?;
            let shape = d.shape();
            if v.dims == ColumnChannelBin
                && shape.len() == 3
                && shape[1..] == want[1..]
                && shape[0] != self.columns
            {
                return Err(Error::output(
                    path,
                    format!(
                        "`{name}` is {} (column, channel, bin): its {} columns disagree with \
                         the coordinate `{region}/column`, which has {}",
                        shape_text(&shape),
                        shape[0],
                        self.columns
                    ),
                ));
            }
            if shape != want || !is_float(&d) {
                return Err(Error::output(
                    path,
                    format!(
                        "`{name}` is {}, not {} floating-point numbers",
                        shape_text(&d.shape()),
                        shape_text(&want)
                    ),
                ));
            }
            check_storage(path, &name, &d)?;
        }
        Ok(())
    }

    /// Refuses a region whose truth is not the product's: a (profile, …) variable of
    /// another shape or not finite, `column` or `k` empty, or a profile whose
    /// `profile_column` and `profile_column_weight` are impossible (a column outside
    /// `column`, one given twice, the first slot unused, a weight outside [0, 1], a
    /// used slot of weight 0 or an unused one of weight ≠ 0, weights not summing to 1).
    fn check_truth(&self, g: &Group, path: &Path, region: &str) -> Result<()> {
        use crate::output::raw_file::integrity::check_column_rows;
        use crate::output::raw_file::read::{check_finite, check_storage, shape_text};
        let bad = |why: String| Error::output(path, format!("{region}: {why}"));
        if self.columns == 0 || self.slots == 0 || self.slots > self.columns {
            return Err(bad(format!(
                "`column` ({}) and `k` ({}) are not 1 ≤ k ≤ column",
                self.columns, self.slots
            )));
        }
        let get = |name: &str| {
            g.dataset(name)
                .map_err(|_| bad(format!("no `{name}`: not a product of this version")))
        };
        let vars = per_profile_variables(self.geolocation);
        let names = vars
            .iter()
            .map(|v| v.name.as_str())
            .chain(["profile_column"]);
        for name in names {
            let d = get(name)?;
            let width = match vars.iter().find(|v| v.name == name) {
                Some(v) => self.truth_width(v.dims),
                None => self.slots,
            };
            let want = match d.ndim() {
                1 => vec![self.rows],
                _ => vec![self.rows, width],
            };
            if d.shape() != want || (width != 1 && d.ndim() == 1) {
                let want = match d.ndim() {
                    1 if width == 1 => vec![self.rows],
                    _ => vec![self.rows, width],
                };
                return Err(bad(format!(
                    "`{name}` is {}, not {} (profile, …)",
                    shape_text(&d.shape()),
                    shape_text(&want)
                )));
            }
            check_storage(path, &format!("{region}/{name}"), &d)?;
            match d.ndim() {
                1 => check_finite(path, &format!("{region}/{name}"), &d)?,
                _ if name != "profile_column" => self.check_finite_rows(&d, &bad, name)?,
                _ => {}
            }
        }
        let (columns, weights) = (get("profile_column")?, get("profile_column_weight")?);
        let prefix = format!("{region}/");
        check_column_rows(path, &prefix, &columns, &weights, self.columns)?;
        Ok(())
    }

    /// Refuses a (profile, n) variable with a value that is not finite.
    fn check_finite_rows(
        &self,
        d: &Dataset,
        bad: &dyn Fn(String) -> Error,
        name: &str,
    ) -> Result<()> {
        for start in (0..self.rows).step_by(CHECK_ROWS) {
            let end = (start + CHECK_ROWS).min(self.rows);
            let v = d
                .read_slice::<f64, _, ndarray::Ix2>(s![start..end, ..])
                .map_err(|e| bad(format!("cannot read `{name}`: {e}")))?;
            if let Some(i) = v.iter().position(|x| !x.is_finite()) {
                let row = start + i / v.ncols().max(1);
                return Err(bad(format!("`{name}` of profile row {row} is not finite")));
            }
        }
        Ok(())
    }

    /// Values of a row of a per-profile variable of `dims`.
    fn truth_width(&self, dims: crate::output::product::RegionDims) -> usize {
        use crate::output::product::RegionDims::{ProfileChannel, ProfileK};
        match dims {
            ProfileChannel => self.channels,
            ProfileK => self.slots,
            _ => 1,
        }
    }
}

/// Rows of a (profile, n) variable checked at once.
const CHECK_ROWS: usize = 65_536;
