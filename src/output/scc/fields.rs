//! What goes into the SCC file: every value derived from a [`RawRun`], with the choices
//! documented in the parent module (`super`) and in `docs/scc.md`.

use std::path::Path;
use std::time::{Duration, SystemTime, UNIX_EPOCH};

use super::options::SccOptions;
use super::read::{RawRun, bad};
use crate::config::DetectorConfig;
use crate::constants::SPEED_OF_LIGHT_M_PER_S;
use crate::detector::DeadTimeModel;
use crate::error::{Error, Result};
use crate::receiver::ChannelConfig;

/// `Molecular_Calc` written: 4 = US Standard Atmosphere 1976 (SCC netCDF input format
/// after its 2021 revision; 0 = automatic, 1 = radiosounding, 2 = model).
pub const MOLECULAR_CALC_US_STANDARD: i32 = 4;
/// `Acquisition_Mode` of a photon-counting channel (field notes: 0 analog, 1 photon
/// counting, as `atmospheric_lidar` writes them).
pub const ACQUISITION_PHOTON_COUNTING: i32 = 1;
/// `Acquisition_Mode` of an analog channel.
pub const ACQUISITION_ANALOG: i32 = 0;
/// `Background_Mode` written: 1 = atmospheric background from the far range given by
/// `Background_Low`/`Background_High` in m (as in the `atmospheric_lidar` examples).
pub const BACKGROUND_MODE_FAR_RANGE: i32 = 1;
/// `LR_Input` written: 1, as in every `atmospheric_lidar` parameter example.
pub const LR_INPUT: i32 = 1;
/// A bin is "signal-free" when its expected signal is below this share of its expected
/// background + dark counts (or is exactly 0).
pub const SIGNAL_FREE_SHARE: f64 = 0.01;

/// One SCC channel's parameters.
#[derive(Debug, Clone, PartialEq)]
pub struct SccChannel {
    /// lidarsim channel name, e.g. `532_total`.
    pub name: String,
    /// `channel_ID`.
    pub id: i32,
    /// `Laser_Repetition_Rate`, Hz.
    pub rep_rate_hz: i32,
    /// `Emitted_Wavelength`: the laser line, nm.
    pub wavelength_nm: f64,
    /// `Detected_Wavelength`: the laser line for an elastic channel, the Raman line for
    /// a Raman channel, nm.
    pub detected_wavelength_nm: f64,
    /// `Raw_Data_Range_Resolution`, m.
    pub range_resolution_m: f64,
    /// `Background_Low`, `Background_High`: range window, m.
    pub background_m: (f64, f64),
    /// `Dead_Time`, ns.
    pub dead_time_ns: f64,
    /// `Dead_Time_Corr_Type`: 0 non-paralyzable, 1 paralyzable.
    pub dead_time_type: i32,
    /// `Trigger_Delay`, ns: 2·r/c at the start of bin `First_Signal_Rangebin`.
    pub trigger_delay_ns: f64,
    /// `First_Signal_Rangebin`: the file's pre-trigger bins (root `pretrigger_bins`),
    /// so that bin is the first after the pulse leaves (0 without pre-trigger bins).
    pub first_signal_rangebin: i32,
    /// `Acquisition_Mode`: [`ACQUISITION_ANALOG`] or [`ACQUISITION_PHOTON_COUNTING`].
    pub acquisition_mode: i32,
    /// `DAQ_Range`: an analog channel's ADC input range, mV (0 for photon counting).
    pub daq_range_mv: f64,
    /// An analog channel's mV per ADC code: its `Raw_Lidar_Data` is the mean signal per
    /// shot in mV, `counts / n_shots · this` (as `atmospheric_lidar`'s Licel reader
    /// gives analog data); `None` for photon counting (raw counts).
    pub analog_mv_per_code: Option<f64>,
}

