//! Scale-out: a run cut into N shards, each drawn by its own process (a Slurm array task,
//! a Kubernetes indexed Job's pod), then merged into the file the whole run writes
//! (`docs/scale.md`).
//!
//! Counts depend on (seed, profile, block) only, so shard K of N of a P-profile run
//! draws exactly the whole run's counts for its profiles `⌊K·P/N⌋ … ⌊(K+1)·P/N⌋ − 1`
//! ([`Shard::rows`]). The same cut splits `validate`'s realizations.
//!
//! * this module: the shard (`K/N`, or `auto` from an array job's environment,
//!   [`mod@env`]), its rows, the run's identity ([`run_id`]), the attributes of a shard file
//!   ([`shard_spec`]), the lidar of a stored config ([`stored_lidar`]) and the checks that
//!   pieces cover one run exactly once ([`check_cover`]), one file each;
//! * `lidarsim merge OUT.h5 SHARD.h5 ...` lives with the command whose shards it merges:
//!   `simulate::merge` (raw shards), `onboard::merge` (product shards).

mod arg;
mod cut;
pub mod env;
mod files;
mod identity;
mod pieces;

pub use arg::ShardArg;
pub use cut::Shard;
pub use files::{
    FileAttributes, MergeSummary, ShardKind, kind_of_shards, open_shard, require_disk_for_merge,
    stored_lidar,
};
pub use identity::{SHARD_ATTRIBUTES, fingerprint, fingerprint_with, run_id, shard_spec};
pub use pieces::{Piece, RunIdentity, check_cover, check_pieces, check_same_run, read_partial};
