//! Export of a lidarsim raw file (format version 2) to the EARLINET Single Calculus
//! Chain (SCC) raw-data NetCDF format. `docs/scc.md` has the full mapping table.
//!
//! # Sources
//!
//! * **SCC**: "The SCC input netCDF file format", docs.scc.imaa.cnr.it
//!   (`file_formats/netcdf_file`), and its revision of 2021-06-17 ("new options for
//!   Molecular_Calc", sccdocs changeset 6757f7d0af2a).
//! * **atmospheric_lidar** (the SCC writer `save_as_SCC_netcdf` in
//!   `atmospheric_lidar/generic.py`, read as vendored in `luisaddm/milgrau`): the
//!   dimensions `points`, `channels`, `time` (unlimited), `nb_of_time_scales`,
//!   `scan_angles`; the per-channel names and types (`_get_scc_channel_variables`: int
//!   `Laser_Repetition_Rate`, `Background_Mode`, `Dead_Time_Corr_Type`,
//!   `Acquisition_Mode`, `LR_Input`, `First_Signal_Rangebin`; double the wavelengths,
//!   `Raw_Data_Range_Resolution`, `Background_Low/High`, `Dead_Time`, `Trigger_Delay`,
//!   `DAQ_Range`); int `channel_ID`, `id_timescale`, `Molecular_Calc` (scalar),
//!   `Laser_Pointing_Angle_of_Profiles`, `Raw_Data_Start/Stop_Time`, `Laser_Shots`;
//!   double `Laser_Pointing_Angle`, `Raw_Lidar_Data`, `Pressure_at_Lidar_Station`
//!   (hPa), `Temperature_at_Lidar_Station` (°C, from its `set_PT`); the global attributes
//!   and their `YYYYMMDD` / `HHMMSS` formats; `Measurement_ID` = date + call sign + `NN`.
//! * Its parameter examples (`alh_parameters_scc_*.py` in gfatpy, `cf_netcdf_parameters.py`):
//!   `Background_Mode` 1 with `Background_Low/High` in m far away, `LR_Input` 1,
//!   `DAQ_Range` 0 for photon counting, `First_Signal_Rangebin`.
//! * `Molecular_Calc` codes 0 automatic, 1 radiosonde, 2 Cloudnet model, 4 standard
//!   atmosphere: `pollyxt_pipelines` (`Atmosphere` enum), consistent with the SCC
//!   revision above; before 2021, 0 meant the standard atmosphere.
//!
//! # Choices (each also in `docs/scc.md`)
//!
//! * **Format**: NetCDF-3 classic (64-bit offset beyond 2 GiB) with the pure-Rust
//!   `netcdf3` crate, so no system library is needed. `atmospheric_lidar` writes
//!   `NETCDF4` by default but lists `NETCDF3_CLASSIC` as a choice; the SCC reads its
//!   input with the netCDF library, which reads both. Not checked by uploading to an SCC.
//! * `Molecular_Calc` = 4 (US Standard Atmosphere 1976, lidarsim's `us76`), with
//!   station p and T from US76 at `platform.altitude_km`.
//! * `Background_Low/High` (range, m, the unit of the `atmospheric_lidar` examples:
//!   19–20 km, 50–60 km, 75–105 km, beyond any bin count): the limits of the longest run
//!   of consecutive bins whose expected record per shot beyond the background + dark
//!   (the signal, its signal-induced counts and its afterpulses) is below 1 % of the
//!   expected background + dark (the farthest of equal runs; in a changing scene the largest
//!   signal and smallest background over the profiles), within the pre-trigger bins when
//!   the file has `pretrigger_bins`; no such bin is refused with what to do.
//! * `First_Signal_Rangebin` = N, the file's pre-trigger bins (0 without), and
//!   `Trigger_Delay` (ns) = 2·r₀/c with r₀ the range at the start of bin N, so that bin
//!   `N + i` spans `c·Trigger_Delay/2 + [i, i+1)·Raw_Data_Range_Resolution` (0 for a
//!   ground run whose window starts at the station, which pre-trigger bins require).
//! * `Latitude_degrees_north`, `Longitude_degrees_east` from `platform.latitude_deg`,
//!   `platform.longitude_deg` when the config gives both (one alone is refused).
//! * `Dead_Time` in ns (SCC documentation, not re-read here: to confirm);
//!   `Dead_Time_Corr_Type` 0 non-paralyzable, 1 paralyzable; no detector = 0 ns, type 0.
//! * `Scattering_Mechanism` and `Signal_Type` are **not written**: their codes are SCC
//!   database codes that could not be verified, and the SCC takes a value found in the
//!   file over its database, so a wrong code would be worse than none.
//! * `channel_ID` = [`SccOptions::channel_ids`], else 1, 2, …: placeholders that must be
//!   replaced by the station's SCC channel IDs before a real submission.
//! * `Laser_Pointing_Angle` = `platform.off_nadir_deg` (from zenith for a ground run),
//!   one scan angle, every profile at index 0; one time scale (`id_timescale` 0).
//! * `Raw_Data_Start/Stop_Time` = `time ∓ accumulation_time_s/2`, rounded to whole
//!   seconds after the measurement start (the first profile's start, floored).
//! * No `Latitude`/`Longitude`/`Location`: lidarsim configs have none.

mod calibration;
mod fields;
mod options;
mod read;
mod write;

use std::path::Path;

pub use calibration::{CALIBRATION_ROTATIONS_DEG, SccCalibrationOptions};
pub use fields::{SIGNAL_FREE_SHARE, SccChannel, SccContent, background_bins, signal_free};
pub use options::SccOptions;
pub use read::{RawRun, read_raw};
pub use write::{POL_CALIB_VARIABLES, SCC_VARIABLES, SccType};

use crate::error::Result;

/// Reads the lidarsim raw file `raw_h5` and writes the SCC raw NetCDF file at exactly
/// `out_nc` (temporary names and renames are the caller's). Refuses, with a one-line
/// error naming the file, anything that is not a ground-based lidarsim raw file of
/// format version 2.
pub fn export_scc(raw_h5: &Path, out_nc: &Path, opts: &SccOptions) -> Result<()> {
    let raw = read_raw(raw_h5)?;
    let content = fields::scc_content(raw_h5, raw, opts)?;
    write::write_scc(out_nc, &content)
}

/// Reads the +45° and −45° calibration runs (`simulate --calibration plus45|minus45`) and
/// writes their Δ90 calibration measurement as one SCC raw NetCDF file at exactly
/// `out_nc` (`docs/scc.md` "The ±45° calibration measurement").
pub fn export_scc_calibration(
    plus45_h5: &Path,
    minus45_h5: &Path,
    out_nc: &Path,
    opts: &SccCalibrationOptions,
) -> Result<()> {
    let content = calibration::calibration_content(plus45_h5, minus45_h5, opts)?;
    write::write_scc(out_nc, &content)
}