/// Everything the SCC file holds.
#[derive(Debug, Clone)]
pub struct SccContent {
    /// Length of `time`.
    pub n_profiles: usize,
    /// Length of `points`.
    pub n_bins: usize,
    /// One per `channels`.
    pub channels: Vec<SccChannel>,
    /// Counts (time, channels, points), row-major.
    pub counts: Vec<u64>,
    /// `Laser_Shots` (time, channels).
    pub laser_shots: Vec<i32>,
    /// `Raw_Data_Start_Time` (time), s after the measurement start.
    pub start_s: Vec<i32>,
    /// `Raw_Data_Stop_Time` (time), s after the measurement start.
    pub stop_s: Vec<i32>,
    /// `Laser_Pointing_Angle`, degrees from zenith.
    pub pointing_angle_deg: f64,
    /// `Pressure_at_Lidar_Station`, hPa.
    pub pressure_hpa: f64,
    /// `Temperature_at_Lidar_Station`, °C.
    pub temperature_c: f64,
    /// Global text attributes, in order.
    pub text_attributes: Vec<(&'static str, String)>,
    /// `Altitude_meter_asl`.
    pub altitude_m_asl: f64,
    /// `Latitude_degrees_north` and `Longitude_degrees_east` (`platform.latitude_deg`,
    /// `platform.longitude_deg`), when the config gives both.
    pub station_lat_lon_deg: Option<(f64, f64)>,
    /// The measurement's start (whole seconds), which `start_s` and `stop_s` count from.
    pub start: SystemTime,
    /// A calibration measurement's `Pol_Calib_Range_Min/Max` (m); `None` for a
    /// measurement (the variables are not written).
    pub pol_calib_range_m: Option<(f64, f64)>,
}

/// Derives the SCC content of `raw` (read from `path`).
pub fn scc_content(path: &Path, raw: RawRun, opts: &SccOptions) -> Result<SccContent> {
    let platform = table(&raw.config, "platform");
    let kind = platform
        .and_then(|p| p.get("kind"))
        .and_then(|k| k.as_str());
    match kind {
        Some("ground") => {}
        Some("spaceborne") => {
            return Err(bad(
                path,
                "a spaceborne run: the SCC processes ground-based stations only",
            ));
        }
        _ => return Err(bad(path, "the `config` attribute has no `platform.kind`")),
    }
    let altitude_m = num(platform, "altitude_km").unwrap_or(0.0) * 1e3;
    let (start_s, stop_s, t0) = time_scale(path, &raw)?;
    let channels = channels(path, &raw, opts)?;
    let state = crate::atmosphere::us76::state(altitude_m).ok_or_else(|| {
        bad(
            path,
            &format!("station altitude {altitude_m} m is outside the US Standard Atmosphere"),
        )
    })?;
    let stop = t0 + Duration::from_secs(stop_s.iter().copied().max().unwrap_or(0) as u64);
    let text_attributes = text_attributes(&raw.config, opts, t0, stop)?;
    Ok(SccContent {
        n_profiles: raw.n_profiles,
        n_bins: raw.n_bins,
        laser_shots: laser_shots(path, &raw)?,
        counts: raw.counts,
        channels,
        start_s,
        stop_s,
        pointing_angle_deg: num(platform, "off_nadir_deg").unwrap_or(0.0),
        pressure_hpa: state.pressure_pa / 100.0,
        temperature_c: state.temperature_k - 273.15,
        text_attributes,
        altitude_m_asl: altitude_m,
        station_lat_lon_deg: station_lat_lon(path, platform)?,
        start: t0,
        pol_calib_range_m: None,
    })
}

/// The station's latitude and longitude from `platform.latitude_deg/longitude_deg`: both
/// or neither (one alone is refused, naming the key that is missing).
fn station_lat_lon(path: &Path, platform: Option<&toml::Table>) -> Result<Option<(f64, f64)>> {
    match (
        num(platform, "latitude_deg"),
        num(platform, "longitude_deg"),
    ) {
        (Some(lat), Some(lon)) => Ok(Some((lat, lon))),
        (None, None) => Ok(None),
        (Some(_), None) => Err(bad(
            path,
            "`platform.latitude_deg` without `platform.longitude_deg`: the SCC needs both",
        )),
        (None, Some(_)) => Err(bad(
            path,
            "`platform.longitude_deg` without `platform.latitude_deg`: the SCC needs both",
        )),
    }
}

fn table<'a>(t: &'a toml::Table, key: &str) -> Option<&'a toml::Table> {
    t.get(key).and_then(|v| v.as_table())
}

