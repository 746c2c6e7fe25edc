//! Onboard averaging (issue 10, docs/model.md): altitude regions, each with a vertical
//! resolution (native bins merged) and a horizontal one (shots summed), applied to the
//! shot-level counts as an onboard processor would: integer sums, nothing in floating
//! point in the data path. The sum of Poisson counts is Poisson, so a stationary scene
//! averaged onboard has the law of a direct simulation at the coarse resolution; over
//! broken cloud or with dead time it does not, and that is what averaging studies
//! measure.

mod draw;
pub mod identity;
pub mod merge;
pub mod native;
pub mod partial;
pub mod report;
pub mod run;
pub mod scheme;
pub mod shard;
mod shard_region;
pub mod sum;
pub mod truth;

pub use scheme::{Region, RegionLayout, Scheme};
pub use sum::Averager;
