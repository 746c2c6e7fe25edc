//! Averaging schemes: built-in `none`, `uniform:N` and `caliop` (interface.md), or a
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
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SchemeFile {
    regions: Vec<Region>,
}

/// CALIOP's onboard averaging on its 30 m native grid (interface.md; Hunt et al. 2009,
/// J. Atmos. Oceanic Technol. 26, 1214): 583 bins.
pub fn caliop_regions() -> Vec<Region> {
    let r = |top_km, bottom_km, vertical_resolution_m, shots_averaged| Region {
        top_km,
        bottom_km,
        vertical_resolution_m,
        shots_averaged,
    };
    vec![
        r(40.0, 30.1, 300.0, 15),
        r(30.1, 20.2, 180.0, 5),
        r(20.2, 8.2, 60.0, 3),
        r(8.2, -0.5, 30.0, 1),
        r(-0.5, -2.0, 300.0, 1),
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
            }),
            "caliop" => Ok(Scheme {
                name: "caliop".into(),
                regions: caliop_regions(),
                uniform_shots: 1,
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
                })
            }
            _ => {
                let path = std::path::Path::new(spec);
                let text = std::fs::read_to_string(path).map_err(|e| Error::Io {
                    path: path.to_path_buf(),
                    source: e,
                })?;
                let file: SchemeFile =
                    toml::from_str(&text).map_err(|e| fail(e.message().replace('\n', " ")))?;
                let name = path
                    .file_stem()
                    .map_or(spec.into(), |s| s.to_string_lossy().into());
                let scheme = Scheme {
                    name,
                    regions: file.regions,
                    uniform_shots: 1,
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
            }]);
        }
        let top_bin = |top_m: f64| (0..n_bins).find(|&i| bin_altitude_m(i) < top_m);
        let mut out = Vec::with_capacity(self.regions.len());
        for (k, r) in self.regions.iter().enumerate() {
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
                None => top_bin(r.top_km * 1e3).ok_or_else(|| {
                    Error::Unsupported(format!(
                        "scheme {}: the window does not reach {} km",
                        self.name, r.top_km
                    ))
                })?,
            };
            if first_bin + merge * bins > n_bins {
                // where the scheme's last bin ends: the bins the window lacks, below its
                // last bin (altitude falls with the bin for a space-borne lidar)
                let needed: usize = self.regions[k + 1..]
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
}
