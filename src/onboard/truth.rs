//! The truth of the onboard product (docs/file-format.md, "The truth of the onboard
//! product"), averaged exactly as the counts are summed: per region, the truth of each
//! distinct column of the scene at the region's resolution (the raw file's point truth
//! averaged over each region bin's native bins, the expected signal summed over them),
//! and per downlinked profile the columns its shots saw with their shares, the mean
//! background and dark counts per shot and native bin, the pulse energy and, with an
//! orbit, the geolocation of its centre.
//!
//! The names, long names and units of the point truth are the raw file's
//! ([`crate::output::raw_file::truth::COLUMN_TRUTH`]); the per-column truth is computed
//! once per column, the per-profile rows from the shots' columns as the draw assigns them.

use super::RegionLayout;
use crate::error::Result;
use crate::output::product::{RegionDims, RegionTruth, RegionVar};
use crate::output::raw_file::AttrValue;
use crate::output::raw_file::bin_mean::{self, BIN_MEAN_TRUTH, CELL_METHODS};
use crate::output::raw_file::content::{GEOLOCATION, geolocation_variables};
use crate::output::raw_file::truth::COLUMN_TRUTH;
use crate::output::raw_file::truth::Truth;
use crate::scenario::{ExpectedProfile, Lidar};
use crate::scene::orbit::Orbit;
use std::ops::Range;

/// `long_name`, `units`, then `extra`, as a region variable's attributes.
fn attributes(long_name: &str, units: &str, extra: &[(&str, &str)]) -> Vec<(String, AttrValue)> {
    [("long_name", long_name), ("units", units)]
        .iter()
        .chain(extra)
        .map(|(k, v)| (k.to_string(), AttrValue::Str(v.to_string())))
        .collect()
}

/// What the suffix of an averaged point truth's long name says.
const AVERAGED: &str = ": mean over the region bin's native bins of the value at their centres";

/// The fixed variables of a region, in order: `range_weight` (bin), `lidar_constant`,
/// `nominal_pulse_energy`, `counts_per_photoelectron` and `counts_offset` (channel: how
/// the channel's counts record photoelectrons, 1 and 0 for a photon counter), the point truth of [`COLUMN_TRUTH`], the bin means of
/// [`BIN_MEAN_TRUTH`] (the mean of the native bins' means is the region bin's), then
/// `expected_signal` and `attenuated_backscatter` (column, channel, bin); `data(name)`
/// gives each one's values, `beta_mol` the attributes of `beta_mol` beyond its long name
/// and units (the raw file's, [`crate::output::raw_file::truth::beta_mol_attributes`]).
pub fn fixed_variables(
    beta_mol: &[(String, AttrValue)],
    mut data: impl FnMut(&str) -> Result<Vec<f64>>,
) -> Result<Vec<RegionVar>> {
    use RegionDims::{Bin, Channel, ColumnChannelBin};
    let mut vars = Vec::new();
    let mut push = |name: &str, dims, attributes| -> Result<()> {
        vars.push(RegionVar {
            name: name.into(),
            dims,
            attributes,
            data: data(name)?,
        });
        Ok(())
    };
    push(
        "range_weight",
        Bin,
        attributes(
            "range weight of the region bin: sum over its native bins of the integral of overlap / range^2",
            "m-1",
            &[],
        ),
    )?;
    push(
        "lidar_constant",
        Channel,
        attributes(
            "lidar constant C = K E0 (lambda/hc) A TR TF Q: expected_signal = C attenuated_backscatter range_weight",
            "m2 sr",
            &[],
        ),
    )?;
    push(
        "nominal_pulse_energy",
        Channel,
        attributes(
            "nominal emitted pulse energy E0 of the channel (expected_signal and lidar_constant are at this energy)",
            "J",
            &[],
        ),
    )?;
    push(
        "counts_per_photoelectron",
        Channel,
        attributes(
            "mean counts one photoelectron adds to one shot's native bin: 1 for a photon-counting channel; for an analog channel its ADC codes per photoelectron (the raw file's analog_counts_per_photoelectron, of the low-passed photoelectrons)",
            "count",
            &[],
        ),
    )?;
    push(
        "counts_offset",
        Channel,
        attributes(
            "mean counts one shot's native bin records without light: 0 for a photon-counting channel; for an analog channel its baseline in ADC codes (analog_offset / adc_volts_per_count); a region bin of native_bins_merged native bins and a profile of n_shots shots hold n_shots x native_bins_merged x this",
            "count",
            &[],
        ),
    )?;
    for (name, long_name, units, _) in COLUMN_TRUTH {
        let mut a = attributes(&format!("{long_name}{AVERAGED}"), units, &[]);
        if name == "beta_mol" {
            a.extend(beta_mol.iter().cloned());
        }
        push(name, ColumnChannelBin, a)?;
    }
    for (name, long_name, units, _) in BIN_MEAN_TRUTH {
        let long_name = format!("{long_name}: the region bin's, the mean over its native bins");
        push(
            name,
            ColumnChannelBin,
            attributes(&long_name, units, &[CELL_METHODS]),
        )?;
    }
    push(
        "expected_signal",
        ColumnChannelBin,
        attributes(
            "expected signal counts per shot at the nominal pulse energy in the column, summed over the region bin's native bins",
            "count",
            &[],
        ),
    )?;
    push(
        "attenuated_backscatter",
        ColumnChannelBin,
        attributes(
            "attenuated backscatter of the column averaged as the counts integrate it: expected_signal / (lidar_constant range_weight)",
            "m-1 sr-1",
            &[(
                "standard_name",
                "volume_attenuated_backwards_scattering_function_in_air",
            )],
        ),
    )?;
    Ok(vars)
}

