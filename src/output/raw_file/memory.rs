//! A raw file held in memory: every variable of [`super::schema`] as a flat array, the
//! per-profile ones filled profile by profile from the same [`ProfileRecord`]s the
//! `RawFileWriter` takes, checked the same way ([`RecordShape::check`]). The
//! Python module's in-memory `simulate` (docs/python.md) hands these arrays to numpy
//! without copying them; nothing is compressed and nothing touches the disk.

use super::check::{RecordShape, Row};
use super::schema::{Element, PerProfile, Values, VarSchema, schema};
use super::spec::{AttrValue, CountWidth, ProfileRecord, RawFileSpec};
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

/// `var`'s array: its values where known up front, else empty with room for `n`
/// elements (filled profile by profile, in order).
fn array(var: &VarSchema, n: usize) -> Result<Array> {
    let what = format!("the in-memory `{}`", var.name);
    let what = what.as_str();
    use crate::resources::try_with_capacity as room;
    Ok(match (var.values, var.element) {
        (Values::Index { first }, _) => Array::I64((0..n).map(|i| (first + i) as i64).collect()),
        (Values::Text(t), _) => Array::Text(t.to_vec()),
        (Values::F64(v), _) => Array::F64(v.to_vec()),
        // NaN, the `_FillValue`, where no column comes
        (Values::Streamed, _) => Array::F64(crate::resources::try_vec(what, n, f64::NAN)?),
        (Values::PerProfile(_), Element::Count(CountWidth::U16)) => {
            Array::U16(mapped(room(what, n)?))
        }
        (Values::PerProfile(_), Element::Count(CountWidth::U32)) => {
            Array::U32(mapped(room(what, n)?))
        }
        (Values::PerProfile(_), Element::Count(CountWidth::U64) | Element::U64) => {
            Array::U64(mapped(room(what, n)?))
        }
        (Values::PerProfile(_), Element::I32) => Array::I32(mapped(room(what, n)?)),
        (Values::PerProfile(_), _) => Array::F64(mapped(room(what, n)?)),
    })
}

/// Maps a large array's memory in at once, in parallel (Linux's
/// `MADV_POPULATE_WRITE`), rather than one page fault per 4 KiB as the profiles fill
/// it. Skipped where the kernel does not know the advice (before Linux 5.14).
fn mapped<T: Send>(mut v: Vec<T>) -> Vec<T> {
    #[cfg(target_os = "linux")]
    {
        use rayon::prelude::*;
        const PIECE: usize = 4 << 20;
        let bytes = v.capacity() * std::mem::size_of::<T>();
        let start = v.as_mut_ptr() as usize;
        let first = start.next_multiple_of(4096);
        let end = (start + bytes) / 4096 * 4096;
        if bytes >= PIECE && end > first {
            (first..end).into_par_iter().step_by(PIECE).for_each(|a| {
                let len = PIECE.min(end - a);
                // SAFETY: whole pages inside this vector's own allocation, not yet
                // written: the kernel maps them in zero-filled; no byte that the vector
                // holds changes, and a refusal (an error return) changes nothing.
                unsafe {
                    libc::madvise(a as *mut libc::c_void, len, libc::MADV_POPULATE_WRITE);
                }
            });
        }
    }
    v
}

/// The variables of `spec`'s file that are known before the first profile (the
/// coordinates, the truth, the instrument), as the file holds them: what `expect`
/// returns in Python. Takes the spec: its values move into the variables, uncopied.
pub fn fixed_variables(mut spec: RawFileSpec) -> Result<Vec<MemoryVariable>> {
    // the spec's own values (Values::F64) are moved in below, once the schema is done
    let mut fixed = Vec::new();
    for v in schema(&spec).iter() {
        match v.values {
            Values::PerProfile(_) => {}
            Values::F64(_) => fixed.push((
                true,
                variable(
                    &VarSchema {
                        values: Values::F64(&[]),
                        ..v.clone()
                    },
                    0,
                )?,
            )),
            _ => fixed.push((false, variable(v, v.len())?)),
        }
    }
    Ok(fixed
        .into_iter()
        .map(|(of_spec, mut m)| {
            let source = spec
                .variables
                .iter_mut()
                .find(|v| of_spec && v.name == m.name);
            if let Some(v) = source {
                m.data = Array::F64(std::mem::take(&mut v.data));
            }
            m
        })
        .collect())
}

