//! The module import graph of `src/` (docs/architecture.md, "Module layout"):
//! `config` sits at the bottom (no circle of imports passes through it), the sampler
//! below the detector and the onboard sums, `sampling` and `config` naming only the
//! leaves, and no circle but the raw-file reader's two halves (`ALLOWED_CIRCLES`).
//!
//! A module is a file (`src/a/b.rs` and `src/a/b/mod.rs` are `a::b`, `src/lib.rs` the
//! crate root; `src/main.rs` is the binary and uses the library by its name). An edge
//! `A → B` is a path in A's code or doc comments (other comments and string literals
//! stripped: a doc link names a module as a `use` does) that starts
//! with `crate::`, `super::`, `self::` or a child module of A (`use dead_time::…` in
//! `detector/mod.rs`), mapped to the deepest module file it names
//! (`crate::sampling::approx::MAX_TOLERANCE` → `sampling::approx`). `mod x;`
//! declarations are not edges; inline modules (`mod tests { … }`) belong to their
//! file. A circle is a strongly connected component of more than one file.
//!
//! Run: `cargo test --release --test import_graph -- --nocapture` (prints the
//! circles; with `IMPORT_GRAPH_EDGES=1` every module's edges too).

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The largest circle the tree may have, in files.
const MAX_CIRCLE_FILES: usize = 2;

/// The only circles the tree may have, each with its reason. A raw file's reader is one
/// check in two halves: `read` checks the header and then calls `integrity` on what the
/// values mean, and `integrity` reads the values through `read`'s typed readers (one
/// place that decides how a dataset is read and when it is refused).
const ALLOWED_CIRCLES: [&[&str]; 1] = [&["output::raw_file::integrity", "output::raw_file::read"]];

/// Modules no circle may pass through: they sit at the bottom of the graph.
const BOTTOM: [&str; 1] = ["config"];

type Graph = BTreeMap<String, BTreeSet<String>>;

#[test]
fn config_is_in_no_circle_and_circles_do_not_grow() {
    let graph = import_graph(&Path::new(env!("CARGO_MANIFEST_DIR")).join("src"));
    let circles = circles(&graph);
    println!("{} modules, {} circles", graph.len(), circles.len());
    if std::env::var_os("IMPORT_GRAPH_EDGES").is_some() {
        for (m, edges) in &graph {
            println!(
                "{m} -> {}",
                Vec::from_iter(edges.iter().map(String::as_str)).join(", ")
            );
        }
    }
    for c in &circles {
        println!("circle of {} files: {}", c.len(), c.join(", "));
    }
    for bottom in BOTTOM {
        let inside = |m: &String| m == bottom || m.starts_with(&format!("{bottom}::"));
        if let Some(c) = circles.iter().find(|c| c.iter().any(inside)) {
            let start = c.iter().find(|m| inside(m)).unwrap();
            panic!(
                "`{bottom}` is in a circle of {} files; one cycle through it: {}",
                c.len(),
                cycle_through(&graph, c, start).join(" -> ")
            );
        }
    }
    for c in &circles {
        assert!(
            ALLOWED_CIRCLES
                .iter()
                .any(|a| a.len() == c.len() && c.iter().all(|m| a.contains(&m.as_str()))),
            "an import circle outside ALLOWED_CIRCLES: {}",
            c.join(", ")
        );
    }
    let largest = circles.iter().map(Vec::len).max().unwrap_or(0);
    println!("largest circle: {largest} files (allowed: {MAX_CIRCLE_FILES})");
    assert!(
        largest <= MAX_CIRCLE_FILES,
        "the largest import circle grew to {largest} files (at most {MAX_CIRCLE_FILES}): {}",
        circles
            .iter()
            .find(|c| c.len() == largest)
            .unwrap()
            .join(", ")
    );
}

/// Layers that only go one way: no module of the first reaches one of the second
/// (the sampler knows counts and means; the detector and the onboard sums wrap it).
const BELOW: [(&str, &str); 2] = [("sampling", "detector"), ("sampling", "onboard")];

