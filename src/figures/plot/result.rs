//! What drawing a figure returns.

/// The result of drawing: plotters' errors, boxed.
pub type DrawResult = std::result::Result<(), Box<dyn std::error::Error>>;
