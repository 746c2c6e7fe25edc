//! `lidarsim quicklook FILE --png OUT.png [--channel NAME] [--truth]`: the figure every
//! lidar network publishes — the background-subtracted, range-corrected signal on a
//! logarithmic colour scale against time (or along-track distance) and altitude, with
//! the volume depolarization beside it when the file has a ∥/⊥ pair, and with
//! `--truth` the truth on the same scale. For a raw file, a merged file or an onboard
//! product (its regions stitched at their own resolutions).
//!
//! **What is drawn.** Each profile's counts per shot, minus its background, over the
//! channel's lidar constant, `range_weight` (`∫η/r² dr`, so the range correction and
//! the overlap) and the profile's pulse energy over the nominal:
//! `β'_est = (N/M − B)/(C·w·E/E₀)`, in m⁻¹ sr⁻¹ — the attenuated backscatter the counts
//! measure, so that the truth's `attenuated_backscatter` is on the same scale. The
//! background `B` is the mean of the profile's own signal-free bins (the pre-trigger
//! bins, or the bins whose expected signal is below 1 % of their background, as
//! `export-scc`); an onboard product keeps no signal-free bin, so there it is the
//! product's `expected_background + expected_dark` (the title says which). The volume
//! depolarization is `β'_⊥/β'_∥` of the pair's calibrated signals, where `β'_∥` is above
//! the colour scale's floor.
//!
//! **Memory and time.** The file is read a block of profiles at a time and averaged into
//! a grid of the figure's pixels ([`grid::Grid`]); memory is the grid's and one block's,
//! not the file's (`docs/figures.md` has the measured numbers).

pub mod axis;
mod draw;
mod figure;
pub mod grid;
mod product;
mod raw;
mod title;

use std::path::Path;

use crate::error::{Error, Result};
use crate::safe_file::{Outputs, Stream};
pub use axis::{XAxis, x_axis};
pub use draw::{PANEL_HEIGHT, TITLE_HEIGHT};
pub use figure::{
    Background, COLUMNS, Calibration, Mask, Quicklook, ROWS, TOP_KM, View, add_profile, snr,
};
pub use title::{Source, title_line};

/// `lidarsim quicklook FILE --png OUT.png`: reads `file` (raw, merged or onboard
/// product) and writes the figure of `channels` (none: the first channel), stacked
/// top to bottom on one x axis, over `view`'s altitudes and x axis.
pub fn run(file: &Path, png: &Path, channels: &[String], truth: bool, view: View) -> Result<()> {
    let mut outputs = Outputs::new([file]);
    let id = outputs.add("--png", png, Stream::Binary)?;
    let qs: Vec<Quicklook> = if channels.is_empty() {
        vec![read_view(file, None, truth, view)?]
    } else {
        channels
            .iter()
            .map(|c| read_view(file, Some(c), truth, view))
            .collect::<Result<_>>()?
    };
    let bytes = draw::png_bytes(&qs).map_err(|r| Error::output(outputs.shown_path(id), r))?;
    outputs.write(id, |w| w.write_all(&bytes))?;
    outputs.commit()
}

/// Reads what the figure shows from a raw file or an onboard product, over the
/// default altitudes ([`View::default`]).
pub fn read(file: &Path, channel: Option<&str>, truth: bool) -> Result<Quicklook> {
    read_view(file, channel, truth, View::default())
}

/// Reads what the figure shows from a raw file or an onboard product, over `view`'s
/// altitudes.
pub fn read_view(file: &Path, channel: Option<&str>, truth: bool, view: View) -> Result<Quicklook> {
    crate::input_file::check("FILE", file)?;
    let f = hdf5::File::open(file)
        .map_err(|_| Error::output(file, "not a lidarsim raw file or product (not HDF5)"))?;
    if f.attr(crate::output::raw_file::content::PRODUCT_ATTRIBUTE)
        .is_ok()
    {
        product::read(file, &f, channel, truth, view)
    } else {
        raw::read(file, &f, channel, truth, view)
    }
}
