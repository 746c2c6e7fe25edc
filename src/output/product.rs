//! The onboard product (`lidarsim onboard`, interface.md): one HDF5 group per altitude
//! region of the scheme (`region_0` … from the top), each with its own `profile`,
//! `channel` and `bin` dimension scales, `altitude`, `time`, `n_shots` and
//! `counts (profile, channel, bin)` (integer sums, u32), and the region's attributes
//! `altitude_min_km`, `altitude_max_km`, `vertical_resolution_m`, `shots_averaged`.
//! Readable as netCDF-4 (groups with dimensions of their own).

use std::path::Path;

use hdf5::types::VarLenUnicode;
use hdf5::{Dataset, File, Group};

use super::raw_file::hdf5_ds::{attach_scales, set_scale, write_num_attr, write_str_attr};
use crate::error::{Error, Result};
use crate::output::safe_file::describe_hdf5_error;

/// What one region of the product holds, known up front.
#[derive(Debug, Clone)]
pub struct RegionSpec {
    /// Downlinked profiles.
    pub profiles: usize,
    /// Bin-centre altitude of each downlinked bin, m.
    pub altitude_m: Vec<f64>,
    /// Profile-centre time of each downlinked profile, s since the start.
    pub time_s: Vec<f64>,
    /// Shots summed per profile.
    pub shots: u32,
    /// `altitude_min_km`, `altitude_max_km`, `vertical_resolution_m`.
    pub bounds: (f64, f64, f64),
}

/// A product being written.
pub struct ProductWriter {
    file: File,
    counts: Vec<Dataset>,
    written: Vec<usize>,
    channels: usize,
    display: std::path::PathBuf,
}

impl ProductWriter {
    /// Creates the product at exactly `path` (a temporary name from `safe_file`).
    pub fn create(
        path: &Path,
        display: &Path,
        channels: &[String],
        time_units: &str,
        attributes: &[(&str, String)],
        regions: &[RegionSpec],
    ) -> Result<Self> {
        let fail = |e: hdf5::Error| {
            Error::output(
                display,
                format!("cannot write: {}", describe_hdf5_error(&e.to_string())),
            )
        };
        let file = File::create(path).map_err(fail)?;
        for (k, v) in attributes {
            write_str_attr(&file, k, v).map_err(fail)?;
        }
        let counts = regions
            .iter()
            .enumerate()
            .map(|(k, r)| {
                let g = file.create_group(&format!("region_{k}"))?;
                region_layout(&g, r, channels, time_units)
            })
            .collect::<hdf5::Result<Vec<_>>>()
            .map_err(fail)?;
        Ok(ProductWriter {
            file,
            written: vec![0; regions.len()],
            counts,
            channels: channels.len(),
            display: display.to_path_buf(),
        })
    }

    /// Writes the next profile of region `k` (channel-major sums); profiles beyond the
    /// region's size are not written (a trailing partial sum never is).
    pub fn write(&mut self, k: usize, sums: &[u64]) -> Result<()> {
        let ds = &self.counts[k];
        let row = self.written[k];
        if row >= ds.shape()[0] {
            return Ok(());
        }
        let bins = sums.len() / self.channels;
        let data: Vec<u32> = sums
            .iter()
            .map(|&c| u32::try_from(c).unwrap_or(u32::MAX))
            .collect();
        let view = ndarray::ArrayView2::from_shape((self.channels, bins), &data)
            .map_err(|e| Error::output(&self.display, e.to_string()))?;
        ds.write_slice(view, (row, .., ..))
            .map_err(|e| Error::output(&self.display, describe_hdf5_error(&e.to_string())))?;
        self.written[k] += 1;
        Ok(())
    }

    /// Closes the file.
    pub fn finish(self) -> Result<()> {
        let ProductWriter {
            file,
            counts,
            display,
            ..
        } = self;
        drop(counts);
        file.close()
            .map_err(|e| Error::output(display, describe_hdf5_error(&e.to_string())))
    }
}

/// One region's group: its dimension scales, coordinates, attributes and counts.
fn region_layout(
    g: &Group,
    r: &RegionSpec,
    channels: &[String],
    time_units: &str,
) -> hdf5::Result<Dataset> {
    let var = |name: &str, data: &[f64], units: &str| -> hdf5::Result<Dataset> {
        let ds = g.new_dataset::<f64>().shape(data.len()).create(name)?;
        ds.write_raw(data)?;
        write_str_attr(&ds, "units", units)?;
        Ok(ds)
    };
    let profile = g.new_dataset::<i64>().shape(r.profiles).create("profile")?;
    profile.write_raw(&(0..r.profiles as i64).collect::<Vec<_>>())?;
    set_scale(&profile, "profile")?;
    let channel = g
        .new_dataset::<VarLenUnicode>()
        .shape(channels.len())
        .create("channel")?;
    let names: Vec<VarLenUnicode> = channels
        .iter()
        .map(|c| c.parse().unwrap_or_default())
        .collect();
    channel.write_raw(&names)?;
    set_scale(&channel, "channel")?;
    let bin = g
        .new_dataset::<i64>()
        .shape(r.altitude_m.len())
        .create("bin")?;
    bin.write_raw(&(0..r.altitude_m.len() as i64).collect::<Vec<_>>())?;
    set_scale(&bin, "bin")?;
    let altitude = var("altitude", &r.altitude_m, "m")?;
    write_str_attr(&altitude, "standard_name", "altitude")?;
    attach_scales(&altitude, &[&bin])?;
    let time = var("time", &r.time_s, time_units)?;
    write_str_attr(&time, "standard_name", "time")?;
    attach_scales(&time, &[&profile])?;
    let n_shots = g.new_dataset::<u32>().shape(r.profiles).create("n_shots")?;
    n_shots.write_raw(&vec![r.shots; r.profiles])?;
    attach_scales(&n_shots, &[&profile])?;
    let (bins, c) = (r.altitude_m.len(), channels.len());
    let counts = g
        .new_dataset::<u32>()
        .shape((r.profiles, c, bins))
        .chunk((
            (4096 / (c * bins).max(1)).clamp(1, r.profiles.max(1)),
            c,
            bins,
        ))
        .shuffle()
        .deflate(1)
        .create("counts")?;
    write_str_attr(&counts, "units", "count")?;
    write_str_attr(&counts, "coordinates", "time altitude")?;
    attach_scales(&counts, &[&profile, &channel, &bin])?;
    write_num_attr(g, "altitude_min_km", &r.bounds.0)?;
    write_num_attr(g, "altitude_max_km", &r.bounds.1)?;
    write_num_attr(g, "vertical_resolution_m", &r.bounds.2)?;
    write_num_attr(g, "shots_averaged", &r.shots)?;
    Ok(counts)
}
