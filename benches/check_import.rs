//! Cost of `plan-runner check` and `plan-runner import-thesis` on generated inputs of N
//! elements (issue 14, defect 10: both were quadratic — a 100,000-place chain took 37 s to
//! check, 32,000 names 15 s to import).
//!
//! ```text
//! cargo bench --bench check_import -- 1000000
//! ```
//!
//! `check`: a chain of N places (`p0 → t1 → p1 → …`, one token), written as PNML, read back
//! and summarised with its structural warnings. `import-thesis`: the same chain as PIPE XML
//! and a thesis input naming all N places (`places_tuple`, one action per place, one policy
//! entry with an N-element key), imported into a plan that is read back. Prints one JSON
//! line with the seconds of each phase, and the resident memory after each on stderr.
//!
//! `reference_s` calibrates the machine: the N names `p0`, `p1`, … made into strings, put
//! in a hash map and each looked up once in a scattered order — the least any reader that
//! indexes its names does. Its cost per name grows with N too (from about 250 ns at 10⁴ to
//! 850 ns at 10⁶ on the 2-core VM: the map leaves the caches), so a reader whose time per
//! element grows by the same factor is linear in its input, and what remains is the memory
//! hierarchy.

#[path = "support/args.rs"]
mod bench_args;

use std::time::Instant;

use gspn::check::Report;
use gspn::io::{Format, ReadOptions, read_net, write_net};
use gspn::net::{Net, NetBuilder, Servers};
use gspn::plan::thesis::{ImportOptions, import};
use rustc_hash::FxHashMap;

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

/// Seconds to index `n` names in a hash map and look each up once, scattered.
fn reference(n: usize) -> f64 {
    let t = Instant::now();
    let names: Vec<String> = (0..n).map(|i| format!("p{i}")).collect();
    let mut index: FxHashMap<String, u32> = FxHashMap::default();
    for (i, name) in names.iter().enumerate() {
        index.insert(name.clone(), i as u32);
    }
    let mut sum = 0u64;
    for i in 0..n {
        sum += u64::from(index[&format!("p{}", (i * 7919) % n)]);
    }
    std::hint::black_box(sum);
    t.elapsed().as_secs_f64()
}

/// The process's resident and peak resident memory so far, in MB (Linux; 0 elsewhere).
fn memory_mb() -> (f64, f64) {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    let field = |name: &str| {
        status
            .lines()
            .find_map(|l| l.strip_prefix(name))
            .and_then(|v| v.trim().trim_end_matches(" kB").trim().parse::<f64>().ok())
            .map_or(0.0, |kb| kb / 1024.0)
    };
    (field("VmRSS:"), field("VmHWM:"))
}

fn main() {
    let n: usize = bench_args::args()
        .nth(1)
        .map(|s| s.parse().expect("N, a number of places"))
        .unwrap_or(100_000);
    let reference_s = reference(n);
    let dir = std::env::temp_dir().join(format!("gspn-bench-check-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a temporary directory");
    let net = chain(n);
    eprintln!("built: rss/peak {:?} MB", memory_mb());

    let pnml = dir.join("chain.pnml");
    write_net(&net, &pnml, Format::Pnml).expect("write PNML");
    let t = Instant::now();
    let loaded = read_net(&pnml, &ReadOptions::default()).expect("read PNML");
    let read_s = t.elapsed().as_secs_f64();
    eprintln!("read PNML: rss/peak {:?} MB", memory_mb());
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
    eprintln!("imported: rss/peak {:?} MB", memory_mb());
    assert_eq!(imported.plan.net.place_count(), n);
    println!(
        "{}",
        serde_json::json!({
            "places": n,
            "read_pnml_s": read_s,
            "check_s": check_s,
            "check_warnings": report.warnings.len(),
            "import_thesis_s": import_s,
            "reference_s": reference_s,
        })
    );
    if std::env::var_os("GSPN_BENCH_KEEP").is_none() {
        let _ = std::fs::remove_dir_all(&dir);
    }
}
