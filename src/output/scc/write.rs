//! Writing [`SccContent`] as a NetCDF-3 file with the pure-Rust `netcdf3` crate.

use std::path::Path;

use netcdf3::{DataSet, FileWriter, Version};

use super::fields::{
    BACKGROUND_MODE_FAR_RANGE, LR_INPUT, MOLECULAR_CALC_US_STANDARD, SccChannel, SccContent,
};
use crate::error::{Error, Result};

/// The netCDF type of an SCC variable.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SccType {
    /// `int` (NC_INT, 32-bit).
    Int,
    /// `double` (NC_DOUBLE).
    Double,
}

const CH: &[&str] = &["channels"];
const TS: &[&str] = &["time", "nb_of_time_scales"];

/// Every variable the export writes: name, dimensions, type (as in `atmospheric_lidar`'s
/// `save_as_SCC_netcdf` and `_get_scc_channel_variables`).
pub const SCC_VARIABLES: &[(&str, &[&str], SccType)] = &[
    ("channel_ID", CH, SccType::Int),
    ("Laser_Repetition_Rate", CH, SccType::Int),
    ("Emitted_Wavelength", CH, SccType::Double),
    ("Detected_Wavelength", CH, SccType::Double),
    ("Raw_Data_Range_Resolution", CH, SccType::Double),
    ("Background_Mode", CH, SccType::Int),
    ("Background_Low", CH, SccType::Double),
    ("Background_High", CH, SccType::Double),
    ("Dead_Time_Corr_Type", CH, SccType::Int),
    ("Dead_Time", CH, SccType::Double),
    ("Acquisition_Mode", CH, SccType::Int),
    ("Trigger_Delay", CH, SccType::Double),
    ("LR_Input", CH, SccType::Int),
    ("DAQ_Range", CH, SccType::Double),
    ("First_Signal_Rangebin", CH, SccType::Int),
    ("id_timescale", CH, SccType::Int),
    ("Laser_Pointing_Angle", &["scan_angles"], SccType::Double),
    ("Molecular_Calc", &[], SccType::Int),
    ("Laser_Pointing_Angle_of_Profiles", TS, SccType::Int),
    ("Raw_Data_Start_Time", TS, SccType::Int),
    ("Raw_Data_Stop_Time", TS, SccType::Int),
    ("Laser_Shots", &["time", "channels"], SccType::Int),
    (
        "Raw_Lidar_Data",
        &["time", "channels", "points"],
        SccType::Double,
    ),
    ("Pressure_at_Lidar_Station", &[], SccType::Double),
    ("Temperature_at_Lidar_Station", &[], SccType::Double),
];

/// The variables a calibration measurement adds (`atmospheric_lidar`'s
/// `LicelCalibrationMeasurement`): the range (m) where the calibration factor is taken.
pub const POL_CALIB_VARIABLES: [&str; 2] = ["Pol_Calib_Range_Min", "Pol_Calib_Range_Max"];

/// A NetCDF writer's error in plain words: the OS reason of an I/O failure ("no space
/// left on device"), never the library's debug text (`IOErrorKind(StorageFull)`).
fn describe(e: &netcdf3::WriteError) -> String {
    match e {
        netcdf3::WriteError::IOErrorKind(kind) => {
            crate::error::describe_io(&std::io::Error::from(*kind))
        }
        _ => "the NetCDF writer refused the data (a lidarsim bug; please report it)".into(),
    }
}

/// Writes `c` to `out` (created or truncated).
pub fn write_scc(out: &Path, c: &SccContent) -> Result<()> {
    let fail = |what: &str, e: &netcdf3::WriteError| {
        Error::output(
            out,
            format!("cannot write the SCC file ({what}): {}", describe(e)),
        )
    };
    let ds = define(c).map_err(|_| {
        // the layout is lidarsim's own: a refusal here is a bug, not the user's input
        Error::output(
            out,
            "cannot write the SCC file: its variables could not be laid out (a lidarsim bug; please report it)",
        )
    })?;
    let file = std::fs::File::create(out).map_err(|e| Error::Io {
        path: out.to_path_buf(),
        source: e,
    })?;
    let name = out.to_string_lossy();
    let mut w = FileWriter::open_seek_write(&name, Box::new(file)).map_err(|e| fail("open", &e))?;
    w.set_def(&ds, version(c), 0)
        .map_err(|e| fail("header", &e))?;
    write_data(&mut w, c).map_err(|e| fail("data", &e))?;
    w.close().map_err(|e| fail("close", &e))
}

/// Classic format while every offset fits 31 bits, else 64-bit offset.
fn version(c: &SccContent) -> Version {
    let bytes = (c.counts.len() as u64) * 8 + 1_000_000;
    if bytes < (1 << 31) - 1 {
        Version::Classic
    } else {
        Version::Offset64Bit
    }
}

fn define(c: &SccContent) -> std::result::Result<DataSet, netcdf3::InvalidDataSet> {
    let mut ds = DataSet::new();
    ds.add_fixed_dim("points", c.n_bins)?;
    ds.add_fixed_dim("channels", c.channels.len())?;
    ds.set_unlimited_dim("time", c.n_profiles)?;
    ds.add_fixed_dim("nb_of_time_scales", 1)?;
    ds.add_fixed_dim("scan_angles", 1)?;
    for (name, dims, ty) in SCC_VARIABLES {
        match ty {
            SccType::Int => ds.add_var_i32(name, dims)?,
            SccType::Double => ds.add_var_f64(name, dims)?,
        }
    }
    if c.pol_calib_range_m.is_some() {
        for name in POL_CALIB_VARIABLES {
            ds.add_var_f64(name, CH)?;
            ds.add_var_attr_string(name, "units", "m")?;
        }
    }
    add_units(&mut ds)?;
    for (name, value) in &c.text_attributes {
        ds.add_global_attr_string(name, value)?;
    }
    ds.add_global_attr_f64("Altitude_meter_asl", vec![c.altitude_m_asl])?;
    if let Some((lat, lon)) = c.station_lat_lon_deg {
        ds.add_global_attr_f64("Latitude_degrees_north", vec![lat])?;
        ds.add_global_attr_f64("Longitude_degrees_east", vec![lon])?;
    }
    Ok(ds)
}

