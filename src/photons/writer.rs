//! The photon file (docs/photons.md): every recorded event of a run, streamed to HDF5 in
//! chunks (shuffle + deflate), memory flat: at most [`FLUSH_EVENTS`] events and
//! [`FLUSH_EVENTS`] shots are held before they are appended.

use std::path::{Path, PathBuf};

use hdf5::{Dataset, File, Group, H5Type};

use super::model::ORIGINS;
use crate::error::{Error, Result};
use crate::hdf5_ds::{attach_scales, set_scale, write_num_attr, write_str_attr};

/// Events (and shots) held before they are appended to the file; also the chunk length.
pub const FLUSH_EVENTS: usize = 1 << 16;

/// Deflate level of the photon file (as the raw file's counts: fast, the shuffle doing
/// most of the work).
const DEFLATE_LEVEL: u8 = 1;

/// One event as the file stores it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EventRow {
    /// Time of the shot since the run's start, s.
    pub delta_time: f64,
    /// Shot index in the run (0-based).
    pub pulse: u64,
    /// Channel index.
    pub channel: u16,
    /// Detector pixel.
    pub pixel: u16,
    /// The raw file's bin holding the event.
    pub bin: u32,
    /// Range from the instrument, m.
    pub range_m: f64,
    /// Time of flight since the pulse left, s.
    pub tof_s: f64,
    /// Height above sea level, m.
    pub h_ph: f64,
    /// Origin code (`model::Origin`).
    pub origin: u8,
}

/// One shot as the file stores it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShotRow {
    /// Time since the run's start, s.
    pub delta_time: f64,
    /// Emitted energy, J.
    pub energy_j: f64,
    /// Latitude and longitude, degrees (NaN without an orbit).
    pub latitude: f64,
    /// See `latitude`.
    pub longitude: f64,
}

/// What the file says of its run.
#[derive(Debug, Clone)]
pub struct PhotonHeader {
    /// CF units of the times: `seconds since <acquisition.start_time>`.
    pub time_units: String,
    /// Channel names.
    pub channels: Vec<String>,
    /// Detector pixels of each channel.
    pub pixels: Vec<u32>,
    /// The raw file's bins: their start ranges, m.
    pub bin_start_range_m: Vec<f64>,
    /// The raw file's bin width in range, m.
    pub bin_range_m: f64,
    /// The bin width in time, s.
    pub bin_width_s: f64,
    /// Shots per profile of the raw file.
    pub shots_per_profile: u64,
    /// Profiles of the run.
    pub profiles: u64,
    /// Pulse repetition frequency, Hz.
    pub rep_rate_hz: f64,
    /// Seed of the run.
    pub seed: u64,
    /// The run's config (TOML), as the raw file stores it.
    pub config_toml: String,
}

/// Column buffers of events.
#[derive(Default)]
struct EventColumns {
    delta_time: Vec<f64>,
    pulse: Vec<u64>,
    channel: Vec<u16>,
    pixel: Vec<u16>,
    bin: Vec<u32>,
    range_m: Vec<f64>,
    tof_s: Vec<f64>,
    h_ph: Vec<f64>,
    origin: Vec<u8>,
}

/// The photon file being written.
pub struct PhotonWriter {
    file: File,
    shown: PathBuf,
    events: Vec<Dataset>,
    shots: Vec<Dataset>,
    buffered: EventColumns,
    buffered_shots: Vec<ShotRow>,
    written_events: usize,
    written_shots: usize,
}

fn fail(shown: &Path, e: hdf5::Error) -> Error {
    Error::output(
        shown,
        format!(
            "cannot write: {}",
            crate::error::describe_hdf5_error(&e.to_string())
        ),
    )
}

/// A growing 1-D dataset of `T`, chunked and compressed, with its units and description.
fn growing<T: H5Type>(
    g: &Group,
    name: &str,
    units: &str,
    long_name: &str,
) -> hdf5::Result<Dataset> {
    let ds = g
        .new_dataset::<T>()
        .chunk(FLUSH_EVENTS)
        .shape(0..)
        .shuffle()
        .deflate(DEFLATE_LEVEL)
        .obj_track_times(false)
        .create(name)?;
    write_str_attr(&ds, "units", units)?;
    write_str_attr(&ds, "long_name", long_name)?;
    Ok(ds)
}

