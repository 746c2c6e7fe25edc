//! The deterministic model ([`Scenario::expected`]): Eq. 2's bin integral bin by bin, the
//! multiple scattering and the detector's means on top.

use rayon::prelude::*;

use super::Scenario;
use super::expected::{ExpectedProfile, ModelBin};
use crate::atmosphere::multiple_scattering::{self, Footprint};
use crate::config::MultipleScatteringModel;
use crate::error::{Error, Result};
use crate::signal::BinMultipleScattering;

/// Bins of [`Scenario::expected`]'s model computed at once (their [`ModelBin`]s held
/// until taken into the profile): 64 Ki bins, ~17 MB.
const MODEL_PIECE_BINS: usize = 1 << 16;

impl Scenario {
    /// The deterministic model: per-bin expectations and truth (docs/config.md `expect`).
    pub fn expected(&self) -> Result<ExpectedProfile> {
        let g = &self.geometry;
        let n = g.n_bins;
        let mut e = ExpectedProfile {
            background: self.instrument.background_per_bin,
            dark: self.instrument.dark_per_bin,
            ..Default::default()
        };
        e.reserve_exact(n);
        let surface = self.loaded.config.surface.as_ref();
        let span = crate::signal::BeamPath::altitude_span(
            &self.atmosphere,
            g,
            surface.map(crate::surface::Surface::from_config).as_ref(),
        );
        for i in 0..g.pretrigger_bins {
            self.push_pretrigger_bin(&mut e, g.bin_centre_range_m(i));
        }
        // the bins are independent: computed in parallel a piece at a time, taken in order
        // (the first bad bin's error, as a loop would give it); only a piece's bins are
        // held twice, not the window's
        for start in (g.pretrigger_bins..n).step_by(MODEL_PIECE_BINS) {
            let bins: Vec<Result<ModelBin>> = (start..(start + MODEL_PIECE_BINS).min(n))
                .into_par_iter()
                .with_min_len(256)
                .map(|i| self.model_bin(i, span))
                .collect();
            for bin in bins {
                e.push_bin(bin?);
            }
        }
        self.add_multiple_scattering(&mut e);
        e.alpha_aer_by_species = self.alpha_aer_by_species(&e);
        let detector = self.loaded.config.instrument.detector.as_ref();
        if let Some(sin) = detector.and_then(|d| d.signal_induced_noise.as_ref()) {
            let power_law = matches!(
                sin,
                crate::config::SignalInducedNoiseConfig::PowerLaw { .. }
            );
            let most = crate::detector::induced::MAX_POWER_LAW_BINS;
            if power_law && n > most {
                return Err(Error::config(
                    self.loaded.file_label(),
                    "instrument.detector.signal_induced_noise.model",
                    format!(
                        "\"power_law\" convolves the signal directly, in time growing as the \
                         square of the bins: at most {most} bins, the window has {n}; use \
                         \"exponential\" (any number of bins) or fewer bins"
                    ),
                ));
            }
            e.induced = sin.induced_counts(&e.signal, self.instrument.bin_width_s);
        }
        e.recorded = match &self.instrument.dead_time {
            Some(d) if self.instrument.pulse_energy_jitter > 0.0 => {
                let laser = crate::laser::PulseEnergy::from_config(&self.loaded.config.instrument);
                d.recorded_moments(&e.photon_signal(), e.background + e.dark, &laser)
                    .0
            }
            Some(d) => d.recorded_means(&e.total_per_shot()),
            None => match &self.instrument.analog {
                // the mean code is linear in the photoelectrons: jitter leaves it
                Some(a) => a.expected_codes(&e.total_per_shot()),
                None => e.total_per_shot(),
            },
        };
        if let Some(ap) = &self.instrument.afterpulsing {
            e.afterpulse = ap.expected(&e.recorded);
            e.recorded
                .iter_mut()
                .zip(&e.afterpulse)
                .for_each(|(r, a)| *r += a);
        }
        e.background_bin_indices = self.background_bin_indices();
        e.background_bins = e.background_bin_indices.len();
        check_finite(&e)?;
        Ok(e)
    }

