//! The HDF5 calls the `hdf5` crate does not make for us: dimension scales (`H5DS*`, from
//! libhdf5_hl, built by the `hl` feature of `hdf5-metno-sys`), the direct chunk write
//! (`H5Dwrite_chunk`), and the attribute helpers of every file lidarsim writes (the raw
//! file, products, photon files: variable-length UTF-8 text, scalar numbers).
//!
//! HDF5 calls go through the `hdf5` crate, whose global lock serializes them; the
//! dimension-scale and chunk calls are made under the same lock.

use std::ffi::CString;

use hdf5::types::VarLenUnicode;
use hdf5::{Dataset, H5Type, Location};

mod ffi {
    use hdf5_sys::h5::herr_t;
    use hdf5_sys::h5i::hid_t;
    use std::ffi::{c_char, c_uint};

    unsafe extern "C" {
        /// Turns dataset `dsid` into a dimension scale named `dimname`.
        pub fn H5DSset_scale(dsid: hid_t, dimname: *const c_char) -> herr_t;
        /// Attaches scale `dsid` to dimension `idx` of dataset `did`.
        pub fn H5DSattach_scale(did: hid_t, dsid: hid_t, idx: c_uint) -> herr_t;
    }
}

/// Runs `f` under the `hdf5` crate's global lock.
pub fn locked<T>(f: impl FnOnce() -> T) -> T {
    hdf5::sync::sync(f)
}

/// Writes a scalar variable-length UTF-8 string attribute (netCDF `NC_STRING`), which
/// h5py returns as `str` and netCDF readers as text.
pub fn write_str_attr(loc: &Location, name: &str, value: &str) -> hdf5::Result<()> {
    let v: VarLenUnicode = value
        .parse()
        .map_err(|_| hdf5::Error::from(format!("attribute `{name}` contains a NUL character")))?;
    loc.new_attr::<VarLenUnicode>()
        .shape(())
        .create(name)?
        .write_scalar(&v)
}

/// Writes a scalar numeric attribute.
pub fn write_num_attr<T: H5Type>(loc: &Location, name: &str, value: &T) -> hdf5::Result<()> {
    loc.new_attr::<T>()
        .shape(())
        .create(name)?
        .write_scalar(value)
}

/// Makes `ds` the dimension scale named `name`.
pub fn set_scale(ds: &Dataset, name: &str) -> hdf5::Result<()> {
    let c_name =
        CString::new(name).map_err(|_| hdf5::Error::from("dimension name contains NUL"))?;
    locked(|| hdf5::h5check(unsafe { ffi::H5DSset_scale(ds.id(), c_name.as_ptr()) }).map(|_| ()))
}

/// Attaches `scales[i]` to dimension `i` of `ds`.
pub fn attach_scales(ds: &Dataset, scales: &[&Dataset]) -> hdf5::Result<()> {
    locked(|| {
        for (idx, scale) in scales.iter().enumerate() {
            hdf5::h5check(unsafe { ffi::H5DSattach_scale(ds.id(), scale.id(), idx as u32) })?;
        }
        Ok(())
    })
}

/// Writes one chunk of a chunked dataset as it is stored in the file (HDF5's direct chunk
/// write, `H5Dwrite_chunk`): `bytes` have been through every filter of the dataset's
/// pipeline (filter mask 0), `offset` is the chunk's first element.
pub fn write_chunk(ds: &Dataset, offset: &[u64], bytes: &[u8]) -> hdf5::Result<()> {
    use hdf5_sys::h5d::H5Dwrite_chunk;
    use hdf5_sys::h5p::H5P_DEFAULT;
    locked(|| {
        hdf5::h5check(unsafe {
            H5Dwrite_chunk(
                ds.id(),
                H5P_DEFAULT,
                0,
                offset.as_ptr(),
                bytes.len(),
                bytes.as_ptr().cast(),
            )
        })
        .map(|_| ())
    })
}
