//! Writers: the `expect` CSV and terminal table, the S/N map, the raw HDF5 file.
//! Every output goes through [`safe_file`]: one rule for temporary names, renames,
//! locks, special files, standard output and signals.

pub mod curtain;
pub mod expect;
pub mod plot;
pub mod product;
pub mod quicklook;
pub mod raw_file;
pub mod safe_file;
pub mod scc;
pub mod snr_map;
pub mod sweep_plot;
