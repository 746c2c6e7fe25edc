//! The truth of each profile rebuilt from the compact form (docs/file-format.md, "The
//! truth of each profile"): one rule for the writer of `--truth per-profile`, which
//! writes exactly these values, and for every reader, which rebuilds them from whatever
//! form the file holds (format 3's (profile, channel, bin) rows, one column's (channel,
//! bin), or version 4's compact form), so that both give the same bits.
//!
//! The rules, element by element, in this order of operations (the Python module's
//! `lidarsim.per_profile` makes the same ones with numpy):
//!
//! * a (column, channel, bin) variable `x`: `Σ_j w_j·x[c_j]` over the profile's slots `j`
//!   in order, from 0, an unused slot (−1, weight 0) taken as column 0 ([`mix_into`]);
//! * `expected_background` (profile, channel): the same in every bin;
//! * `expected_counts` where the file has none (ideal detectors): `(signal + background)
//!   + dark`;
//! * `snr_eq4` where the file has none: Eq. 4 of those, [`crate::snr::eq4`] with the
//!   profile's `n_shots`.

use std::path::Path;

use hdf5::Dataset;
use ndarray::{Ix1, Ix2, Ix3, s};

use super::read::RawHeader;
use super::read::unreadable;
use crate::error::{Error, Result};

/// The variables a reader may ask per profile, in the order `--truth per-profile` writes
/// them.
pub const PER_PROFILE_NAMES: [&str; 5] = [
    "expected_signal",
    "expected_background",
    "expected_counts",
    "snr_eq4",
    "attenuated_backscatter",
];

/// `out[i] += w_j·x_j[i]` for each slot `(w_j, x_j)` in order: a profile's mix of its
/// columns' rows (`out` zeroed by the caller).
pub fn mix_into<'a>(out: &mut [f64], slots: impl IntoIterator<Item = (f64, &'a [f64])>) {
    for (w, x) in slots {
        out.iter_mut().zip(x).for_each(|(o, x)| *o += w * x);
    }
}

/// A column index of a slot: an unused slot (−1) reads column 0 (its weight is 0).
pub fn slot_column(c: i32) -> usize {
    usize::try_from(c).unwrap_or(0)
}

/// Expected recorded counts of an ideal photon counter: `(signal + background) + dark`.
pub fn ideal_counts(signal: f64, background: f64, dark: f64) -> f64 {
    signal + background + dark
}

/// How a file holds one of [`PER_PROFILE_NAMES`].
enum Form {
    /// (profile, channel, bin).
    Rows(Dataset),
    /// (channel, bin): every profile the same.
    Fixed(Vec<f64>),
    /// (column, channel, bin), mixed by each profile's columns.
    Columns(Vec<f64>),
    /// (profile, channel): the same in every bin.
    PerChannel(Dataset),
    /// Not stored: `expected_counts` of ideal detectors.
    Sum,
    /// Not stored: `snr_eq4`.
    Eq4,
}

/// Reads the (profile, channel, bin) truth of a checked raw file ([`super::read::check`])
/// whatever its form.
pub struct PerProfileReader<'a> {
    path: &'a Path,
    f: &'a hdf5::Group,
    n_channels: usize,
    n_bins: usize,
    n_columns: usize,
    forms: Vec<Form>,
}

impl<'a> PerProfileReader<'a> {
    /// The forms of `f`'s truth; refuses a file without `expected_signal`,
    /// `expected_background` or `expected_dark`, or with one of them of another shape.
    pub fn new(path: &'a Path, f: &'a hdf5::Group, h: &RawHeader) -> Result<Self> {
        let (p, c, b) = (h.n_profiles, h.channels.len(), h.n_bins);
        let n_columns = f
            .dataset(super::COLUMN_DIM)
            .map_or(0, |d| d.shape().first().copied().unwrap_or(0));
        let mut forms = Vec::new();
        for name in PER_PROFILE_NAMES {
            let form = match f.dataset(name) {
                Err(_) if name == "expected_counts" => Form::Sum,
                Err(_) if name == "snr_eq4" => Form::Eq4,
                Err(_) => {
                    return Err(Error::output(
                        path,
                        format!("has no `{name}`, which this reader needs"),
                    ));
                }
                Ok(d) => {
                    let shape = d.shape();
                    let read =
                        |d: &Dataset| d.read_raw::<f64>().map_err(|e| unreadable(path, name, e));
                    if shape == [p, c, b] && (p != n_columns || is_per_profile(&d)) {
                        Form::Rows(d)
                    } else if shape == [c, b] {
                        Form::Fixed(read(&d)?)
                    } else if n_columns > 0 && shape == [n_columns, c, b] {
                        Form::Columns(read(&d)?)
                    } else if shape == [p, c] {
                        Form::PerChannel(d)
                    } else {
                        return Err(Error::output(
                            path,
                            format!(
                                "`{name}` is {shape:?}: neither (channel, bin), (column, \
                                 channel, bin), (profile, channel) nor (profile, channel, bin)"
                            ),
                        ));
                    }
                }
            };
            forms.push(form);
        }
        if f.dataset("expected_dark").is_err() {
            return Err(Error::output(
                path,
                "has no `expected_dark`, which this reader needs",
            ));
        }
        Ok(PerProfileReader {
            path,
            f,
            n_channels: c,
            n_bins: b,
            n_columns,
            forms,
        })
    }

