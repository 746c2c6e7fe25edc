//! What a recorded event is, where it came from, and where inside its bin it lies: the
//! per-bin shares of its origins and the within-bin shapes (docs/photons.md).
//!
//! * **Origins.** A bin's expected counts per shot split into molecules, aerosol, cloud
//!   (the atmospheric signal in the shares of the bin-mean backscatter, the molecules'
//!   at the bin centre), the surface echo, signal-induced counts, sky background and
//!   dark counts; afterpulses are drawn apart (they follow recorded events).
//! * **Shapes.** Background, dark, induced counts and afterpulses: uniform in the bin.
//!   The atmospheric signal: piecewise constant on [`SUB_BINS`] equal sub-bins, each the
//!   exact bin integral of Eq. 2 over it (a layer edge or a cloud top inside the bin
//!   shows up at 1/16 of the bin). The surface echo: the laser pulse's Gaussian
//!   (`instrument.pulse_fwhm_s`) centred on the surface range, truncated to the bin (all
//!   of it at the surface range without a pulse width).

use rand::{Rng, RngExt};

use crate::error::{Error, Result};

/// Sub-bins of the atmospheric signal's within-bin shape.
pub const SUB_BINS: usize = 16;

/// Where a recorded event came from (the photon file's `truth_origin`, ATL03's
/// `signal_conf_ph` in spirit: the truth, not a classifier's confidence).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[repr(u8)]
pub enum Origin {
    /// Backscatter by molecules.
    Molecules = 1,
    /// Backscatter by aerosol.
    Aerosol = 2,
    /// Backscatter by cloud.
    Cloud = 3,
    /// The surface echo.
    Surface = 4,
    /// Sky background.
    Background = 5,
    /// Dark counts.
    Dark = 6,
    /// Afterpulses of recorded events.
    Afterpulse = 7,
    /// Signal-induced noise (`signal_induced_noise`).
    Induced = 8,
}

/// The origins drawn from a bin's shares, in this order.
pub const SHARED_ORIGINS: [Origin; 7] = [
    Origin::Molecules,
    Origin::Aerosol,
    Origin::Cloud,
    Origin::Surface,
    Origin::Induced,
    Origin::Background,
    Origin::Dark,
];

/// Every origin, as the file's attribute enumerates them.
pub const ORIGINS: [(Origin, &str); 8] = [
    (Origin::Molecules, "molecules"),
    (Origin::Aerosol, "aerosol"),
    (Origin::Cloud, "cloud"),
    (Origin::Surface, "surface"),
    (Origin::Background, "sky_background"),
    (Origin::Dark, "dark"),
    (Origin::Afterpulse, "afterpulse"),
    (Origin::Induced, "signal_induced"),
];

/// One recorded event of a profile: its shot within the profile, detector pixel, bin,
/// place within the bin (0 ≤ `frac` < 1, in time) and origin.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Event {
    /// Shot within its profile.
    pub shot: u32,
    /// Channel index.
    pub channel: u16,
    /// Detector pixel (0 with one pixel).
    pub pixel: u16,
    /// Bin index.
    pub bin: u32,
    /// Place within the bin, a fraction of its width.
    pub frac: f64,
    /// Origin.
    pub origin: Origin,
}

/// The surface echo inside its bin: its centre and rms width, in bins from the bin's start.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EchoInBin {
    /// The bin holding the surface.
    pub bin: usize,
    /// The surface's place in the bin, a fraction of its width.
    pub centre: f64,
    /// The pulse's rms width on the range axis, a fraction of a bin (0: a delta).
    pub sigma: f64,
}

impl EchoInBin {
    /// A place in the bin from the truncated Gaussian (inverse CDF; the centre where the
    /// width is 0).
    pub fn draw<R: Rng>(&self, rng: &mut R) -> f64 {
        if self.sigma <= 0.0 {
            return self.centre;
        }
        let (lo, hi) = (self.cdf_at(0.0), self.cdf_at(1.0));
        let u = lo + (hi - lo) * rng.random::<f64>();
        let x = self.centre
            + self.sigma * std::f64::consts::SQRT_2 * statrs::function::erf::erf_inv(2.0 * u - 1.0);
        x.clamp(0.0, BELOW_ONE)
    }

    /// The untruncated Gaussian's CDF at place `x` of the bin.
    pub fn cdf_at(&self, x: f64) -> f64 {
        0.5 * (1.0
            + statrs::function::erf::erf(
                (x - self.centre) / (self.sigma * std::f64::consts::SQRT_2),
            ))
    }

    /// The truncated shape's CDF at place `x` of the bin (what the test compares with).
    pub fn truncated_cdf(&self, x: f64) -> f64 {
        if self.sigma <= 0.0 {
            return f64::from(u8::from(x >= self.centre));
        }
        let (lo, hi) = (self.cdf_at(0.0), self.cdf_at(1.0));
        ((self.cdf_at(x.clamp(0.0, 1.0)) - lo) / (hi - lo)).clamp(0.0, 1.0)
    }
}