/// A number (float or integer) under `key` of `t`.
fn num(t: Option<&toml::Table>, key: &str) -> Option<f64> {
    match t?.get(key)? {
        toml::Value::Float(x) => Some(*x),
        toml::Value::Integer(i) => Some(*i as f64),
        _ => None,
    }
}

/// Per-profile start and stop seconds after the measurement start, and that start
/// (whole seconds): profile `p` spans `time[p] ± accumulation_time_s / 2`.
fn time_scale(path: &Path, raw: &RawRun) -> Result<(Vec<i32>, Vec<i32>, SystemTime)> {
    let origin = raw
        .time_units
        .strip_prefix("seconds since ")
        .and_then(|s| humantime::parse_rfc3339_weak(s.trim()).ok())
        .ok_or_else(|| {
            bad(
                path,
                &format!(
                    "`time` units `{}` are not `seconds since <date>`",
                    raw.time_units
                ),
            )
        })?;
    let origin_s = origin
        .duration_since(UNIX_EPOCH)
        .map_err(|_| bad(path, "the measurement starts before 1970"))?
        .as_secs_f64();
    let half = raw.accumulation_time_s / 2.0;
    let first = raw.time_s.iter().copied().fold(f64::INFINITY, f64::min);
    let t0 = (origin_s + first - half).floor();
    if !t0.is_finite() || t0 < 0.0 {
        return Err(bad(path, "`time` holds a value that is not a finite time"));
    }
    let rel = |t: f64| (origin_s + t - t0).round();
    let to_i32 = |x: f64| {
        i32::try_from(x as i64).map_err(|_| {
            bad(
                path,
                &format!("a profile {x} s after the start overflows int"),
            )
        })
    };
    let start = raw.time_s.iter().map(|&t| to_i32(rel(t - half)));
    let stop = raw.time_s.iter().map(|&t| to_i32(rel(t + half)));
    Ok((
        start.collect::<Result<_>>()?,
        stop.collect::<Result<_>>()?,
        UNIX_EPOCH + Duration::from_secs(t0 as u64),
    ))
}

fn laser_shots(path: &Path, raw: &RawRun) -> Result<Vec<i32>> {
    let n_channels = raw.channels.len();
    let mut out = Vec::with_capacity(raw.n_profiles * n_channels);
    for &n in &raw.n_shots {
        let n = i32::try_from(n).map_err(|_| {
            bad(
                path,
                &format!("{n} shots in a profile do not fit `Laser_Shots` (int)"),
            )
        })?;
        out.extend(std::iter::repeat_n(n, n_channels));
    }
    Ok(out)
}

fn channels(path: &Path, raw: &RawRun, opts: &SccOptions) -> Result<Vec<SccChannel>> {
    let n = raw.channels.len();
    let ids: Vec<i32> = match &opts.channel_ids {
        Some(ids) if ids.len() != n => {
            return Err(bad(
                path,
                &format!(
                    "{} SCC channel IDs given for {n} channels ({})",
                    ids.len(),
                    raw.channels.join(", ")
                ),
            ));
        }
        Some(ids) => ids.clone(),
        None => (1..=n as i32).collect(),
    };
    let receiver = receiver_channels(path, raw)?;
    raw.channels
        .iter()
        .enumerate()
        .map(|(c, name)| {
            let cfg = receiver.iter().find(|r| &r.name == name).ok_or_else(|| {
                bad(
                    path,
                    &format!("channel `{name}` is not a channel of the `config` attribute"),
                )
            })?;
            channel(path, raw, c, cfg, ids[c])
        })
        .collect()
}

/// The receiver's channels as the simulation saw them: the `config` attribute expanded
/// by the same code ([`crate::receiver::expand`]), so each channel's wavelength and
/// detector are exactly those its counts were drawn with.
pub(super) fn receiver_channels(path: &Path, raw: &RawRun) -> Result<Vec<ChannelConfig>> {
    let text = toml::to_string(&raw.config)
        .map_err(|e| bad(path, &format!("the `config` attribute: {e}")))?;
    let loaded = crate::loaded::load_str(&text, path, &[])
        .map_err(|e| bad(path, &format!("the `config` attribute: {e}")))?;
    Ok(loaded.channels)
}