    /// Whether `name` is the same in every profile ((channel, bin) in the file, or
    /// rebuilt from such).
    pub fn is_fixed(&self, name: &str) -> bool {
        match PER_PROFILE_NAMES.iter().position(|&x| x == name) {
            None => name == "expected_dark",
            Some(i) => match self.forms[i] {
                Form::Fixed(_) => true,
                Form::Sum | Form::Eq4 => {
                    self.is_fixed("expected_signal") && self.is_fixed("expected_background")
                }
                _ => false,
            },
        }
    }

    /// Rows `rows` of `name` (one of [`PER_PROFILE_NAMES`], or `expected_dark`),
    /// (profile, channel, bin) row-major.
    pub fn rows(&self, name: &str, rows: std::ops::Range<usize>) -> Result<Vec<f64>> {
        let per = self.n_channels * self.n_bins;
        let n = rows.len();
        if name == "expected_dark" {
            let d = self.dataset(name)?;
            let dark = d
                .read_raw::<f64>()
                .map_err(|e| unreadable(self.path, name, e))?;
            return Ok(repeat(&dark, n));
        }
        let i = PER_PROFILE_NAMES
            .iter()
            .position(|&x| x == name)
            .ok_or_else(|| Error::output(self.path, format!("`{name}` is not per profile")))?;
        Ok(match &self.forms[i] {
            Form::Rows(d) => d
                .read_slice::<f64, _, Ix3>(s![rows, .., ..])
                .map_err(|e| unreadable(self.path, name, e))?
                .into_iter()
                .collect(),
            Form::Fixed(v) => repeat(v, n),
            Form::Columns(x) => {
                let (cols, w) = self.columns(rows)?;
                let k = cols.len().checked_div(n).unwrap_or(0);
                let mut out = vec![0.0; n * per];
                for (r, row) in out.chunks_mut(per.max(1)).enumerate() {
                    let slots = (0..k).map(|j| {
                        let c = slot_column(cols[r * k + j]).min(self.n_columns - 1);
                        (w[r * k + j], &x[c * per..(c + 1) * per])
                    });
                    mix_into(row, slots);
                }
                out
            }
            Form::PerChannel(d) => d
                .read_slice::<f64, _, Ix2>(s![rows, ..])
                .map_err(|e| unreadable(self.path, name, e))?
                .into_iter()
                .flat_map(|v| std::iter::repeat_n(v, self.n_bins))
                .collect(),
            Form::Sum => {
                let [s, b, d] = self.parts(rows)?;
                (0..s.len())
                    .map(|j| ideal_counts(s[j], b[j], d[j]))
                    .collect()
            }
            Form::Eq4 => {
                let [s, b, d] = self.parts(rows.clone())?;
                let shots = self
                    .dataset("n_shots")?
                    .read_slice::<u64, _, Ix1>(s![rows])
                    .map_err(|e| unreadable(self.path, "n_shots", e))?;
                (0..s.len())
                    .map(|j| crate::snr::eq4(s[j], b[j], d[j], shots[j / per] as f64))
                    .collect()
            }
        })
    }

    /// Signal, background and dark rows.
    fn parts(&self, rows: std::ops::Range<usize>) -> Result<[Vec<f64>; 3]> {
        Ok([
            self.rows("expected_signal", rows.clone())?,
            self.rows("expected_background", rows.clone())?,
            self.rows("expected_dark", rows)?,
        ])
    }

    /// `profile_column` and `profile_column_weight` of `rows`.
    fn columns(&self, rows: std::ops::Range<usize>) -> Result<(Vec<i32>, Vec<f64>)> {
        let [c, w] = super::PROFILE_COLUMN_NAMES;
        let cols = self
            .dataset(c)?
            .read_slice::<i32, _, Ix2>(s![rows.clone(), ..])
            .map_err(|e| unreadable(self.path, c, e))?;
        let weights = self
            .dataset(w)?
            .read_slice::<f64, _, Ix2>(s![rows, ..])
            .map_err(|e| unreadable(self.path, w, e))?;
        Ok((cols.into_iter().collect(), weights.into_iter().collect()))
    }

    fn dataset(&self, name: &str) -> Result<Dataset> {
        self.f
            .dataset(name)
            .map_err(|_| Error::output(self.path, format!("has no `{name}`")))
    }
}

/// `n` copies of `row`.
fn repeat(row: &[f64], n: usize) -> Vec<f64> {
    let mut out = Vec::with_capacity(row.len() * n);
    (0..n).for_each(|_| out.extend_from_slice(row));
    out
}

/// Whether a dataset whose first length is both the profiles' and the columns' is per
/// profile: its `coordinates` name `time`, as lidarsim writes every (profile, …)
/// variable's.
fn is_per_profile(d: &Dataset) -> bool {
    d.attr("coordinates")
        .and_then(|a| a.read_scalar::<hdf5::types::VarLenUnicode>())
        .is_ok_and(|c| c.as_str().split(' ').any(|w| w == "time"))
}