/// A fixed 1-D dataset.
fn fixed<T: H5Type>(g: &Group, name: &str, data: &[T], units: &str) -> hdf5::Result<Dataset> {
    let ds = g
        .new_dataset::<T>()
        .shape(data.len())
        .obj_track_times(false)
        .create(name)?;
    ds.write(data)?;
    write_str_attr(&ds, "units", units)?;
    Ok(ds)
}

/// Appends `data` to the growing dataset `ds` of `len` elements.
fn append<T: H5Type>(ds: &Dataset, len: usize, data: &[T]) -> hdf5::Result<()> {
    if data.is_empty() {
        return Ok(());
    }
    ds.resize(len + data.len())?;
    ds.write_slice(data, len..len + data.len())
}

/// A new group of `parent` without times (the same bytes for the same run).
fn group(parent: &Group, name: &str) -> hdf5::Result<Group> {
    parent
        .create_group_builder()
        .with_gcpl(|gcpl| gcpl.obj_track_times(false))
        .create(name)
}

/// The new file at `path` (shown as `shown`): LIBVER 1.8, no times (same bytes for the
/// same run).
fn create(path: &Path) -> hdf5::Result<File> {
    use hdf5::file::LibraryVersion;
    File::with_options()
        .with_fapl(|fapl| fapl.libver_bounds(LibraryVersion::V18, LibraryVersion::V18))
        .with_fcpl(|fcpl| fcpl.obj_track_times(false))
        .create(path)
}

impl PhotonWriter {
    /// Creates the photon file at exactly `path` (a temporary name), shown as `shown`.
    pub fn create(path: &Path, shown: &Path, h: &PhotonHeader) -> Result<Self> {
        let f = |e| fail(shown, e);
        let file = create(path).map_err(f)?;
        let make = || -> hdf5::Result<(Vec<Dataset>, Vec<Dataset>)> {
            write_str_attr(&file, "title", "lidarsim time-tagged photon events")?;
            write_str_attr(&file, "Conventions", "CF-1.10")?;
            let history = format!(
                "lidarsim simulate --photons: every recorded event, seed {}",
                h.seed
            );
            write_str_attr(&file, "history", &history)?;
            write_str_attr(&file, "lidarsim_photon_format", "1")?;
            write_str_attr(&file, "channels", &h.channels.join(","))?;
            write_num_attr(&file, "shots_per_profile", &h.shots_per_profile)?;
            write_num_attr(&file, "profiles", &h.profiles)?;
            write_num_attr(&file, "rep_rate_hz", &h.rep_rate_hz)?;
            write_num_attr(&file, "bin_width_s", &h.bin_width_s)?;
            write_num_attr(&file, "bin_range_m", &h.bin_range_m)?;
            write_num_attr(&file, "seed", &h.seed)?;
            write_str_attr(&file, "config", &h.config_toml)?;
            let bins = group(&file, "bins")?;
            fixed(&bins, "range_start", &h.bin_start_range_m, "m")?;
            let chans = group(&file, "channels")?;
            fixed(&chans, "pixels", &h.pixels, "1")?;
            let heights = group(&file, "heights")?;
            let flag_values: Vec<u8> = ORIGINS.iter().map(|(o, _)| *o as u8).collect();
            let flag_meanings = ORIGINS
                .iter()
                .map(|(_, n)| *n)
                .collect::<Vec<_>>()
                .join(" ");
            let events = vec![
                growing::<f64>(
                    &heights,
                    "delta_time",
                    &h.time_units,
                    "time of the event's shot",
                )?,
                growing::<u64>(
                    &heights,
                    "ph_id_pulse",
                    "1",
                    "shot index in the run, 0-based",
                )?,
                growing::<u16>(
                    &heights,
                    "ph_id_channel",
                    "1",
                    "channel index (attribute `channels` of the file)",
                )?,
                growing::<u16>(&heights, "ph_id_pixel", "1", "detector pixel, 0-based")?,
                growing::<u32>(
                    &heights,
                    "ph_id_bin",
                    "1",
                    "the raw file's bin holding the event",
                )?,
                growing::<f64>(&heights, "range", "m", "range from the instrument")?,
                growing::<f64>(
                    &heights,
                    "time_of_flight",
                    "s",
                    "time since the pulse left (negative in pre-trigger bins)",
                )?,
                growing::<f64>(
                    &heights,
                    "h_ph",
                    "m",
                    "height above sea level along the beam",
                )?,
                growing::<u8>(
                    &heights,
                    "truth_origin",
                    "1",
                    "where the event came from (truth)",
                )?,
            ];
            events[8]
                .new_attr::<u8>()
                .shape(flag_values.len())
                .create("flag_values")?
                .write(&flag_values)?;
            write_str_attr(&events[8], "flag_meanings", &flag_meanings)?;
            let pulse = group(&file, "pulse")?;
            let shots = vec![
                growing::<f64>(&pulse, "delta_time", &h.time_units, "time of the shot")?,
                growing::<f64>(
                    &pulse,
                    "energy",
                    "J",
                    "emitted pulse energy (the profile's mean)",
                )?,
                growing::<f64>(
                    &pulse,
                    "latitude",
                    "degrees_north",
                    "latitude of the footprint (NaN without an orbit)",
                )?,
                growing::<f64>(
                    &pulse,
                    "longitude",
                    "degrees_east",
                    "longitude of the footprint (NaN without an orbit)",
                )?,
            ];
            // the events' and the shots' times as their dimension scales (as ATL03's
            // `delta_time`), CF time units
            for (times, others) in [(&events[0], &events[1..]), (&shots[0], &shots[1..])] {
                set_scale(times, "delta_time")?;
                write_str_attr(times, "standard_name", "time")?;
                write_str_attr(times, "calendar", "standard")?;
                write_str_attr(times, "axis", "T")?;
                for ds in others {
                    attach_scales(ds, &[times])?;
                }
            }
            Ok((events, shots))
        };
        let (events, shots) = make().map_err(f)?;
        Ok(PhotonWriter {
            file,
            shown: shown.to_path_buf(),
            events,
            shots,
            buffered: EventColumns::default(),
            buffered_shots: Vec::new(),
            written_events: 0,
            written_shots: 0,
        })
    }

