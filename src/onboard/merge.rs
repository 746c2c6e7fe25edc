//! `lidarsim merge OUT.h5 SHARD.h5 ...` of product shards (`onboard --shard K/N`): the
//! product the whole run writes, byte for byte (docs/scale.md).
//!
//! 1. Each shard's root attributes say which run it belongs to and which shots it holds
//!    ([`crate::shard::SHARD_ATTRIBUTES`] and [`super::shard::FRAME_ATTRIBUTE`]); shards
//!    of different runs, a gap, an overlap, a file given twice or regions other than the
//!    run's are refused, naming the file.
//! 2. The whole product's root and regions are those of the shards (the same attributes,
//!    coordinates and bounds; the profiles of all of them, their times read in order).
//! 3. Each region's rows are streamed from the shards a block at a time and sent to the
//!    [`ProductWriter`] in the whole run's order (the row that completes first, at shot
//!    `(j + 1)·shots_averaged`, the upper region first at a tie), so that its chunks are
//!    stored in the same order: memory does not grow with the run.

use std::ops::Range;
use std::path::{Path, PathBuf};
use std::time::Instant;

use hdf5::{Dataset, Group};
use ndarray::{Ix1, Ix2, Ix3, s};

use super::identity::{METHOD, ProductIdentity, product_attributes, source};
use super::shard::{FRAME_ATTRIBUTE, profiles_within, shard_shots};
use super::shard_region::ShardRegion;
use super::truth::{fixed_variables, per_profile_variables, profile_coordinates};
use crate::error::describe_hdf5_error;
use crate::error::{Error, Result};
use crate::output::product::{ProductHeader, ProductWriter, RegionSpec};
use crate::output::product::{ProfileRow, RegionTruth};
use crate::output::raw_file::AttrValue;
use crate::safe_file::{OutputId, Outputs};
use crate::shard::{
    FileAttributes, MergeSummary, Piece, RunIdentity, Shard, ShardKind, check_pieces, open_shard,
    require_disk_for_merge,
};

/// Bytes of rows read from a shard at once, over every region.
pub const BLOCK_BYTES: usize = 8 << 20;

/// A product shard and what its root attributes say of it (the file is closed: it is
/// opened again while its rows are read, so that the shards done and to come hold no
/// memory).
struct ProductShard {
    path: PathBuf,
    shard: Shard,
    /// Shots of the run, its first, and of a frame.
    run_shots: u64,
    first_shot: u64,
    frame: u64,
    run_id: String,
    seed: u64,
    config: String,
    source: String,
    scheme: String,
    /// `history` without its date: the command line the run recorded.
    command: String,
    regions: Vec<ShardRegion>,
}

/// A failure reading `path`, in one line.
fn unreadable(path: &Path) -> impl Fn(hdf5::Error) -> Error + '_ {
    move |e| {
        Error::output(
            path,
            format!("cannot read: {}", describe_hdf5_error(&e.to_string())),
        )
    }
}

impl ProductShard {
    /// Opens `path` (a product shard, [`crate::shard::kind_of_shards`]) and reads its
    /// identity and regions.
    fn open(path: &Path) -> Result<ProductShard> {
        let (file, kind) = open_shard(path)?;
        if kind != ShardKind::Product {
            return Err(Error::output(
                path,
                "a raw shard (of `simulate --shard`), not a product shard",
            ));
        }
        let a = FileAttributes { file: &file, path };
        let (history, created) = (a.text("history")?, a.text("date_created")?);
        let command = history
            .strip_prefix(&format!("{created} "))
            .ok_or_else(|| {
                Error::output(path, "its `history` does not start with its `date_created`")
            })?
            .to_string();
        let mut regions = Vec::new();
        while let Ok(g) = file.group(&format!("region_{}", regions.len())) {
            regions.push(ShardRegion::of(&g, path)?);
        }
        Ok(ProductShard {
            shard: a.shard()?,
            run_shots: a.number("run_profiles")?,
            first_shot: a.number("shard_first_profile")?,
            frame: a.number(FRAME_ATTRIBUTE)?,
            run_id: a.text("run_id")?,
            seed: a.number("seed")?,
            config: a.text("config")?,
            source: a.text("source")?,
            scheme: a.text("scheme")?,
            command,
            regions,
            path: path.to_path_buf(),
        })
    }

