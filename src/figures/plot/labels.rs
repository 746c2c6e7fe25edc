//! Human labels with units for every config key and metric a figure shows (one table,
//! one place): `instrument.pulse_energy_j` reads "pulse energy (mJ)", `snr_at:10km`
//! reads "S/N at 10 km". A key not in the table is named from its last part, its unit
//! from its suffix (`_j`, `_hz`, `_m2`, …: the config's own convention, docs/config.md).

/// How a quantity is shown: its name, its unit, and the factor from the config's unit
/// to the shown one (values are multiplied by it).
#[derive(Debug, Clone, PartialEq)]
pub struct Label {
    /// What it is, in words.
    pub name: String,
    /// Unit as shown ("" for a ratio).
    pub unit: &'static str,
    /// Shown value = config value × scale.
    pub scale: f64,
}

impl Label {
    /// "name (unit)", or the name alone for a ratio.
    pub fn text(&self) -> String {
        if self.unit.is_empty() {
            self.name.clone()
        } else {
            format!("{} ({})", self.name, self.unit)
        }
    }
}

/// Config keys with a name or a shown unit of their own: (key, name, unit, scale).
const KEYS: &[(&str, &str, &str, f64)] = &[
    ("instrument.pulse_energy_j", "pulse energy", "mJ", 1e3),
    ("instrument.rep_rate_hz", "repetition rate", "Hz", 1.0),
    ("instrument.telescope_area_m2", "telescope area", "m²", 1.0),
    (
        "instrument.fov_rad",
        "field of view (full angle)",
        "µrad",
        1e6,
    ),
    (
        "instrument.beam_divergence_rad",
        "beam divergence (1/e half-width)",
        "µrad",
        1e6,
    ),
    ("instrument.filter_width_nm", "filter width", "nm", 1.0),
    (
        "instrument.filter_transmission",
        "filter transmission",
        "",
        1.0,
    ),
    (
        "instrument.receiver_efficiency",
        "receiver efficiency",
        "",
        1.0,
    ),
    (
        "instrument.optical_efficiency",
        "optical efficiency",
        "",
        1.0,
    ),
    (
        "instrument.quantum_efficiency",
        "quantum efficiency",
        "",
        1.0,
    ),
    ("instrument.wavelength_nm", "wavelength", "nm", 1.0),
    ("instrument.bin_width_s", "bin width", "ns", 1e9),
    (
        "instrument.dark_count_rate_hz",
        "dark count rate",
        "counts/s",
        1.0,
    ),
    (
        "acquisition.accumulation_time_s",
        "accumulation time",
        "s",
        1.0,
    ),
    ("platform.altitude_km", "platform altitude", "km", 1.0),
    ("platform.off_nadir_deg", "off-nadir angle", "°", 1.0),
    (
        "background.radiance",
        "background radiance",
        "photons m⁻² s⁻¹ sr⁻¹ nm⁻¹",
        1.0,
    ),
];

/// Units by key suffix, longest first: (suffix, unit, scale).
const SUFFIXES: &[(&str, &str, f64)] = &[
    ("_per_km", "km⁻¹", 1.0),
    ("_m2", "m²", 1.0),
    ("_hz", "Hz", 1.0),
    ("_km", "km", 1.0),
    ("_nm", "nm", 1.0),
    ("_um", "µm", 1.0),
    ("_sr", "sr", 1.0),
    ("_deg", "°", 1.0),
    ("_rad", "rad", 1.0),
    ("_j", "J", 1.0),
    ("_s", "s", 1.0),
    ("_m", "m", 1.0),
];

/// The label of a config key (`instrument.pulse_energy_j`) or a metric (`snr_at:10km`,
/// `max_altitude:snr=3`, `time_to_snr:10@15km`, `counts_per_shot`, …).
pub fn describe(key: &str) -> Label {
    if let Some(l) = metric(key) {
        return l;
    }
    if let Some(&(_, name, unit, scale)) = KEYS.iter().find(|k| k.0 == key) {
        return Label {
            name: name.into(),
            unit,
            scale,
        };
    }
    let last = key.rsplit('.').next().unwrap_or(key);
    let (stem, unit, scale) = SUFFIXES
        .iter()
        .find_map(|&(s, u, f)| last.strip_suffix(s).map(|stem| (stem, u, f)))
        .unwrap_or((last, "", 1.0));
    Label {
        name: stem.replace('_', " "),
        unit,
        scale,
    }
}

/// The sweep metrics (`src/design/sweep.rs`) and the quantities of the quicklook.
fn metric(key: &str) -> Option<Label> {
    let label = |name: String, unit: &'static str| Label {
        name,
        unit,
        scale: 1.0,
    };
    let (kind, arg) = key.split_once(':').unwrap_or((key, ""));
    Some(match kind {
        "snr_at" => label(format!("S/N at {}", arg.replace("km", " km")), ""),
        "max_altitude" => label(
            format!(
                "highest altitude with S/N ≥ {}",
                arg.trim_start_matches("snr=")
            ),
            "km",
        ),
        "time_to_snr" => {
            let (x, z) = arg.split_once('@').unwrap_or((arg, ""));
            label(
                format!("time to S/N {x} at {}", z.replace("km", " km")),
                "s",
            )
        }
        "range_corrected_signal" => label("range-corrected signal".into(), "counts per shot × km²"),
        "attenuated_backscatter" => label("attenuated backscatter".into(), "m⁻¹ sr⁻¹"),
        "volume_depolarization" => label("volume depolarization ratio".into(), ""),
        "counts_per_shot" => label("counts per shot".into(), ""),
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_read_with_units() {
        assert_eq!(
            describe("instrument.pulse_energy_j").text(),
            "pulse energy (mJ)"
        );
        assert_eq!(describe("instrument.pulse_energy_j").scale, 1e3);
        assert_eq!(
            describe("instrument.telescope_area_m2").text(),
            "telescope area (m²)"
        );
        // from the suffix
        assert_eq!(
            describe("atmosphere.aerosol.visibility_km").text(),
            "visibility (km)"
        );
        assert_eq!(describe("detector.dead_time_s").text(), "dead time (s)");
        assert_eq!(describe("something.plain").text(), "plain");
    }

    #[test]
    fn metrics_read_in_words() {
        assert_eq!(describe("snr_at:20km").text(), "S/N at 20 km");
        assert_eq!(
            describe("max_altitude:snr=3").text(),
            "highest altitude with S/N ≥ 3 (km)"
        );
        assert_eq!(
            describe("time_to_snr:10@10km").text(),
            "time to S/N 10 at 10 km (s)"
        );
    }
}
