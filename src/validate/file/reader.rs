//! Reading a checked raw file for `check_file` (`validate --file`): block by block, the counts and
//! what their law needs, refusing impossible expectations.

use std::path::Path;

use hdf5::types::{VarLenAscii, VarLenUnicode};
use ndarray::{Ix1, Ix2, Ix3, s};

use super::sums::{Channels, Sums};
use crate::error::{Error, Result};
use crate::output::raw_file::per_profile::PerProfileReader;
use crate::output::raw_file::read::unreadable;
use crate::output::raw_file::read::{self, RawHeader};

/// A (channel) or (bin) variable of floats, whole (bounded by the header's lengths).
pub(super) fn read_all(path: &Path, f: &hdf5::File, name: &str) -> Result<Vec<f64>> {
    let d = f.dataset(name).map_err(|_| {
        Error::output(
            path,
            format!(
                "has no `{name}`, which `validate --file` needs (a lidarsim raw file of format 3)"
            ),
        )
    })?;
    d.read_raw::<f64>().map_err(|e| unreadable(path, name, e))
}

/// The expectation variables, by their index in a [`Block`].
const EXPECTED: [&str; 4] = [
    "expected_counts",
    "expected_signal",
    "expected_background",
    "expected_dark",
];

/// Reads a checked raw file block by block.
pub(super) struct Reader<'a> {
    path: &'a Path,
    f: &'a hdf5::File,
    /// The (channel, bin) expectations of a static scene (None: per profile).
    fixed: Vec<Option<Vec<f64>>>,
    /// The expectations of each profile, whatever their form in the file.
    truth: PerProfileReader<'a>,
    has_weights: bool,
    pub(super) first_shots: u64,
    header: RawHeader,
}

/// The profiles of one block: counts and what the law needs, row-major.
pub(super) struct Block {
    counts: Vec<u64>,
    shots: Vec<u64>,
    /// The energy factors `E/E₀`, (profile, channel) row-major.
    energy: Vec<f64>,
    /// Per expectation variable: its values of every row (one row when static).
    expected: Vec<(Vec<f64>, bool)>,
    /// Whether each row's shots saw more than one column.
    mixed: Vec<bool>,
    first: usize,
}

impl<'a> Reader<'a> {
    pub(super) fn new(path: &'a Path, f: &'a hdf5::File, h: &RawHeader) -> Result<Self> {
        let truth = PerProfileReader::new(path, f, h)?;
        let mut fixed = Vec::new();
        for name in EXPECTED {
            if truth.is_fixed(name) {
                let v = truth.rows(name, 0..1)?;
                check_expected(path, name, &v, 0, h)?;
                fixed.push(Some(v));
            } else {
                fixed.push(None);
            }
        }
        let first_shots = f
            .dataset("n_shots")
            .and_then(|d| d.read_slice_1d::<u64, _>(ndarray::s![0..1]))
            .map_err(|e| unreadable(path, "n_shots", e))?[0];
        Ok(Reader {
            path,
            f,
            fixed,
            truth,
            has_weights: f.dataset("profile_column_weight").is_ok(),
            first_shots,
            header: h.clone(),
        })
    }

    /// Rows `rows` of a dataset whose first dimension is the profile.
    fn rows<T: hdf5::H5Type>(&self, name: &str, rows: std::ops::Range<usize>) -> Result<Vec<T>> {
        let d = self
            .f
            .dataset(name)
            .map_err(|_| Error::output(self.path, format!("has no `{name}`")))?;
        let read = match d.ndim() {
            1 => d
                .read_slice::<T, _, Ix1>(s![rows])
                .map(|a| a.into_iter().collect()),
            2 => d
                .read_slice::<T, _, Ix2>(s![rows, ..])
                .map(|a| a.into_iter().collect()),
            _ => d
                .read_slice::<T, _, Ix3>(s![rows, .., ..])
                .map(|a| a.into_iter().collect()),
        };
        read.map_err(|e| unreadable(self.path, name, e))
    }

    /// Rows `rows`, the energy factors at the channels' `nominal` energies.
    pub(super) fn block(&mut self, rows: std::ops::Range<usize>, nominal: &[f64]) -> Result<Block> {
        let mut expected = Vec::new();
        for (name, fixed) in EXPECTED.iter().zip(&self.fixed) {
            expected.push(match fixed {
                Some(v) => (v.clone(), false),
                None => (self.truth.rows(name, rows.clone())?, true),
            });
        }
        let per_profile = expected.iter().any(|e| e.1);
        let mixed = if self.has_weights {
            let w = self.rows::<f64>("profile_column_weight", rows.clone())?;
            match w.len() / rows.len() {
                0 => vec![per_profile; rows.len()],
                k => w
                    .chunks(k)
                    .map(|r| r.iter().filter(|&&x| x > 0.0).count() > 1)
                    .collect(),
            }
        } else {
            // a format-2 file: which columns a profile saw is not recorded
            vec![per_profile; rows.len()]
        };
        Ok(Block {
            counts: self.rows::<u64>("counts", rows.clone())?,
            shots: self.rows::<u64>("n_shots", rows.clone())?,
            energy: read::energy_factors(self.path, self.f, &self.header, rows.clone(), nominal)?,
            expected,
            mixed,
            first: rows.start,
        })
    }

