//! Averaging schemes: built-in `none`, `uniform:N` and `caliop` (docs/config.md), or a
//! TOML file of `[[regions]]` with `top_km`, `bottom_km`, `vertical_resolution_m` and
//! `shots_averaged`, from the top down.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// One altitude region of a scheme.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Region {
    /// Top of the region, km.
    pub top_km: f64,
    /// Bottom of the region, km.
    pub bottom_km: f64,
    /// Vertical resolution of the downlinked bins, m (a whole number of native bins).
    pub vertical_resolution_m: f64,
    /// Shots summed per downlinked profile.
    pub shots_averaged: u32,
}

/// A named averaging scheme; `regions` empty = everything at native resolution.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Scheme {
    /// Its name (`caliop`, `uniform:15`, the file's stem).
    pub name: String,
    /// Regions from the top down; empty for `none` and `uniform:N` (the whole window).
    pub regions: Vec<Region>,
    /// Shots summed over the whole window when `regions` is empty.
    pub uniform_shots: u32,
    /// The scheme file it was read from (an input no output may replace); not part of
    /// the scheme's identity.
    #[serde(skip)]
    pub file: Option<std::path::PathBuf>,
    /// Channels with a layout of their own (built-in schemes only: `caliop`'s 1064 nm
    /// channel); every other channel takes `regions`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub channel_regions: Vec<ChannelRegions>,
}

/// The regions of the channels at one wavelength, from the top down.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ChannelRegions {
    /// The channels' wavelength, nm.
    pub wavelength_nm: f64,
    /// Their regions, from the top down.
    pub regions: Vec<Region>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SchemeFile {
    regions: Vec<Region>,
}

/// A region from (top km, bottom km, vertical resolution m, shots averaged).
fn region(top_km: f64, bottom_km: f64, vertical_resolution_m: f64, shots_averaged: u32) -> Region {
    Region {
        top_km,
        bottom_km,
        vertical_resolution_m,
        shots_averaged,
    }
}

/// CALIOP's onboard averaging of its 532 nm channels on its 30 m native grid
/// (docs/config.md; Hunt et al. 2009, J. Atmos. Oceanic Technol. 26, 1214, Table 2;
/// Winker et al. 2009, J. Atmos. Oceanic Technol. 26, 2310, Table 1; the CALIPSO Data
/// Products Catalog, PC-SCI-503, Lidar Level 1B, altitude regions): 583 bins.
pub fn caliop_regions() -> Vec<Region> {
    vec![
        region(40.0, 30.1, 300.0, 15),
        region(30.1, 20.2, 180.0, 5),
        region(20.2, 8.2, 60.0, 3),
        region(8.2, -0.5, 30.0, 1),
        region(-0.5, -2.0, 300.0, 1),
    ]
}

/// CALIOP's onboard averaging of its 1064 nm channel (same sources as
/// [`caliop_regions`]): nothing above 30.1 km, 60 m from −0.5 to 8.2 km (not 30 m), the
/// 532 nm layout elsewhere: 55 + 200 + 145 + 5 = 405 bins. With the 532 nm channels'
/// 583 bins twice, 16-bit words and 20.16 shots s⁻¹ the downlink is 315 kbit/s, CALIOP's
/// 316 kbit/s (docs/model.md).
pub fn caliop_1064_regions() -> Vec<Region> {
    vec![
        region(30.1, 20.2, 180.0, 5),
        region(20.2, 8.2, 60.0, 3),
        region(8.2, -0.5, 60.0, 1),
        region(-0.5, -2.0, 300.0, 1),
    ]
}

