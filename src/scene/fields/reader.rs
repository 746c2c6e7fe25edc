//! The model's files as variables to read by slab: netCDF-4 through HDF5
//! (`hdf5-metno`) and netCDF-3 classic through the `netcdf3` crate. A slab is a box of
//! start and count per dimension, read as f64 with CF packing (`scale_factor`,
//! `add_offset`) applied and fill values (`_FillValue`, `missing_value`) as NaN.
//! netCDF-4 reads only the box; netCDF-3 reads only the records (time steps) of the
//! box, whole (the `netcdf3` crate reads whole variables or records).

use std::cell::RefCell;
use std::path::{Path, PathBuf};

use hdf5::types::{FixedAscii, FixedUnicode, VarLenAscii, VarLenUnicode};

/// One open file.
enum Handle {
    Nc4(hdf5::File),
    Nc3(RefCell<netcdf3::FileReader>),
}

/// The open files of `[scene.model_fields] files`.
pub struct Files {
    paths: Vec<PathBuf>,
    handles: Vec<Handle>,
}

/// A variable found in one of the files.
#[derive(Debug, Clone)]
pub struct Var {
    /// Index of its file.
    pub file: usize,
    /// Its name.
    pub name: String,
    /// Its shape.
    pub shape: Vec<usize>,
}

/// A failure to name: the file, the variable and the reason.
pub type Fail = (PathBuf, String);

impl Files {
    /// Opens every file (netCDF-4 first, then netCDF-3 classic).
    pub fn open(paths: &[PathBuf]) -> Result<Files, Fail> {
        let mut handles = Vec::new();
        for p in paths {
            let h = if let Ok(f) = hdf5::File::open(p) {
                Handle::Nc4(f)
            } else if let Ok(r) = netcdf3::FileReader::open(p) {
                Handle::Nc3(RefCell::new(r))
            } else {
                return Err((
                    p.clone(),
                    "cannot open it as netCDF-4 (HDF5) or netCDF-3 classic".into(),
                ));
            };
            handles.push(h);
        }
        Ok(Files {
            paths: paths.to_vec(),
            handles,
        })
    }

    /// The path of file `k`.
    pub fn path(&self, k: usize) -> &Path {
        &self.paths[k]
    }

    /// The first file's variable named `name`.
    pub fn find(&self, name: &str) -> Option<Var> {
        self.handles.iter().enumerate().find_map(|(file, h)| {
            let shape = match h {
                Handle::Nc4(f) => f.dataset(name).ok()?.shape(),
                Handle::Nc3(r) => {
                    let r = r.borrow();
                    let ds = r.data_set();
                    let v = ds.get_var(name)?;
                    v.get_dims().iter().map(|d| d.size()).collect()
                }
            };
            Some(Var {
                file,
                name: name.to_string(),
                shape,
            })
        })
    }

    /// A text attribute of `v` (e.g. `units`), if it has one.
    pub fn text_attr(&self, v: &Var, attr: &str) -> Option<String> {
        match &self.handles[v.file] {
            Handle::Nc4(f) => {
                let a = f.dataset(&v.name).ok()?.attr(attr).ok()?;
                a.read_scalar::<VarLenUnicode>()
                    .map(|s| s.as_str().to_string())
                    .or_else(|_| a.read_scalar::<VarLenAscii>().map(|s| s.as_str().into()))
                    .or_else(|_| {
                        a.read_scalar::<FixedAscii<1024>>()
                            .map(|s| s.as_str().into())
                    })
                    .or_else(|_| {
                        a.read_scalar::<FixedUnicode<1024>>()
                            .map(|s| s.as_str().into())
                    })
                    .ok()
            }
            Handle::Nc3(r) => r
                .borrow()
                .data_set()
                .get_var(&v.name)?
                .get_attr_as_string(attr),
        }
    }

    /// A numeric attribute of `v` (its first value), if it has one.
    fn number_attr(&self, v: &Var, attr: &str) -> Option<f64> {
        match &self.handles[v.file] {
            Handle::Nc4(f) => {
                let a = f.dataset(&v.name).ok()?.attr(attr).ok()?;
                a.read_raw::<f64>().ok()?.first().copied()
            }
            Handle::Nc3(r) => {
                let r = r.borrow();
                let a = r.data_set().get_var(&v.name)?.get_attr(attr)?;
                use netcdf3::DataType as T;
                match a.data_type() {
                    T::F64 => a.get_f64().and_then(|x| x.first().copied()),
                    T::F32 => a.get_f32().and_then(|x| x.first().map(|&y| f64::from(y))),
                    T::I32 => a.get_i32().and_then(|x| x.first().map(|&y| f64::from(y))),
                    T::I16 => a.get_i16().and_then(|x| x.first().map(|&y| f64::from(y))),
                    T::I8 => a.get_i8().and_then(|x| x.first().map(|&y| f64::from(y))),
                    T::U8 => a.get_u8().and_then(|x| x.first().map(|&y| f64::from(y))),
                }
            }
        }
    }

