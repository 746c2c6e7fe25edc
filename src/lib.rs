//! lidarsim: Monte Carlo simulation of photon-counting backscatter lidar signals.
//!
//! The physics follows Fochesatto et al. (2004), Adv. Space Res. 34, 2227–2231,
//! as restated and completed in `docs/model.md`.

/// `eprintln!` that never panics: when standard error is closed (`lidarsim … 2>&1 |
/// head`, the reader gone) the line is dropped instead of ending the thread that writes
/// it with a panic; the signal watcher must always reach its exit.
#[macro_export]
macro_rules! tell {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stderr(), $($arg)*);
    }};
}

pub mod atmosphere;
pub mod cli_values;
pub mod commands;
pub mod config;
pub mod constants;
pub mod design;
pub mod detector;
pub mod error;
pub mod figures;
pub mod geometry;
pub mod hdf5_ds;
pub mod input_file;
pub mod instrument;
pub mod laser;
pub mod limits;
pub mod loaded;
pub mod onboard;
pub mod output;
pub mod photons;
pub mod receiver;
pub mod resources;
pub mod safe_file;
pub mod sampling;
pub mod scenario;
pub mod scene;
pub mod shard;
pub mod signal;
pub mod simulate;
pub mod snr;
pub mod surface;
pub mod validate;