#[test]
fn the_sampler_reaches_neither_detector_nor_onboard() {
    let graph = import_graph(&Path::new(env!("CARGO_MANIFEST_DIR")).join("src"));
    let under = |m: &str, top: &str| m == top || m.starts_with(&format!("{top}::"));
    for (low, high) in BELOW {
        for start in graph.keys().filter(|m| under(m, low)) {
            let mut seen = BTreeSet::from([start.as_str()]);
            let mut todo = vec![(start.as_str(), vec![start.clone()])];
            while let Some((m, path)) = todo.pop() {
                for next in graph.get(m).into_iter().flatten() {
                    let path: Vec<String> = path.iter().cloned().chain([next.clone()]).collect();
                    assert!(
                        !under(next, high),
                        "{low} reaches {high}: {}",
                        path.join(" -> ")
                    );
                    if seen.insert(next) {
                        todo.push((next, path));
                    }
                }
            }
        }
    }
}

/// Folders at the bottom of the graph and the only modules outside themselves they may
/// name: the leaves (`constants`, `error`, `limits`). The sampler knows counts and
/// means, not lasers, configs or files (a laser hands it energy factors through a trait
/// of its own); the config parses and holds the typed sections, and each domain module
/// checks its own keys (docs/architecture.md).
const LEAF_ONLY: [&str; 2] = ["sampling", "config"];
const LEAVES: [&str; 3] = ["constants", "error", "limits"];

#[test]
fn sampling_and_config_import_only_the_leaves() {
    let graph = import_graph(&Path::new(env!("CARGO_MANIFEST_DIR")).join("src"));
    let under = |m: &str, top: &str| m == top || m.starts_with(&format!("{top}::"));
    let mut wrong = Vec::new();
    for folder in LEAF_ONLY {
        for (m, edges) in graph.iter().filter(|(m, _)| under(m, folder)) {
            for e in edges {
                if !under(e, folder) && !LEAVES.iter().any(|leaf| under(e, leaf)) {
                    wrong.push(format!("{m} -> {e}"));
                }
            }
        }
    }
    assert!(
        wrong.is_empty(),
        "sampling and config may name only themselves and {LEAVES:?}: {}",
        wrong.join(", ")
    );
}

/// The graph of every module file under `src`, by module path.
fn import_graph(src: &Path) -> Graph {
    let mut files = Vec::new();
    rust_files(src, &mut files);
    let modules: BTreeMap<String, PathBuf> = files
        .into_iter()
        .filter_map(|f| module_of(src, &f).map(|m| (m, f)))
        .collect();
    let known: BTreeSet<String> = modules.keys().cloned().collect();
    modules
        .iter()
        .map(|(m, f)| {
            let (code, docs) = strip(&std::fs::read_to_string(f).unwrap());
            let mut edges = imports(m, &tokens(&code), &known);
            // a doc comment's braces are prose: only its paths count
            let doc_paths: Vec<String> = tokens(&docs)
                .into_iter()
                .filter(|t| !matches!(t.as_str(), "{" | "}" | "mod"))
                .collect();
            edges.extend(imports(m, &doc_paths, &known));
            edges.remove(m);
            (m.clone(), edges)
        })
        .collect()
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let p = entry.unwrap().path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|e| e == "rs") {
            out.push(p);
        }
    }
}

/// `a::b` for `src/a/b.rs` or `src/a/b/mod.rs`, `""` for `src/lib.rs`; `None` for the
/// binary.
fn module_of(src: &Path, file: &Path) -> Option<String> {
    let rel = file.strip_prefix(src).unwrap().with_extension("");
    let mut parts: Vec<String> = rel
        .components()
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect();
    match parts.last().map(String::as_str) {
        Some("main") if parts.len() == 1 => return None,
        Some("lib") if parts.len() == 1 => return Some(String::new()),
        Some("mod") => {
            parts.pop();
        }
        _ => {}
    }
    Some(parts.join("::"))
}

