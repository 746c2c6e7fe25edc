//! The raw lidar file, format version 4: HDF5 readable as netCDF-4, with CF-1.10
//! metadata (`docs/file-format.md` lists every variable and attribute).
//!
//! | name | dims | type |
//! |---|---|---|
//! | `profile`, `bin` | (profile), (bin) | i64 index coordinates, dimension scales |
//! | `channel` | (channel) | string coordinate (channel names), dimension scale |
//! | `counts` | (profile, channel, bin) | u16 / u32 / u64 ([`CountWidth`]), chunked, shuffle + deflate |
//! | `signal_counts`, `background_counts`, `dark_counts` | (profile, channel, bin) | as `counts`, only with [`RawFileSpec::components`] |
//! | `time` | (profile) | f64, CF time (`seconds since <start>`) |
//! | `n_shots` | (profile) | u64 |
//! | `pulse_energy` | (profile, channel) | f64, J: each channel's laser line |
//! | one per [`Variable`] | (bin), (channel), (channel, bin), (column, bin) or (column, channel, bin) | f64 |
//! | one per [`TextVariable`] | (channel) | string |
//! | `column` | (column) | i64 index coordinate of the scene's distinct columns, with [`RawFileSpec::n_columns`] |
//! | `profile_column`, `profile_column_weight` | (profile, k) | i32, f64: the columns each profile's shots saw and their shares, with [`RawFileSpec::column_slots`] |
//!
//! The modules: [`schema`] describes every variable (name, dimensions, type,
//! attributes), [`layout`] creates them in the file with everything known up front,
//! [`writer`] streams the profiles, [`check`] checks a profile record before it is
//! buffered, [`chunk`] fills and encodes whole chunks as HDF5's shuffle and deflate
//! filters would ([`planes`] the counts' chunks, byte plane by byte plane, their noise
//! planes stored), [`content`] decides what a simulation puts in the
//! file ([`truth`] the truth beside the counts), `hdf5_ds` makes the HDF5 calls the `hdf5` crate does not;
//! [`memory`] holds the same variables in memory instead of a file; [`per_profile`]
//! rebuilds a changing scene's truth of each profile from its compact form.
//!
//! The writer creates the file at exactly the path it is given: where the file goes, its
//! temporary name, the final rename, locks and signals are decided by
//! [`crate::safe_file`].

pub mod bin_mean;
pub mod check;
pub mod chunk;
mod column_stream;
pub mod content;
pub mod detection;
pub(crate) mod hdf5_ds;
pub mod integrity;
pub mod layout;
pub mod memory;
pub mod per_profile;
pub mod planes;
pub mod read;
pub mod schema;
pub mod spec;
pub mod truth;
pub mod writer;

pub use spec::{
    AttrValue, BIN_DIM, CHANNEL_DIM, CHANNEL_NAME, COLUMN_DIM, COMPONENT_NAMES, CONVENTIONS,
    CountWidth, Dims, FORMAT_VERSION, PROFILE_COLUMN_NAMES, PROFILE_DIM, ProfileRecord,
    ProfileSink, RESERVED_NAMES, RawFileSpec, SLOT_DIM, TextVariable, Variable,
};
pub use writer::RawFileWriter;