/// The per-profile f64 variables of a region, in the order of a row's values:
/// `pulse_energy`, the geolocation (with an orbit), `expected_background`,
/// `expected_dark`, `profile_column_weight`.
pub fn per_profile_variables(geolocation: bool) -> Vec<RegionVar> {
    use RegionDims::{Profile, ProfileChannel, ProfileK};
    let var = |name: &str, dims, attributes| RegionVar {
        name: name.into(),
        dims,
        attributes,
        data: Vec::new(),
    };
    let mut vars = vec![var(
        "pulse_energy",
        ProfileChannel,
        attributes(
            "mean emitted pulse energy of the profile's shots at the channel's laser line, as an energy monitor reports it",
            "J",
            &[],
        ),
    )];
    if geolocation {
        // the raw file's definitions, long names and attributes
        vars.extend(geolocation_variables().into_iter().map(|v| {
            let mut a = attributes(&v.long_name, &v.units, &[]);
            a.extend(v.attributes);
            var(&v.name, Profile, a)
        }));
    }
    vars.extend([
        var(
            "expected_background",
            ProfileChannel,
            attributes(
                "expected sky-background counts per shot and native bin, mean over the profile's shots",
                "count",
                &[],
            ),
        ),
        var(
            "expected_dark",
            ProfileChannel,
            attributes(
                "expected dark counts per shot and native bin, mean over the profile's shots",
                "count",
                &[],
            ),
        ),
        var(
            "profile_column_weight",
            ProfileK,
            attributes(
                "share of the profile's shots that saw each of profile_column (0 in an unused slot)",
                "1",
                &[],
            ),
        ),
    ]);
    vars
}

/// The `coordinates` of a region's (profile, …) variables.
pub fn profile_coordinates(geolocation: bool) -> String {
    match geolocation {
        true => format!("time {}", GEOLOCATION.join(" ")),
        false => "time".into(),
    }
}

/// The `k` slots of a region of `shots` shots in a scene of `columns` columns: the most
/// columns its profiles can see.
pub fn slots(columns: usize, shots: u32) -> usize {
    columns.min(shots as usize).max(1)
}

/// The cells of a region's truth: every column of the scene, every channel the region
/// holds, every region bin (column-major, then channel-major).
struct RegionCells<'a> {
    /// Per column, per channel: the model.
    columns: &'a [&'a [ExpectedProfile]],
    held: Vec<usize>,
    r: &'a RegionLayout,
}

