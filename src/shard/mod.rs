//! Scale-out: a run cut into N shards, each drawn by its own process (a Slurm array task,
//! a Kubernetes indexed Job's pod), then merged into the file the whole run writes
//! (`docs/scale.md`).
//!
//! Counts depend on (seed, profile, block) only, so shard K of N of a P-profile run
//! draws exactly the whole run's counts for its profiles `⌊K·P/N⌋ … ⌊(K+1)·P/N⌋ − 1`
//! ([`Shard::rows`]). The same cut splits `validate`'s realizations.
//!
//! * this module: the shard (`K/N`, or `auto` from an array job's environment,
//!   [`mod@env`]), its rows, the run's identity ([`run_id`]), the attributes of a shard file
//!   ([`shard_spec`]), the lidar of a stored config ([`stored_lidar`]) and the checks that
//!   pieces cover one run exactly once ([`check_cover`]);
//! * [`merge`]: `lidarsim merge OUT.h5 SHARD.h5 ...`.

pub mod env;
pub mod merge;

use std::ops::Range;
use std::path::Path;

use crate::error::{Error, Result};
use crate::output::raw_file::{AttrValue, RawFileSpec, Variable};
use crate::scenario::Lidar;

/// One shard of a run: `index` of `count` (0 ≤ index < count).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// K, from 0.
    pub index: usize,
    /// N, at least 1.
    pub count: usize,
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

impl Shard {
    /// Shard `index` of `count`; refuses `count = 0` and `index ≥ count`.
    pub fn new(index: usize, count: usize) -> std::result::Result<Shard, String> {
        if count == 0 {
            return Err("the shard count N must be at least 1".into());
        }
        if index >= count {
            return Err(format!(
                "shard {index} of {count} does not exist: K runs from 0 to N-1 = {}",
                count - 1
            ));
        }
        Ok(Shard { index, count })
    }

    /// Its rows of `total`: `⌊K·total/N⌋ .. ⌊(K+1)·total/N⌋` (empty when N > total).
    pub fn rows(self, total: usize) -> Range<usize> {
        let at = |k: usize| (k as u128 * total as u128 / self.count as u128) as usize;
        at(self.index)..at(self.index + 1)
    }

    /// [`Shard::rows`], refusing a cut that leaves shards empty (N greater than the
    /// `total` of `what`, e.g. profiles): an empty shard could not be a valid raw file.
    pub fn rows_of(self, total: usize, what: &str) -> Result<Range<usize>> {
        if self.count > total {
            return Err(Error::Unsupported(format!(
                "--shard {self}: {} shards of {total} {what} would leave shards empty; \
                 use at most {total} shards",
                self.count
            )));
        }
        Ok(self.rows(total))
    }
}

/// The value of `--shard`: `K/N`, or `auto` (from the environment of an array job).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ShardArg {
    /// `K/N`.
    Fixed(Shard),
    /// `auto`: [`env::from_environment`].
    Auto,
}

impl std::str::FromStr for ShardArg {
    type Err = String;

    fn from_str(s: &str) -> std::result::Result<Self, String> {
        let s = s.trim();
        if s == "auto" {
            return Ok(ShardArg::Auto);
        }
        let form = || format!("{s:?} is not K/N (e.g. 0/4) or auto");
        let (k, n) = s.split_once('/').ok_or_else(form)?;
        let k: usize = k.trim().parse().map_err(|_| form())?;
        let n: usize = n.trim().parse().map_err(|_| form())?;
        Shard::new(k, n).map(ShardArg::Fixed)
    }
}

impl ShardArg {
    /// The shard: as given, or read from this process's environment.
    pub fn resolve(self) -> Result<Shard> {
        match self {
            ShardArg::Fixed(s) => Ok(s),
            ShardArg::Auto => env::from_environment(|name| std::env::var(name).ok()),
        }
    }
}

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

/// The lidar of a config stored in a file (`config`: the resolved TOML; `config_file`:
/// the config's path as the run named it, against which the files it names resolve).
pub fn stored_lidar(config: &str, config_file: &str) -> Result<Lidar> {
    let loaded = crate::loaded::load_str(config, Path::new(config_file), &[])?;
    Lidar::from_loaded(loaded)
}

/// What makes pieces of a run (shard files, validation partials) belong to one run.
#[derive(Debug, Clone, PartialEq)]
pub struct RunIdentity {
    /// The resolved config.
    pub config: String,
    /// The seed.
    pub seed: u64,
    /// The method used.
    pub method: String,
    /// N.
    pub shard_count: usize,
    /// Profiles (or realizations) of the whole run.
    pub total: usize,
    /// The run's hash ([`run_id`], [`fingerprint`]).
    pub run_id: String,
}

