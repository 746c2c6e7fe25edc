//! A raw file held in memory: every variable of [`super::schema`] as a flat array, the
//! per-profile ones filled profile by profile from the same [`ProfileRecord`]s the
//! [`super::RawFileWriter`] takes, checked the same way ([`RecordShape::check`]). The
//! Python module's in-memory `simulate` (docs/python.md) hands these arrays to numpy
//! without copying them; nothing is compressed and nothing touches the disk.

use super::check::{RecordShape, Row};
use super::schema::{Element, PerProfile, Values, VarSchema, schema};
use super::{AttrValue, CountWidth, ProfileRecord, RawFileSpec};
use crate::error::{Error, Result};

/// A variable's values, row-major over its shape.
#[derive(Clone, Debug, PartialEq)]
pub enum Array {
    I64(Vec<i64>),
    Text(Vec<String>),
    U16(Vec<u16>),
    U32(Vec<u32>),
    U64(Vec<u64>),
    F64(Vec<f64>),
    I32(Vec<i32>),
}

/// One variable of a raw file in memory.
#[derive(Clone, Debug, PartialEq)]
pub struct MemoryVariable {
    /// Name, as in the file.
    pub name: String,
    /// Dimension names, outermost first.
    pub dims: Vec<&'static str>,
    /// Length of each dimension.
    pub shape: Vec<usize>,
    /// Attributes, as in the file, in its order.
    pub attributes: Vec<(String, AttrValue)>,
    pub data: Array,
}

/// A whole raw file in memory: its variables in the file's order and its root
/// attributes.
#[derive(Clone, Debug, PartialEq)]
pub struct MemoryFile {
    pub variables: Vec<MemoryVariable>,
    pub root_attributes: Vec<(String, AttrValue)>,
}

/// An empty array of `var`'s element type and length (its values where known up front).
fn array(var: &VarSchema, n: usize) -> Result<Array> {
    let what = format!("the in-memory `{}`", var.name);
    let zeros = |n| crate::resources::try_vec(&what, n, 0.0f64);
    Ok(match (var.values, var.element) {
        (Values::Index { first }, _) => Array::I64((0..n).map(|i| (first + i) as i64).collect()),
        (Values::Text(t), _) => Array::Text(t.to_vec()),
        (Values::F64(v), _) => Array::F64(v.to_vec()),
        (Values::PerProfile(_), Element::Count(CountWidth::U16)) => {
            Array::U16(crate::resources::try_vec(&what, n, 0)?)
        }
        (Values::PerProfile(_), Element::Count(CountWidth::U32)) => {
            Array::U32(crate::resources::try_vec(&what, n, 0)?)
        }
        (Values::PerProfile(_), Element::Count(CountWidth::U64) | Element::U64) => {
            Array::U64(crate::resources::try_vec(&what, n, 0)?)
        }
        (Values::PerProfile(_), Element::I32) => {
            Array::I32(crate::resources::try_vec(&what, n, -1)?)
        }
        (Values::PerProfile(_), _) => Array::F64(zeros(n)?),
    })
}

/// The variables of `spec`'s file that are known before the first profile (the
/// coordinates, the truth, the instrument), as the file holds them: what `expect`
/// returns in Python.
pub fn fixed_variables(spec: &RawFileSpec) -> Result<Vec<MemoryVariable>> {
    schema(spec)
        .iter()
        .filter(|v| !matches!(v.values, Values::PerProfile(_)))
        .map(|v| variable(v))
        .collect()
}

fn variable(v: &VarSchema) -> Result<MemoryVariable> {
    Ok(MemoryVariable {
        name: v.name.to_string(),
        dims: v.dims.clone(),
        shape: v.shape.clone(),
        attributes: v.attributes.clone(),
        data: array(v, v.len())?,
    })
}

/// Bytes the per-profile arrays of `spec`'s file take in memory.
pub fn memory_bytes(spec: &RawFileSpec) -> f64 {
    schema(spec)
        .iter()
        .filter(|v| matches!(v.values, Values::PerProfile(_)))
        .map(|v| {
            let size = match v.element {
                Element::Count(w) => w.bytes(),
                Element::I32 => 4,
                _ => 8,
            };
            v.len() as f64 * size as f64
        })
        .sum()
}

