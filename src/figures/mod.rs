//! Figures: every PNG lidarsim draws. The shared pieces ([`plot`]: embedded font and
//! text, ticks, colour scales, isolines, image panels) and one module per figure: the
//! quicklook of a raw file or product, the S/N map (Fochesatto et al. 2004, Figs. 2–3),
//! the sweep panels and the curtain. A figure is encoded in memory and written by its
//! caller through [`crate::safe_file`] (complete or not at all); files that
//! hold data are [`crate::output`]'s.

pub mod curtain;
pub mod plot;
pub mod quicklook;
pub mod snr_map;
pub mod sweep_plot;
