//! Limits that the command line and another module both enforce: one value for an
//! option and the key or file that carries the same number (a leaf: it names no other
//! module).

/// Largest `--profiles` (and `acquisition.profiles`): far beyond any disk, refused up
/// front whatever the memory and disk say.
pub const MAX_PROFILES: u64 = 1_000_000_000_000;
/// Largest `--realizations` of `validate` (and the realizations a partial file of a
/// sharded `validate` may state).
pub const MAX_REALIZATIONS: u64 = 100_000_000;
/// Most subcolumns a model-field profile may have (`scene.model_fields.subcolumns`,
/// checked by the config, drawn by `scene::fields::subcolumns`).
pub const MAX_SUBCOLUMNS: u32 = 100;
