//! The serde defaults several sections share (an absent flag is true, an absent factor 1).

pub(super) fn yes() -> bool {
    true
}
pub(super) fn one() -> f64 {
    1.0
}