/// The code without comments, string and character literals (their braces and paths
/// are not code), and apart the text of the doc comments (whose links name modules).
fn strip(text: &str) -> (String, String) {
    let c: Vec<char> = text.chars().collect();
    let mut out = String::with_capacity(text.len());
    let mut docs = String::new();
    let mut i = 0;
    while i < c.len() {
        if c[i] == '/' && at(&c, i + 1) == '/' {
            let doc = matches!(at(&c, i + 2), '/' | '!');
            while i < c.len() && c[i] != '\n' {
                if doc {
                    docs.push(c[i]);
                }
                i += 1;
            }
            docs.push('\n');
        } else if c[i] == '/' && at(&c, i + 1) == '*' {
            let mut depth = 0;
            while i < c.len() {
                if c[i] == '/' && at(&c, i + 1) == '*' {
                    depth += 1;
                    i += 2;
                } else if c[i] == '*' && at(&c, i + 1) == '/' {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    i += 1;
                }
            }
        } else if c[i] == 'r'
            && (at(&c, i + 1) == '#' || at(&c, i + 1) == '"')
            && !ident_before(&c, i)
        {
            let hashes = (1..).take_while(|&k| at(&c, i + k) == '#').count();
            if at(&c, i + 1 + hashes) != '"' {
                out.push(c[i]);
                i += 1;
                continue;
            }
            let close: String = std::iter::once('"')
                .chain(std::iter::repeat_n('#', hashes))
                .collect();
            i += 2 + hashes;
            while i < c.len() && !c[i..].iter().collect::<String>().starts_with(&close) {
                i += 1;
            }
            i += close.len();
            out.push_str("\"\"");
        } else if c[i] == '"' {
            i += 1;
            while i < c.len() && c[i] != '"' {
                i += if c[i] == '\\' { 2 } else { 1 };
            }
            i += 1;
            out.push_str("\"\"");
        } else if c[i] == '\'' && (at(&c, i + 2) == '\'' || at(&c, i + 1) == '\\') {
            // a character literal ('x', '\n', '\u{7f}'), not a lifetime
            i += 1;
            while i < c.len() && c[i] != '\'' {
                i += if c[i] == '\\' { 2 } else { 1 };
            }
            i += 1;
            out.push_str("' '");
        } else {
            out.push(c[i]);
            i += 1;
        }
    }
    (out, docs)
}

fn at(c: &[char], k: usize) -> char {
    c.get(k).copied().unwrap_or(' ')
}

fn ident_before(c: &[char], i: usize) -> bool {
    i > 0 && (c[i - 1].is_alphanumeric() || c[i - 1] == '_')
}

/// Identifiers, `::` and single punctuation characters.
fn tokens(code: &str) -> Vec<String> {
    let c: Vec<char> = code.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < c.len() {
        if c[i].is_alphanumeric() || c[i] == '_' {
            let start = i;
            while i < c.len() && (c[i].is_alphanumeric() || c[i] == '_') {
                i += 1;
            }
            out.push(c[start..i].iter().collect());
        } else if c[i] == ':' && c.get(i + 1) == Some(&':') {
            out.push("::".into());
            i += 2;
        } else {
            if !c[i].is_whitespace() {
                out.push(c[i].to_string());
            }
            i += 1;
        }
    }
    out
}

/// The modules the code of module `module` names.
fn imports(module: &str, t: &[String], known: &BTreeSet<String>) -> BTreeSet<String> {
    let own: Vec<String> = segments(module);
    let mut inline: Vec<(String, usize)> = Vec::new(); // inline modules and their depth
    let mut depth = 0;
    let mut edges = BTreeSet::new();
    let mut i = 0;
    while i < t.len() {
        match t[i].as_str() {
            "{" => depth += 1,
            "}" => {
                depth -= 1;
                if inline.last().is_some_and(|(_, d)| *d == depth) {
                    inline.pop();
                }
            }
            "mod" if t.get(i + 2).is_some_and(|s| s == "{") => {
                inline.push((t[i + 1].clone(), depth));
                depth += 1;
                i += 3;
                continue;
            }
            _ => {}
        }
        let here: Vec<String> = own
            .iter()
            .cloned()
            .chain(inline.iter().map(|(m, _)| m.clone()))
            .collect();
        let starts_path = t.get(i + 1).is_some_and(|s| s == "::")
            && (i == 0 || t[i - 1] != "::")
            && match t[i].as_str() {
                "crate" | "super" | "self" => true,
                child => known.contains(&join(&here, Some(child))),
            };
        if starts_path {
            let mut paths = Vec::new();
            use_tree(t, &mut i, here, &mut paths);
            edges.extend(paths.iter().filter_map(|p| deepest(p, known)));
        } else {
            i += 1;
        }
    }
    edges
}

/// Reads one path or use tree at `t[*i]`, relative to `base`, into `out`.
fn use_tree(t: &[String], i: &mut usize, base: Vec<String>, out: &mut Vec<Vec<String>>) {
    let mut path = base;
    while *i < t.len() {
        match t[*i].as_str() {
            "{" => {
                *i += 1;
                while *i < t.len() && t[*i] != "}" {
                    use_tree(t, i, path.clone(), out);
                    if t.get(*i).is_some_and(|s| s == ",") {
                        *i += 1;
                    }
                }
                *i += 1;
                return;
            }
            "*" => {
                *i += 1;
                break;
            }
            "crate" => path.clear(),
            "super" => {
                path.pop();
            }
            "self" => {}
            s if s.chars().all(|c| c.is_alphanumeric() || c == '_') => path.push(s.into()),
            _ => break,
        }
        *i += 1;
        if t.get(*i).is_some_and(|s| s == "::") {
            *i += 1;
        } else {
            if t.get(*i).is_some_and(|s| s == "as") {
                *i += 2;
            }
            break;
        }
    }
    out.push(path);
}