/// `v` with its values known up front, else room for `n` elements.
fn variable(v: &VarSchema, n: usize) -> Result<MemoryVariable> {
    Ok(MemoryVariable {
        name: v.name.to_string(),
        dims: v.dims.clone(),
        shape: v.shape.clone(),
        attributes: v.attributes.clone(),
        data: array(v, n)?,
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

/// Fills a [`MemoryFile`] profile by profile, in order, as `RawFileWriter`
/// fills a file: each per-profile array grows by a profile's row (no array is written
/// twice, none zeroed first).
pub struct MemoryWriter {
    shape: RecordShape,
    file: MemoryFile,
    /// Indices in `file.variables` of each [`PerProfile`] field's variables, in order.
    slots: Vec<(PerProfile, usize)>,
    /// Those of the count rows (`counts`, the components), in order.
    count_rows: Vec<usize>,
    /// Indices in `file.variables` of the streamed (column, …) variables, in order.
    streamed: Vec<usize>,
    n_written: usize,
}

impl MemoryWriter {
    /// Every variable of `spec`'s file, the per-profile ones empty until their profiles
    /// come. Errors, naming the variable, if the memory cannot be had.
    pub fn new(spec: &RawFileSpec) -> Result<Self> {
        super::layout::validate_spec(spec).map_err(Error::Unsupported)?;
        let vars = schema(spec);
        let slots: Vec<(PerProfile, usize)> = vars
            .iter()
            .enumerate()
            .filter_map(|(k, v)| match v.values {
                Values::PerProfile(p) => Some((p, k)),
                _ => None,
            })
            .collect();
        let count_rows = (slots.iter())
            .filter(|&&(p, k)| p == PerProfile::Row && matches!(vars[k].element, Element::Count(_)))
            .map(|&(_, k)| k)
            .collect();
        let streamed = (0..vars.len())
            .filter(|&k| vars[k].values == Values::Streamed)
            .collect();
        let variables = vars
            .iter()
            .map(|v| variable(v, v.len()))
            .collect::<Result<_>>()?;
        Ok(MemoryWriter {
            shape: RecordShape::of(spec),
            file: MemoryFile {
                variables,
                root_attributes: spec.root_attributes.clone(),
            },
            slots,
            count_rows,
            streamed,
            n_written: 0,
        })
    }

    /// Takes column `c`'s truth: one row per streamed (column, …) variable, in order.
    pub fn write_column(&mut self, c: usize, rows: &[&[f64]]) -> Result<()> {
        let refused = |reason: String| Error::Unsupported(format!("in-memory run: {reason}"));
        if rows.len() != self.streamed.len() {
            return Err(refused(format!(
                "column {c}: {} rows for {} column variables",
                rows.len(),
                self.streamed.len()
            )));
        }
        for (&k, row) in self.streamed.iter().zip(rows) {
            let v = &mut self.file.variables[k];
            let n = row.len();
            match &mut v.data {
                Array::F64(data) if n > 0 && (c + 1) * n <= data.len() => {
                    data[c * n..(c + 1) * n].copy_from_slice(row)
                }
                _ => return Err(refused(format!("column {c} does not fit `{}`", v.name))),
            }
        }
        Ok(())
    }

    /// Takes the next profile: checked first as the file writer checks it (a refused
    /// record changes nothing), then appended to every per-profile array. Profiles come
    /// in order (`index` 0, 1, 2, …), as `simulate` sends them.
    pub fn write_profile(&mut self, rec: &ProfileRecord) -> Result<()> {
        let refused = |reason: String| Error::Unsupported(format!("in-memory run: {reason}"));
        self.shape.check_but_widths(rec).map_err(refused)?;
        if rec.index != self.n_written {
            return Err(refused(format!(
                "profile {} came after {} profiles: an in-memory run takes them in order",
                rec.index, self.n_written
            )));
        }
        let (rows, values) = self.shape.split(rec);
        // the counts first, narrowed as their width is checked (one pass over them); a
        // count too wide leaves every array as it was
        let names = std::iter::once("counts").chain(super::spec::COMPONENT_NAMES);
        for (k, (&at, what)) in self.count_rows.iter().zip(names).enumerate() {
            let Some(&Row::Counts(c)) = rows.get(k) else {
                break;
            };
            let fits = match &mut self.file.variables[at].data {
                Array::U16(a) => narrow(a, c, u16::MAX),
                Array::U32(a) => narrow(a, c, u32::MAX),
                Array::U64(a) => {
                    a.extend_from_slice(c);
                    true
                }
                _ => false,
            };
            if !fits {
                for &v in &self.count_rows[..=k] {
                    truncate(&mut self.file.variables[v].data, self.n_written * c.len());
                }
                let e = self.shape.width_error(rec.index, what, c);
                return Err(refused(
                    e.err()
                        .unwrap_or_else(|| "internal: a count unlike its variable".into()),
                ));
            }
        }
        let (mut rows, mut values) = (rows.into_iter(), values.into_iter());
        for &(per, at) in &self.slots {
            let data = &mut self.file.variables[at].data;
            match (per, data) {
                (PerProfile::Row, data) => match (rows.next(), data) {
                    (Some(Row::Counts(_)), Array::U16(_) | Array::U32(_) | Array::U64(_)) => {}
                    (Some(Row::Floats(f)), Array::F64(a)) => a.extend_from_slice(f),
                    _ => return Err(refused("internal: a row unlike its variable".into())),
                },
                (PerProfile::Time, Array::F64(a)) => a.push(rec.time_s),
                (PerProfile::NShots, Array::U64(a)) => a.push(rec.n_shots),
                (PerProfile::PulseEnergy, Array::F64(a)) => a.extend_from_slice(rec.pulse_energy_j),
                (PerProfile::Value, Array::F64(a)) => {
                    a.extend_from_slice(values.next().unwrap_or_default());
                }
                (PerProfile::Columns, Array::I32(a)) => a.extend_from_slice(rec.columns),
                (PerProfile::ColumnWeights, Array::F64(a)) => {
                    a.extend_from_slice(rec.column_weights);
                }
                _ => return Err(refused("internal: a value unlike its variable".into())),
            }
        }
        self.n_written += 1;
        Ok(())
    }

    /// The whole file, once every profile has come.
    pub fn finish(self) -> Result<MemoryFile> {
        if self.n_written != self.shape.n_profiles {
            return Err(Error::Unsupported(format!(
                "in-memory run incomplete: {} of {} profiles",
                self.n_written, self.shape.n_profiles
            )));
        }
        Ok(self.file)
    }
}

/// Appends `from` narrowed to `T`, and whether every count fit (`max`, 2^k − 1, holds
/// them when their bitwise OR does); one pass.
fn narrow<T: Copy + Into<u64>>(to: &mut Vec<T>, from: &[u64], max: T) -> bool
where
    u64: NarrowTo<T>,
{
    let mut all = 0u64;
    to.extend(from.iter().map(|&c| {
        all |= c;
        c.narrow()
    }));
    all <= max.into()
}

/// `as` for the count widths.
trait NarrowTo<T> {
    fn narrow(self) -> T;
}
impl NarrowTo<u16> for u64 {
    fn narrow(self) -> u16 {
        self as u16
    }
}
impl NarrowTo<u32> for u64 {
    fn narrow(self) -> u32 {
        self as u32
    }
}

/// Drops the elements of a per-profile array past `len` (a refused profile's).
fn truncate(a: &mut Array, len: usize) {
    match a {
        Array::U16(v) => v.truncate(len),
        Array::U32(v) => v.truncate(len),
        Array::U64(v) => v.truncate(len),
        _ => {}
    }
}

impl super::spec::ProfileSink for MemoryWriter {
    fn write_profile(&mut self, rec: &ProfileRecord) -> Result<()> {
        MemoryWriter::write_profile(self, rec)
    }

    fn write_column(&mut self, column: usize, rows: &[&[f64]]) -> Result<()> {
        MemoryWriter::write_column(self, column, rows)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::raw_file::schema::example_spec as spec;

    /// Profile `i`'s counts (components summing to them) and values.
    fn write(w: &mut MemoryWriter, i: usize) -> Result<()> {
        let signal: Vec<u64> = (0..6).map(|b| (1000 * i + b) as u64 * 10).collect();
        let background = vec![1u64; 6];
        let dark = vec![65_000 - 10 * 6006; 6];
        let counts: Vec<u64> = (0..6)
            .map(|b| signal[b] + background[b] + dark[b])
            .collect();
        let latitude = [i as f64];
        let expected: Vec<f64> = (0..6).map(|b| b as f64 + 0.25).collect();
        w.write_profile(&ProfileRecord {
            index: i,
            time_s: 10.0 * i as f64,
            n_shots: 7,
            pulse_energy_j: &[0.1, 0.2],
            counts: &counts,
            components: Some([&signal, &background, &dark]),
            values: &[&latitude, &expected],
            columns: &[0],
            column_weights: &[1.0],
        })
    }

    fn data<'a>(f: &'a MemoryFile, name: &str) -> &'a Array {
        &f.variables.iter().find(|v| v.name == name).unwrap().data
    }

    #[test]
    fn a_file_in_memory_holds_each_record_at_its_row() {
        let mut w = MemoryWriter::new(&spec()).unwrap();
        for i in 0..4 {
            write(&mut w, i).unwrap();
        }
        let f = w.finish().unwrap();
        let names: Vec<&str> = f.variables.iter().map(|v| v.name.as_str()).collect();
        let spec = spec();
        let described: Vec<&str> = schema(&spec).iter().map(|v| v.name).collect();
        assert_eq!(names, described);
        let Array::U16(counts) = data(&f, "counts") else {
            panic!("counts are the file's u16")
        };
        // profile 3, channel b, bin 2: signal 30,050, background 1, dark 4,940
        assert_eq!(counts.len(), 4 * 6);
        assert_eq!(counts[3 * 6 + 5], 30_050 + 1 + 4_940);
        assert_eq!(counts[0], 1 + 4_940);
        let Array::U16(signal) = data(&f, "signal_counts") else {
            panic!()
        };
        assert_eq!(signal[2 * 6 + 4], 20_040);
        assert_eq!(data(&f, "time"), &Array::F64(vec![0.0, 10.0, 20.0, 30.0]));
        assert_eq!(data(&f, "n_shots"), &Array::U64(vec![7; 4]));
        assert_eq!(data(&f, "latitude"), &Array::F64(vec![0.0, 1.0, 2.0, 3.0]));
        assert_eq!(data(&f, "profile_column"), &Array::I32(vec![0; 4]));
        assert_eq!(data(&f, "t2"), &Array::F64(vec![0.5; 6]));
        assert_eq!(data(&f, "profile"), &Array::I64(vec![0, 1, 2, 3]));
        let Array::F64(expected) = data(&f, "expected_signal") else {
            panic!()
        };
        assert_eq!(expected[6 + 1], 1.25);
        assert_eq!(f.root_attributes, spec.root_attributes);
    }

    #[test]
    fn records_out_of_order_too_wide_or_missing_are_refused() {
        let mut w = MemoryWriter::new(&spec()).unwrap();
        let e = write(&mut w, 1).unwrap_err().to_string();
        assert!(e.contains("an in-memory run takes them in order"), "{e}");
        write(&mut w, 0).unwrap();
        let e = write(&mut w, 0).unwrap_err().to_string();
        assert!(e.contains("profile 0 came after 1"), "{e}");
        // a count beyond u16: refused, nothing kept
        let wide = vec![70_000u64; 6];
        let none = vec![0u64; 6];
        let rec = ProfileRecord {
            index: 1,
            time_s: 0.0,
            n_shots: 1,
            pulse_energy_j: &[0.1, 0.2],
            counts: &wide,
            components: Some([&wide, &none, &none]),
            values: &[&[0.0], &[0.0; 6]],
            columns: &[0],
            column_weights: &[1.0],
        };
        let e = w.write_profile(&rec).unwrap_err().to_string();
        assert!(
            e.contains("counts 70000 exceeds the file's u16 range"),
            "{e}"
        );
        write(&mut w, 1).unwrap();
        let e = w.finish().unwrap_err().to_string();
        assert!(e.contains("incomplete: 2 of 4 profiles"), "{e}");
        // the refused record left nothing behind: profile 1 is the one written after it
        let mut w = MemoryWriter::new(&spec()).unwrap();
        write(&mut w, 0).unwrap();
        assert!(w.write_profile(&rec).is_err());
        (1..4).for_each(|i| write(&mut w, i).unwrap());
        let f = w.finish().unwrap();
        let Array::U16(counts) = data(&f, "counts") else {
            panic!()
        };
        assert_eq!(counts.len(), 24);
        assert_eq!(counts[6], 10_000 + 1 + 4_940);
    }

    #[test]
    fn the_fixed_variables_are_the_schemas_known_values_moved_not_copied() {
        let spec = spec();
        let t2 = spec.variables[3].data.as_ptr();
        let fixed = fixed_variables(spec).unwrap();
        let names: Vec<&str> = fixed.iter().map(|v| v.name.as_str()).collect();
        assert_eq!(
            names,
            [
                "profile",
                "channel",
                "bin",
                "channel_name",
                "column",
                "k",
                "altitude",
                "t2"
            ]
        );
        let Array::F64(moved) = &fixed[7].data else {
            panic!()
        };
        assert_eq!(moved.as_ptr(), t2);
        assert_eq!(fixed[7].shape, [1, 2, 3]);
        assert_eq!(
            memory_bytes(&self::spec()),
            // counts and components; time, n_shots, latitude; pulse_energy (profile,
            // channel); expected_signal; the column slots
            (4.0 * 6.0 * 2.0) * 4.0
                + 4.0 * 8.0 * 3.0
                + 4.0 * 2.0 * 8.0
                + 4.0 * 6.0 * 8.0
                + 4.0 * (4.0 + 8.0)
        );
    }
}
