//! The onboard product (`lidarsim onboard`, docs/file-format.md): one HDF5 group per altitude
//! region of the scheme (`region_0` … from the top), each with its own `profile`,
//! `channel` (the numbers of the channels the region holds, named by `channel_name`: all
//! of them but where a channel has a layout of its own, as CALIOP's 1064 nm) and `bin`
//! dimension scales, `altitude`, `time`, `n_shots` and
//! `counts (profile, channel, bin)` (integer sums, u32), and the region's attributes
//! `altitude_min_km`, `altitude_max_km`, `vertical_resolution_m`, `shots_averaged`,
//! `native_bins_merged`, and the truth averaged as the counts (`onboard::truth`).
//! Readable as netCDF-4 (groups with dimensions of their own).
//!
//! The bytes depend on the content only (as the raw file's, `raw_file::layout`): no
//! modification times, and `counts` written a whole chunk at a time by HDF5's direct
//! chunk write, in the order the rows complete their chunks, so that the merge of a
//! run's shards (`onboard::merge`), sending the rows in the whole run's order,
//! writes the whole run's file byte for byte.

use std::ops::Range;
use std::path::Path;

use hdf5::types::VarLenUnicode;
use hdf5::{Dataset, File, Group};

use super::raw_file::chunk::{self, Filling};
use super::raw_file::layout::{create_file, create_group, create_var, write_index};
use super::raw_file::{AttrValue, CHANNEL_NAME, check::Row, hdf5_ds};
use crate::error::describe_hdf5_error;
use crate::error::{Error, Result};

/// Elements of one chunk of a region's `counts` (16 KiB of u32).
const CHUNK_ELEMS: usize = 4096;
/// Rows of `time` written per call at creation (bounds memory).
const TIME_BLOCK: usize = 64 * 1024;

/// What the product's root holds besides its regions.
#[derive(Debug, Clone, PartialEq)]
pub struct ProductHeader {
    /// Every channel's name (a region holds those of [`RegionSpec::channels`]).
    pub channels: Vec<String>,
    /// CF units of `time`.
    pub time_units: String,
    /// Root attributes, in this order.
    pub attributes: Vec<(String, AttrValue)>,
}

/// What one region of the product holds, known up front.
#[derive(Debug, Clone, PartialEq)]
pub struct RegionSpec {
    /// Index in the run of the file's first profile of the region (0 but in a shard).
    pub first_profile: usize,
    /// Downlinked profiles in the file.
    pub profiles: usize,
    /// The names of the channels it holds (its `channel_name` coordinate).
    pub channels: Vec<String>,
    /// Their numbers among the run's channels (its `channel` coordinate, as a raw file
    /// numbers them: 0, 1, …), strictly increasing.
    pub channel_numbers: Vec<i64>,
    /// Bin-centre altitude of each downlinked bin, m.
    pub altitude_m: Vec<f64>,
    /// Shots summed per profile.
    pub shots: u32,
    /// Native bins summed per bin (`native_bins_merged`).
    pub merge: u32,
    /// `altitude_min_km`, `altitude_max_km`, `vertical_resolution_m`.
    pub bounds: (f64, f64, f64),
    /// Its truth and per-profile variables.
    pub truth: RegionTruth,
}

/// The dimensions of a region's truth and per-profile variables.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RegionDims {
    /// (bin): `range_weight`.
    Bin,
    /// (channel): `lidar_constant`, `nominal_pulse_energy`.
    Channel,
    /// (column, channel, bin), column-major then channel-major: the truth per column.
    ColumnChannelBin,
    /// (profile): `pulse_energy`, geolocation.
    Profile,
    /// (profile, channel): `expected_background`, `expected_dark`.
    ProfileChannel,
    /// (profile, k): `profile_column_weight`.
    ProfileK,
}