/// The deepest known module a path names.
fn deepest(path: &[String], known: &BTreeSet<String>) -> Option<String> {
    (0..=path.len())
        .rev()
        .map(|n| path[..n].join("::"))
        .find(|m| known.contains(m))
}

fn segments(module: &str) -> Vec<String> {
    module
        .split("::")
        .filter(|s| !s.is_empty())
        .map(String::from)
        .collect()
}

fn join(base: &[String], child: Option<&str>) -> String {
    base.iter()
        .map(String::as_str)
        .chain(child)
        .collect::<Vec<_>>()
        .join("::")
}

/// The strongly connected components of more than one module (Tarjan), largest first.
fn circles(g: &Graph) -> Vec<Vec<String>> {
    struct State<'a> {
        g: &'a Graph,
        index: BTreeMap<&'a str, usize>,
        low: BTreeMap<&'a str, usize>,
        stack: Vec<&'a str>,
        on_stack: BTreeSet<&'a str>,
        out: Vec<Vec<String>>,
    }
    fn visit<'a>(s: &mut State<'a>, v: &'a str) {
        let n = s.index.len();
        s.index.insert(v, n);
        s.low.insert(v, n);
        s.stack.push(v);
        s.on_stack.insert(v);
        for w in s.g[v].iter().filter(|w| s.g.contains_key(*w)) {
            if !s.index.contains_key(w.as_str()) {
                visit(s, w);
                let low = s.low[v].min(s.low[w.as_str()]);
                s.low.insert(v, low);
            } else if s.on_stack.contains(w.as_str()) {
                let low = s.low[v].min(s.index[w.as_str()]);
                s.low.insert(v, low);
            }
        }
        if s.low[v] == s.index[v] {
            let mut component = Vec::new();
            while let Some(w) = s.stack.pop() {
                s.on_stack.remove(w);
                component.push(w.to_string());
                if w == v {
                    break;
                }
            }
            if component.len() > 1 {
                component.sort();
                s.out.push(component);
            }
        }
    }
    let mut s = State {
        g,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        on_stack: BTreeSet::new(),
        out: Vec::new(),
    };
    for v in g.keys() {
        if !s.index.contains_key(v.as_str()) {
            visit(&mut s, v);
        }
    }
    s.out.sort_by_key(|c| std::cmp::Reverse(c.len()));
    s.out
}

/// A shortest cycle from `start` back to itself inside `component` (breadth first).
fn cycle_through(g: &Graph, component: &[String], start: &str) -> Vec<String> {
    let inside: BTreeSet<&str> = component.iter().map(String::as_str).collect();
    let mut parent: BTreeMap<&str, &str> = BTreeMap::new();
    let mut queue = std::collections::VecDeque::from([start]);
    while let Some(v) = queue.pop_front() {
        for w in g[v].iter().map(String::as_str) {
            if w == start {
                let mut chain = Vec::new();
                let mut at = v;
                while at != start {
                    chain.push(at.to_string());
                    at = parent[at];
                }
                chain.reverse();
                return std::iter::once(start.to_string())
                    .chain(chain)
                    .chain([start.to_string()])
                    .collect();
            }
            if inside.contains(w) && !parent.contains_key(w) {
                parent.insert(w, v);
                queue.push_back(w);
            }
        }
    }
    vec![start.to_string()]
}

#[test]
fn reads_paths_groups_and_relative_modules() {
    let known: BTreeSet<String> = ["", "a", "a::b", "c", "c::d", "e"]
        .into_iter()
        .map(String::from)
        .collect();
    let (code, _) = strip(
        "use crate::{a::b::{X, Y}, e};\n\
         use super::d; // crate::e\n\
         fn f() { let s = \"crate::e\"; d::g(); crate::a::Z; }\n\
         mod tests { use super::*; use super::super::a; }",
    );
    let edges = imports("c::d", &tokens(&code), &known);
    let edges: Vec<&str> = edges.iter().map(String::as_str).collect();
    assert_eq!(edges, ["a", "a::b", "c", "c::d", "e"]);
}