fn add_units(ds: &mut DataSet) -> std::result::Result<(), netcdf3::InvalidDataSet> {
    let units = [
        ("Emitted_Wavelength", "nm"),
        ("Detected_Wavelength", "nm"),
        ("Raw_Data_Range_Resolution", "m"),
        ("Background_Low", "m"),
        ("Background_High", "m"),
        ("Dead_Time", "ns"),
        ("Trigger_Delay", "ns"),
        ("Laser_Pointing_Angle", "degrees"),
        ("Raw_Data_Start_Time", "s"),
        ("Raw_Data_Stop_Time", "s"),
        ("Pressure_at_Lidar_Station", "hPa"),
        ("Temperature_at_Lidar_Station", "degC"),
        (
            "Raw_Lidar_Data",
            "counts (photon counting, Acquisition_Mode 1); mV per shot (analog, Acquisition_Mode 0)",
        ),
    ];
    for (var, u) in units {
        ds.add_var_attr_string(var, "units", u)?;
    }
    Ok(())
}

type W<'a> = FileWriter<'a>;
type WResult = std::result::Result<(), netcdf3::WriteError>;

fn per_channel<T>(c: &SccContent, f: impl Fn(&SccChannel) -> T) -> Vec<T> {
    c.channels.iter().map(f).collect()
}

fn write_data(w: &mut W, c: &SccContent) -> WResult {
    write_channel_vars(w, c)?;
    let n_ch = c.channels.len();
    w.write_var_f64("Laser_Pointing_Angle", &[c.pointing_angle_deg])?;
    w.write_var_i32("Molecular_Calc", &[MOLECULAR_CALC_US_STANDARD])?;
    w.write_var_i32("Laser_Pointing_Angle_of_Profiles", &vec![0; c.n_profiles])?;
    w.write_var_i32("Raw_Data_Start_Time", &c.start_s)?;
    w.write_var_i32("Raw_Data_Stop_Time", &c.stop_s)?;
    w.write_var_i32("Laser_Shots", &c.laser_shots)?;
    let per_record = n_ch * c.n_bins;
    for p in 0..c.n_profiles {
        // photon counts as counted; an analog channel's codes as mV per shot
        let shots = f64::from(c.laser_shots[p * n_ch].max(1));
        let row: Vec<f64> = c.counts[p * per_record..(p + 1) * per_record]
            .chunks(c.n_bins)
            .zip(&c.channels)
            .flat_map(|(bins, ch)| {
                bins.iter().map(move |&n| match ch.analog_mv_per_code {
                    Some(mv) => n as f64 / shots * mv,
                    None => n as f64,
                })
            })
            .collect();
        w.write_record_f64("Raw_Lidar_Data", p, &row)?;
    }
    w.write_var_f64("Pressure_at_Lidar_Station", &[c.pressure_hpa])?;
    w.write_var_f64("Temperature_at_Lidar_Station", &[c.temperature_c])
}

fn write_channel_vars(w: &mut W, c: &SccContent) -> WResult {
    let n = c.channels.len();
    w.write_var_i32("channel_ID", &per_channel(c, |ch| ch.id))?;
    w.write_var_i32(
        "Laser_Repetition_Rate",
        &per_channel(c, |ch| ch.rep_rate_hz),
    )?;
    w.write_var_f64("Emitted_Wavelength", &per_channel(c, |ch| ch.wavelength_nm))?;
    let detected = per_channel(c, |ch| ch.detected_wavelength_nm);
    w.write_var_f64("Detected_Wavelength", &detected)?;
    let res = per_channel(c, |ch| ch.range_resolution_m);
    w.write_var_f64("Raw_Data_Range_Resolution", &res)?;
    w.write_var_i32("Background_Mode", &vec![BACKGROUND_MODE_FAR_RANGE; n])?;
    w.write_var_f64("Background_Low", &per_channel(c, |ch| ch.background_m.0))?;
    w.write_var_f64("Background_High", &per_channel(c, |ch| ch.background_m.1))?;
    w.write_var_i32(
        "Dead_Time_Corr_Type",
        &per_channel(c, |ch| ch.dead_time_type),
    )?;
    w.write_var_f64("Dead_Time", &per_channel(c, |ch| ch.dead_time_ns))?;
    w.write_var_i32(
        "Acquisition_Mode",
        &per_channel(c, |ch| ch.acquisition_mode),
    )?;
    w.write_var_f64("Trigger_Delay", &per_channel(c, |ch| ch.trigger_delay_ns))?;
    w.write_var_i32("LR_Input", &vec![LR_INPUT; n])?;
    w.write_var_f64("DAQ_Range", &per_channel(c, |ch| ch.daq_range_mv))?;
    w.write_var_i32(
        "First_Signal_Rangebin",
        &per_channel(c, |ch| ch.first_signal_rangebin),
    )?;
    w.write_var_i32("id_timescale", &vec![0; n])?;
    if let Some((lo, hi)) = c.pol_calib_range_m {
        w.write_var_f64(POL_CALIB_VARIABLES[0], &vec![lo; n])?;
        w.write_var_f64(POL_CALIB_VARIABLES[1], &vec![hi; n])?;
    }
    Ok(())
}
