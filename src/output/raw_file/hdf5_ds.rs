//! The raw file's own attribute helper over the crate's HDF5 calls
//! ([`crate::hdf5_ds`], re-exported here for the writers of `output/`).

use hdf5::Location;

pub use crate::hdf5_ds::{attach_scales, set_scale, write_chunk, write_num_attr, write_str_attr};

use super::spec::AttrValue;

/// Writes a scalar attribute of any [`AttrValue`] kind.
pub fn write_attr(loc: &Location, name: &str, value: &AttrValue) -> hdf5::Result<()> {
    match value {
        AttrValue::Str(s) => write_str_attr(loc, name, s),
        AttrValue::U64(v) => write_num_attr(loc, name, v),
        AttrValue::I32(v) => write_num_attr(loc, name, v),
        AttrValue::F64(v) => write_num_attr(loc, name, v),
    }
}
