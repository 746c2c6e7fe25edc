//! Limits that both the config and the command line enforce: one value for a key and
//! its option (a leaf: it names no other module).

/// Largest `--profiles` (and `acquisition.profiles`): far beyond any disk, refused up
/// front whatever the memory and disk say.
pub const MAX_PROFILES: u64 = 1_000_000_000_000;