fn channel(
    path: &Path,
    raw: &RawRun,
    c: usize,
    cfg: &ChannelConfig,
    id: i32,
) -> Result<SccChannel> {
    let instrument = &cfg.config.instrument;
    let analog = match (cfg.record, instrument.detector.as_ref()) {
        (crate::receiver::Record::Analog, Some(d)) => {
            Some(crate::detector::Analog::from_config(d, raw.bin_width_s))
        }
        _ => None,
    };
    let (dead_time_ns, dead_time_type) = match analog {
        Some(_) => (0.0, 0),
        None => dead_time(instrument.detector.as_ref()),
    };
    let res = SPEED_OF_LIGHT_M_PER_S * raw.bin_width_s / 2.0;
    // the first bin after the trigger: bin `pretrigger_bins` (the pre-trigger bins
    // before it, at negative range), whose start is the range Trigger_Delay encodes
    let first_signal_bin = raw.pretrigger_bins.min(raw.n_bins - 1);
    let first_bin_start_m = raw.range_m[first_signal_bin] - res / 2.0;
    let bins = c * raw.n_bins..(c + 1) * raw.n_bins;
    let noise = &raw.expected_noise[bins.clone()];
    let not_background = not_background(raw, bins, cfg, analog.is_some());
    let window = background_bins(&not_background, noise, raw.pretrigger_bins)
        .ok_or_else(|| no_background(path, &cfg.name, raw.pretrigger_bins))?;
    Ok(SccChannel {
        name: cfg.name.clone(),
        id,
        rep_rate_hz: raw.rep_rate_hz.round() as i32,
        wavelength_nm: instrument.wavelength_nm,
        detected_wavelength_nm: cfg.detection_wavelength_nm(),
        range_resolution_m: res,
        background_m: (
            raw.range_m[window.start] - res / 2.0,
            raw.range_m[window.end - 1] + res / 2.0,
        ),
        dead_time_ns,
        dead_time_type,
        trigger_delay_ns: 2.0 * first_bin_start_m / SPEED_OF_LIGHT_M_PER_S * 1e9,
        first_signal_rangebin: first_signal_bin as i32,
        acquisition_mode: match analog {
            Some(_) => ACQUISITION_ANALOG,
            None => ACQUISITION_PHOTON_COUNTING,
        },
        daq_range_mv: analog.as_ref().map_or(0.0, |a| a.adc_range_v * 1e3),
        analog_mv_per_code: analog.as_ref().map(|a| a.volts_per_code() * 1e3),
    })
}

/// `Dead_Time` (ns) and `Dead_Time_Corr_Type` (0 non-paralyzable, 1 paralyzable) of a
/// detector; an absent detector is an ideal counter (0 ns, type 0).
fn dead_time(detector: Option<&DetectorConfig>) -> (f64, i32) {
    match detector {
        None => (0.0, 0),
        Some(d) => (
            d.dead_time_s * 1e9,
            match d.dead_time_model {
                DeadTimeModel::Nonparalyzable => 0,
                DeadTimeModel::Paralyzable => 1,
            },
        ),
    }
}