impl Scheme {
    /// `none`, `uniform:N`, `caliop`, or a TOML file's path.
    pub fn parse(spec: &str) -> Result<Scheme> {
        let fail = |why: String| Error::Unsupported(format!("--scheme {spec}: {why}"));
        match spec {
            "none" => Ok(Scheme {
                name: "none".into(),
                regions: vec![],
                uniform_shots: 1,
                file: None,
                channel_regions: vec![],
            }),
            "caliop" => Ok(Scheme {
                name: "caliop".into(),
                regions: caliop_regions(),
                uniform_shots: 1,
                file: None,
                channel_regions: vec![ChannelRegions {
                    wavelength_nm: 1064.0,
                    regions: caliop_1064_regions(),
                }],
            }),
            _ if spec.starts_with("uniform:") => {
                let n: u32 = spec["uniform:".len()..]
                    .parse()
                    .ok()
                    .filter(|&n| (1..=1_000_000).contains(&n))
                    .ok_or_else(|| fail("N must be a whole number from 1 to 1e6".into()))?;
                Ok(Scheme {
                    name: spec.into(),
                    regions: vec![],
                    uniform_shots: n,
                    file: None,
                    channel_regions: vec![],
                })
            }
            _ => {
                let path = std::path::Path::new(spec);
                let text = crate::input_file::read_to_string("--scheme", path)?;
                let file: SchemeFile =
                    toml::from_str(&text).map_err(|e| fail(e.message().replace('\n', " ")))?;
                let name = path
                    .file_stem()
                    .map_or(spec.into(), |s| s.to_string_lossy().into());
                let scheme = Scheme {
                    name,
                    regions: file.regions,
                    uniform_shots: 1,
                    file: Some(path.to_path_buf()),
                    channel_regions: vec![],
                };
                scheme.check().map_err(fail)?;
                Ok(scheme)
            }
        }
    }

    /// Regions from the top down, each below the previous, with positive resolutions.
    fn check(&self) -> std::result::Result<(), String> {
        if self.regions.is_empty() {
            return Err("a scheme file needs at least one [[regions]]".into());
        }
        for (i, r) in self.regions.iter().enumerate() {
            let finite = [r.top_km, r.bottom_km, r.vertical_resolution_m]
                .iter()
                .all(|x| x.is_finite());
            if !finite
                || r.top_km <= r.bottom_km
                || r.vertical_resolution_m <= 0.0
                || r.shots_averaged == 0
            {
                return Err(format!(
                    "regions[{i}]: needs top_km > bottom_km, vertical_resolution_m > 0, shots_averaged ≥ 1"
                ));
            }
            let thickness_m = (r.top_km - r.bottom_km) * 1e3;
            if (thickness_m / r.vertical_resolution_m).round() < 1.0 {
                return Err(format!(
                    "regions[{i}]: top_km − bottom_km = {} m holds no bin of \
                     vertical_resolution_m = {} m; a region is at least one bin thick",
                    format_args!("{thickness_m:.1}"),
                    r.vertical_resolution_m
                ));
            }
            if i > 0 && (r.top_km - self.regions[i - 1].bottom_km).abs() > 1e-9 {
                return Err(format!(
                    "regions[{i}]: its top must be the previous region's bottom"
                ));
            }
        }
        Ok(())
    }

    /// The regions laid on a native grid: `bin_altitude_m(i)` gives bin i's centre
    /// altitude (bins in range order, altitude decreasing for a space-borne lidar),
    /// `native_vertical_m` the altitude extent of one native bin.
    pub fn layout(
        &self,
        n_bins: usize,
        bin_altitude_m: &dyn Fn(usize) -> f64,
        native_vertical_m: f64,
    ) -> Result<Vec<RegionLayout>> {
        if self.regions.is_empty() {
            return Ok(vec![RegionLayout {
                first_bin: 0,
                merge: 1,
                bins: n_bins,
                shots: self.uniform_shots,
                region: None,
                channels: None,
            }]);
        }
        self.regions_layout(
            &self.regions,
            None,
            n_bins,
            bin_altitude_m,
            native_vertical_m,
        )
    }

