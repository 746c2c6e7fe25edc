//! placeholder until the plotting module lands
use crate::error::{Error, Result};
/// S/N map data.
pub struct SnrMap { pub altitude_km: Vec<f64>, pub accumulation_time_s: Vec<f64>, pub snr: Vec<Vec<f64>>, pub title: String, pub subtitle: String }
/// Placeholder.
pub fn write_png(path: &std::path::Path, _map: &SnrMap) -> Result<()> { Err(Error::output(path, "not yet")) }