    /// Dataset `name` of its region `k`.
    fn dataset(&self, k: usize, name: &str) -> Result<Dataset> {
        let mut mdc = hdf5::plist::file_access::MetadataCacheConfig::default();
        (mdc.max_size, mdc.initial_size) = (4 << 20, 1 << 20);
        hdf5::File::with_options()
            .with_fapl(|fapl| fapl.mdc_config(&mdc).chunk_cache(0, 0, 1.0))
            .open(&self.path)
            .and_then(|f| f.dataset(&format!("region_{k}/{name}")))
            .map_err(unreadable(&self.path))
    }

    /// The shots of its shard.
    fn shots(&self) -> Range<u64> {
        shard_shots(self.shard, self.run_shots, self.frame)
    }

    /// It as a piece of its run: the shots from its first to its shard's end (its
    /// regions' profiles are checked against them by [`check_regions`]).
    fn piece(&self) -> Piece<'_> {
        Piece {
            path: &self.path,
            identity: RunIdentity {
                config: self.config.clone(),
                seed: self.seed,
                method: METHOD.into(),
                shard_count: self.shard.count,
                total: self.run_shots as usize,
                run_id: self.run_id.clone(),
            },
            shard_index: self.shard.index,
            rows: self.first_shot as usize..self.shots().end as usize,
        }
    }
}

/// Checks region group `g` of the product at `path` as `merge` checks every region of
/// every shard (its counts, coordinates, calibration and truth; [`ShardRegion::of`]):
/// the one check of a product's integrity every reader applies (`quicklook`).
pub fn check_region(g: &Group, path: &Path) -> Result<()> {
    ShardRegion::of(g, path).map(|_| ())
}

/// Region `k` of the whole product, as the first shard (open as `file`) describes it,
/// with `profiles`.
fn region_spec(
    f: &ProductShard,
    file: &hdf5::File,
    k: usize,
    profiles: usize,
) -> Result<RegionSpec> {
    let g = file
        .group(&format!("region_{k}"))
        .map_err(unreadable(&f.path))?;
    let num = |name: &str| {
        g.attr(name)
            .and_then(|a| a.read_scalar::<f64>())
            .map_err(unreadable(&f.path))
    };
    let altitude = g.dataset("altitude").map_err(unreadable(&f.path))?;
    let (channels, numbers) = region_channels(&f.path, &g)?;
    let r = &f.regions[k];
    let fixed = fixed_variables(&beta_mol_attributes(&g, &f.path)?, |name| {
        g.dataset(name)
            .and_then(|d| d.read_raw::<f64>())
            .map_err(|_| Error::output(&f.path, format!("region_{k} has no readable `{name}`")))
    })?;
    Ok(RegionSpec {
        truth: RegionTruth {
            columns: r.columns,
            slots: r.slots,
            fixed,
            per_profile: per_profile_variables(r.geolocation),
            profile_coordinates: profile_coordinates(r.geolocation),
        },
        first_profile: 0,
        profiles,
        channels,
        channel_numbers: numbers,
        altitude_m: altitude.read_raw::<f64>().map_err(unreadable(&f.path))?,
        shots: f.regions[k].shots,
        merge: g
            .attr("native_bins_merged")
            .and_then(|a| a.read_scalar::<u32>())
            .map_err(unreadable(&f.path))?,
        bounds: (
            num("altitude_min_km")?,
            num("altitude_max_km")?,
            num("vertical_resolution_m")?,
        ),
    })
}

/// The names and numbers of region `g`'s channels (`channel_name`, `channel`); a
/// product of an earlier version, whose `channel` held the names, is refused.
fn region_channels(path: &Path, g: &Group) -> Result<(Vec<String>, Vec<i64>)> {
    let prefix = format!("{}/", g.name().trim_start_matches('/'));
    match crate::output::raw_file::integrity::channel_labels(path, g, &prefix)? {
        (names, Some(numbers)) => Ok((names, numbers)),
        _ => Err(Error::output(
            path,
            format!("`{prefix}channel` holds the names: a product of an earlier version"),
        )),
    }
}