/// Refuses pieces of different runs: each of `pieces` (a file and its identity) against
/// the first, naming the file, the field that differs and its two values. `kind` names
/// the pieces (`shard`, `partial`), `total` what the run counts (`profiles`).
pub fn check_same_run(pieces: &[(&Path, &RunIdentity)], kind: &str, total: &str) -> Result<()> {
    let Some(&(first_path, f)) = pieces.first() else {
        return Ok(());
    };
    for &(path, p) in pieces {
        let pair = |a: &dyn std::fmt::Display, b: &dyn std::fmt::Display| format!(" ({a} vs {b})");
        // the fields with values first: the stored config holds the seed and profiles
        // too, so a seed that differs makes the config differ as well
        let differs = [
            ("seed", f.seed != p.seed, pair(&p.seed, &f.seed)),
            ("method", f.method != p.method, pair(&p.method, &f.method)),
            (
                "shard count N",
                f.shard_count != p.shard_count,
                pair(&p.shard_count, &f.shard_count),
            ),
            (total, f.total != p.total, pair(&p.total, &f.total)),
            ("config", f.config != p.config, String::new()),
            ("run_id", f.run_id != p.run_id, pair(&p.run_id, &f.run_id)),
        ];
        if let Some((what, _, values)) = differs.into_iter().find(|d| d.1) {
            return Err(Error::output(
                path,
                format!(
                    "a {kind} of another run than {}: its {what} differs{values}",
                    first_path.display()
                ),
            ));
        }
    }
    Ok(())
}

/// Checks that `pieces` (a name and a shard each, every shard of the same count) cover
/// the run exactly once, and gives their order by shard index. A shard given twice is
/// an overlap, a missing one a gap; both are refused naming the files or the shard and
/// the `what` it would have held (`rows` gives them).
pub fn check_cover(
    pieces: &[(&Path, Shard)],
    rows: impl Fn(Shard) -> Range<usize>,
    what: &str,
) -> Result<Vec<usize>> {
    let Some(&(_, first)) = pieces.first() else {
        return Err(Error::Unsupported("no shard given".into()));
    };
    let mut order: Vec<Option<usize>> = vec![None; first.count];
    for (i, &(path, shard)) in pieces.iter().enumerate() {
        if let Some(j) = order[shard.index] {
            let r = rows(shard);
            let reason = if pieces[j].0 == path {
                format!("given twice (shard {shard})")
            } else {
                format!(
                    "overlaps {}: both are shard {shard} ({what} {}–{})",
                    pieces[j].0.display(),
                    r.start,
                    r.end.saturating_sub(1)
                )
            };
            return Err(Error::output(path, reason));
        }
        order[shard.index] = Some(i);
    }
    let missing: Vec<String> = (0..first.count)
        .filter(|&k| order[k].is_none())
        .map(|k| {
            let s = Shard {
                index: k,
                count: first.count,
            };
            let r = rows(s);
            format!("shard {s} ({what} {}–{})", r.start, r.end.saturating_sub(1))
        })
        .collect();
    if !missing.is_empty() {
        return Err(Error::Unsupported(format!(
            "a gap: {} of the run {} missing; give every shard once",
            missing.join(", "),
            if missing.len() > 1 { "are" } else { "is" }
        )));
    }
    Ok(order.into_iter().flatten().collect())
}

/// A piece of a run (a shard file, a partial): its file, the run it says it belongs to,
/// its shard index and the rows it holds.
pub struct Piece<'a> {
    /// Its file.
    pub path: &'a Path,
    /// The run it belongs to (with the shard count N).
    pub identity: RunIdentity,
    /// K.
    pub shard_index: usize,
    /// The rows of the run it holds.
    pub rows: Range<usize>,
}