/// What a channel's expected record per shot holds beyond its background + dark, bin by
/// bin (`bins` its rows of the (channel, bin) variables): the expected signal, the
/// signal-induced counts (`expected_induced`) and the afterpulses beyond those the
/// background + dark alone would give — `expected_afterpulse` less the afterpulses of a
/// record of background + dark only (through the dead time), by the simulation's own
/// laws (`Afterpulsing::expected`, `DeadTime::recorded_means`). The afterpulses of the
/// background + dark are part of the constant level the SCC subtracts; those of the
/// signal are not. An analog record has no afterpulses.
fn not_background(
    raw: &RawRun,
    bins: std::ops::Range<usize>,
    cfg: &ChannelConfig,
    analog: bool,
) -> Vec<f64> {
    let noise = &raw.expected_noise[bins.clone()];
    let detector = cfg.config.instrument.detector.as_ref();
    let afterpulsing = detector
        .and_then(|d| d.afterpulsing.as_ref())
        .filter(|_| !analog);
    let of_background = match afterpulsing {
        Some(a) => {
            let recorded = match detector.filter(|d| d.dead_time_s > 0.0) {
                Some(d) => crate::detector::DeadTime {
                    tau_s: d.dead_time_s,
                    model: d.dead_time_model,
                    bin_width_s: raw.bin_width_s,
                    pixels: d.pixels.unwrap_or(1),
                }
                .recorded_means(noise),
                None => noise.to_vec(),
            };
            crate::detector::afterpulse::Afterpulsing::from_config(a, raw.bin_width_s)
                .expected(&recorded)
        }
        None => vec![0.0; noise.len()],
    };
    let afterpulse = &raw.expected_afterpulse[bins.clone()];
    raw.expected_signal[bins.clone()]
        .iter()
        .zip(&raw.expected_induced[bins])
        .zip(afterpulse.iter().zip(&of_background))
        .map(|((s, i), (a, b))| s + i + (a - b).max(0.0))
        .collect()
}

/// Whether a bin is free of signal: its expected signal per shot is below
/// [`SIGNAL_FREE_SHARE`] of its expected background + dark per shot, or is exactly 0.
pub fn signal_free(signal: f64, noise: f64) -> bool {
    signal == 0.0 || signal < SIGNAL_FREE_SHARE * noise
}

/// The bins of the SCC background window (`Background_Low/High`): the longest run of
/// consecutive [`signal_free`] bins, the farthest of equally long runs; within the
/// first `pretrigger_bins` bins (recorded before the pulse) when there are any, else
/// anywhere in the profile. `None` when no bin qualifies. `signal` is what the expected
/// record holds beyond the background + dark (the largest over the profiles: the
/// signal, its signal-induced counts and its afterpulses), `noise` the smallest
/// background + dark.
pub fn background_bins(
    signal: &[f64],
    noise: &[f64],
    pretrigger_bins: usize,
) -> Option<std::ops::Range<usize>> {
    let n = if pretrigger_bins > 0 {
        pretrigger_bins.min(signal.len())
    } else {
        signal.len()
    };
    let mut best: Option<std::ops::Range<usize>> = None;
    let mut start = None;
    for i in 0..=n {
        let free = i < n && signal_free(signal[i], noise[i]);
        match (free, start) {
            (true, None) => start = Some(i),
            (false, Some(s)) => {
                if best.as_ref().is_none_or(|b| i - s >= b.len()) {
                    best = Some(s..i);
                }
                start = None;
            }
            _ => {}
        }
    }
    best
}

/// The refusal when a channel has no signal-free bin, with what to do about it.
fn no_background(path: &Path, channel: &str, pretrigger_bins: usize) -> Error {
    let share = SIGNAL_FREE_SHARE * 100.0;
    let reason = if pretrigger_bins > 0 {
        format!(
            "channel `{channel}`: none of the {pretrigger_bins} pre-trigger bins has an \
             expected signal (with its signal-induced counts and afterpulses) below {share} % \
             of the expected background + dark, so the SCC background window \
             (Background_Low/High) has no place: check the pre-trigger bins"
        )
    } else {
        format!(
            "channel `{channel}`: no bin has an expected signal (with its signal-induced \
             counts and afterpulses) below {share} % of the expected background + dark, so \
             the SCC background window \
             (Background_Low/High) has no place: record bins beyond the signal (raise \
             acquisition.top_altitude_km, e.g. above 86 km where the US76 atmosphere ends) \
             or pre-trigger bins"
        )
    };
    bad(path, &reason)
}