/// A variable of a region besides its coordinates and `counts`: its attributes in order
/// (`long_name`, `units`, then any other) and, for a fixed variable, its values (a
/// per-profile variable's rows come with each profile, [`ProfileRow::values`]).
#[derive(Debug, Clone, PartialEq)]
pub struct RegionVar {
    /// Name in the region's group.
    pub name: String,
    /// Its dimensions.
    pub dims: RegionDims,
    /// Attributes, in order.
    pub attributes: Vec<(String, AttrValue)>,
    /// Values of a fixed variable (empty for a per-profile one).
    pub data: Vec<f64>,
}

/// What a region holds beside its counts: the truth of each of the scene's columns at
/// the region's resolution, and the names of its per-profile variables.
#[derive(Debug, Clone, PartialEq)]
pub struct RegionTruth {
    /// The scene's distinct columns (the `column` dimension; 1 in a static scene).
    pub columns: usize,
    /// The most columns one profile of the region can see (the `k` dimension).
    pub slots: usize,
    /// The (bin), (channel) and (column, channel, bin) variables, with their values.
    pub fixed: Vec<RegionVar>,
    /// The (profile, …) f64 variables, in the order of [`ProfileRow::values`];
    /// `profile_column` (int32) comes after them.
    pub per_profile: Vec<RegionVar>,
    /// The `coordinates` attribute of (profile, …) data variables: `time`, then the
    /// geolocation where the run has an orbit.
    pub profile_coordinates: String,
}

impl RegionTruth {
    /// Values of one profile's row of `var` (1, channels or slots).
    pub fn width(&self, dims: RegionDims, channels: usize) -> usize {
        match dims {
            RegionDims::ProfileChannel => channels,
            RegionDims::ProfileK => self.slots,
            _ => 1,
        }
    }
}

/// One downlinked profile of a region: its counts (channel-major sums), the row of each
/// of the region's per-profile variables (concatenated in their order) and the columns
/// its shots saw (`profile_column`, `k` slots).
#[derive(Debug, Clone, Copy)]
pub struct ProfileRow<'a> {
    /// The channel-major sums.
    pub counts: &'a [u64],
    /// [`RegionTruth::per_profile`]'s rows, concatenated.
    pub values: &'a [f64],
    /// `profile_column`'s row.
    pub columns: &'a [i32],
}

/// Rows of the per-profile variables written per call (bounds memory).
const PROFILE_BLOCK: usize = 4096;

/// The times of a region's profiles: `(region, rows)` gives the profile-centre times (s
/// since the start) of rows `rows` of the file's region.
pub type Times<'a> = dyn FnMut(usize, Range<usize>) -> Result<Vec<f64>> + 'a;

/// One region's `counts` being filled, chunk by chunk, and its per-profile variables a
/// block of rows at a time.
struct RegionCounts {
    ds: Dataset,
    channels: usize,
    filling: Filling,
    written: usize,
    profiles: usize,
    /// The per-profile f64 variables and the values of a row of each.
    values: Vec<(Dataset, usize)>,
    /// `profile_column` and its slots.
    columns: (Dataset, usize),
    /// Rows not written yet, from row `pending_first`.
    pending_values: Vec<f64>,
    pending_columns: Vec<i32>,
    pending_first: usize,
}

impl RegionCounts {
    /// Writes the pending rows of the per-profile variables.
    fn flush(&mut self) -> hdf5::Result<()> {
        let width: usize = self.values.iter().map(|v| v.1).sum();
        let rows = self.pending_columns.len() / self.columns.1.max(1);
        if rows == 0 {
            return Ok(());
        }
        let at = self.pending_first..self.pending_first + rows;
        let mut offset = 0;
        for (ds, w) in &self.values {
            let part: Vec<f64> = (0..rows)
                .flat_map(|i| {
                    let start = i * width + offset;
                    self.pending_values[start..start + w].iter().copied()
                })
                .collect();
            write_rows(ds, &part, at.clone(), *w)?;
            offset += w;
        }
        write_rows(&self.columns.0, &self.pending_columns, at, self.columns.1)?;
        self.pending_first += rows;
        self.pending_values.clear();
        self.pending_columns.clear();
        Ok(())
    }
}