/// The attributes of a region's `beta_mol` beyond its long name and units, as the run
/// wrote them (`line`, and `lidar_ratio_sr` when every channel agrees).
fn beta_mol_attributes(g: &Group, path: &Path) -> Result<Vec<(String, AttrValue)>> {
    let d = g.dataset("beta_mol").map_err(unreadable(path))?;
    let line = d
        .attr("line")
        .and_then(|a| a.read_scalar::<hdf5::types::VarLenUnicode>())
        .map_err(unreadable(path))?;
    let mut attrs = vec![("line".to_string(), AttrValue::Str(line.as_str().into()))];
    if let Ok(ratio) = d
        .attr("lidar_ratio_sr")
        .and_then(|a| a.read_scalar::<f64>())
    {
        attrs.push(("lidar_ratio_sr".into(), AttrValue::F64(ratio)));
    }
    Ok(attrs)
}

/// The whole product's root, as the first shard (open as `file`) describes it: the run's
/// command line in `history`, with the merge's date (`SOURCE_DATE_EPOCH` when set), as
/// the whole run records it.
fn header(f: &ProductShard, file: &hdf5::File) -> Result<ProductHeader> {
    let g = file.group("region_0").map_err(unreadable(&f.path))?;
    let (channels, _) = region_channels(&f.path, &g)?;
    let time_units = g
        .dataset("time")
        .and_then(|d| d.attr("units"))
        .and_then(|a| a.read_scalar::<hdf5::types::VarLenUnicode>())
        .map_err(unreadable(&f.path))?
        .as_str()
        .to_string();
    Ok(ProductHeader {
        channels,
        time_units,
        attributes: {
            let created = crate::output::raw_file::content::creation_time()?;
            let id = ProductIdentity {
                scheme: f.scheme.clone(),
                source: f.source.clone(),
                config: f.config.clone(),
                seed: f.seed,
            };
            product_attributes(&id, &format!("{created} {}", f.command), &created)
        },
    })
}

/// A merge of product shards checked and planned, ready to write.
pub struct ProductMerge {
    files: Vec<ProductShard>,
    header: ProductHeader,
    specs: Vec<RegionSpec>,
    out: PathBuf,
    start: Instant,
}

/// Refuses a shard whose regions are not the first one's or do not hold its shots'
/// profiles, or that another lidarsim wrote.
fn check_regions(first: &ProductShard, f: &ProductShard) -> Result<()> {
    let shape = |f: &ProductShard| -> Vec<(u32, usize, usize, usize, bool)> {
        let r = f.regions.iter();
        r.map(|r| (r.shots, r.row_elems, r.columns, r.slots, r.geolocation))
            .collect()
    };
    if shape(f) != shape(first) || f.regions.is_empty() {
        return Err(Error::output(
            &f.path,
            format!(
                "its regions (shots, channels × bins, columns, slots, geolocation) {:?} are not \
                 those of {} {:?}",
                shape(f),
                first.path.display(),
                shape(first)
            ),
        ));
    }
    let shots = f.shots();
    for (k, r) in f.regions.iter().enumerate() {
        let want = profiles_within(r.shots, &shots);
        if want.len() != r.rows {
            return Err(Error::output(
                &f.path,
                format!(
                    "region_{k} holds {} profiles, but its shots {}–{} make {}",
                    r.rows,
                    shots.start,
                    shots.end.saturating_sub(1),
                    want.len()
                ),
            ));
        }
    }
    if f.command != first.command {
        return Err(Error::output(
            &f.path,
            format!(
                "its `history` records `{}`, but {} records `{}`: shards of one run record \
                 one command line",
                f.command,
                first.path.display(),
                first.command
            ),
        ));
    }
    if f.source != source() {
        return Err(Error::output(
            &f.path,
            format!(
                "written by {}, not by this {}: merge with the lidarsim that wrote the shards",
                f.source,
                source()
            ),
        ));
    }
    Ok(())
}

