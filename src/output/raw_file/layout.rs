//! Creating a raw file: dimensions, coordinates, variables and attributes, everything
//! known before the first profile (the module docs of [`super`] list the layout).
//!
//! Choices that make the file portable and reproducible:
//! * HDF5 1.8 file format (`libver_bounds(V18, V18)`): readable by every HDF5 since 1.8
//!   and so by any netCDF-4 build, with dense attribute storage for long attributes;
//! * no object modification times (`obj_track_times(false)` on the root group and every
//!   dataset), so the same content gives the same bytes;
//! * named dimensions through HDF5 dimension scales, so netCDF readers see `profile`,
//!   `channel` and `bin` rather than `phony_dim_*`;
//! * a `coordinates` attribute on every data variable, so xarray attaches `time`,
//!   `altitude` and `range` as coordinates.

use std::path::Path;

use hdf5::plist::dataset_create::AttrCreationOrder;
use hdf5::plist::file_access::LibraryVersion;
use hdf5::plist::file_create::LinkCreationOrder;
use hdf5::types::VarLenUnicode;
use hdf5::{Dataset, File, Group, H5Type};

use super::chunk;
use super::hdf5_ds::{attach_scales, set_scale, write_attr, write_str_attr};
use super::{
    BIN_DIM, CHANNEL_DIM, COLUMN_DIM, COMPONENT_NAMES, CountWidth, Dims, PROFILE_COLUMN_NAMES,
    PROFILE_DIM, RESERVED_NAMES, RawFileSpec, SLOT_DIM,
};

/// Target size of one chunk of a (profile, channel, bin) variable, in bytes, for that
/// variable's own element size (u16 counts get four times the rows of f64 truth). Within
/// HDF5's default 1 MiB per-dataset chunk cache, so a reader reading profile by profile
/// decompresses each chunk once; large enough that the byte planes of slowly varying f64
/// truth compress well (12× at 512 KiB against 10× at 256 KiB on the orbit's S/N).
pub const TARGET_CHUNK_BYTES: usize = 512 * 1024;
/// Rows of the `profile` coordinate written per call at creation (bounds memory).
const COORD_BLOCK: usize = 64 * 1024;
/// The auxiliary coordinates of (profile, channel, bin) and (bin) data variables.
const COORDS_PROFILE_BIN: &str = "time altitude range";
const COORDS_BIN: &str = "altitude range";

/// A (profile, channel, bin) variable, chunked along profiles, shuffled and deflated;
/// the writer fills and writes it a whole chunk at a time.
pub struct RowVar {
    /// Name in the file, for messages.
    pub name: String,
    pub ds: Dataset,
    /// Bytes per element (2, 4 or 8).
    pub elem_bytes: usize,
    /// Profiles per chunk (the chunk holds every channel and bin of them).
    pub chunk_rows: usize,
    /// Whether its rows are fresh random draws (the count variables), whose chunks are
    /// encoded plane by plane, noise planes stored (`planes.rs`); otherwise (a changing
    /// scene's truth, often the same from row to row) each chunk is deflated whole.
    pub by_planes: bool,
}

/// Open HDF5 handles of a file being written.
pub struct OpenFile {
    pub file: File,
    /// Every (profile, channel, bin) variable: `counts`, then `signal_counts`,
    /// `background_counts` and `dark_counts` if the spec has components, then the spec's
    /// (profile, channel, bin) variables in its order.
    pub rows: Vec<RowVar>,
    pub time: Dataset,
    pub n_shots: Dataset,
    pub pulse_energy: Dataset,
    /// The spec's (profile) variables, in its order.
    pub columns: Vec<Dataset>,
    /// `profile_column` and `profile_column_weight`, if the spec has column slots.
    pub profile_columns: Option<(Dataset, Dataset)>,
}

impl OpenFile {
    /// Closes every handle, the file last, reporting an error from the final flush.
    pub fn close(self) -> hdf5::Result<()> {
        let OpenFile {
            file,
            rows,
            time,
            n_shots,
            pulse_energy,
            columns,
            profile_columns,
        } = self;
        drop((rows, time, n_shots, pulse_energy, columns, profile_columns));
        file.close()
    }
}