impl RegionCells<'_> {
    /// The native bins of region bin `j`.
    fn native_bins(&self, j: usize) -> std::ops::Range<usize> {
        let r = self.r;
        r.first_bin + j * r.merge..r.first_bin + (j + 1) * r.merge
    }

    /// `f(model, native bins)` in every cell.
    fn values(&self, f: &dyn Fn(&ExpectedProfile, std::ops::Range<usize>) -> f64) -> Vec<f64> {
        let mut out = Vec::with_capacity(self.columns.len() * self.held.len() * self.r.bins);
        for col in self.columns {
            for &c in &self.held {
                out.extend((0..self.r.bins).map(|j| f(&col[c], self.native_bins(j))));
            }
        }
        out
    }

    /// The mean of point truth `f` over each cell's native bins.
    fn mean(&self, f: crate::output::raw_file::truth::Truth) -> Vec<f64> {
        let m = self.r.merge as f64;
        self.values(&|e, bins| bins.map(|i| f(e, i)).sum::<f64>() / m)
    }
}

/// `signal / (constant · range_weight)` per cell (`constant` per held channel,
/// `range_weight` per region bin), 0 where either is 0.
fn attenuated_backscatter(signal: &[f64], constant: &[f64], range_weight: &[f64]) -> Vec<f64> {
    let bins = range_weight.len().max(1);
    signal
        .iter()
        .enumerate()
        .map(|(i, s)| {
            let (c, w) = (constant[i / bins % constant.len()], range_weight[i % bins]);
            if w > 0.0 && c > 0.0 { s / (c * w) } else { 0.0 }
        })
        .collect()
}

/// The truth of region `r`: every one of the scene's `columns` (per column, per channel:
/// the model) at the region's resolution, and its per-profile variables.
pub fn region_truth(
    lidar: &Lidar,
    columns: &[&[ExpectedProfile]],
    r: &RegionLayout,
    geolocation: bool,
) -> Result<RegionTruth> {
    let cells = RegionCells {
        columns,
        held: r.channel_indices(lidar.channels.len()),
        r,
    };
    let e0 = &columns[0][0];
    let range_weight: Vec<f64> = (0..r.bins)
        .map(|j| e0.range_weight[cells.native_bins(j)].iter().sum())
        .collect();
    let channel = |f: &dyn Fn(usize) -> f64| cells.held.iter().map(|&c| f(c)).collect::<Vec<_>>();
    let constant = channel(&|c| lidar.channels[c].instrument.signal_constant);
    let expected_signal = cells.values(&|e, bins| e.signal[bins].iter().sum());
    let attenuated_backscatter = attenuated_backscatter(&expected_signal, &constant, &range_weight);
    let beta_mol = crate::output::raw_file::truth::beta_mol_attributes(lidar);
    let fixed = fixed_variables(&beta_mol, |name| {
        if let Some((ms_alpha, alpha)) = bin_mean::ms_weighted(name) {
            let sum = |f: Truth, e: &ExpectedProfile, bins: Range<usize>| -> f64 {
                bins.map(|i| f(e, i)).sum()
            };
            return Ok(cells.values(&|e, bins| {
                let (a, b) = (sum(ms_alpha, e, bins.clone()), sum(alpha, e, bins));
                crate::atmosphere::bin_mean::ms_factor(a, b)
            }));
        }
        Ok(match name {
            "range_weight" => range_weight.clone(),
            "lidar_constant" => constant.clone(),
            "nominal_pulse_energy" => {
                channel(&|c| lidar.channels[c].loaded.config.instrument.pulse_energy_j)
            }
            "counts_per_photoelectron" => channel(&|c| {
                let analog = lidar.channels[c].instrument.analog.as_ref();
                analog.map_or(1.0, crate::detector::Analog::codes_per_photoelectron)
            }),
            "counts_offset" => channel(&|c| {
                let analog = lidar.channels[c].instrument.analog.as_ref();
                analog.map_or(0.0, crate::detector::Analog::offset_codes)
            }),
            "expected_signal" => expected_signal.clone(),
            "attenuated_backscatter" => attenuated_backscatter.clone(),
            _ => {
                let mut truth = COLUMN_TRUTH.iter().chain(&BIN_MEAN_TRUTH);
                let f = truth.find(|t| t.0 == name).map(|t| t.3);
                f.map(|f| cells.mean(f)).unwrap_or_default()
            }
        })
    })?;
    Ok(RegionTruth {
        columns: columns.len(),
        slots: slots(columns.len(), r.shots),
        fixed,
        per_profile: per_profile_variables(geolocation),
        profile_coordinates: profile_coordinates(geolocation),
    })
}