/// Writes `data` into rows `rows` of a (profile) dataset, or of a (profile, w) one.
fn write_rows<T: hdf5::H5Type>(
    ds: &Dataset,
    data: &[T],
    rows: Range<usize>,
    w: usize,
) -> hdf5::Result<()> {
    match ds.ndim() {
        1 => ds.write_slice(data, rows),
        _ => {
            let view = ndarray::ArrayView2::from_shape((rows.len(), w), data)
                .map_err(|e| hdf5::Error::from(e.to_string().as_str()))?;
            ds.write_slice(view, (rows, ..))
        }
    }
}

/// A product being written.
pub struct ProductWriter {
    file: File,
    regions: Vec<RegionCounts>,
    spare: Vec<Vec<u8>>,
    display: std::path::PathBuf,
}

impl ProductWriter {
    /// Creates the product at exactly `path` (a temporary name from `safe_file`), with
    /// every region's coordinates (`times` gives the times, in blocks).
    pub fn create(
        path: &Path,
        display: &Path,
        header: &ProductHeader,
        regions: &[RegionSpec],
        times: &mut Times,
    ) -> Result<Self> {
        let fail = |e: hdf5::Error| {
            Error::output(
                display,
                format!("cannot write: {}", describe_hdf5_error(&e.to_string())),
            )
        };
        let file = create_file(path).map_err(fail)?;
        for (k, v) in &header.attributes {
            hdf5_ds::write_attr(&file, k, v).map_err(fail)?;
        }
        let mut out = Vec::with_capacity(regions.len());
        for (k, r) in regions.iter().enumerate() {
            let g = create_group(&file, &format!("region_{k}")).map_err(fail)?;
            let (ds, time, (values, columns)) = region_layout(&g, r, header).map_err(fail)?;
            for start in (0..r.profiles).step_by(TIME_BLOCK) {
                let rows = start..(start + TIME_BLOCK).min(r.profiles);
                let values = times(k, rows.clone())?;
                time.write_slice(&values[..], rows).map_err(fail)?;
            }
            let row_elems = r.channels.len() * r.altitude_m.len();
            let chunk_rows = ds.chunk().map_or(1, |c| c[0]);
            out.push(RegionCounts {
                ds,
                channels: r.channels.len(),
                filling: Filling::new(4, chunk_rows, row_elems, r.profiles),
                written: 0,
                profiles: r.profiles,
                values,
                columns: (columns, r.truth.slots),
                pending_values: Vec::new(),
                pending_columns: Vec::new(),
                pending_first: 0,
            });
        }
        Ok(ProductWriter {
            file,
            regions: out,
            spare: Vec::new(),
            display: display.to_path_buf(),
        })
    }

    /// Writes the next profile of region `k` (channel-major sums, saturated at u32's
    /// largest value, and its per-profile rows); profiles beyond the region's size are
    /// not written (a trailing partial sum never is). A chunk is stored when its last
    /// row arrives; the per-profile rows every [`PROFILE_BLOCK`] rows and at the end.
    pub fn write(&mut self, k: usize, row: ProfileRow) -> Result<()> {
        let display = &self.display;
        let r = &mut self.regions[k];
        let sums = row.counts;
        let at = r.written;
        if at >= r.profiles {
            return Ok(());
        }
        r.pending_values.extend_from_slice(row.values);
        r.pending_columns.extend_from_slice(row.columns);
        if at + 1 - r.pending_first == PROFILE_BLOCK {
            r.flush()
                .map_err(|e| Error::output(display, describe_hdf5_error(&e.to_string())))?;
        }
        let row = at;
        debug_assert_eq!(sums.len() % r.channels.max(1), 0);
        let clamped: Vec<u64> = sums.iter().map(|&c| c.min(u64::from(u32::MAX))).collect();
        let done = r
            .filling
            .put(row, Row::Counts(&clamped), &mut self.spare)
            .map_err(|e| Error::output(display, e))?;
        r.written += 1;
        if let Some((c, data)) = done {
            let bytes = chunk::deflate(&data).map_err(|e| Error::output(display, e))?;
            let first = (c * r.filling.chunk_rows()) as u64;
            hdf5_ds::write_chunk(&r.ds, &[first, 0, 0], &bytes)
                .map_err(|e| Error::output(display, describe_hdf5_error(&e.to_string())))?;
            self.spare.push(data);
            self.spare.truncate(1);
        }
        Ok(())
    }