    /// The point truth's aerosol extinction by species (`ExpectedProfile::
    /// alpha_aer_by_species`): at each bin centre with aerosol, the species of the layers
    /// there; 0 where the point truth has none (below the surface, before the trigger).
    fn alpha_aer_by_species(&self, e: &ExpectedProfile) -> Vec<(usize, Vec<f64>)> {
        let species = self.atmosphere.aerosol_species();
        let Some(last) = species.last() else {
            return Vec::new();
        };
        let n = e.altitude_m.len();
        let mut out: Vec<(usize, Vec<f64>)> = species.iter().map(|s| (*s, vec![0.0; n])).collect();
        let mut at = vec![0.0; last + 1];
        for i in (0..n).filter(|i| e.point[*i].alpha_aer > 0.0) {
            at.fill(0.0);
            self.atmosphere
                .add_aerosol_species_extinction(e.altitude_m[i], &mut at);
            for (s, v) in &mut out {
                v[i] = at[*s];
            }
        }
        out
    }

    /// The model of bin `i` (past the pre-trigger bins): Eq. 2's bin integral, the truth
    /// at the bin centre and the optics averaged over the bin (along the beam path's
    /// altitude `span`).
    fn model_bin(&self, i: usize, span: (f64, f64)) -> Result<ModelBin> {
        let g = &self.geometry;
        let (ra, rb) = g.bin_range_bounds(i);
        let r = g.bin_centre_range_m(i);
        let z = g.altitude_at_range(r);
        // below the surface the beam does not go: no optics there (t2 stays the
        // surface's), the molecular state that of the atmosphere continued
        let point = if r <= self.path.end_range_m() {
            self.atmosphere.optics_at(z)
        } else {
            self.atmosphere.no_optics()
        };
        let z_ends = (g.altitude_at_range(ra), g.altitude_at_range(rb));
        let bin_mean = self
            .atmosphere
            .bin_mean(span, (ra, rb), z_ends, |z| g.range_at_altitude(z));
        let integral = self.path.bin_integral(ra, rb)?;
        let signal = self.instrument.signal_constant * integral;
        let weight = self.path.range_weight(ra, rb);
        if !signal.is_finite() {
            return Err(Error::Unsupported(format!(
                "bin {i} (altitude {z:.0} m): the signal is not finite"
            )));
        }
        Ok(ModelBin {
            altitude_m: z,
            range_m: r,
            point,
            bin_mean,
            state: self.atmosphere.state_at(z),
            overlap: self.path.overlap().eta(r),
            t2: self.path.two_way_transmission(r),
            signal,
            range_weight: weight,
            attenuated_backscatter: if weight > 0.0 { integral / weight } else { 0.0 },
        })
    }

    /// Multiplies each bin's signal and attenuated backscatter by its multiple-scattering
    /// ratio ([`BeamPath::multiple_scattering_bins`]) when the config asks for the
    /// `small_angle` or `small_and_wide_angle` model.
    fn add_multiple_scattering(&self, e: &mut ExpectedProfile) {
        let cfg = &self.loaded.config;
        if cfg.multiple_scattering.model == MultipleScatteringModel::Constant {
            return;
        }
        let footprint = Footprint {
            divergence_rad: cfg.instrument.beam_divergence_rad.unwrap_or(0.0),
            fov_half_angle_rad: cfg.instrument.fov_rad / 2.0,
        };
        let g = &self.geometry;
        let bins: Vec<(f64, f64)> = (g.pretrigger_bins..g.n_bins)
            .map(|i| g.bin_range_bounds(i))
            .collect();
        e.multiple_scattering = vec![BinMultipleScattering::NONE; g.pretrigger_bins];
        e.multiple_scattering
            .extend(self.path.multiple_scattering_bins(
                footprint,
                &bins,
                cfg.multiple_scattering.model == MultipleScatteringModel::SmallAndWideAngle,
            ));
        for (i, m) in e.multiple_scattering.iter().enumerate() {
            e.signal[i] *= m.ratio;
            e.attenuated_backscatter[i] *= m.ratio;
        }
        self.depolarize_water_clouds(e);
    }