/// The first half of `lidarsim merge OUT SHARD...` for product shards: checks that
/// `shards` are one run's, each once, and lays out the whole product (nothing written).
pub fn prepare(out: &Path, shards: &[PathBuf]) -> Result<ProductMerge> {
    let start = Instant::now();
    let files = shards
        .iter()
        .map(|p| ProductShard::open(p))
        .collect::<Result<Vec<_>>>()?;
    let first = files
        .first()
        .ok_or_else(|| Error::Unsupported("merge needs at least one shard".into()))?;
    let pieces: Vec<Piece> = files.iter().map(ProductShard::piece).collect();
    let rows = |s: Shard| {
        let r = shard_shots(s, first.run_shots, first.frame);
        r.start as usize..r.end as usize
    };
    let order = check_pieces(&pieces, "shard", "shots", rows)?;
    for f in &files {
        check_regions(first, f)?;
    }
    let mut files: Vec<Option<ProductShard>> = files.into_iter().map(Some).collect();
    let files: Vec<ProductShard> = order.iter().filter_map(|&i| files[i].take()).collect();
    let f = &files[0];
    let file = hdf5::File::open(&f.path).map_err(unreadable(&f.path))?;
    let whole = 0..f.run_shots;
    let specs = (0..f.regions.len())
        .map(|k| {
            let profiles = profiles_within(f.regions[k].shots, &whole).len();
            region_spec(f, &file, k, profiles)
        })
        .collect::<Result<_>>()?;
    let header = header(f, &file)?;
    drop(file);
    Ok(ProductMerge {
        header,
        files,
        specs,
        out: out.to_path_buf(),
        start,
    })
}

/// The rows of one region of the whole run (counts and per-profile variables), read
/// from the shards in order, a block of rows at a time.
struct RegionRows<'a> {
    files: &'a [ProductShard],
    k: usize,
    /// The per-profile f64 variables, each with its values per row.
    vars: Vec<(String, usize)>,
    /// The shard read and its next row.
    shard: usize,
    row: usize,
    /// Rows of the shard read, `block_start .. block_start + block_len`: counts, every
    /// per-profile variable, `profile_column`.
    counts: Vec<u64>,
    values: Vec<Vec<f64>>,
    columns: Vec<i32>,
    block_start: usize,
    block_len: usize,
    /// Rows read at once.
    block_rows: usize,
    /// The row's values, concatenated.
    scratch: Vec<f64>,
}

impl<'a> RegionRows<'a> {
    fn new(files: &'a [ProductShard], spec: &RegionSpec, k: usize, bytes: usize) -> Self {
        let r = &files[0].regions[k];
        let vars: Vec<(String, usize)> = spec
            .truth
            .per_profile
            .iter()
            .map(|v| (v.name.clone(), spec.truth.width(v.dims, r.channels)))
            .collect();
        let per_row = r.row_elems + vars.iter().map(|v| v.1).sum::<usize>() + r.slots;
        RegionRows {
            files,
            k,
            vars,
            shard: 0,
            row: 0,
            counts: Vec::new(),
            values: Vec::new(),
            columns: Vec::new(),
            block_start: 0,
            block_len: 0,
            block_rows: (bytes / (8 * per_row.max(1))).max(1),
            scratch: Vec::new(),
        }
    }

    /// Reads rows `rows` of the shard's region into the block.
    fn read_block(&mut self, rows: Range<usize>) -> Result<()> {
        let f = &self.files[self.shard];
        let (k, fail) = (self.k, unreadable(&f.path));
        let sel = s![rows.clone(), ..];
        let counts = f.dataset(k, "counts")?;
        self.counts = counts
            .read_slice::<u64, _, Ix3>(s![rows.clone(), .., ..])
            .map_err(&fail)?
            .into_raw_vec();
        self.values.clear();
        for (name, width) in &self.vars {
            let d = f.dataset(k, name)?;
            let v = match width {
                1 if d.ndim() == 1 => d
                    .read_slice::<f64, _, Ix1>(s![rows.clone()])
                    .map(|a| a.to_vec()),
                _ => d.read_slice::<f64, _, Ix2>(sel).map(|a| a.into_raw_vec()),
            };
            self.values.push(v.map_err(&fail)?);
        }
        self.columns = f
            .dataset(k, "profile_column")?
            .read_slice::<i32, _, Ix2>(sel)
            .map_err(&fail)?
            .into_raw_vec();
        (self.block_start, self.block_len) = (rows.start, rows.len());
        Ok(())
    }