/// The largest `f64` below 1.
const BELOW_ONE: f64 = 1.0 - f64::EPSILON / 2.0;

/// One channel's origins and within-bin shapes.
#[derive(Debug, Clone)]
pub struct ChannelModel {
    /// Per bin, the cumulative expected counts per shot of [`SHARED_ORIGINS`].
    cumulative: Vec<[f64; 7]>,
    /// Per bin, the cumulative shares of the atmospheric signal over the sub-bins
    /// (the last 1), empty where the bin has no atmospheric signal.
    sub: Vec<[f64; SUB_BINS]>,
    /// The surface echo.
    echo: Option<EchoInBin>,
}

/// A bin's expected counts per shot by origin, and its atmospheric signal's sub-bin
/// integrals.
#[derive(Debug, Clone, Default)]
pub struct BinParts {
    /// Molecules, aerosol, cloud, surface, induced, background, dark.
    pub expected: [f64; 7],
    /// The atmospheric signal's integral over each sub-bin (any unit).
    pub sub: [f64; SUB_BINS],
}

impl ChannelModel {
    /// The model of bins `parts` with the surface `echo`.
    pub fn new(parts: &[BinParts], echo: Option<EchoInBin>) -> Result<Self> {
        let mut cumulative = Vec::with_capacity(parts.len());
        let mut sub = Vec::with_capacity(parts.len());
        for (i, p) in parts.iter().enumerate() {
            if p.expected.iter().any(|x| !x.is_finite() || *x < 0.0) {
                return Err(Error::Unsupported(format!(
                    "--photons: bin {i}'s expected counts by origin are not finite and \
                     non-negative: {:?}",
                    p.expected
                )));
            }
            let mut c = [0.0; 7];
            let mut s = 0.0;
            for (k, x) in p.expected.iter().enumerate() {
                s += x;
                c[k] = s;
            }
            cumulative.push(c);
            let total: f64 = p.sub.iter().sum();
            let mut cs = [0.0; SUB_BINS];
            if total > 0.0 && total.is_finite() {
                let mut s = 0.0;
                for (k, x) in p.sub.iter().enumerate() {
                    s += x.max(0.0);
                    cs[k] = s / total;
                }
                cs[SUB_BINS - 1] = 1.0;
            } else {
                // no atmospheric signal: uniform
                for (k, x) in cs.iter_mut().enumerate() {
                    *x = (k + 1) as f64 / SUB_BINS as f64;
                }
            }
            sub.push(cs);
        }
        Ok(ChannelModel {
            cumulative,
            sub,
            echo,
        })
    }

    /// Bins.
    pub fn bins(&self) -> usize {
        self.cumulative.len()
    }

    /// The surface echo.
    pub fn echo(&self) -> Option<EchoInBin> {
        self.echo
    }

    /// The expected counts per shot of bin `b` by origin ([`SHARED_ORIGINS`]' order).
    pub fn expected(&self, b: usize) -> [f64; 7] {
        let c = &self.cumulative[b];
        std::array::from_fn(|k| if k == 0 { c[0] } else { c[k] - c[k - 1] })
    }

    /// The origin of an event of bin `b`, drawn from the bin's shares (uniform `u`).
    pub fn origin(&self, b: usize, u: f64) -> Origin {
        let c = &self.cumulative[b];
        let x = u * c[6];
        let k = c.iter().position(|&s| x < s).unwrap_or_else(|| {
            // rounding at the top: the last origin with a share
            (0..7)
                .rev()
                .find(|&k| self.expected(b)[k] > 0.0)
                .unwrap_or(6)
        });
        SHARED_ORIGINS[k]
    }

    /// A place in bin `b` for an event of `origin`.
    pub fn place<R: Rng>(&self, b: usize, origin: Origin, rng: &mut R) -> f64 {
        match origin {
            Origin::Molecules | Origin::Aerosol | Origin::Cloud => {
                let c = &self.sub[b];
                let u: f64 = rng.random();
                let k = c.iter().position(|&s| u < s).unwrap_or(SUB_BINS - 1);
                let lo = if k == 0 { 0.0 } else { c[k - 1] };
                let w = c[k] - lo;
                let within = if w > 0.0 { (u - lo) / w } else { 0.5 };
                ((k as f64 + within) / SUB_BINS as f64).min(BELOW_ONE)
            }
            Origin::Surface => match self.echo.filter(|e| e.bin == b) {
                Some(e) => e.draw(rng),
                None => rng.random::<f64>(),
            },
            _ => rng.random::<f64>(),
        }
    }
}
