//! Scenario configuration: TOML text with the keys of `docs/config.md`,
//! `--set KEY=VALUE` dotted overrides, typed sections and their own checks.
//!
//! Parsing happens in three steps ([`parse`]): the text is parsed into a TOML table,
//! the overrides are applied to that table, and the table is deserialized into
//! [`ScenarioConfig`] (unknown keys are errors). [`ScenarioConfig::validate`] checks
//! what the config alone can tell (ranges, consistency between sections); a check
//! that needs a module's physics or limits lives in that module, beside them, and the
//! loader (`src/loaded.rs`) hands them in ([`OwnerChecks`]), so that every key is
//! still checked in the same order and a config with several errors is told the same
//! first one. Every error names the file, the dotted key and the reason ([`Checker`]
//! words them alike wherever they are checked).
//!
//! This module sits at the bottom of the import graph: it names the error type and
//! leaf modules only (`tests/import_graph.rs` fails if a circle comes through it).
//!
//! One file per section of the schema holds its types: `instrument.rs`, `detector.rs`,
//! `atmosphere.rs`, `multiple_scattering.rs`, `scene.rs` (platform, orbit, scene,
//! surface), `acquisition.rs`, `background.rs`, `simulation.rs`, with `scenario.rs` the
//! whole; `load.rs` parses, `overrides.rs` applies `--set`, `check/` validates (one file
//! per section) and `warnings.rs` warns. Every public item is re-exported here, so a
//! user names `crate::config::Item`; the files name each other directly, never this one.

mod acquisition;
mod atmosphere;
mod background;
mod check;
mod defaults;
mod detector;
mod instrument;
mod load;
mod model_fields;
mod multiple_scattering;
mod overrides;
mod scenario;
mod scene;
mod simulation;
mod warnings;

pub use acquisition::{AcquisitionConfig, DEFAULT_START_TIME};
pub use atmosphere::{
    AerosolConfig, AtmosphereConfig, CloudPhase, ExtinctionSource, LayerConfig, LayerKind,
    MolecularConfig, MolecularLine, MolecularModel, SpeciesExtinction, StratosphericAerosol,
    WaterVapourConfig,
};
pub use background::{BackgroundConfig, BackgroundEfficiency, BackgroundModel};
pub use check::{Checker, OwnerCheck, OwnerChecks};
pub use detector::{
    AfterpulsingConfig, DeadTimeModel, DetectionMode, DetectorConfig, SignalInducedNoiseConfig,
};
pub use instrument::{
    Channel, EnergyDriftConfig, InstrumentConfig, OverlapConfig, WAVELENGTH_RANGE_NM,
};
pub use load::{Parsed, deserialize, parse, plain_serde_message};
pub use model_fields::{
    AerosolDepolarization, FieldsInterpolation, FieldsModel, FieldsMolecules, ModelFieldsConfig,
};
pub use multiple_scattering::{MultipleScatteringConfig, MultipleScatteringModel};
pub use overrides::{apply_override, attribute_to_override};
pub use scenario::ScenarioConfig;
pub use scene::{
    DEFAULT_ADVECTION_SPEED_M_PER_S, OrbitConfig, PlatformConfig, PlatformKind, SceneConfig,
    SegmentAerosol, SegmentConfig, SurfaceConfig, SurfaceKind,
};
pub use simulation::{Method, SimulationConfig, TruthForm, seed_value};
pub use warnings::{
    PLAUSIBLE_PULSE_ENERGY_J, PLAUSIBLE_WINDOW_BEYOND_GROUND_KM, unambiguous_range_m,
};