/// The global attributes: measurement ID, start date and times, system (from the run's
/// `config` attribute).
pub(super) fn text_attributes(
    config: &toml::Table,
    opts: &SccOptions,
    start: SystemTime,
    stop: SystemTime,
) -> Result<Vec<(&'static str, String)>> {
    let s = humantime::format_rfc3339_seconds(start).to_string(); // 2004-03-21T06:30:00Z
    let e = humantime::format_rfc3339_seconds(stop).to_string();
    let date = s[0..10].replace('-', "");
    let hms = |t: &str| t[11..19].replace(':', "");
    let id = measurement_id(opts, &date)?;
    let system = config
        .get("name")
        .and_then(|v| v.as_str())
        .map_or_else(|| "lidarsim".to_string(), |n| format!("lidarsim: {n}"));
    Ok(vec![
        ("Measurement_ID", id),
        ("RawData_Start_Date", date),
        ("RawData_Start_Time_UT", hms(&s)),
        ("RawData_Stop_Time_UT", hms(&e)),
        ("System", system),
    ])
}

/// `Measurement_ID`: the one given (checked against `YYYYMMDDccNN`), else the start
/// date, the station ID and `00`.
fn measurement_id(opts: &SccOptions, date: &str) -> Result<String> {
    let station = &opts.station_id;
    let ok_station = station.len() == 2 && station.bytes().all(|b| b.is_ascii_alphanumeric());
    if !ok_station {
        return Err(Error::Unsupported(format!(
            "SCC station ID `{station}`: must be two letters or digits (the EARLINET call sign)"
        )));
    }
    let Some(id) = &opts.measurement_id else {
        return Ok(format!("{date}{station}00"));
    };
    let b = id.as_bytes();
    let ok = b.len() == 12
        && b[..8].iter().all(u8::is_ascii_digit)
        && b[8..10].iter().all(u8::is_ascii_alphanumeric)
        && b[10..].iter().all(u8::is_ascii_digit);
    let form = format!(
        "must be YYYYMMDDccNN: the data's start date, a 2-character station ID, 2 digits \
         (e.g. {date}{station}00)"
    );
    if !ok {
        return Err(Error::Unsupported(format!("--measurement-id {id}: {form}")));
    }
    let given = &id[..8];
    if !is_calendar_date(given) {
        return Err(Error::Unsupported(format!(
            "--measurement-id {id}: {given} is not a calendar date; {form}"
        )));
    }
    if given != date {
        return Err(Error::Unsupported(format!(
            "--measurement-id {id}: its date {given} is not the data's start date {date} \
             (RawData_Start_Date); {form}"
        )));
    }
    Ok(id.clone())
}

/// Whether `yyyymmdd` (8 ASCII digits) is a date of the Gregorian calendar.
fn is_calendar_date(yyyymmdd: &str) -> bool {
    let num = |r: std::ops::Range<usize>| yyyymmdd[r].parse::<u32>().unwrap_or(0);
    let (y, m, d) = (num(0..4), num(4..6), num(6..8));
    let leap = (y % 4 == 0 && y % 100 != 0) || y % 400 == 0;
    let days = match m {
        1 | 3 | 5 | 7 | 8 | 10 | 12 => 31,
        4 | 6 | 9 | 11 => 30,
        2 if leap => 29,
        2 => 28,
        _ => return false,
    };
    (1..=days).contains(&d)
}

#[cfg(test)]
mod measurement_id_tests {
    use super::*;

    #[test]
    fn measurement_ids_carry_a_calendar_date_equal_to_the_data_start() {
        for good in ["20240229", "20000229", "20241231", "20040321"] {
            assert!(is_calendar_date(good), "{good}");
        }
        for bad in [
            "20241301", "20230229", "19000229", "20240431", "20240100", "20240001",
        ] {
            assert!(!is_calendar_date(bad), "{bad}");
        }
        let opts = |id: &str| SccOptions {
            measurement_id: Some(id.into()),
            station_id: "ls".into(),
            channel_ids: None,
        };
        assert_eq!(
            measurement_id(&opts("20040321ls07"), "20040321").unwrap(),
            "20040321ls07"
        );
        let e = measurement_id(&opts("20241301ls00"), "20241301").unwrap_err();
        assert!(e.to_string().contains("not a calendar date"), "{e}");
        let e = measurement_id(&opts("20040322ls00"), "20040321").unwrap_err();
        assert!(
            e.to_string().contains("not the data's start date 20040321"),
            "{e}"
        );
    }
}