    /// The whole of `v`.
    pub fn read_all(&self, v: &Var) -> Result<Vec<f64>, String> {
        let count = v.shape.clone();
        self.read(v, &vec![0; count.len()], &count)
    }

    /// The box `start`, `count` of `v`, row-major, unpacked, fill values as NaN.
    pub fn read(&self, v: &Var, start: &[usize], count: &[usize]) -> Result<Vec<f64>, String> {
        let unreadable = || format!("`{}` is not readable as numbers", v.name);
        let raw: Vec<f64> = match &self.handles[v.file] {
            Handle::Nc4(f) => {
                let d = f.dataset(&v.name).map_err(|_| unreadable())?;
                if v.shape.is_empty() {
                    d.read_raw::<f64>().map_err(|_| unreadable())?
                } else {
                    let slab: Vec<hdf5::SliceOrIndex> = start
                        .iter()
                        .zip(count)
                        .map(|(&start, &count)| hdf5::SliceOrIndex::SliceCount {
                            start,
                            step: 1,
                            count,
                            block: 1,
                        })
                        .collect();
                    let sel = hdf5::Selection::from(hdf5::Hyperslab::from(slab));
                    let a = d
                        .read_slice::<f64, _, ndarray::IxDyn>(sel)
                        .map_err(|_| unreadable())?;
                    a.iter().copied().collect()
                }
            }
            Handle::Nc3(r) => {
                read_nc3(&mut r.borrow_mut(), v, start, count).ok_or_else(unreadable)?
            }
        };
        let scale = self.number_attr(v, "scale_factor").unwrap_or(1.0);
        let offset = self.number_attr(v, "add_offset").unwrap_or(0.0);
        let fills = [
            self.number_attr(v, "_FillValue"),
            self.number_attr(v, "missing_value"),
        ];
        Ok(raw
            .into_iter()
            .map(|x| {
                if fills.iter().flatten().any(|&f| x == f) {
                    f64::NAN
                } else {
                    x * scale + offset
                }
            })
            .collect())
    }
}

/// A netCDF-3 variable's box: the box's records (or the whole variable), cut.
fn read_nc3(
    r: &mut netcdf3::FileReader,
    v: &Var,
    start: &[usize],
    count: &[usize],
) -> Option<Vec<f64>> {
    let record = r.data_set().is_record_var(&v.name)?;
    let rows: Vec<Vec<f64>> = if record && !v.shape.is_empty() {
        (start[0]..start[0] + count[0])
            .map(|t| r.read_record(&v.name, t).ok().map(to_f64))
            .collect::<Option<_>>()?
    } else {
        vec![to_f64(r.read_var(&v.name).ok()?)]
    };
    let k = usize::from(record && !v.shape.is_empty());
    let (dims, s, c) = (&v.shape[k..], &start[k..], &count[k..]);
    let inner: usize = dims.iter().product();
    let mut out = Vec::with_capacity(count.iter().product());
    for data in rows {
        if data.len() != inner {
            return None;
        }
        cut(&data, dims, s, c, &mut out);
    }
    Some(out)
}

/// Appends the box `start`, `count` of the row-major array `data` of shape `dims`.
fn cut(data: &[f64], dims: &[usize], start: &[usize], count: &[usize], out: &mut Vec<f64>) {
    if dims.is_empty() {
        out.extend_from_slice(data);
        return;
    }
    let inner: usize = dims[1..].iter().product();
    for i in start[0]..start[0] + count[0] {
        cut(
            &data[i * inner..(i + 1) * inner],
            &dims[1..],
            &start[1..],
            &count[1..],
            out,
        );
    }
}

/// Any netCDF-3 vector as f64.
fn to_f64(d: netcdf3::DataVector) -> Vec<f64> {
    use netcdf3::DataVector as D;
    match d {
        D::I8(v) => v.into_iter().map(f64::from).collect(),
        D::U8(v) => v.into_iter().map(f64::from).collect(),
        D::I16(v) => v.into_iter().map(f64::from).collect(),
        D::I32(v) => v.into_iter().map(f64::from).collect(),
        D::F32(v) => v.into_iter().map(f64::from).collect(),
        D::F64(v) => v,
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn a_box_is_cut_row_major() {
        // 2 × 3 × 4 array of 0..24; the box [1.., 1..3, 2..4]
        let data: Vec<f64> = (0..24).map(f64::from).collect();
        let mut out = Vec::new();
        super::cut(&data, &[2, 3, 4], &[1, 1, 2], &[1, 2, 2], &mut out);
        assert_eq!(out, [18.0, 19.0, 22.0, 23.0]);
    }
}