/// Checks the spec's own consistency (a programming error, reported as a message).
pub fn validate_spec(spec: &RawFileSpec) -> Result<(), String> {
    if spec.n_bins == 0 || spec.n_profiles == 0 || spec.channels.is_empty() {
        return Err(format!(
            "a raw file needs at least one bin, channel and profile (got {} bins, {} channels, {} profiles)",
            spec.n_bins,
            spec.channels.len(),
            spec.n_profiles
        ));
    }
    let mut seen: Vec<&str> = Vec::new();
    for text in &spec.channel_text {
        if text.values.len() != spec.channels.len() {
            return Err(format!(
                "variable `{}` has {} values, the file has {} channels",
                text.name,
                text.values.len(),
                spec.channels.len()
            ));
        }
        if text.values.iter().any(|v| v.contains('\0')) {
            return Err(format!("variable `{}` holds a NUL", text.name));
        }
        seen.push(&text.name);
    }
    if spec.n_columns > i32::MAX as usize || (spec.column_slots > 0) != (spec.n_columns > 0) {
        return Err(format!(
            "{} columns with {} slots per profile: both or neither, at most 2^31 − 1 columns",
            spec.n_columns, spec.column_slots
        ));
    }
    for var in &spec.variables {
        if var.name.is_empty() || var.name.contains(['/', '\0']) {
            return Err(format!("invalid variable name {:?}", var.name));
        }
        if RESERVED_NAMES.contains(&var.name.as_str()) || seen.contains(&var.name.as_str()) {
            return Err(format!(
                "variable `{}` is reserved or given twice",
                var.name
            ));
        }
        seen.push(&var.name);
        let want = match var.dims {
            Dims::Bin => spec.n_bins,
            Dims::Channel => spec.channels.len(),
            Dims::ChannelBin => spec.counts_per_profile(),
            Dims::ColumnBin => spec.n_columns * spec.n_bins,
            Dims::ColumnChannelBin => spec.n_columns * spec.counts_per_profile(),
            Dims::Profile | Dims::ProfileChannelBin => 0,
        };
        if matches!(var.dims, Dims::ColumnBin | Dims::ColumnChannelBin) && spec.n_columns == 0 {
            return Err(format!("variable `{}` needs a column dimension", var.name));
        }
        if var.data.len() != want {
            return Err(format!(
                "variable `{}` has {} values, its dimensions hold {want}",
                var.name,
                var.data.len()
            ));
        }
    }
    let mut seen_attrs: Vec<&str> = Vec::new();
    for (name, _) in &spec.root_attributes {
        if name.is_empty() || seen_attrs.contains(&name.as_str()) {
            return Err(format!("root attribute {name:?} is empty or given twice"));
        }
        seen_attrs.push(name);
    }
    Ok(())
}

/// Profiles per chunk of a (profile, channel, bin) variable of `elem_bytes`-byte
/// elements: about [`TARGET_CHUNK_BYTES`], at least one profile, at most all of them.
pub fn chunk_rows(spec: &RawFileSpec, elem_bytes: usize) -> usize {
    let row_bytes = spec.counts_per_profile() * elem_bytes;
    (TARGET_CHUNK_BYTES / row_bytes.max(1)).clamp(1, spec.n_profiles)
}

/// Creates an empty (profile, channel, bin) count variable at the file's width, its
/// chunks encoded by planes.
fn create_count_var(file: &File, name: &str, spec: &RawFileSpec) -> hdf5::Result<RowVar> {
    let var = match spec.count_width {
        CountWidth::U16 => create_rows::<u16>(file, name, spec),
        CountWidth::U32 => create_rows::<u32>(file, name, spec),
        CountWidth::U64 => create_rows::<u64>(file, name, spec),
    }?;
    Ok(RowVar {
        by_planes: true,
        ..var
    })
}

/// Creates a (profile, channel, bin) variable of `T`, chunked along profiles with the
/// filters shuffle then deflate declared (the writer stores chunks it encoded itself
/// exactly as these filters would, `chunk.rs`, and readers decode them through them).
fn create_rows<T: H5Type>(file: &File, name: &str, spec: &RawFileSpec) -> hdf5::Result<RowVar> {
    let (c, b) = (spec.channels.len(), spec.n_bins);
    let elem_bytes = std::mem::size_of::<T>();
    let chunk_rows = chunk_rows(spec, elem_bytes);
    let ds = file
        .new_dataset::<T>()
        .shape((spec.n_profiles, c, b))
        .chunk((chunk_rows, c, b))
        .shuffle()
        .deflate(chunk::DEFLATE_LEVEL)
        .obj_track_times(false)
        .attr_creation_order(AttrCreationOrder::Indexed)
        .create(name)?;
    Ok(RowVar {
        name: name.to_string(),
        ds,
        elem_bytes,
        chunk_rows,
        by_planes: false,
    })
}

