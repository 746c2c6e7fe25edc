//! The pieces of a run (shard files, partials): that they belong to one run and cover it
//! exactly once; a partial read.

use std::ops::Range;
use std::path::Path;

use super::cut::Shard;
use crate::error::{Error, Result};

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
    /// The run's hash ([`run_id`](super::identity::run_id),
    /// [`fingerprint`](super::identity::fingerprint)).
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

#[cfg(test)]
mod tests {
    use super::*;

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
