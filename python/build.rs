//! `lidarsim.__version__` (docs/python.md): the lidarsim crate's version, read from its
//! own `Cargo.toml` (`[package] version`, the one source of truth) at build time.
fn main() {
    let manifest = concat!(env!("CARGO_MANIFEST_DIR"), "/../Cargo.toml");
    println!("cargo:rerun-if-changed={manifest}");
    let text = std::fs::read_to_string(manifest).expect("the lidarsim crate's Cargo.toml");
    let version = text
        .split("[package]")
        .nth(1)
        .and_then(|package| {
            package
                .lines()
                .take_while(|l| !l.trim_start().starts_with('['))
                .find_map(|l| l.trim().strip_prefix("version")?.trim().strip_prefix('='))
        })
        .map(|v| v.trim().trim_matches('"').to_string())
        .expect("a version in the lidarsim crate's [package]");
    println!("cargo:rustc-env=LIDARSIM_VERSION={version}");
}