/// Creates an empty contiguous variable of the given shape (no modification time, its
/// attributes in creation order).
pub(crate) fn create_var<T: H5Type>(
    group: &Group,
    name: &str,
    shape: &[usize],
) -> hdf5::Result<Dataset> {
    group
        .new_dataset::<T>()
        .shape(shape)
        .obj_track_times(false)
        .attr_creation_order(AttrCreationOrder::Indexed)
        .create(name)
}

/// Writes `first..first + n` into a 1-D i64 variable, in blocks.
pub(crate) fn write_index(ds: &Dataset, first: usize, n: usize) -> hdf5::Result<()> {
    let mut block = Vec::with_capacity(n.min(COORD_BLOCK));
    for start in (0..n).step_by(COORD_BLOCK) {
        let end = (start + COORD_BLOCK).min(n);
        block.clear();
        block.extend((start..end).map(|i| (first + i) as i64));
        ds.write_slice(&block[..], start..end)?;
    }
    Ok(())
}

/// Writes text attributes on a variable.
fn write_attrs(ds: &Dataset, attrs: &[(&str, &str)]) -> hdf5::Result<()> {
    attrs.iter().try_for_each(|(k, v)| write_str_attr(ds, k, v))
}

/// A new HDF5 file at `path` (truncating it) with the choices of the module docs: the
/// 1.8 file format, links and attributes in creation order, no modification times.
pub(crate) fn create_file(path: &Path) -> hdf5::Result<File> {
    File::with_options()
        .with_fapl(|fapl| fapl.libver_bounds(LibraryVersion::V18, LibraryVersion::V18))
        .with_fcpl(|fcpl| {
            fcpl.link_creation_order(LinkCreationOrder::Indexed)
                .attr_creation_order(AttrCreationOrder::Indexed)
                .obj_track_times(false)
        })
        .create(path)
}

/// A new group of `parent` with the file's choices ([`create_file`]).
pub(crate) fn create_group(parent: &Group, name: &str) -> hdf5::Result<Group> {
    parent
        .create_group_builder()
        .with_gcpl(|gcpl| {
            gcpl.link_creation_order(LinkCreationOrder::Indexed)
                .attr_creation_order(AttrCreationOrder::Indexed)
                .obj_track_times(false)
        })
        .create(name)
}

