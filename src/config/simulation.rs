//! `[simulation]`: the Monte Carlo method, the seed and the components kept.

use serde::{Deserialize, Serialize};

/// Monte Carlo method (docs/config.md `--method`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize, Serialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// `aggregate` whenever the scene allows it, else `shot`.
    #[default]
    Auto,
    /// Every shot drawn.
    Shot,
    /// One exact Poisson(M·λ) draw per bin per profile.
    Aggregate,
}

/// How a changing scene's truth is stored in the raw file (docs/file-format.md, "The
/// truth of each profile"): at the dimensions of what it depends on, or also per profile.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize, Serialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum TruthForm {
    /// Per column what depends on the atmosphere, per (profile, channel) what depends
    /// on the profile alone, per (profile, channel, bin) only what varies in all three.
    #[default]
    Compact,
    /// Also the format-3 arrays (profile, channel, bin) of `expected_signal`,
    /// `expected_background`, `expected_counts`, `snr_eq4` and `attenuated_backscatter`.
    PerProfile,
}

/// Monte Carlo settings.
#[derive(Debug, Clone, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SimulationConfig {
    /// Random seed: a whole number, or one above 2^63 − 1 (beyond a TOML integer) as a
    /// string of its digits ([`seed_value`]).
    #[serde(default, deserialize_with = "seed_of")]
    pub seed: u64,
    /// Sampling method.
    #[serde(default)]
    pub method: Method,
    /// Store signal, background and dark counts separately as well.
    #[serde(default)]
    pub components: bool,
    /// With `method = "auto"`: the largest Kolmogorov–Smirnov distance per bin to the
    /// exact law that a faster approximate method may have (see `docs/simulation.md`).
    #[serde(default)]
    pub tolerance: Option<f64>,
    /// How a changing scene's truth is stored (`--truth`).
    #[serde(default)]
    pub truth: TruthForm,
}

/// The TOML value of `simulation.seed`: an integer, or the string of its digits above
/// 2^63 − 1, which a TOML integer cannot hold (every seed `--seed` takes, 0 to 2^64 − 1,
/// can so be written into a config).
pub fn seed_value(seed: u64) -> toml::Value {
    match i64::try_from(seed) {
        Ok(n) => toml::Value::Integer(n),
        Err(_) => toml::Value::String(seed.to_string()),
    }
}

/// Reads `simulation.seed` as [`seed_value`] writes it.
fn seed_of<'de, D: serde::Deserializer<'de>>(d: D) -> std::result::Result<u64, D::Error> {
    struct Seed;
    impl serde::de::Visitor<'_> for Seed {
        type Value = u64;
        fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            f.write_str("a whole number from 0 to 18446744073709551615")
        }
        fn visit_u64<E: serde::de::Error>(self, v: u64) -> std::result::Result<u64, E> {
            Ok(v)
        }
        fn visit_i64<E: serde::de::Error>(self, v: i64) -> std::result::Result<u64, E> {
            u64::try_from(v).map_err(|_| E::invalid_value(serde::de::Unexpected::Signed(v), &self))
        }
        fn visit_str<E: serde::de::Error>(self, v: &str) -> std::result::Result<u64, E> {
            v.trim()
                .parse()
                .map_err(|_| E::invalid_value(serde::de::Unexpected::Str(v), &self))
        }
    }
    d.deserialize_any(Seed)
}