    /// The next row of the region.
    fn next(&mut self) -> Result<ProfileRow<'_>> {
        while self.row >= self.files[self.shard].regions[self.k].rows {
            if self.shard + 1 == self.files.len() {
                return Err(Error::Unsupported(
                    "the shards hold fewer profiles than the run".into(),
                ));
            }
            (self.shard, self.row, self.block_start, self.block_len) = (self.shard + 1, 0, 0, 0);
        }
        let r = &self.files[self.shard].regions[self.k];
        let (elems, slots) = (r.row_elems, r.slots);
        if self.row >= self.block_start + self.block_len {
            let end = (self.row + self.block_rows).min(r.rows);
            self.read_block(self.row..end)?;
        }
        let i = self.row - self.block_start;
        self.row += 1;
        self.scratch.clear();
        for ((_, w), v) in self.vars.iter().zip(&self.values) {
            self.scratch.extend_from_slice(&v[i * w..(i + 1) * w]);
        }
        Ok(ProfileRow {
            counts: &self.counts[i * elems..(i + 1) * elems],
            values: &self.scratch,
            columns: &self.columns[i * slots..(i + 1) * slots],
        })
    }
}

/// Times of rows `rows` of region `k` of the whole run, read from the shards in order.
fn read_times(files: &[ProductShard], k: usize, rows: Range<usize>) -> Result<Vec<f64>> {
    let mut out = Vec::with_capacity(rows.len());
    let mut offset = 0;
    for f in files {
        let r = &f.regions[k];
        let (a, b) = (rows.start.max(offset), rows.end.min(offset + r.rows));
        if a < b {
            let part = f
                .dataset(k, "time")?
                .read_slice::<f64, _, Ix1>(s![a - offset..b - offset])
                .map_err(unreadable(&f.path))?;
            out.extend(part.iter());
        }
        offset += r.rows;
    }
    Ok(out)
}

impl ProductMerge {
    /// Writes the whole run's product as output `id` of `outputs` (complete or absent),
    /// streaming the shards' rows in the whole run's order.
    pub fn write(self, outputs: Outputs, id: OutputId) -> Result<MergeSummary> {
        require_disk_for_merge(&self.out, self.files.iter().map(|f| f.path.as_path()))?;
        let files = &self.files;
        let mut times = |k: usize, rows: Range<usize>| read_times(files, k, rows);
        let mut writer = ProductWriter::create(
            outputs.temp_path(id)?,
            &self.out,
            &self.header,
            &self.specs,
            &mut times,
        )?;
        let per_region = BLOCK_BYTES / self.specs.len().max(1);
        let mut readers: Vec<RegionRows> = (0..self.specs.len())
            .map(|k| RegionRows::new(files, &self.specs[k], k, per_region))
            .collect();
        let mut next = vec![0usize; self.specs.len()];
        // the row that completes first in the whole run (at shot (j + 1)·shots), the
        // upper region first at a tie: the order the whole run writes them in
        while let Some(k) = (0..self.specs.len())
            .filter(|&k| next[k] < self.specs[k].profiles)
            .min_by_key(|&k| ((next[k] as u128 + 1) * u128::from(self.specs[k].shots), k))
        {
            writer.write(k, readers[k].next()?)?;
            next[k] += 1;
        }
        writer.finish()?;
        outputs.commit()?;
        Ok(MergeSummary {
            output: self.out,
            shards: self.files.len(),
            profiles: self.files[0].run_shots as usize,
            what: "shots",
            file: "product",
            elapsed: self.start.elapsed(),
        })
    }
}