    /// Closes the file.
    pub fn finish(self) -> Result<()> {
        let ProductWriter {
            file,
            mut regions,
            display,
            ..
        } = self;
        for r in &mut regions {
            r.flush()
                .map_err(|e| Error::output(&display, describe_hdf5_error(&e.to_string())))?;
        }
        drop(regions);
        file.close()
            .map_err(|e| Error::output(display, describe_hdf5_error(&e.to_string())))
    }
}

/// A region's dimension scales `profile` (the run's indices), `channel` and `bin`.
fn dimension_scales(g: &Group, r: &RegionSpec, channels: &[String]) -> hdf5::Result<[Dataset; 3]> {
    let text = |ds: &Dataset, k: &str, v: &str| hdf5_ds::write_str_attr(ds, k, v);
    let profile = create_var::<i64>(g, "profile", &[r.profiles])?;
    write_index(&profile, r.first_profile, r.profiles)?;
    text(
        &profile,
        "long_name",
        "index of the region's downlinked profile in the run",
    )?;
    text(&profile, "units", "1")?;
    hdf5_ds::set_scale(&profile, "profile")?;
    let channel = create_var::<i64>(g, "channel", &[channels.len()])?;
    channel.write_raw(&r.channel_numbers)?;
    text(
        &channel,
        "long_name",
        "receiver channel number (as the raw file numbers it)",
    )?;
    text(&channel, "units", "1")?;
    hdf5_ds::set_scale(&channel, "channel")?;
    let bin = create_var::<i64>(g, "bin", &[r.altitude_m.len()])?;
    write_index(&bin, 0, r.altitude_m.len())?;
    text(
        &bin,
        "long_name",
        "downlinked range bin index, from the top",
    )?;
    text(&bin, "units", "1")?;
    hdf5_ds::set_scale(&bin, "bin")?;
    let name = create_var::<VarLenUnicode>(g, CHANNEL_NAME, &[channels.len()])?;
    let names: Vec<VarLenUnicode> = channels
        .iter()
        .map(|c| c.parse().unwrap_or_default())
        .collect();
    name.write_raw(&names)?;
    text(&name, "long_name", "receiver channel name")?;
    hdf5_ds::attach_scales(&name, &[&channel])?;
    Ok([profile, channel, bin])
}

/// A variable of a region's truth, chunked along its first dimension and deflated after
/// shuffle (as `counts`, through HDF5's filters): a (profile, …) variable in chunks of
/// [`PROFILE_BLOCK`] rows, which the writer fills whole but the last, a (column, …) one a
/// column a chunk, with no chunk cache. Its bytes depend on the values and the order of
/// the writes only.
fn compressed_var<T: hdf5::H5Type>(
    g: &Group,
    name: &str,
    shape: &[usize],
) -> hdf5::Result<Dataset> {
    if shape.len() < 2 && shape.first().is_none_or(|&n| n <= 64) {
        return create_var::<T>(g, name, shape);
    }
    let mut chunk = shape.to_vec();
    chunk[0] = match shape.len() {
        3 => 1,
        _ => PROFILE_BLOCK.min(shape[0]),
    }
    .max(1);
    chunk.iter_mut().for_each(|c| *c = (*c).max(1));
    // no chunk cache: a block of rows goes to the file when written, so that memory does
    // not grow with the regions (a 1 MiB cache per variable otherwise)
    g.new_dataset::<T>()
        .chunk_cache(0, 0, 1.0)
        .shape(shape)
        .chunk(chunk)
        .shuffle()
        .deflate(chunk::DEFLATE_LEVEL)
        .obj_track_times(false)
        .attr_creation_order(hdf5::plist::dataset_create::AttrCreationOrder::Indexed)
        .create(name)
}

