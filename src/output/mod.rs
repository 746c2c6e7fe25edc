//! Files: the `expect` CSV and terminal table, the raw HDF5 file, the onboard product,
//! the SCC export. Every output, the figures (`src/figures/`) too, goes through
//! [`safe_file`]: one rule for temporary names, renames, locks, special files, standard
//! output and signals.

pub mod expect;
pub mod product;
pub mod raw_file;
pub mod scc;