/// Checks that `pieces` belong to one run ([`check_same_run`]), that each holds the rows
/// of its shard (`rows` gives them) and that they cover the run exactly once
/// ([`check_cover`]); gives their order by shard index. `kind` names the pieces
/// (`shard`, `partial`), `what` the rows (`profiles`, `realizations`, `shots`).
pub fn check_pieces(
    pieces: &[Piece],
    kind: &str,
    what: &str,
    rows: impl Fn(Shard) -> Range<usize>,
) -> Result<Vec<usize>> {
    let same: Vec<(&Path, &RunIdentity)> = pieces.iter().map(|p| (p.path, &p.identity)).collect();
    check_same_run(&same, kind, what)?;
    let mut shards = Vec::with_capacity(pieces.len());
    for p in pieces {
        let shard = Shard::new(p.shard_index, p.identity.shard_count)
            .map_err(|why| Error::output(p.path, format!("shard_index/shard_count: {why}")))?;
        let want = rows(shard);
        if want != p.rows {
            let span = |r: &Range<usize>| format!("{}–{}", r.start, r.end.saturating_sub(1));
            return Err(Error::output(
                p.path,
                format!(
                    "holds {what} {}, but shard {shard} of the run's {} {what} is {what} {}",
                    span(&p.rows),
                    p.identity.total,
                    span(&want)
                ),
            ));
        }
        shards.push((p.path, shard));
    }
    check_cover(&shards, rows, what)
}

/// Reads a partial (JSON) whose `format` must be `format`; one line naming the file when
/// it is not one (`made_by`: the command that writes such partials).
pub fn read_partial<T: serde::de::DeserializeOwned>(
    path: &Path,
    format: &str,
    made_by: &str,
) -> Result<T> {
    // the text, and what it parses to: a number of the sums takes at least 2 bytes of
    // text and at most 16 bytes parsed, so about 8 times the file at most
    if let Ok(m) = std::fs::metadata(path) {
        crate::resources::require_memory(
            &format!("{}: reading the partial", path.display()),
            9.0 * m.len() as f64,
        )?;
    }
    let text = crate::input_file::read_to_string("--combine", path)?;
    let not_one = |e: &dyn std::fmt::Display| {
        Error::output(path, format!("not a partial of `{made_by}` ({e})"))
    };
    let value: serde_json::Value = serde_json::from_str(&text).map_err(|e| not_one(&e))?;
    match value.get("format").and_then(|f| f.as_str()) {
        Some(f) if f == format => serde_json::from_value(value).map_err(|e| not_one(&e)),
        Some(f) => Err(Error::output(
            path,
            format!("a partial of format {f:?}; this lidarsim reads {format:?} here"),
        )),
        None => Err(not_one(&"no `format`")),
    }
}

/// The root attributes of an HDF5 shard file, read with one-line errors naming it.
pub struct FileAttributes<'a> {
    /// The open file.
    pub file: &'a hdf5::File,
    /// Its path, for messages.
    pub path: &'a Path,
}

impl FileAttributes<'_> {
    fn fail(&self, why: String) -> Error {
        Error::output(self.path, why)
    }

    /// A text attribute.
    pub fn text(&self, name: &str) -> Result<String> {
        self.file
            .attr(name)
            .and_then(|a| a.read_scalar::<hdf5::types::VarLenUnicode>())
            .map(|v| v.as_str().to_string())
            .map_err(|_| self.fail(format!("has no text attribute `{name}`")))
    }

    /// A whole-number attribute.
    pub fn number(&self, name: &str) -> Result<u64> {
        self.file
            .attr(name)
            .and_then(|a| a.read_scalar::<u64>())
            .map_err(|_| self.fail(format!("has no whole-number attribute `{name}`")))
    }

    /// A whole-number attribute as a size.
    pub fn whole(&self, name: &str) -> Result<usize> {
        usize::try_from(self.number(name)?).map_err(|_| self.fail(format!("`{name}` too large")))
    }

    /// A real attribute, if present.
    pub fn real(&self, name: &str) -> Option<f64> {
        self.file
            .attr(name)
            .and_then(|a| a.read_scalar::<f64>())
            .ok()
    }

    /// Its shard (`shard_index` of `shard_count`).
    pub fn shard(&self) -> Result<Shard> {
        Shard::new(self.whole("shard_index")?, self.whole("shard_count")?)
            .map_err(|why| self.fail(format!("shard_index/shard_count: {why}")))
    }
}

/// What a shard file is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ShardKind {
    /// A raw file of `simulate --shard`.
    Raw,
    /// An onboard product of `onboard --shard`.
    Product,
}

impl ShardKind {
    fn describe(self) -> &'static str {
        match self {
            ShardKind::Raw => "a raw shard (of `simulate --shard`)",
            ShardKind::Product => "a product shard (of `onboard --shard`)",
        }
    }
}