/// A region's per-profile datasets (the f64 ones with their widths, and `profile_column`).
type ProfileDatasets = (Vec<(Dataset, usize)>, Dataset);

/// A region's truth: the `column` and `k` dimension scales, the fixed variables with
/// their values, and the empty per-profile variables and `profile_column`.
fn truth_layout(
    g: &Group,
    r: &RegionSpec,
    [profile, channel, bin]: [&Dataset; 3],
) -> hdf5::Result<ProfileDatasets> {
    let t = &r.truth;
    let index = |name: &str, n: usize, long_name: &str| -> hdf5::Result<Dataset> {
        let ds = create_var::<i64>(g, name, &[n])?;
        write_index(&ds, 0, n)?;
        hdf5_ds::write_str_attr(&ds, "long_name", long_name)?;
        hdf5_ds::write_str_attr(&ds, "units", "1")?;
        hdf5_ds::set_scale(&ds, name)?;
        Ok(ds)
    };
    let column = index("column", t.columns, "distinct column of the scene")?;
    let k = index("k", t.slots, "slot of a column seen by the profile's shots")?;
    let channels = r.channels.len();
    let shape = |dims: RegionDims, rows: usize| -> (Vec<usize>, Vec<&Dataset>) {
        let bins = r.altitude_m.len();
        match dims {
            RegionDims::Bin => (vec![bins], vec![bin]),
            RegionDims::Channel => (vec![channels], vec![channel]),
            RegionDims::ColumnChannelBin => {
                (vec![t.columns, channels, bins], vec![&column, channel, bin])
            }
            RegionDims::Profile => (vec![rows], vec![profile]),
            RegionDims::ProfileChannel => (vec![rows, channels], vec![profile, channel]),
            RegionDims::ProfileK => (vec![rows, t.slots], vec![profile, &k]),
        }
    };
    for v in &t.fixed {
        let (dims, scales) = shape(v.dims, r.profiles);
        let ds = compressed_var::<f64>(g, &v.name, &dims)?;
        ds.write_raw(&v.data)?;
        for (name, value) in &v.attributes {
            hdf5_ds::write_attr(&ds, name, value)?;
        }
        let coordinates = match v.dims {
            RegionDims::Bin => "altitude",
            RegionDims::Channel => CHANNEL_NAME,
            RegionDims::ColumnChannelBin => "altitude channel_name",
            _ => "",
        };
        if !coordinates.is_empty() {
            hdf5_ds::write_str_attr(&ds, "coordinates", coordinates)?;
        }
        hdf5_ds::attach_scales(&ds, &scales)?;
    }
    let mut values = Vec::with_capacity(t.per_profile.len());
    let coordinate = |name: &str| t.profile_coordinates.split(' ').any(|c| c == name);
    for v in &t.per_profile {
        let (dims, scales) = shape(v.dims, r.profiles);
        let ds = compressed_var::<f64>(g, &v.name, &dims)?;
        for (name, value) in &v.attributes {
            hdf5_ds::write_attr(&ds, name, value)?;
        }
        if !coordinate(&v.name) {
            let label = match v.dims {
                RegionDims::ProfileChannel => " channel_name",
                _ => "",
            };
            let coordinates = format!("{}{label}", t.profile_coordinates);
            hdf5_ds::write_str_attr(&ds, "coordinates", &coordinates)?;
        }
        hdf5_ds::attach_scales(&ds, &scales)?;
        values.push((ds, t.width(v.dims, channels)));
    }
    let columns = compressed_var::<i32>(g, "profile_column", &[r.profiles, t.slots])?;
    hdf5_ds::write_str_attr(
        &columns,
        "long_name",
        "columns the profile's shots saw (indices of column, in the order first seen; -1 = unused slot)",
    )?;
    hdf5_ds::write_str_attr(&columns, "units", "1")?;
    hdf5_ds::write_str_attr(&columns, "coordinates", &t.profile_coordinates)?;
    hdf5_ds::attach_scales(&columns, &[profile, &k])?;
    Ok((values, columns))
}

