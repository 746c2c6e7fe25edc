//! The recorded events of a shot-level run (`simulate --photons`, docs/photons.md): each
//! channel's counts drawn exactly as the raw file's (the same samplers, seeds and
//! streams), then each count made an event from streams of its own; the origin model of
//! each channel from its expected profile and beam path.

use rand::{Rng, RngExt};

use super::sampler::{StreamSampler, pixel_seed};
use crate::detector::afterpulse::AFTERPULSE_STREAM;
use crate::error::{Error, Result};
use crate::photons::{BinParts, ChannelModel, EchoInBin, Event, Origin, SUB_BINS};
use crate::sampling::{self, stream_rng};
use crate::scenario::{ExpectedProfile, Scenario};

/// Mixed into a stream's seed for its events' draws (shot, origin, place in the bin).
const EVENT_STREAM: u64 = 0x5EED_0FE7_E475_A1C3;
/// Block of the events' stream that draws the afterpulses' events.
const AFTERPULSE_EVENTS: u64 = u64::MAX - 1;

/// FWHM of a Gaussian over its rms width.
const FWHM_PER_SIGMA: f64 = 2.354_820_045_030_949_4;

/// The origins and within-bin shapes of channel `c`'s bins (expected profile `e`).
pub fn channel_model(c: &Scenario, e: &ExpectedProfile) -> Result<ChannelModel> {
    let g = &c.geometry;
    let path = &c.path;
    let echo = path.surface();
    let mut echo_in_bin = None;
    let mut parts = Vec::with_capacity(g.n_bins);
    for i in 0..g.n_bins {
        let mut p = BinParts::default();
        p.expected[5] = e.background;
        p.expected[6] = e.dark;
        if let Some(x) = e.induced.get(i) {
            p.expected[4] = *x;
        }
        if i < g.pretrigger_bins {
            parts.push(p);
            continue;
        }
        let (ra, rb) = g.bin_range_bounds(i);
        let w = (rb - ra) / SUB_BINS as f64;
        for (j, s) in p.sub.iter_mut().enumerate() {
            let a = ra + j as f64 * w;
            let b = if j + 1 == SUB_BINS { rb } else { a + w };
            *s = path.bin_integral(a, b)?;
        }
        let mut echo_part = 0.0;
        if let Some(s) = echo.filter(|s| s.range_m >= ra && s.range_m < rb) {
            let r = s.range_m;
            echo_part =
                path.overlap().eta(r) * s.integrated_backscatter_sr * path.two_way_transmission(r)
                    / (r * r);
            let j = (((r - ra) / w) as usize).min(SUB_BINS - 1);
            p.sub[j] = (p.sub[j] - echo_part).max(0.0);
            let fwhm_s = c.loaded.config.instrument.pulse_fwhm_s.unwrap_or(0.0);
            // the pulse on the range axis: c·t/2
            let sigma_m = fwhm_s / FWHM_PER_SIGMA * crate::constants::SPEED_OF_LIGHT_M_PER_S / 2.0;
            echo_in_bin = Some(EchoInBin {
                bin: i,
                centre: (r - ra) / (rb - ra),
                sigma: sigma_m / (rb - ra),
            });
        }
        let atm: f64 = p.sub.iter().sum();
        let signal = e.signal[i];
        let surface = if atm + echo_part > 0.0 {
            signal * echo_part / (atm + echo_part)
        } else {
            0.0
        };
        let atmosphere = (signal - surface).max(0.0);
        let (mol, aer, cld) = (
            e.point[i].beta_mol.max(0.0),
            e.bin_mean[i].beta_aer.max(0.0),
            e.bin_mean[i].beta_cld.max(0.0),
        );
        let beta = mol + aer + cld;
        if beta > 0.0 {
            p.expected[0] = atmosphere * mol / beta;
            p.expected[1] = atmosphere * aer / beta;
            p.expected[2] = atmosphere * cld / beta;
        } else {
            p.expected[0] = atmosphere;
        }
        p.expected[3] = surface;
        parts.push(p);
    }
    ChannelModel::new(&parts, echo_in_bin)
}

/// Refuses `--photons` for a sampler whose events cannot be drawn (before any work).
pub fn check_sampler(s: &StreamSampler, channel: &str) -> Result<()> {
    match s {
        StreamSampler::Shot(_)
        | StreamSampler::Modulated(_)
        | StreamSampler::DeadTimed(_)
        | StreamSampler::Pixels { .. } => Ok(()),
        StreamSampler::Afterpulsed(inner, _) => check_sampler(inner, channel),
        StreamSampler::AnalogShots(..) | StreamSampler::AnalogAggregate(..) => {
            Err(Error::Unsupported(format!(
                "--photons: channel `{channel}` is analog (ADC codes, no events); time-tagged \
                 events come from photon-counting channels only"
            )))
        }
        _ => Err(Error::Unsupported(
            "--photons needs every shot drawn: set --method shot (the aggregate methods \
             draw a profile's sums, not its shots' events)"
                .into(),
        )),
    }
}

/// Events of bins `counts` of one pixel: each count given a shot, an origin and a place.
fn from_counts<R: Rng>(
    model: &ChannelModel,
    counts: &[u64],
    shots: u64,
    channel: u16,
    pixel: u16,
    rng: &mut R,
    out: &mut Vec<Event>,
) {
    for (b, &n) in counts.iter().enumerate() {
        for _ in 0..n {
            let shot = rng.random_range(0..shots) as u32;
            let origin = model.origin(b, rng.random());
            let frac = model.place(b, origin, rng);
            out.push(Event {
                shot,
                channel,
                pixel,
                bin: b as u32,
                frac,
                origin,
            });
        }
    }
}