/// Fills a [`MemoryFile`] profile by profile, as [`super::RawFileWriter`] fills a file.
pub struct MemoryWriter {
    shape: RecordShape,
    file: MemoryFile,
    /// Indices in `file.variables` of each [`PerProfile`] field's variables, in order.
    slots: Vec<(PerProfile, usize)>,
    written: Vec<bool>,
    n_written: usize,
}

impl MemoryWriter {
    /// Every variable of `spec`'s file, the per-profile ones zero (columns −1) until their
    /// profiles come. Errors, naming the variable, if the memory cannot be allocated.
    pub fn new(spec: &RawFileSpec) -> Result<Self> {
        super::layout::validate_spec(spec).map_err(Error::Unsupported)?;
        let vars = schema(spec);
        let slots = vars
            .iter()
            .enumerate()
            .filter_map(|(k, v)| match v.values {
                Values::PerProfile(p) => Some((p, k)),
                _ => None,
            })
            .collect();
        let variables = vars.iter().map(variable).collect::<Result<_>>()?;
        Ok(MemoryWriter {
            shape: RecordShape::of(spec),
            file: MemoryFile {
                variables,
                root_attributes: spec.root_attributes.clone(),
            },
            slots,
            written: crate::resources::try_vec(
                "the record of written profiles",
                spec.n_profiles,
                false,
            )?,
            n_written: 0,
        })
    }

    /// Takes one profile: checked first as the file writer checks it (a refused record
    /// changes nothing), then copied into every per-profile array at its row.
    pub fn write_profile(&mut self, rec: &ProfileRecord) -> Result<()> {
        let refused = |reason: String| Error::Unsupported(format!("in-memory run: {reason}"));
        self.shape.check(rec).map_err(refused)?;
        let i = rec.index;
        if self.written[i] {
            return Err(refused(format!("profile {i} written twice")));
        }
        let (rows, values) = self.shape.split(rec);
        let (mut rows, mut values) = (rows.into_iter(), values.into_iter());
        let n = self.shape.n_per_profile;
        let k = self.shape.column_slots;
        for &(per, at) in &self.slots {
            let data = &mut self.file.variables[at].data;
            match (per, data) {
                (PerProfile::Row, data) => match (rows.next(), data) {
                    (Some(Row::Counts(c)), Array::U16(a)) => put(&mut a[i * n..][..n], c),
                    (Some(Row::Counts(c)), Array::U32(a)) => put(&mut a[i * n..][..n], c),
                    (Some(Row::Counts(c)), Array::U64(a)) => a[i * n..][..n].copy_from_slice(c),
                    (Some(Row::Floats(f)), Array::F64(a)) => a[i * n..][..n].copy_from_slice(f),
                    _ => return Err(refused("a row does not match its variable".into())),
                },
                (PerProfile::Time, Array::F64(a)) => a[i] = rec.time_s,
                (PerProfile::NShots, Array::U64(a)) => a[i] = rec.n_shots,
                (PerProfile::PulseEnergy, Array::F64(a)) => a[i] = rec.pulse_energy_j,
                (PerProfile::Value, Array::F64(a)) => a[i] = values.next().unwrap_or(f64::NAN),
                (PerProfile::Columns, Array::I32(a)) => {
                    a[i * k..][..k].copy_from_slice(rec.columns);
                }
                (PerProfile::ColumnWeights, Array::F64(a)) => {
                    a[i * k..][..k].copy_from_slice(rec.column_weights);
                }
                _ => return Err(refused("a value does not match its variable".into())),
            }
        }
        self.written[i] = true;
        self.n_written += 1;
        Ok(())
    }

    /// The whole file, once every profile has come.
    pub fn finish(self) -> Result<MemoryFile> {
        if self.n_written != self.written.len() {
            return Err(Error::Unsupported(format!(
                "in-memory run incomplete: {} of {} profiles",
                self.n_written,
                self.written.len()
            )));
        }
        Ok(self.file)
    }
}

/// Narrows checked counts (each fits the width: [`RecordShape::check`]).
fn put<T: TryFrom<u64> + Default>(to: &mut [T], from: &[u64]) {
    for (t, &c) in to.iter_mut().zip(from) {
        *t = T::try_from(c).unwrap_or_default();
    }
}

impl super::ProfileSink for MemoryWriter {
    fn write_profile(&mut self, rec: &ProfileRecord) -> Result<()> {
        MemoryWriter::write_profile(self, rec)
    }
}
