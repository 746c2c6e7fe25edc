//! Memory limits (RLIMIT_AS, cgroups) and signals during the commit (issue 18, items 4 and 5).

#![allow(unused_imports)]

use super::{Case, Run, Scratch, Want, args};

/// This topic's cases, run after the older ones.
pub fn cases() -> Vec<Case> {
    vec![]
}

/// Prepares the scratch directory of one of this topic's cases: `None` when the case
/// is not this topic's, `Some(false)` when its preparation is not possible here.
pub fn prepare(name: &str, dir: &Scratch) -> Option<bool> {
    let _ = (name, dir);
    None
}