/// What one native shot saw: its column, each channel's expected background and dark
/// counts per native bin, and its energy factor (relative to the nominal energy).
#[derive(Debug, Clone)]
pub struct ShotTruth {
    /// Index of its column (0 in a static scene).
    pub column: usize,
    /// Per channel: background counts per native bin.
    pub background: Vec<f64>,
    /// Per channel: dark counts per native bin.
    pub dark: Vec<f64>,
    /// Its energy factor.
    pub energy: f64,
}

/// The running sums of one region's pending profile.
#[derive(Debug, Clone, Default)]
struct PendingProfile {
    /// (column, shots) in the order first seen.
    columns: Vec<(usize, u64)>,
    background: Vec<f64>,
    dark: Vec<f64>,
    energy: f64,
    shots: u64,
}

/// The per-profile rows of every region of the product, built shot by shot.
pub struct ProfileRows {
    regions: Vec<(RegionLayout, usize)>,
    /// Per region: the channels it holds.
    held: Vec<Vec<usize>>,
    pending: Vec<PendingProfile>,
    /// Per region: the run's index of its next profile.
    next: Vec<usize>,
    orbit: Option<Orbit>,
    rep_rate_hz: f64,
    /// Each channel's nominal pulse energy (its laser line's), J.
    nominal_energy_j: Vec<f64>,
}

impl ProfileRows {
    /// The rows of `regions` (each with its slots) of an instrument of `channels`
    /// channels, whose first profiles in the run are `first`.
    pub fn new(
        regions: Vec<(RegionLayout, usize)>,
        channels: usize,
        first: Vec<usize>,
        orbit: Option<Orbit>,
        rep_rate_hz: f64,
        nominal_energy_j: Vec<f64>,
    ) -> Self {
        ProfileRows {
            held: regions
                .iter()
                .map(|(r, _)| r.channel_indices(channels))
                .collect(),
            pending: vec![PendingProfile::default(); regions.len()],
            regions,
            next: first,
            orbit,
            rep_rate_hz,
            nominal_energy_j,
        }
    }

    /// Adds one shot to every region's pending profile.
    pub fn add_shot(&mut self, shot: &ShotTruth) {
        for (held, p) in self.held.iter().zip(&mut self.pending) {
            p.background.resize(held.len(), 0.0);
            p.dark.resize(held.len(), 0.0);
            for (h, &c) in held.iter().enumerate() {
                p.background[h] += shot.background[c];
                p.dark[h] += shot.dark[c];
            }
            p.energy += shot.energy;
            p.shots += 1;
            match p.columns.iter_mut().find(|c| c.0 == shot.column) {
                Some(c) => c.1 += 1,
                None => p.columns.push((shot.column, 1)),
            }
        }
    }

    /// The row of region `k`'s profile that its last shot completed (values and
    /// columns, as [`crate::output::product::ProfileRow`] takes them); starts the next.
    pub fn take(&mut self, k: usize) -> (Vec<f64>, Vec<i32>) {
        let p = std::mem::take(&mut self.pending[k]);
        let (r, slots) = &self.regions[k];
        let j = self.next[k];
        self.next[k] += 1;
        let n = p.shots.max(1) as f64;
        // E0_c·(Σf_s/n) of each channel held: exactly E0_c when every factor is 1
        let factor = p.energy / n;
        let mut values: Vec<f64> = self.held[k]
            .iter()
            .map(|&c| self.nominal_energy_j[c] * factor)
            .collect();
        if let Some(o) = &self.orbit {
            let g = o.position(profile_time(j, r.shots, self.rep_rate_hz));
            values.extend([g.latitude_deg, g.longitude_deg, g.along_track_m]);
        }
        values.extend(p.background.iter().map(|b| b / n));
        values.extend(p.dark.iter().map(|d| d / n));
        let (columns, weights) = crate::simulate::profile_columns(&p.columns, *slots);
        values.extend(weights);
        (values, columns)
    }
}

/// Profile-centre time of profile `j` of a region of `shots` shots, s since the start.
pub fn profile_time(j: usize, shots: u32, rep_rate_hz: f64) -> f64 {
    (j as f64 + 0.5) * f64::from(shots) / rep_rate_hz
}