    /// Appends events.
    pub fn events(&mut self, rows: &[EventRow]) -> Result<()> {
        for r in rows {
            let b = &mut self.buffered;
            b.delta_time.push(r.delta_time);
            b.pulse.push(r.pulse);
            b.channel.push(r.channel);
            b.pixel.push(r.pixel);
            b.bin.push(r.bin);
            b.range_m.push(r.range_m);
            b.tof_s.push(r.tof_s);
            b.h_ph.push(r.h_ph);
            b.origin.push(r.origin);
            if b.pulse.len() >= FLUSH_EVENTS {
                self.flush_events()?;
            }
        }
        Ok(())
    }

    /// Appends shots.
    pub fn shots(&mut self, rows: &[ShotRow]) -> Result<()> {
        for r in rows {
            self.buffered_shots.push(*r);
            if self.buffered_shots.len() >= FLUSH_EVENTS {
                self.flush_shots()?;
            }
        }
        Ok(())
    }

    fn flush_events(&mut self) -> Result<()> {
        let b = std::mem::take(&mut self.buffered);
        let n = self.written_events;
        let e = &self.events;
        let w = || -> hdf5::Result<()> {
            append(&e[0], n, &b.delta_time)?;
            append(&e[1], n, &b.pulse)?;
            append(&e[2], n, &b.channel)?;
            append(&e[3], n, &b.pixel)?;
            append(&e[4], n, &b.bin)?;
            append(&e[5], n, &b.range_m)?;
            append(&e[6], n, &b.tof_s)?;
            append(&e[7], n, &b.h_ph)?;
            append(&e[8], n, &b.origin)
        };
        w().map_err(|e| fail(&self.shown, e))?;
        self.written_events += b.pulse.len();
        Ok(())
    }

    fn flush_shots(&mut self) -> Result<()> {
        let s = std::mem::take(&mut self.buffered_shots);
        let n = self.written_shots;
        let col = |f: fn(&ShotRow) -> f64| s.iter().map(f).collect::<Vec<f64>>();
        let d = &self.shots;
        let w = || -> hdf5::Result<()> {
            append(&d[0], n, &col(|r| r.delta_time))?;
            append(&d[1], n, &col(|r| r.energy_j))?;
            append(&d[2], n, &col(|r| r.latitude))?;
            append(&d[3], n, &col(|r| r.longitude))
        };
        w().map_err(|e| fail(&self.shown, e))?;
        self.written_shots += s.len();
        Ok(())
    }

    /// Events written so far (flushed or not).
    pub fn n_events(&self) -> usize {
        self.written_events + self.buffered.pulse.len()
    }

    /// Writes what is held and closes the file.
    pub fn finish(mut self) -> Result<u64> {
        self.flush_events()?;
        self.flush_shots()?;
        write_num_attr(&self.file, "n_events", &(self.written_events as u64))
            .map_err(|e| fail(&self.shown, e))?;
        Ok(self.written_events as u64)
    }
}