    /// Gives each water cloud's apparent return the depolarization of Hu et al. (2006)
    /// (`multiple_scattering::water_cloud_depolarization`, docs/model.md §4j): the
    /// channel sees the cloud's apparent return in every polarization with that
    /// depolarization instead of the droplets' own (`depolarization`, kept where it is
    /// larger); the air's part keeps its own. The cloud's apparent return in every
    /// polarization, `W_i`, is the bin's own (`BinMultipleScattering::cloud_apparent`),
    /// the same for every channel, never the channel's return divided by its share of
    /// the droplets' own depolarization: that share is 0 for a perpendicular channel
    /// without cross-talk under droplets of δ = 0, whose multiply scattered light the
    /// channel does see. The channel's return becomes
    /// `old − W_i·share(δ_own) + W_i·share(δ_i)`.
    fn depolarize_water_clouds(&self, e: &mut ExpectedProfile) {
        let g = &self.geometry;
        let share = |d: f64| {
            self.atmosphere
                .polarization
                .share(self.atmosphere.channel, d)
        };
        let particle_line = self.atmosphere.lines.particle;
        let mut k = g.pretrigger_bins;
        while k < g.n_bins {
            if e.point[k].alpha_water <= 0.0 {
                k += 1;
                continue;
            }
            let start = k;
            while k < g.n_bins && e.point[k].alpha_water > 0.0 {
                k += 1;
            }
            // the cloud's multiple scattering in every polarization, alike for every
            // channel (a channel's own ratio weights a bin across the cloud's base by
            // its own mix of cloud and air)
            let before = e
                .multiple_scattering_at(start.saturating_sub(1))
                .total_ratio;
            let (mut single, mut apparent, mut tau, mut whole) = (vec![], vec![], vec![], vec![]);
            let mut depth = 0.0;
            for i in start..k {
                let (ra, rb) = g.bin_range_bounds(i);
                let half = 0.5 * e.point[i].alpha_water * (rb - ra);
                tau.push(depth + half);
                depth += 2.0 * half;
                // the clouds' own return in every polarization, bin-averaged, through
                // the channel's particle line: alike for every channel
                let m = &e.multiple_scattering[i];
                whole.push(particle_line * m.cloud_apparent);
                single.push(m.cloud_single);
                apparent.push(m.cloud_apparent / before);
            }
            let delta = multiple_scattering::water_cloud_depolarization(&single, &apparent, &tau);
            for ((i, d), w) in (start..k).zip(delta).zip(whole) {
                let own = e.point[i].depol_cld();
                let d = d.max(own);
                let old = e.attenuated_backscatter[i];
                // the channel's return less the cloud's part of it, plus the cloud's
                // apparent return with its new depolarization
                let new = (old - w * share(own)).max(0.0) + w * share(d);
                let factor = if old > 0.0 {
                    new / old
                } else if new > 0.0 {
                    f64::INFINITY // the channel saw none of the cloud's single scattering
                } else {
                    1.0
                };
                e.signal[i] = if old > 0.0 {
                    e.signal[i] * factor
                } else {
                    self.instrument.signal_constant * e.range_weight[i] * new
                };
                e.attenuated_backscatter[i] = new;
                e.multiple_scattering[i].water_depolarization = d;
                e.multiple_scattering[i].polarization_factor = factor;
            }
        }
    }

    /// A pre-trigger bin at (negative) range `r_m`: recorded before the pulse leaves, it
    /// sees nothing: no signal, no optics, η = 0, T² = 1, and the molecular state of the
    /// air at the station (docs/file-format.md "Pre-trigger bins").
    fn push_pretrigger_bin(&self, e: &mut ExpectedProfile, r_m: f64) {
        let station_m = self.geometry.platform_altitude_m;
        e.altitude_m.push(self.geometry.altitude_at_range(r_m));
        e.range_m.push(r_m);
        e.point.push(self.atmosphere.no_optics());
        e.bin_mean.push(Default::default());
        e.state.push(self.atmosphere.state_at(station_m));
        e.overlap.push(0.0);
        e.t2.push(1.0);
        e.signal.push(0.0);
        e.range_weight.push(0.0);
        e.attenuated_backscatter.push(0.0);
    }
}

/// No expectation that is not finite reaches a sampler or a file: the first bin whose
/// signal, induced noise, afterpulses, recorded mean or attenuated backscatter is NaN or
/// infinite (or a background or dark rate that is) is a clear error instead.
fn check_finite(e: &ExpectedProfile) -> Result<()> {
    for (what, rate) in [("background", e.background), ("dark", e.dark)] {
        if !rate.is_finite() {
            return Err(Error::Unsupported(format!(
                "the expected {what} counts per bin are not finite ({rate})"
            )));
        }
    }
    let rows: [(&str, &[f64]); 5] = [
        ("signal", &e.signal),
        ("signal-induced noise", &e.induced),
        ("afterpulses", &e.afterpulse),
        ("recorded mean", &e.recorded),
        ("attenuated backscatter", &e.attenuated_backscatter),
    ];
    for (what, row) in rows {
        if let Some(i) = row.iter().position(|v| !v.is_finite()) {
            let z = e.altitude_m.get(i).copied().unwrap_or(f64::NAN);
            return Err(Error::Unsupported(format!(
                "bin {i} (altitude {z:.0} m): the expected {what} is not finite ({}); \
                 a model gave no number there",
                row[i]
            )));
        }
    }
    Ok(())
}
