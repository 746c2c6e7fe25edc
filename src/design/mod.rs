//! Design tools on the deterministic model: sweeps over config keys (`sweep`).

pub mod sweep;