    pub(super) fn altitude(&self) -> Result<Vec<f64>> {
        read_all(self.path, self.f, "altitude")
    }

    pub(super) fn text_attr(&self, name: &str) -> Option<String> {
        let a = self.f.attr(name).ok()?;
        a.read_scalar::<VarLenUnicode>()
            .map(|s| s.as_str().to_string())
            .ok()
            .or_else(|| {
                a.read_scalar::<VarLenAscii>()
                    .map(|s| s.as_str().to_string())
                    .ok()
            })
    }
}

/// Refuses an expectation value that is not finite or is negative, naming the place.
fn check_expected(path: &Path, name: &str, v: &[f64], first: usize, h: &RawHeader) -> Result<()> {
    match v.iter().position(|x| !(x.is_finite() && *x >= 0.0)) {
        None => Ok(()),
        Some(j) => {
            let per = h.counts_per_profile();
            let (p, r) = (first + j / per, j % per);
            let place = if v.len() == per && first == 0 && name != "counts" {
                String::new()
            } else {
                format!("profile {p}, ")
            };
            Err(Error::output(
                path,
                format!(
                    "`{name}` at {place}channel {}, bin {} is {}; an expectation is finite \
                     and not negative",
                    h.channels[r / h.n_bins],
                    r % h.n_bins,
                    v[j]
                ),
            ))
        }
    }
}

impl Block {
    /// Adds the judged counts of the block to `sums`; `judged` counts each channel's
    /// judged profiles.
    pub(super) fn accumulate(
        &self,
        path: &Path,
        ch: &Channels,
        n_bins: usize,
        sums: &mut [Sums],
        judged: &mut [usize],
    ) -> Result<()> {
        let per = ch.names.len() * n_bins;
        let channels = ch.names.len();
        for (r, &shots) in self.shots.iter().enumerate() {
            for (k, dead) in ch.dead.iter().enumerate() {
                let factor = self.energy[r * channels + k];
                let constant = factor == 1.0;
                let ok = match dead {
                    None => constant || !self.mixed[r],
                    Some(_) => constant && !self.mixed[r],
                };
                if !ok {
                    continue;
                }
                judged[k] += 1;
                let expected = |v: usize, j: usize| {
                    let (vals, rows) = &self.expected[v];
                    if *rows { vals[r * per + j] } else { vals[j] }
                };
                // a dead-time channel's variance per shot, bin by bin from the channel's
                // arriving means (the dead time carried from bin to bin)
                let recorded_var = dead.as_ref().map(|d| {
                    let lambda: Vec<f64> = (0..n_bins)
                        .map(|i| (1..4).map(|v| expected(v, k * n_bins + i)).sum())
                        .collect();
                    d.recorded_mean_and_variance(&lambda).1
                });
                for i in 0..n_bins {
                    let j = k * n_bins + i;
                    let e: [f64; 4] = std::array::from_fn(|v| expected(v, j));
                    let v = recorded_var.as_ref().map(|v| v[i]);
                    let (mu, var) = law(v, shots as f64, factor, e);
                    if !(mu.is_finite() && var.is_finite()) {
                        return Err(Error::output(
                            path,
                            format!(
                                "the expected count of profile {}, channel {}, bin {i} is \
                                 {mu:e}: its energy factor {factor:e} or `n_shots` {shots} \
                                 is impossible",
                                self.first + r,
                                ch.names[k]
                            ),
                        ));
                    }
                    sums[j].push(self.counts[r * per + j], mu, var);
                }
            }
        }
        Ok(())
    }

    /// Refuses impossible per-profile expectations of the block.
    pub(super) fn validate(&self, path: &Path, h: &RawHeader) -> Result<()> {
        for (name, (v, rows)) in EXPECTED.iter().zip(&self.expected) {
            if *rows {
                check_expected(path, name, v, self.first, h)?;
            }
        }
        Ok(())
    }
}

/// Mean and variance of a profile's count over `m` shots at energy factor `factor`, from
/// the per-shot `expected_counts`, `_signal`, `_background` and `_dark` at the nominal
/// energy (module docs of [`super`]); `recorded_var` the per-shot variance of a dead-time channel's count
/// ([`crate::detector::DeadTime::recorded_mean_and_variance`]), `None` for an ideal detector.
fn law(recorded_var: Option<f64>, m: f64, factor: f64, e: [f64; 4]) -> (f64, f64) {
    let [counts, signal, ..] = e;
    match recorded_var {
        None => {
            let mu = m * (counts - signal + factor * signal).max(0.0);
            (mu, mu)
        }
        Some(v) => (m * counts, m * v),
    }
}
