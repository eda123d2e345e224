//! Regressions (issue 32, item 9): 30 of 7,191 fuzz runs were refused without a line and
//! column — a plan whose `net = "/etc/passwd"` (no net of a known kind) was blamed on the net
//! file, and missing thesis keys, parallel arcs whose weights add past the largest token
//! count and empty files named only the file. Each is now refused with exit code 2 at
//! `file:line:column`, the place to look at: the plan's `net = …` value, the thesis object's
//! closing brace, the arc that went past the maximum, the first character of an empty file.

use std::path::Path;
use std::process::Command;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_plan-runner"))
}

/// Runs `plan-runner ARGS`, expects exit code 2 and returns stderr.
fn refused(args: &[&std::ffi::OsStr]) -> String {
    let out = bin().args(args).output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    stderr
}

fn check(file: &Path) -> String {
    refused(&["check".as_ref(), file.as_os_str()])
}

#[test]
fn a_plan_whose_net_is_no_net_file_is_refused_at_its_net_line() {
    let dir = tempfile::tempdir().unwrap();
    let plan = dir.path().join("plan.toml");
    std::fs::write(dir.path().join("empty.xml"), " \n").unwrap();
    for (net, why) in [
        (
            "/etc/passwd",
            "net file `/etc/passwd` (/etc/passwd): unknown format ``: expected .xml (PIPE), \
             .pnml, .PNPRO or .toml (plan)",
        ),
        ("empty.xml", "net file `empty.xml`"),
    ] {
        std::fs::write(&plan, format!("seed = 1\n\nnet = \"{net}\"\n")).unwrap();
        let stderr = check(&plan);
        let at = format!("{}:3:7: ", plan.display());
        assert!(stderr.contains(&at), "{stderr}");
        assert!(stderr.contains(why), "{stderr}");
    }
}

#[test]
fn empty_files_are_refused_at_their_first_line_and_column() {
    let dir = tempfile::tempdir().unwrap();
    for name in ["net.xml", "net.pnml", "net.PNPRO", "plan.toml"] {
        let path = dir.path().join(name);
        std::fs::write(&path, "\n\n").unwrap();
        let stderr = check(&path);
        assert!(
            stderr.contains(&format!("{}:1:1: the file is empty", path.display())),
            "{stderr}"
        );
    }
    let input = dir.path().join("input.json");
    std::fs::write(&input, "").unwrap();
    let stderr = refused(&[
        "import-thesis".as_ref(),
        input.as_os_str(),
        "--out".as_ref(),
        dir.path().join("out").as_os_str(),
    ]);
    assert!(
        stderr.contains(&format!("{}:1:1: the file is empty", input.display())),
        "{stderr}"
    );
}

#[test]
fn a_thesis_input_without_a_required_key_is_refused_at_its_closing_brace() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("input.json");
    std::fs::write(
        &input,
        "{\n  \"gspn\": \"net.xml\",\n  \"places_tuple\": \"('p1',)\"\n}\n",
    )
    .unwrap();
    let stderr = refused(&[
        "import-thesis".as_ref(),
        input.as_os_str(),
        "--out".as_ref(),
        dir.path().join("out").as_os_str(),
    ]);
    assert!(
        stderr.contains(&format!(
            "{}:4:1: `policy_dictionary` is missing",
            input.display()
        )),
        "{stderr}"
    );
}

/// A PIPE net with arcs `P -> T` of weights `a` and `b` (the second on line 11).
fn pipe_with_parallel_arcs(a: u64, b: u64) -> String {
    format!(
        r#"<?xml version="1.0"?>
<pnml><net id="n" type="P/T net">
<place id="P"><initialMarking><value>Default,0</value></initialMarking></place>
<transition id="T"><rate><value>1.0</value></rate></transition>
<arc id="a1" source="P" target="T">
  <inscription><value>Default,{a}</value></inscription>
</arc>
<arc id="a2" source="T" target="P">
  <inscription><value>Default,1</value></inscription>
</arc>
<arc id="a3" source="P" target="T">
  <inscription><value>Default,{b}</value></inscription>
</arc>
</net></pnml>
"#
    )
}

#[test]
fn parallel_arcs_adding_past_the_maximum_are_refused_at_the_arc_that_did_it() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("net.xml");
    std::fs::write(&path, pipe_with_parallel_arcs(4_294_967_295, 1)).unwrap();
    let stderr = check(&path);
    assert!(
        stderr.contains(&format!(
            "{}:11:1: arcs between `P` and `T` add up to more than the maximum token count \
             4294967295",
            path.display()
        )),
        "{stderr}"
    );
    // Within the maximum, the same arcs are one arc of their sum.
    std::fs::write(&path, pipe_with_parallel_arcs(4_294_967_294, 1)).unwrap();
    let out = bin().arg("check").arg(&path).output().unwrap();
    assert_ne!(
        out.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}