/// Opens the shard file at `path` and says what it is; one line naming the file when it
/// is not HDF5 or not a shard.
pub fn open_shard(path: &Path) -> Result<(hdf5::File, ShardKind)> {
    let fail = |why: &str| Error::output(path, why);
    crate::input_file::check("SHARD.h5", path)?;
    let file = hdf5::File::open(path)
        .map_err(|_| fail("not a lidarsim raw file or product (not HDF5, or unreadable)"))?;
    if file.attr("shard_index").is_err() {
        return Err(fail(
            "not a shard (no `shard_index` attribute): merge takes the files of \
             `simulate --shard K/N` or of `onboard --shard K/N`",
        ));
    }
    let kind = match file.attr(crate::onboard::run::PRODUCT_ATTRIBUTE) {
        Ok(_) => ShardKind::Product,
        Err(_) => ShardKind::Raw,
    };
    Ok((file, kind))
}

/// What the shards given to `merge` are: all raw or all product shards; refuses a file
/// that is no shard, and a mix, naming the file.
pub fn kind_of_shards(paths: &[std::path::PathBuf]) -> Result<ShardKind> {
    let mut first: Option<(&Path, ShardKind)> = None;
    for path in paths {
        let kind = open_shard(path)?.1;
        match first {
            Some((p, k)) if k != kind => {
                return Err(Error::output(
                    path,
                    format!(
                        "{}, but {} is {}: merge raw shards and product shards apart",
                        kind.describe(),
                        p.display(),
                        k.describe()
                    ),
                ));
            }
            None => first = Some((path, kind)),
            _ => {}
        }
    }
    first
        .map(|(_, k)| k)
        .ok_or_else(|| Error::Unsupported("merge needs at least one shard".into()))
}

/// Refuses a merge into `out` where the free space is below the shards' size.
pub fn require_disk_for_merge<'a>(
    out: &Path,
    shards: impl IntoIterator<Item = &'a Path>,
) -> Result<()> {
    let bytes: u64 = shards
        .into_iter()
        .filter_map(|p| std::fs::metadata(p).ok())
        .map(|m| m.len())
        .sum();
    crate::resources::require_disk("OUT.h5", out, bytes as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_cut_the_run_in_order_exactly_once() {
        for total in [1usize, 7, 10, 12, 1000] {
            for count in 1..=total.min(9) {
                let mut next = 0;
                for index in 0..count {
                    let r = Shard::new(index, count).unwrap().rows(total);
                    assert_eq!(r.start, next);
                    assert!(!r.is_empty(), "{index}/{count} of {total}");
                    next = r.end;
                }
                assert_eq!(next, total);
            }
        }
        assert_eq!(Shard::new(1, 3).unwrap().rows(10), 3..6);
    }

    #[test]
    fn shard_arguments_parse_or_say_why_not() {
        assert_eq!(
            "2/4".parse::<ShardArg>(),
            Ok(ShardArg::Fixed(Shard { index: 2, count: 4 }))
        );
        assert_eq!("auto".parse::<ShardArg>(), Ok(ShardArg::Auto));
        assert!(
            "4/4"
                .parse::<ShardArg>()
                .unwrap_err()
                .contains("0 to N-1 = 3")
        );
        assert!(
            "0/0"
                .parse::<ShardArg>()
                .unwrap_err()
                .contains("at least 1")
        );
        assert!("x".parse::<ShardArg>().unwrap_err().contains("K/N"));
        let s = Shard::new(0, 5).unwrap();
        assert!(s.rows_of(4, "profiles").is_err());
        assert_eq!(s.rows_of(5, "profiles").unwrap(), 0..1);
    }

    #[test]
    fn gaps_and_overlaps_are_named() {
        let (a, b, c) = (Path::new("a.h5"), Path::new("b.h5"), Path::new("c.h5"));
        let s = |k| Shard { index: k, count: 3 };
        let rows = |s: Shard| s.rows(10);
        assert_eq!(
            check_cover(&[(c, s(2)), (a, s(0)), (b, s(1))], rows, "profiles").unwrap(),
            vec![1, 2, 0]
        );
        let gap = check_cover(&[(a, s(0)), (c, s(2))], rows, "profiles").unwrap_err();
        assert!(
            gap.to_string().contains("shard 1/3 (profiles 3–5)"),
            "{gap}"
        );
        let overlap = check_cover(&[(a, s(0)), (b, s(0))], rows, "profiles").unwrap_err();
        assert!(
            overlap.to_string().starts_with("b.h5: overlaps a.h5"),
            "{overlap}"
        );
    }
}