    /// The layout of every channel, the channels at `wavelengths_nm` (one per channel,
    /// in order): each channel takes its own regions ([`Scheme::channel_regions`], else
    /// [`Scheme::regions`]); a region that several channels share is one region listing
    /// them ([`RegionLayout::channels`]; `None` when it holds every channel). Regions in
    /// order of their first native bin (from the top), then of their resolution. A scheme
    /// without channel regions gives [`Scheme::layout`].
    pub fn channel_layout(
        &self,
        wavelengths_nm: &[f64],
        n_bins: usize,
        bin_altitude_m: &dyn Fn(usize) -> f64,
        native_vertical_m: f64,
    ) -> Result<Vec<RegionLayout>> {
        let own = |w: f64| {
            self.channel_regions
                .iter()
                .position(|c| (c.wavelength_nm - w).abs() < 1e-6)
        };
        let groups: Vec<Option<usize>> = wavelengths_nm.iter().map(|&w| own(w)).collect();
        if groups.iter().all(Option::is_none) {
            return self.layout(n_bins, bin_altitude_m, native_vertical_m);
        }
        let base = self.layout(n_bins, bin_altitude_m, native_vertical_m)?;
        let mut out: Vec<RegionLayout> = Vec::new();
        let mut kinds: Vec<Option<usize>> = groups.clone();
        kinds.sort();
        kinds.dedup();
        for kind in kinds {
            let channels: Vec<usize> = (0..groups.len()).filter(|&c| groups[c] == kind).collect();
            let laid = match kind {
                None => base.clone(),
                Some(k) => {
                    // starting where the common layout's region of the same top starts,
                    // so that shared regions fall on the same native bins
                    let regions = &self.channel_regions[k].regions;
                    let start = regions.first().and_then(|first| {
                        base.iter()
                            .find(|b| {
                                b.region
                                    .as_ref()
                                    .is_some_and(|r| (r.top_km - first.top_km).abs() < 1e-9)
                            })
                            .map(|b| b.first_bin)
                    });
                    self.regions_layout(regions, start, n_bins, bin_altitude_m, native_vertical_m)?
                }
            };
            for r in laid {
                let same = |o: &&mut RegionLayout| {
                    (o.first_bin, o.merge, o.bins, o.shots)
                        == (r.first_bin, r.merge, r.bins, r.shots)
                };
                match out.iter_mut().find(same) {
                    Some(o) => {
                        let held = o.channels.get_or_insert_with(Vec::new);
                        held.extend(&channels);
                        held.sort_unstable();
                    }
                    None => out.push(RegionLayout {
                        channels: Some(channels.clone()),
                        ..r
                    }),
                }
            }
        }
        for r in &mut out {
            if r.channels
                .as_ref()
                .is_some_and(|c| c.len() == wavelengths_nm.len())
            {
                r.channels = None;
            }
        }
        out.sort_by_key(|r| (r.first_bin, r.merge));
        Ok(out)
    }

