//! Reading nets: the biggest MCC PNML model and generated PIPE rings, in MB/s; and one
//! ~100 MB PIPE file loaded once, with its throughput and the peak memory (VmHWM) of the
//! load, to show that no DOM is built.
//!
//! `cargo bench --bench read_xml` (set `GSPN_BIG_PLACES` to change the big file's size).

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use gspn::io::{ReadOptions, read_net};

#[path = "support/fixtures.rs"]
mod fixtures_root;

fn fixtures() -> PathBuf {
    fixtures_root::root()
}

/// Writes a PIPE ring of `n` places and `n` transitions (one token per 10 places) without
/// holding it in memory.
fn write_ring(path: &Path, n: usize) {
    let f = std::fs::File::create(path).unwrap();
    let mut w = std::io::BufWriter::new(f);
    writeln!(
        w,
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<pnml>\n<net id=\"ring\" type=\"P/T net\">"
    )
    .unwrap();
    for i in 0..n {
        let k = usize::from(i % 10 == 0);
        write!(
            w,
            "  <place id=\"p{i}\">\n    <graphics>\n      <position x=\"{}.0\" y=\"{}.0\"/>\n    </graphics>\n    \
             <name>\n      <value>p{i}</value>\n      <graphics>\n        <offset x=\"0.0\" y=\"0.0\"/>\n      </graphics>\n    </name>\n    \
             <initialMarking>\n      <value>Default,{k}</value>\n    </initialMarking>\n    <capacity>\n      <value>0</value>\n    </capacity>\n  </place>\n",
            i % 1000 * 60,
            i / 1000 * 60
        )
        .unwrap();
    }
    for i in 0..n {
        write!(
            w,
            "  <transition id=\"t{i}\">\n    <graphics>\n      <position x=\"{}.0\" y=\"{}.0\"/>\n    </graphics>\n    \
             <name>\n      <value>t{i}</value>\n    </name>\n    <orientation>\n      <value>0</value>\n    </orientation>\n    \
             <rate>\n      <value>1.0</value>\n    </rate>\n    <timed>\n      <value>true</value>\n    </timed>\n    \
             <infiniteServer>\n      <value>false</value>\n    </infiniteServer>\n    <priority>\n      <value>1</value>\n    </priority>\n  </transition>\n",
            i % 1000 * 60 + 30,
            i / 1000 * 60
        )
        .unwrap();
    }
    for i in 0..n {
        let j = (i + 1) % n;
        for (s, t) in [
            (format!("p{i}"), format!("t{i}")),
            (format!("t{i}"), format!("p{j}")),
        ] {
            write!(
                w,
                "  <arc id=\"{s} to {t}\" source=\"{s}\" target=\"{t}\">\n    <graphics/>\n    <inscription>\n      \
                 <value>Default,1</value>\n      <graphics/>\n    </inscription>\n    <tagged>\n      <value>false</value>\n    </tagged>\n    \
                 <arcpath id=\"000\" x=\"1\" y=\"2\" curvePoint=\"false\"/>\n    <type value=\"normal\"/>\n  </arc>\n"
            )
            .unwrap();
        }
    }
    writeln!(w, "</net>\n</pnml>").unwrap();
}

/// `VmHWM` (peak resident set) of this process, in MiB.
fn vm_hwm_mib() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb / 1024.0)
}

fn vm_rss_mib() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with("VmRSS:"))?;
    let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb / 1024.0)
}

/// One load of a ~100 MB PIPE file: throughput and peak memory, printed.
fn big_file_once(dir: &Path) {
    let n: usize = std::env::var("GSPN_BIG_PLACES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(75_000);
    let path = dir.join("big_ring.xml");
    write_ring(&path, n);
    let bytes = std::fs::metadata(&path).unwrap().len() as f64;
    // Reset the high-water mark so it measures the load alone (Linux ≥ 4.0).
    let _ = std::fs::write("/proc/self/clear_refs", "5");
    let before = vm_rss_mib().unwrap_or(0.0);
    let t = Instant::now();
    let net = read_net(&path, &ReadOptions::default()).unwrap().net;
    let secs = t.elapsed().as_secs_f64();
    let hwm = vm_hwm_mib().unwrap_or(f64::NAN);
    println!(
        "big PIPE file: {:.1} MB, {} places, {} transitions, {} arcs: loaded in {:.3} s = {:.1} MB/s; \
         peak RSS during the load {:.0} MiB (RSS before {:.0} MiB; file {:.0} MiB)",
        bytes / 1e6,
        net.place_count(),
        net.transition_count(),
        net.arcs().len(),
        secs,
        bytes / 1e6 / secs,
        hwm,
        before,
        bytes / 1048576.0
    );
    drop(net);
    let _ = std::fs::remove_file(&path);
}

fn bench(c: &mut Criterion) {
    let dir = tempfile::tempdir().unwrap();
    big_file_once(dir.path());

    let mut g = c.benchmark_group("read_xml");
    let mcc = fixtures().join("mcc/TokenRing-PT-005/model.pnml");
    let len = std::fs::metadata(&mcc).unwrap().len();
    g.throughput(Throughput::Bytes(len));
    g.bench_function("pnml_TokenRing-PT-005", |b| {
        b.iter(|| read_net(std::hint::black_box(&mcc), &ReadOptions::default()).unwrap())
    });
    let ring = dir.path().join("ring_10k.xml");
    write_ring(&ring, 10_000);
    let len = std::fs::metadata(&ring).unwrap().len();
    g.throughput(Throughput::Bytes(len));
    g.sample_size(20);
    g.bench_function("pipe_ring_10k_places", |b| {
        b.iter(|| read_net(std::hint::black_box(&ring), &ReadOptions::default()).unwrap())
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
