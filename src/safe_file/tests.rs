//! Tests of the one rule for outputs.

use super::*;

struct Dir(PathBuf);
impl Drop for Dir {
    fn drop(&mut self) {
        let _ = fs::remove_dir_all(&self.0);
    }
}
fn scratch(name: &str) -> Dir {
    let d = std::env::temp_dir().join(format!("lidarsim-safe-{name}-{}", std::process::id()));
    let _ = fs::remove_dir_all(&d);
    fs::create_dir_all(&d).unwrap();
    Dir(d)
}
fn entries(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn commit_renames_every_output_and_leaves_nothing_else() {
    let d = scratch("commit");
    let mut outs = Outputs::new([]);
    let a = outs.add("--csv", &d.0.join("a.csv"), Stream::Text).unwrap();
    let b = outs
        .add("--png", &d.0.join("b.png"), Stream::Binary)
        .unwrap();
    outs.write(a, |w| w.write_all(b"x,y\n")).unwrap();
    outs.write(b, |w| w.write_all(b"png")).unwrap();
    outs.commit().unwrap();
    assert_eq!(entries(&d.0), ["a.csv", "b.png"]);
    assert_eq!(fs::read(d.0.join("a.csv")).unwrap(), b"x,y\n");
}

#[test]
fn a_failure_leaves_none_of_the_outputs() {
    let d = scratch("fail");
    fs::write(d.0.join("old.csv"), "old").unwrap();
    {
        let mut outs = Outputs::new([]);
        let a = outs
            .add("--csv", &d.0.join("old.csv"), Stream::Text)
            .unwrap();
        let b = outs
            .add("--png", &d.0.join("b.png"), Stream::Binary)
            .unwrap();
        outs.write(a, |w| w.write_all(b"new")).unwrap();
        let r = outs.write(b, |_| Err(io::Error::other("drawing failed")));
        assert!(r.is_err());
    }
    assert_eq!(entries(&d.0), ["old.csv"]);
    assert_eq!(fs::read_to_string(d.0.join("old.csv")).unwrap(), "old");
}

#[test]
fn special_files_inputs_and_duplicates_are_refused() {
    let d = scratch("refuse");
    let input = d.0.join("cfg.toml");
    fs::write(&input, "x").unwrap();
    let mut outs = Outputs::new([input.as_path()]);
    for (p, why) in [
        (Path::new("/dev/null"), "character device"),
        (d.0.as_path(), "directory"),
        (input.as_path(), "is the input"),
        (Path::new("/no/such/dir/x.h5"), "no such file"),
    ] {
        let e = outs.add("-o", p, Stream::Binary).unwrap_err().to_string();
        assert!(e.contains(why), "{p:?}: {e}");
    }
    let e = outs.add("--png", Path::new("-"), Stream::Binary);
    assert!(e.unwrap_err().to_string().contains("standard output"));
    outs.add("--csv", &d.0.join("x"), Stream::Text).unwrap();
    let e = outs
        .add("--json", &d.0.join("x"), Stream::Text)
        .unwrap_err();
    assert!(e.to_string().contains("also the output of --csv"), "{e}");
    drop(outs);
    assert_eq!(entries(&d.0), ["cfg.toml"]);
    assert!(Path::new("/dev/null").exists());
}

#[test]
fn a_symlink_is_followed_and_stays_a_link() {
    let d = scratch("link");
    let link = d.0.join("link.csv");
    std::os::unix::fs::symlink("real.csv", &link).unwrap();
    let mut outs = Outputs::new([]);
    let a = outs.add("--csv", &link, Stream::Text).unwrap();
    outs.write(a, |w| w.write_all(b"1")).unwrap();
    outs.commit().unwrap();
    assert!(
        fs::symlink_metadata(&link)
            .unwrap()
            .file_type()
            .is_symlink()
    );
    assert_eq!(fs::read_to_string(d.0.join("real.csv")).unwrap(), "1");
    // a link to an input is the input
    let input = d.0.join("cfg.toml");
    fs::write(&input, "x").unwrap();
    std::os::unix::fs::symlink(&input, d.0.join("cfg-link")).unwrap();
    let mut outs = Outputs::new([input.as_path()]);
    assert!(
        outs.add("-o", &d.0.join("cfg-link"), Stream::Binary)
            .is_err()
    );
}

#[test]
fn an_input_learnt_late_is_protected_through_any_link() {
    let d = scratch("protect");
    let input = d.0.join("profile.txt");
    fs::write(&input, "profile").unwrap();
    fs::hard_link(&input, d.0.join("hard")).unwrap();
    std::os::unix::fs::symlink(&input, d.0.join("soft")).unwrap();
    for name in ["profile.txt", "hard", "soft"] {
        let mut outs = Outputs::new([]);
        outs.add("--json", &d.0.join(name), Stream::Text).unwrap();
        let e = outs.protect([input.as_path()]).unwrap_err().to_string();
        assert!(e.contains("--json") && e.contains("is the input"), "{e}");
    }
    // an unrelated output passes, and a later output onto the input is refused
    let mut outs = Outputs::new([]);
    outs.add("--json", &d.0.join("x.json"), Stream::Text)
        .unwrap();
    outs.protect([input.as_path()]).unwrap();
    assert!(outs.add("--csv", &d.0.join("hard"), Stream::Text).is_err());
    drop(outs);
    assert_eq!(fs::read_to_string(&input).unwrap(), "profile");
    assert_eq!(entries(&d.0), ["hard", "profile.txt", "soft"]);
}

#[test]
fn a_second_writer_of_the_same_path_is_refused_while_the_first_runs() {
    let d = scratch("lock");
    let target = d.0.join("x.h5");
    let mut first = Outputs::new([]);
    first.add("-o", &target, Stream::Binary).unwrap();
    let mut second = Outputs::new([]);
    let e = second.add("-o", &target, Stream::Binary).unwrap_err();
    assert!(e.to_string().contains("another run is writing"), "{e}");
    first.commit().unwrap();
    // released: a third run may write it, and no lock file stays
    let mut third = Outputs::new([]);
    third.add("-o", &target, Stream::Binary).unwrap();
    third.commit().unwrap();
    assert_eq!(entries(&d.0), ["x.h5"]);
}