    /// `regions` laid on the native grid (see [`Scheme::layout`]), every channel; the
    /// first starting at native bin `start` if given, else at the first bin below its top.
    fn regions_layout(
        &self,
        regions: &[Region],
        start: Option<usize>,
        n_bins: usize,
        bin_altitude_m: &dyn Fn(usize) -> f64,
        native_vertical_m: f64,
    ) -> Result<Vec<RegionLayout>> {
        let top_bin = |top_m: f64| (0..n_bins).find(|&i| bin_altitude_m(i) < top_m);
        let mut out = Vec::with_capacity(regions.len());
        for (k, r) in regions.iter().enumerate() {
            let merge =
                whole_native_bins(r.vertical_resolution_m, native_vertical_m).ok_or_else(|| {
                    let ratio = r.vertical_resolution_m / native_vertical_m;
                    let lo = ratio.floor().max(1.0);
                    Error::Unsupported(format!(
                        "scheme {}: regions[{k}].vertical_resolution_m = {} m is {ratio:.3} \
                         native bins of {native_vertical_m:.3} m; it must be a whole number of \
                         native bins (within {} %), e.g. {:.2} or {:.2} m",
                        self.name,
                        r.vertical_resolution_m,
                        RESOLUTION_TOLERANCE * 100.0,
                        lo * native_vertical_m,
                        (lo + 1.0) * native_vertical_m
                    ))
                })?;
            let bins = ((r.top_km - r.bottom_km) * 1e3 / r.vertical_resolution_m).round() as usize;
            let first_bin = match out.last() {
                Some(prev) => {
                    let p: &RegionLayout = prev;
                    p.first_bin + p.merge * p.bins
                }
                None => start.or_else(|| top_bin(r.top_km * 1e3)).ok_or_else(|| {
                    Error::Unsupported(format!(
                        "scheme {}: the window does not reach {} km",
                        self.name, r.top_km
                    ))
                })?,
            };
            if first_bin + merge * bins > n_bins {
                // where the scheme's last bin ends: the bins the window lacks, below its
                // last bin (altitude falls with the bin for a space-borne lidar)
                let needed: usize = regions[k + 1..]
                    .iter()
                    .map(|q| {
                        let m = whole_native_bins(q.vertical_resolution_m, native_vertical_m)
                            .unwrap_or(1);
                        m * ((q.top_km - q.bottom_km) * 1e3 / q.vertical_resolution_m).round()
                            as usize
                    })
                    .sum::<usize>()
                    + first_bin
                    + merge * bins;
                let last = bin_altitude_m(n_bins - 1);
                let hint = if n_bins > 1 && bin_altitude_m(0) > last {
                    let reach_m = last - ((needed - n_bins) as f64 + 0.5) * native_vertical_m;
                    let reach_km = (reach_m / 10.0).floor() / 100.0;
                    format!("lower acquisition.bottom_altitude_km to {reach_km} km or below")
                } else {
                    "the window has too few bins for the scheme".to_string()
                };
                return Err(Error::Unsupported(format!(
                    "scheme {}: region {k} ({} to {} km) runs past the window's last bin; {hint}",
                    self.name, r.top_km, r.bottom_km,
                )));
            }
            out.push(RegionLayout {
                first_bin,
                merge,
                bins,
                shots: r.shots_averaged,
                region: Some(r.clone()),
                channels: None,
            });
        }
        Ok(out)
    }
}

/// How far a region's `vertical_resolution_m` may be from a whole number of native bins,
/// relative: 1 %, so that nominal labels pass (CALIOP's "30 m" bins are 29.93 m deep at
/// 3° off nadir, 0.23 % off) and mislabels do not (31 m on 29.93 m bins is 3.6 % off).
pub const RESOLUTION_TOLERANCE: f64 = 0.01;

/// The native bins one downlinked bin of `resolution_m` merges: the nearest whole
/// number, `None` when `resolution_m` is not within [`RESOLUTION_TOLERANCE`] of one.
pub fn whole_native_bins(resolution_m: f64, native_vertical_m: f64) -> Option<usize> {
    let ratio = resolution_m / native_vertical_m;
    let merge = ratio.round();
    (merge >= 1.0 && (ratio / merge - 1.0).abs() <= RESOLUTION_TOLERANCE).then_some(merge as usize)
}

/// A region on the native grid.
#[derive(Debug, Clone, PartialEq)]
pub struct RegionLayout {
    /// Its first native bin.
    pub first_bin: usize,
    /// Native bins merged per downlinked bin.
    pub merge: usize,
    /// Downlinked bins.
    pub bins: usize,
    /// Shots summed per downlinked profile.
    pub shots: u32,
    /// The scheme's region (None for `none` and `uniform:N`).
    pub region: Option<Region>,
    /// The channels it holds, in order (indices into the instrument's channels); `None`:
    /// every channel.
    pub channels: Option<Vec<usize>>,
}

impl RegionLayout {
    /// The channels it holds among `n_channels`.
    pub fn channel_indices(&self, n_channels: usize) -> Vec<usize> {
        self.channels
            .clone()
            .unwrap_or_else(|| (0..n_channels).collect())
    }

    /// The first channel it holds (its report row's channel).
    pub fn first_channel(&self) -> usize {
        self.channels
            .as_ref()
            .and_then(|c| c.first().copied())
            .unwrap_or(0)
    }
}