/// Creates the whole layout in a new HDF5 file at `path` (truncating it).
pub fn create_layout(path: &Path, spec: &RawFileSpec) -> hdf5::Result<OpenFile> {
    let file = create_file(path)?;

    for (name, value) in &spec.root_attributes {
        write_attr(&file, name, value)?;
    }

    // the coordinates of (profile, …) variables: time, and latitude/longitude where given
    let extra: String = spec
        .profile_coordinates
        .iter()
        .map(|c| format!(" {c}"))
        .collect();
    let coords_profile_bin = format!("{COORDS_PROFILE_BIN}{extra}");
    let coords_profile = format!("time{extra}");
    let coords_profile_bin = coords_profile_bin.as_str();
    let coords_profile = coords_profile.as_str();

    // Dimensions: coordinate variables marked as dimension scales.
    let profile = create_var::<i64>(&file, PROFILE_DIM, &[spec.n_profiles])?;
    write_index(&profile, spec.first_profile, spec.n_profiles)?;
    write_attrs(&profile, &[("long_name", "profile index"), ("units", "1")])?;
    set_scale(&profile, PROFILE_DIM)?;

    let channel = create_var::<VarLenUnicode>(&file, CHANNEL_DIM, &[spec.channels.len()])?;
    let names: Vec<VarLenUnicode> = spec
        .channels
        .iter()
        .map(|c| {
            c.parse()
                .map_err(|_| hdf5::Error::from("channel name contains NUL"))
        })
        .collect::<hdf5::Result<_>>()?;
    channel.write(&names[..])?;
    write_attrs(&channel, &[("long_name", "receiver channel")])?;
    set_scale(&channel, CHANNEL_DIM)?;

    let bin = create_var::<i64>(&file, BIN_DIM, &[spec.n_bins])?;
    write_index(&bin, 0, spec.n_bins)?;
    write_attrs(&bin, &[("long_name", "range bin index"), ("units", "1")])?;
    set_scale(&bin, BIN_DIM)?;

    for text in &spec.channel_text {
        write_channel_text(&file, text, &channel)?;
    }
    let column = match spec.n_columns {
        0 => None,
        n => {
            let column = create_var::<i64>(&file, COLUMN_DIM, &[n])?;
            write_index(&column, 0, n)?;
            write_attrs(
                &column,
                &[
                    (
                        "long_name",
                        "distinct column of the scene (segment and cloud cells present)",
                    ),
                    ("units", "1"),
                ],
            )?;
            set_scale(&column, COLUMN_DIM)?;
            Some(column)
        }
    };
    let profile_columns = match spec.column_slots {
        0 => None,
        k => Some(create_profile_columns(
            &file,
            spec,
            k,
            &profile,
            coords_profile,
        )?),
    };

    let dims3 = [&profile, &channel, &bin];
    let counts = create_count_var(&file, "counts", spec)?;
    write_attrs(
        &counts.ds,
        &[
            (
                "long_name",
                "accumulated raw photon counts (signal + background + dark)",
            ),
            ("units", "count"),
            ("coordinates", coords_profile_bin),
        ],
    )?;
    attach_scales(&counts.ds, &dims3)?;
    let mut rows = vec![counts];

    if spec.components {
        let long_names = [
            "accumulated photon counts from the backscattered laser signal",
            "accumulated photon counts from the sky background",
            "accumulated detector dark counts",
        ];
        for (name, long_name) in COMPONENT_NAMES.iter().zip(long_names) {
            let var = create_count_var(&file, name, spec)?;
            write_attrs(
                &var.ds,
                &[
                    ("long_name", long_name),
                    ("units", "count"),
                    ("coordinates", coords_profile_bin),
                ],
            )?;
            attach_scales(&var.ds, &dims3)?;
            rows.push(var);
        }
    }

    let time = create_var::<f64>(&file, "time", &[spec.n_profiles])?;
    write_attrs(
        &time,
        &[
            ("long_name", "profile centre time"),
            ("standard_name", "time"),
            ("units", &spec.time_units),
            ("calendar", "standard"),
            ("axis", "T"),
        ],
    )?;
    attach_scales(&time, &[&profile])?;

    let n_shots = create_var::<u64>(&file, "n_shots", &[spec.n_profiles])?;
    write_attrs(
        &n_shots,
        &[
            ("long_name", "laser shots accumulated in the profile"),
            ("units", "1"),
            ("coordinates", coords_profile),
        ],
    )?;
    attach_scales(&n_shots, &[&profile])?;

    let pulse_energy = create_var::<f64>(&file, "pulse_energy", &[spec.n_profiles])?;
    write_attrs(
        &pulse_energy,
        &[
            (
                "long_name",
                "mean emitted pulse energy of the profile's shots (energy monitor)",
            ),
            ("units", "J"),
            ("coordinates", coords_profile),
        ],
    )?;
    attach_scales(&pulse_energy, &[&profile])?;

    let mut columns = Vec::new();
    for var in &spec.variables {
        let (c, b, n) = (spec.channels.len(), spec.n_bins, spec.n_columns);
        let (shape, scales, coords): (Vec<usize>, Vec<&Dataset>, Option<&str>) = match var.dims {
            Dims::ColumnBin | Dims::ColumnChannelBin => {
                let col = column.as_ref().ok_or("a column variable without columns")?;
                match var.dims {
                    Dims::ColumnBin => (vec![n, b], vec![col, &bin], Some(COORDS_BIN)),
                    _ => (vec![n, c, b], vec![col, &channel, &bin], Some(COORDS_BIN)),
                }
            }
            Dims::Bin => (vec![spec.n_bins], vec![&bin], Some(COORDS_BIN)),
            Dims::Channel => (vec![spec.channels.len()], vec![&channel], None),
            Dims::ChannelBin => (
                vec![spec.channels.len(), spec.n_bins],
                vec![&channel, &bin],
                Some(COORDS_BIN),
            ),
            Dims::Profile => (vec![spec.n_profiles], vec![&profile], Some(coords_profile)),
            Dims::ProfileChannelBin => (
                vec![spec.n_profiles, spec.channels.len(), spec.n_bins],
                vec![&profile, &channel, &bin],
                Some(coords_profile_bin),
            ),
        };
        let (ds, row_var) = match var.dims {
            Dims::ProfileChannelBin => {
                let v = create_rows::<f64>(&file, &var.name, spec)?;
                (v.ds.clone(), Some(v))
            }
            Dims::ColumnBin | Dims::ColumnChannelBin => {
                (create_deflated(&file, &var.name, &shape)?, None)
            }
            _ => (create_var::<f64>(&file, &var.name, &shape)?, None),
        };
        if !var.dims.per_profile() {
            ds.write_raw(&var.data[..])?;
        }
        write_attrs(&ds, &[("long_name", &var.long_name), ("units", &var.units)])?;
        for (k, v) in &var.attributes {
            write_attr(&ds, k, v)?;
        }
        // a coordinate itself (altitude, range, latitude, ...) lists no coordinates
        let is_coordinate = matches!(var.name.as_str(), "altitude" | "range")
            || spec.profile_coordinates.contains(&var.name);
        if let Some(c) = coords.filter(|_| !is_coordinate) {
            write_str_attr(&ds, "coordinates", c)?;
        }
        attach_scales(&ds, &scales)?;
        match (row_var, var.dims) {
            (Some(v), _) => rows.push(v),
            (None, Dims::Profile) => columns.push(ds),
            _ => {}
        }
    }

    Ok(OpenFile {
        file,
        rows,
        time,
        n_shots,
        pulse_energy,
        columns,
        profile_columns,
    })
}