/// One region's group: its dimension scales, coordinates but `time`'s values,
/// attributes, its empty `counts` and its truth ([`truth_layout`]); returns `counts`,
/// `time` and the per-profile datasets.
fn region_layout(
    g: &Group,
    r: &RegionSpec,
    header: &ProductHeader,
) -> hdf5::Result<(Dataset, Dataset, ProfileDatasets)> {
    let text = |ds: &Dataset, k: &str, v: &str| hdf5_ds::write_str_attr(ds, k, v);
    let [profile, channel, bin] = dimension_scales(g, r, &r.channels)?;
    let bins = r.altitude_m.len();
    let altitude = create_var::<f64>(g, "altitude", &[bins])?;
    altitude.write_raw(&r.altitude_m)?;
    text(
        &altitude,
        "long_name",
        "bin-centre altitude above sea level",
    )?;
    text(&altitude, "units", "m")?;
    text(&altitude, "standard_name", "altitude")?;
    text(&altitude, "positive", "up")?;
    hdf5_ds::attach_scales(&altitude, &[&bin])?;
    let time = create_var::<f64>(g, "time", &[r.profiles])?;
    text(&time, "long_name", "profile centre time")?;
    text(&time, "units", &header.time_units)?;
    text(&time, "standard_name", "time")?;
    text(&time, "calendar", "standard")?;
    text(&time, "axis", "T")?;
    hdf5_ds::attach_scales(&time, &[&profile])?;
    let n_shots = create_var::<u32>(g, "n_shots", &[r.profiles])?;
    for start in (0..r.profiles).step_by(TIME_BLOCK) {
        let end = (start + TIME_BLOCK).min(r.profiles);
        n_shots.write_slice(&vec![r.shots; end - start][..], start..end)?;
    }
    text(
        &n_shots,
        "long_name",
        "native laser shots summed in the profile",
    )?;
    text(&n_shots, "units", "1")?;
    text(&n_shots, "coordinates", &r.truth.profile_coordinates)?;
    hdf5_ds::attach_scales(&n_shots, &[&profile])?;
    let c = r.channels.len();
    let counts = g
        .new_dataset::<u32>()
        .shape((r.profiles, c, bins))
        .chunk((
            (CHUNK_ELEMS / (c * bins).max(1)).clamp(1, r.profiles.max(1)),
            c,
            bins,
        ))
        .shuffle()
        .deflate(chunk::DEFLATE_LEVEL)
        .obj_track_times(false)
        .attr_creation_order(hdf5::plist::dataset_create::AttrCreationOrder::Indexed)
        .create("counts")?;
    text(
        &counts,
        "long_name",
        "photon counts summed over the region's shots and native bins (onboard averaging)",
    )?;
    text(&counts, "units", "count")?;
    let coordinates = format!("{} altitude {CHANNEL_NAME}", r.truth.profile_coordinates);
    text(&counts, "coordinates", &coordinates)?;
    hdf5_ds::attach_scales(&counts, &[&profile, &channel, &bin])?;
    let (values, columns) = truth_layout(g, r, [&profile, &channel, &bin])?;
    hdf5_ds::write_num_attr(g, "altitude_min_km", &r.bounds.0)?;
    hdf5_ds::write_num_attr(g, "altitude_max_km", &r.bounds.1)?;
    hdf5_ds::write_num_attr(g, "vertical_resolution_m", &r.bounds.2)?;
    hdf5_ds::write_num_attr(g, "shots_averaged", &r.shots)?;
    hdf5_ds::write_num_attr(g, "native_bins_merged", &r.merge)?;
    Ok((counts, time, (values, columns)))
}
