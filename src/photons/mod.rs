//! Time-tagged photons (issue 42, docs/photons.md): every recorded event of a shot-level
//! run with its truth ([`model`]), streamed to the photon file ([`writer`]), and the
//! profiles made of them at any range resolution and shot accumulation ([`histogram`]).
//!
//! The events are drawn after the counts, from streams of their own: each recorded count
//! of a bin becomes one event (`simulate::events`), so the raw file is the same with and
//! without `--photons` and the histogram of the events is its counts, bit for bit.

pub mod histogram;
pub mod model;
pub mod writer;

pub use model::{BinParts, ChannelModel, EchoInBin, Event, ORIGINS, Origin, SUB_BINS};
pub use writer::{EventRow, PhotonHeader, PhotonWriter, ShotRow};

/// Bytes per event in the photon file after shuffle + deflate (nine values, 47 bytes
/// raw; the estimate assumes no compression, an upper bound).
pub const FILE_BYTES_PER_EVENT: f64 = 47.0;
/// Bytes per shot in the photon file (four f64).
pub const FILE_BYTES_PER_SHOT: f64 = 32.0;