/// The events of one pixel's dead-timed shots: the walk's registrations where the walk
/// draws them, else from its counts; returns their histogram in `counts`.
#[allow(clippy::too_many_arguments)]
fn dead_timed(
    d: &crate::detector::dead_time::DeadTimedShots,
    seed: u64,
    profile: u64,
    shots: u64,
    model: &ChannelModel,
    channel: u16,
    pixel: u16,
    counts: &mut [u64],
    out: &mut Vec<Event>,
) {
    let mut rng = stream_rng(seed ^ EVENT_STREAM, profile, u64::from(pixel));
    let walked = d.walk_registrations(seed, profile, shots, |shot, bin, frac| {
        counts[bin] += 1;
        let origin = model.origin(bin, rng.random());
        out.push(Event {
            shot: shot as u32,
            channel,
            pixel,
            bin: bin as u32,
            frac,
            origin,
        });
    });
    if !walked {
        let mut n = vec![0u64; counts.len()];
        d.profile(seed, profile, shots, &mut n);
        from_counts(model, &n, shots, channel, pixel, &mut rng, out);
        counts.iter_mut().zip(&n).for_each(|(a, x)| *a += x);
    }
}

/// Profile `profile`'s events of one channel's sampler (drawn from `seed`, the stream's
/// own): their histogram is added into `counts`, which is then the raw file's counts of
/// the channel, bit for bit.
#[allow(clippy::too_many_arguments)]
pub fn profile_events(
    sampler: &StreamSampler,
    seed: u64,
    profile: u64,
    shots: u64,
    model: &ChannelModel,
    channel: u16,
    counts: &mut [u64],
    out: &mut Vec<Event>,
) {
    match sampler {
        StreamSampler::DeadTimed(d) => {
            dead_timed(d, seed, profile, shots, model, channel, 0, counts, out)
        }
        StreamSampler::Pixels { pixel, pixels } => {
            for p in 0..*pixels {
                dead_timed(
                    pixel,
                    pixel_seed(seed, p),
                    profile,
                    shots,
                    model,
                    channel,
                    p as u16,
                    counts,
                    out,
                )
            }
        }
        StreamSampler::Afterpulsed(inner, a) => {
            let mut recorded = vec![0u64; counts.len()];
            let first = out.len();
            profile_events(
                inner,
                seed,
                profile,
                shots,
                model,
                channel,
                &mut recorded,
                out,
            );
            let pixels = out[first..]
                .iter()
                .map(|e| e.pixel)
                .max()
                .map_or(1, |p| p + 1);
            let mut rng = sampling::stream_rng(
                seed ^ AFTERPULSE_STREAM,
                profile,
                sampling::AGGREGATE_STREAM,
            );
            let mut after = vec![0u64; counts.len()];
            a.add_profile(&mut rng, &recorded, &mut after);
            let mut rng = stream_rng(seed ^ EVENT_STREAM, profile, AFTERPULSE_EVENTS);
            for (b, &n) in after.iter().enumerate() {
                for _ in 0..n {
                    out.push(Event {
                        shot: rng.random_range(0..shots) as u32,
                        channel,
                        pixel: rng.random_range(0..pixels),
                        bin: b as u32,
                        frac: rng.random(),
                        origin: Origin::Afterpulse,
                    });
                }
            }
            counts
                .iter_mut()
                .zip(recorded.iter().zip(&after))
                .for_each(|(c, (r, a))| *c += r + a);
        }
        other => {
            let mut n = vec![0u64; counts.len()];
            other.profile_counts(seed, profile, shots, &mut n);
            let mut rng = stream_rng(seed ^ EVENT_STREAM, profile, 0);
            from_counts(model, &n, shots, channel, 0, &mut rng, out);
            counts.iter_mut().zip(&n).for_each(|(a, x)| *a += x);
        }
    }
}

/// Draws profile `p` of every channel's stream as [`draw_profile`](super::drawn::draw_profile)
/// does (the same counts, bit for bit: the same samplers from the same streams) and
/// its events, ordered by shot, channel, pixel and time.
pub(super) fn draw_profile_with_events(
    channels: &[Vec<(StreamSampler, u64)>],
    models: &[ChannelModel],
    p: u64,
    shots: u64,
    n_bins: usize,
    energy: &super::energy::RunEnergy,
) -> (super::drawn::DrawnProfile, Vec<Event>) {
    let mut counts = vec![0u64; channels.len() * n_bins];
    let mut events = Vec::new();
    for (k, streams) in channels.iter().enumerate() {
        let acc = &mut counts[k * n_bins..(k + 1) * n_bins];
        for (sampler, seed) in streams {
            profile_events(
                sampler,
                *seed,
                p,
                shots,
                &models[k],
                k as u16,
                acc,
                &mut events,
            );
        }
    }
    events.sort_unstable_by(|a, b| {
        (a.shot, a.channel, a.bin, a.pixel)
            .cmp(&(b.shot, b.channel, b.bin, b.pixel))
            .then(a.frac.total_cmp(&b.frac))
    });
    let energy_seed = energy.seed.unwrap_or_default();
    (
        super::drawn::DrawnProfile {
            counts,
            components: None,
            energy_sum: energy.law.profile_sum(energy_seed, p, shots),
            values: Vec::new(),
            columns: None,
        },
        events,
    )
}
