//! The identity of a run (its `run_id`, a fingerprint of what its whole file holds) and
//! the attributes that make a raw file one shard of it.

use std::ops::Range;

use super::cut::Shard;
use crate::output::raw_file::{AttrValue, RawFileSpec, Variable};

/// A 64-bit FNV-1a hash, fed field by field (each field length-prefixed).
struct Fingerprint(u64);

impl Fingerprint {
    fn new() -> Self {
        Fingerprint(0xcbf2_9ce4_8422_2325)
    }

    fn bytes(&mut self, b: &[u8]) {
        for &x in (b.len() as u64).to_le_bytes().iter().chain(b) {
            self.0 = (self.0 ^ u64::from(x)).wrapping_mul(0x0100_0000_01b3);
        }
    }

    fn str(&mut self, s: &str) {
        self.bytes(s.as_bytes());
    }

    fn num(&mut self, x: u64) {
        self.bytes(&x.to_le_bytes());
    }

    fn f64s(&mut self, xs: &[f64]) {
        self.num(xs.len() as u64);
        xs.iter().for_each(|x| self.num(x.to_bits()));
    }

    fn attr(&mut self, name: &str, value: &AttrValue) {
        self.str(name);
        match value {
            AttrValue::Str(s) => self.str(s),
            AttrValue::U64(v) => self.num(*v),
            AttrValue::I32(v) => self.num(*v as u64),
            AttrValue::F64(v) => self.num(v.to_bits()),
        }
    }

    fn variable(&mut self, v: &Variable) {
        self.str(&v.name);
        self.str(&format!("{:?}", v.dims));
        self.str(&v.long_name);
        self.str(&v.units);
        v.attributes.iter().for_each(|(k, x)| self.attr(k, x));
        self.f64s(&v.data);
    }

    fn hex(&self) -> String {
        format!("{:016x}", self.0)
    }
}

/// Root attributes that record when and how a file was made, not what it holds: left
/// out of the run's identity.
const NOT_IDENTITY: [&str; 2] = ["history", "date_created"];

/// The identity of a run (the `run_id` of its shards): a hash of everything the whole
/// run's file holds besides its profiles and the `history` and `date_created` of its
/// making: the resolved config, seed, method, lidarsim version, profiles, channels,
/// counter width, and every per-bin variable of the model. `merge` recomputes it from
/// the model it rebuilds, so a shard of another run, or a model that would come out
/// differently (another version, a changed file the config names), is refused.
pub fn run_id(spec: &RawFileSpec) -> String {
    let mut h = Fingerprint::new();
    h.num(spec.n_profiles as u64);
    h.num(spec.n_bins as u64);
    spec.channels.iter().for_each(|c| h.str(c));
    h.str(spec.count_width.name());
    h.num(u64::from(spec.components));
    h.str(&spec.time_units);
    spec.variables.iter().for_each(|v| h.variable(v));
    for t in &spec.channel_text {
        h.str(&t.name);
        t.values.iter().for_each(|v| h.str(v));
    }
    h.num(spec.n_columns as u64);
    h.num(spec.column_slots as u64);
    spec.profile_coordinates.iter().for_each(|c| h.str(c));
    spec.root_attributes
        .iter()
        .filter(|(k, _)| !NOT_IDENTITY.contains(&k.as_str()))
        .for_each(|(k, v)| h.attr(k, v));
    h.hex()
}

/// The identity of a validation run: a hash of `parts` (the resolved config, seed,
/// method, realizations, lidarsim version, ...), each field apart.
pub fn fingerprint(parts: &[&str]) -> String {
    fingerprint_with(parts, &[])
}

/// [`fingerprint`] of `parts` and of the bits of `values` (a model the run depends on,
/// so that a run set up again with another model is told apart).
pub fn fingerprint_with(parts: &[&str], values: &[f64]) -> String {
    let mut h = Fingerprint::new();
    parts.iter().for_each(|p| h.str(p));
    if !values.is_empty() {
        h.f64s(values);
    }
    h.hex()
}

/// Root attributes of a shard file, after the whole run's (docs/file-format.md).
pub const SHARD_ATTRIBUTES: [&str; 5] = [
    "shard_index",
    "shard_count",
    "shard_first_profile",
    "run_profiles",
    "run_id",
];

/// The raw file of shard `shard` of the run whose whole file is `spec`: its `rows`,
/// with the profile coordinate of the run, and the [`SHARD_ATTRIBUTES`].
pub fn shard_spec(mut spec: RawFileSpec, shard: Shard, rows: Range<usize>) -> RawFileSpec {
    let id = run_id(&spec);
    let run_profiles = spec.n_profiles as u64;
    spec.n_profiles = rows.len();
    spec.first_profile = rows.start;
    let values = [
        AttrValue::U64(shard.index as u64),
        AttrValue::U64(shard.count as u64),
        AttrValue::U64(rows.start as u64),
        AttrValue::U64(run_profiles),
        AttrValue::Str(id),
    ];
    spec.root_attributes
        .extend(SHARD_ATTRIBUTES.iter().map(|k| k.to_string()).zip(values));
    spec
}