/// A string variable of the channel dimension.
fn write_channel_text(
    file: &File,
    text: &super::TextVariable,
    channel: &Dataset,
) -> hdf5::Result<()> {
    let ds = create_var::<VarLenUnicode>(file, &text.name, &[text.values.len()])?;
    let values: Vec<VarLenUnicode> = text
        .values
        .iter()
        .map(|v| {
            v.parse()
                .map_err(|_| hdf5::Error::from("a text value holds NUL"))
        })
        .collect::<hdf5::Result<_>>()?;
    ds.write(&values[..])?;
    write_attrs(&ds, &[("long_name", &text.long_name)])?;
    attach_scales(&ds, &[channel])
}

/// The `k` dimension and the (profile, k) variables `profile_column` (i32, −1 unused)
/// and `profile_column_weight` (f64), filled as profiles come.
fn create_profile_columns(
    file: &File,
    spec: &RawFileSpec,
    k: usize,
    profile: &Dataset,
    coords_profile: &str,
) -> hdf5::Result<(Dataset, Dataset)> {
    let slot = create_var::<i64>(file, SLOT_DIM, &[k])?;
    write_index(&slot, 0, k)?;
    write_attrs(
        &slot,
        &[("long_name", "slot of a profile's columns"), ("units", "1")],
    )?;
    set_scale(&slot, SLOT_DIM)?;
    let columns = create_var::<i32>(file, PROFILE_COLUMN_NAMES[0], &[spec.n_profiles, k])?;
    write_attrs(
        &columns,
        &[
            (
                "long_name",
                "columns the profile's shots saw (index of the column dimension; -1 = unused slot)",
            ),
            ("units", "1"),
            ("coordinates", coords_profile),
        ],
    )?;
    let weights = create_var::<f64>(file, PROFILE_COLUMN_NAMES[1], &[spec.n_profiles, k])?;
    write_attrs(
        &weights,
        &[
            (
                "long_name",
                "share of the profile's shots that saw the column (sums to 1 over k)",
            ),
            ("units", "1"),
            ("coordinates", coords_profile),
        ],
    )?;
    attach_scales(&columns, &[profile, &slot])?;
    attach_scales(&weights, &[profile, &slot])?;
    Ok((columns, weights))
}

/// A (column, …) f64 variable: chunked along columns (about [`TARGET_CHUNK_BYTES`] a
/// chunk), shuffled and deflated (most of a scene's truth is zeros or repeats).
fn create_deflated(file: &File, name: &str, shape: &[usize]) -> hdf5::Result<Dataset> {
    let row: usize = shape[1..].iter().product::<usize>().max(1);
    let rows = (TARGET_CHUNK_BYTES / (8 * row)).clamp(1, shape[0].max(1));
    let mut chunk = shape.to_vec();
    chunk[0] = rows;
    file.new_dataset::<f64>()
        .shape(shape)
        .chunk(chunk)
        .shuffle()
        .deflate(chunk::DEFLATE_LEVEL)
        .obj_track_times(false)
        .attr_creation_order(AttrCreationOrder::Indexed)
        .create(name)
}
