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
use super::column_stream::StreamedVar;
use super::hdf5_ds::{attach_scales, set_scale, write_attr};
use super::schema::{Element, PerProfile, Storage, Values, schema};
use super::spec::{CountWidth, Dims, RESERVED_NAMES, RawFileSpec};

/// Target size of one chunk of a (profile, channel, bin) variable, in bytes, for that
/// variable's own element size (u16 counts get four times the rows of f64 truth). Within
/// HDF5's default 1 MiB per-dataset chunk cache, so a reader reading profile by profile
/// decompresses each chunk once; large enough that the byte planes of slowly varying f64
/// truth compress well (12× at 512 KiB against 10× at 256 KiB on the orbit's S/N).
pub const TARGET_CHUNK_BYTES: usize = 512 * 1024;
/// Rows of the `profile` coordinate written per call at creation (bounds memory).
const COORD_BLOCK: usize = 64 * 1024;

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
    /// The (column, …) variables whose rows come column by column, in the spec's order.
    pub streamed: Vec<StreamedVar>,
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
            streamed,
        } = self;
        drop((rows, time, n_shots, pulse_energy, columns, profile_columns));
        drop(streamed);
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
            Dims::Profile | Dims::ProfileChannel | Dims::ProfileChannelBin => 0,
        };
        if matches!(var.dims, Dims::ColumnBin | Dims::ColumnChannelBin) && spec.n_columns == 0 {
            return Err(format!("variable `{}` needs a column dimension", var.name));
        }
        let want = match var.dims {
            Dims::ColumnBin | Dims::ColumnChannelBin if spec.streamed_columns => 0,
            _ => want,
        };
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

/// Creates the whole layout in a new HDF5 file at `path` (truncating it): every
/// variable of [`schema`], in its order, with its attributes; the values known up front
/// written, dimensions made scales and attached.
pub fn create_layout(path: &Path, spec: &RawFileSpec) -> hdf5::Result<OpenFile> {
    let file = create_file(path)?;
    for (name, value) in &spec.root_attributes {
        write_attr(&file, name, value)?;
    }
    let mut scales: Vec<(&str, Dataset)> = Vec::new();
    let mut rows = Vec::new();
    let mut singles: Vec<(PerProfile, Dataset)> = Vec::new();
    let mut streamed = Vec::new();
    for var in schema(spec) {
        let ds = match var.storage {
            Storage::Rows { by_planes } => {
                let row = match var.element {
                    Element::Count(CountWidth::U16) => create_rows::<u16>(&file, var.name, spec),
                    Element::Count(CountWidth::U32) => create_rows::<u32>(&file, var.name, spec),
                    Element::Count(CountWidth::U64) => create_rows::<u64>(&file, var.name, spec),
                    _ => create_rows::<f64>(&file, var.name, spec),
                }?;
                let ds = row.ds.clone();
                rows.push(RowVar { by_planes, ..row });
                ds
            }
            Storage::Deflated => {
                // streamed variables share one chunking along columns (that of the
                // widest, (column, channel, bin)): a column completes the same chunk of
                // every one of them
                let streamed_rows = (var.values == Values::Streamed).then(|| {
                    let widest = 8 * spec.counts_per_profile().max(1);
                    (TARGET_CHUNK_BYTES / widest).clamp(1, spec.n_columns.max(1))
                });
                let (ds, chunk_columns) =
                    create_deflated(&file, var.name, &var.shape, streamed_rows)?;
                if var.values == Values::Streamed {
                    let row_len = var.shape[1..].iter().product();
                    streamed.push(StreamedVar {
                        ds: ds.clone(),
                        row_len,
                        channels: (var.shape.len() == 3).then(|| var.shape[1]),
                        chunk_columns,
                    });
                }
                ds
            }
            Storage::Contiguous => match var.element {
                Element::I64 => create_var::<i64>(&file, var.name, &var.shape)?,
                Element::Text => create_var::<VarLenUnicode>(&file, var.name, &var.shape)?,
                Element::U64 => create_var::<u64>(&file, var.name, &var.shape)?,
                Element::I32 => create_var::<i32>(&file, var.name, &var.shape)?,
                Element::F64 | Element::Count(_) => create_var::<f64>(&file, var.name, &var.shape)?,
            },
        };
        match var.values {
            Values::Index { first } => write_index(&ds, first, var.len())?,
            Values::Text(values) => write_text(&ds, values)?,
            Values::F64(values) => ds.write_raw(values)?,
            Values::PerProfile(PerProfile::Row) | Values::Streamed => {}
            Values::PerProfile(per) => singles.push((per, ds.clone())),
        }
        for (k, v) in &var.attributes {
            write_attr(&ds, k, v)?;
        }
        if var.is_dimension {
            set_scale(&ds, var.name)?;
            scales.push((var.name, ds));
        } else {
            let dims = var
                .dims
                .iter()
                .map(|d| scales.iter().find(|(n, _)| n == d).map(|(_, s)| s))
                .collect::<Option<Vec<&Dataset>>>()
                .ok_or("a variable's dimension is not yet a scale")?;
            attach_scales(&ds, &dims)?;
        }
    }
    let mut take = |per: PerProfile| {
        let at = singles.iter().position(|(p, _)| *p == per);
        at.map(|k| singles.remove(k).1)
    };
    let missing = || hdf5::Error::from("the schema lacks time, n_shots or pulse_energy");
    let time = take(PerProfile::Time).ok_or_else(missing)?;
    let n_shots = take(PerProfile::NShots).ok_or_else(missing)?;
    let pulse_energy = take(PerProfile::PulseEnergy).ok_or_else(missing)?;
    let profile_columns = take(PerProfile::Columns).zip(take(PerProfile::ColumnWeights));
    let columns = singles.into_iter().map(|(_, ds)| ds).collect();
    Ok(OpenFile {
        file,
        rows,
        time,
        n_shots,
        pulse_energy,
        columns,
        profile_columns,
        streamed,
    })
}

/// Writes a string variable.
fn write_text(ds: &Dataset, values: &[String]) -> hdf5::Result<()> {
    let values: Vec<VarLenUnicode> = values
        .iter()
        .map(|v| {
            v.parse()
                .map_err(|_| hdf5::Error::from("a text value holds NUL"))
        })
        .collect::<hdf5::Result<_>>()?;
    ds.write(&values[..])
}

/// A (column, …) f64 variable: chunked along columns (about [`TARGET_CHUNK_BYTES`] a
/// chunk), shuffled and deflated (most of a scene's truth is zeros or repeats).
/// `rows` columns a chunk if given. Returns it and its columns per chunk.
fn create_deflated(
    file: &File,
    name: &str,
    shape: &[usize],
    rows: Option<usize>,
) -> hdf5::Result<(Dataset, usize)> {
    let row: usize = shape[1..].iter().product::<usize>().max(1);
    let rows = rows.unwrap_or((TARGET_CHUNK_BYTES / (8 * row)).clamp(1, shape[0].max(1)));
    let mut chunk = shape.to_vec();
    chunk[0] = rows;
    let ds = file
        .new_dataset::<f64>()
        .shape(shape)
        .chunk(chunk)
        .shuffle()
        .deflate(chunk::DEFLATE_LEVEL)
        .obj_track_times(false)
        .attr_creation_order(AttrCreationOrder::Indexed)
        .create(name)?;
    Ok((ds, rows))
}
