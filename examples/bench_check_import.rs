//! Cost of `plan-runner check` and `plan-runner import-thesis` on generated inputs of N
//! elements (issue 14, defect 10: both were quadratic — a 100,000-place chain took 37 s to
//! check, 32,000 names 15 s to import).
//!
//! ```text
//! cargo run --release --example bench_check_import -- 1000000
//! ```
//!
//! `check`: a chain of N places (`p0 → t1 → p1 → …`, one token), written as PNML, read back
//! and summarised with its structural warnings. `import-thesis`: the same chain as PIPE XML
//! and a thesis input naming all N places (`places_tuple`, one action per place, one policy
//! entry with an N-element key), imported into a plan that is read back. Prints one JSON
//! line with the seconds of each phase.

use std::time::Instant;

use gspn::check::Report;
use gspn::io::{Format, ReadOptions, read_net, write_net};
use gspn::net::{Net, NetBuilder, Servers};
use gspn::plan::thesis::{ImportOptions, import};

fn chain(n: usize) -> Net {
    let mut b = NetBuilder::new("chain");
    let mut prev = b.place("p0", 1);
    for i in 1..n {
        let p = b.place(format!("p{i}"), 0);
        let t = b.exponential(format!("t{i}"), 1.0, Servers::Single);
        b.input(prev, t, 1);
        b.output(t, p, 1);
        prev = p;
    }
    // One immediate transition, for the policy entry to choose.
    let t = b.immediate("t0", 1.0, 1);
    b.input(prev, t, 1);
    b.build().expect("a chain is a valid net")
}

fn thesis_input(n: usize) -> String {
    let names: Vec<String> = (0..n).map(|i| format!("'p{i}'")).collect();
    let mapping: Vec<String> = (0..n).map(|i| format!("'p{i}': 'act{i}'")).collect();
    let key: Vec<&str> = (0..n).map(|i| if i == 0 { "1" } else { "'-'" }).collect();
    serde_json::json!({
        "gspn": "chain.xml",
        "place_to_function_mapping": format!("{{{}}}", mapping.join(", ")),
        "resources_list": "[]",
        "places_tuple": format!("({})", names.join(", ")),
        "policy_dictionary": format!("{{({}): {{'t0': 1}}}}", key.join(",")),
    })
    .to_string()
}

fn main() {
    let n: usize = std::env::args()
        .nth(1)
        .map(|s| s.parse().expect("N, a number of places"))
        .unwrap_or(100_000);
    let dir = std::env::temp_dir().join(format!("gspn-bench-check-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a temporary directory");
    let net = chain(n);

    let pnml = dir.join("chain.pnml");
    write_net(&net, &pnml, Format::Pnml).expect("write PNML");
    let t = Instant::now();
    let loaded = read_net(&pnml, &ReadOptions::default()).expect("read PNML");
    let read_s = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let report = Report::for_net(&loaded.net, Format::Pnml, &loaded.warnings);
    let check_s = t.elapsed().as_secs_f64();
    assert_eq!(report.places, n);

    write_net(&net, &dir.join("chain.xml"), Format::Pipe).expect("write PIPE");
    let input = dir.join("input.json");
    std::fs::write(&input, thesis_input(n)).expect("write the input");
    let t = Instant::now();
    let imported = import(
        &input,
        &ImportOptions {
            out: dir.join("out"),
            net: None,
            project_path: None,
        },
    )
    .expect("import");
    let import_s = t.elapsed().as_secs_f64();
    assert_eq!(imported.plan.net.place_count(), n);
    println!(
        "{}",
        serde_json::json!({
            "places": n,
            "read_pnml_s": read_s,
            "check_s": check_s,
            "check_warnings": report.warnings.len(),
            "import_thesis_s": import_s,
        })
    );
    let _ = std::fs::remove_dir_all(&dir);
}
