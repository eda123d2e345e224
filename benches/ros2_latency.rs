//! ROS 2 backend benchmark: latency from a firing to *all* robots notified, with 16 robot
//! processes on loopback, and each process's CPU (from /proc).
//!
//! ```text
//! cargo build --release --features ros2 --bin plan-runner
//! cargo bench --features ros2 --bench ros2_latency -- [--robots 16] [--firings 3000] [--runs 3]
//! ```
//!
//! Each run writes a net of 16 robots alternating between `Work` and `Move` (both `ros2`
//! places, rate 1, robots' time scale 0.05 s: ~320 firings/s in all), starts 16
//! `plan-runner robot --latency-log` processes and one `plan-runner run`, and joins the
//! logs: for each firing, the latency is the last robot's receive time minus the firing's
//! stamp (the supervisor's publish time; one machine, one clock). CPU is utime + stime over
//! each process's lifetime, sampled from /proc/PID/stat every 100 ms.

#[path = "support/args.rs"]
mod bench_args;

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use gspn::io::{Format, write_net};
use gspn::net::{NetBuilder, Servers};

struct Opts {
    robots: usize,
    firings: u64,
    runs: usize,
    scale: f64,
    domain: u16,
}

fn opts() -> Opts {
    let mut o = Opts {
        robots: 16,
        firings: 3000,
        runs: 3,
        scale: 0.05,
        domain: 150,
    };
    let args: Vec<String> = bench_args::args().skip(1).collect();
    for w in args.chunks(2) {
        let v = w.get(1).map(String::as_str).unwrap_or("");
        match w[0].as_str() {
            "--robots" => o.robots = v.parse().expect("--robots N"),
            "--firings" => o.firings = v.parse().expect("--firings N"),
            "--runs" => o.runs = v.parse().expect("--runs N"),
            "--scale" => o.scale = v.parse().expect("--scale SECS"),
            "--domain" => o.domain = v.parse().expect("--domain ID"),
            other => panic!("unknown argument {other}"),
        }
    }
    o
}

fn plan_runner() -> PathBuf {
    // target/release/deps/ros2_latency-HASH → target/release/plan-runner
    let exe = std::env::current_exe().expect("own path");
    let bin = exe
        .parent()
        .and_then(Path::parent)
        .map(|d| d.join("plan-runner"))
        .expect("target dir");
    assert!(
        bin.is_file(),
        "{} missing: cargo build --release --features ros2 --bin plan-runner",
        bin.display()
    );
    bin
}

fn write_plan(dir: &Path, o: &Opts) -> PathBuf {
    let mut b = NetBuilder::new("work_move");
    let work = b.place("Work", o.robots as u32);
    let mv = b.place("Move", 0);
    let done = b.exponential("done", 1.0, Servers::Infinite);
    let arrive = b.exponential("arrive", 1.0, Servers::Infinite);
    b.input(work, done, 1);
    b.output(done, mv, 1);
    b.input(mv, arrive, 1);
    b.output(arrive, work, 1);
    let net = b.build().expect("net");
    write_net(&net, &dir.join("work_move.pnml"), Format::Pnml).expect("write net");
    let robots: Vec<String> = (1..=o.robots).map(|k| format!("\"r{k}\"")).collect();
    let plan = format!(
        "net = \"work_move.pnml\"\nseed = 1\ntime_scale = {}\nrobots = [{}]\n\n\
         [places.Work]\naction = \"ros2\"\n\n[places.Move]\naction = \"ros2\"\n\n\
         [stop]\nmax_firings = {}\n",
        o.scale,
        robots.join(", "),
        o.firings
    );
    let path = dir.join("plan.toml");
    std::fs::write(&path, plan).expect("write plan");
    path
}

/// utime + stime of a process, in seconds.
fn cpu_seconds(pid: u32) -> Option<f64> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    let rest = &stat[stat.rfind(')')? + 2..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks: f64 = f.get(11)?.parse::<f64>().ok()? + f.get(12)?.parse::<f64>().ok()?;
    // SAFETY: sysconf has no preconditions.
    let hz = unsafe { libc::sysconf(libc::_SC_CLK_TCK) } as f64;
    Some(ticks / hz)
}

fn percentile(sorted: &[f64], q: f64) -> f64 {
    let i = ((sorted.len() as f64 - 1.0) * q).round() as usize;
    sorted[i.min(sorted.len() - 1)]
}

struct RunResult {
    p50_ms: f64,
    p99_ms: f64,
    max_ms: f64,
    firings: usize,
    rate: f64,
    complete: bool,
    sup_cpu: f64,
    robot_cpu: Vec<f64>,
    wall: f64,
}

fn run_once(o: &Opts, bin: &Path, k: usize) -> RunResult {
    let dir = tempfile::tempdir().expect("temp dir");
    let plan = write_plan(dir.path(), o);
    let domain = (o.domain + k as u16).to_string();
    let start = Instant::now();
    let mut sup = Command::new(bin)
        .args(["run"])
        .arg(&plan)
        .args(["--json", "--ros2-domain", &domain])
        .args(["--ros2-wait-subscribers", &o.robots.to_string()])
        .args(["--ros2-linger", "1.0"])
        .stdout(Stdio::null())
        .stderr(std::fs::File::create(dir.path().join("supervisor.log")).expect("log"))
        .spawn()
        .expect("supervisor starts");
    // The supervisor first: it takes DDS participant index 0, which every robot announces
    // itself to (RustDDS sends loopback SPDP to indices 0-11 only; see docs/ros2.md).
    std::thread::sleep(Duration::from_millis(500));
    let mut robots: Vec<(Child, Instant)> = (1..=o.robots)
        .map(|r| {
            let child = Command::new(bin)
                .args(["robot", "--id", &format!("r{r}"), "--plan"])
                .arg(&plan)
                .args(["--ros2-domain", &domain, "--latency-log"])
                .arg(dir.path().join(format!("r{r}.log")))
                .stdout(Stdio::null())
                .stderr(Stdio::null())
                .spawn()
                .expect("robot starts");
            (child, Instant::now())
        })
        .collect();
    let mut cpu: HashMap<u32, f64> = HashMap::new();
    let deadline = start + Duration::from_secs(300);
    loop {
        for pid in robots.iter().map(|(c, _)| c.id()).chain([sup.id()]) {
            if let Some(s) = cpu_seconds(pid) {
                cpu.insert(pid, s);
            }
        }
        if sup.try_wait().expect("wait").is_some() || Instant::now() > deadline {
            break;
        }
        std::thread::sleep(Duration::from_millis(100));
    }
    let _ = sup.kill();
    let _ = sup.wait();
    let wall = start.elapsed().as_secs_f64();
    std::thread::sleep(Duration::from_millis(500));
    let robot_cpu: Vec<f64> = robots
        .iter()
        .map(|(c, t)| cpu.get(&c.id()).copied().unwrap_or(0.0) / t.elapsed().as_secs_f64())
        .collect();
    for (c, _) in &mut robots {
        let _ = c.kill();
        let _ = c.wait();
    }
    // seq → (stamp, latest receive, robots that got it)
    let mut seen: HashMap<u64, (i128, i128, usize)> = HashMap::new();
    for r in 1..=o.robots {
        let log = std::fs::read_to_string(dir.path().join(format!("r{r}.log"))).unwrap_or_default();
        for l in log.lines() {
            let v: Vec<i128> = l.split(' ').filter_map(|x| x.parse().ok()).collect();
            if let [seq, stamp, recv] = v[..] {
                let e = seen.entry(seq as u64).or_insert((stamp, recv, 0));
                e.1 = e.1.max(recv);
                e.2 += 1;
            }
        }
    }
    let complete = seen.len() as u64 == o.firings && seen.values().all(|e| e.2 == o.robots);
    let mut lat: Vec<f64> = seen
        .values()
        .filter(|e| e.2 == o.robots)
        .map(|e| (e.1 - e.0) as f64 / 1e6)
        .collect();
    lat.sort_by(f64::total_cmp);
    assert!(
        !lat.is_empty(),
        "no firing reached every robot; supervisor log:\n{}",
        std::fs::read_to_string(dir.path().join("supervisor.log")).unwrap_or_default()
    );
    let first = seen.values().map(|e| e.0).min().unwrap_or(0);
    let last = seen.values().map(|e| e.0).max().unwrap_or(0);
    let rate = seen.len() as f64 / ((last - first) as f64 / 1e9).max(1e-9);
    RunResult {
        rate,
        p50_ms: percentile(&lat, 0.5),
        p99_ms: percentile(&lat, 0.99),
        max_ms: *lat.last().unwrap_or(&0.0),
        firings: lat.len(),
        complete,
        sup_cpu: cpu.get(&sup.id()).copied().unwrap_or(0.0) / wall,
        robot_cpu,
        wall,
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let o = opts();
    let bin = plan_runner();
    println!(
        "{} robots, {} firings per run, robots' time scale {} s, {} runs",
        o.robots, o.firings, o.scale, o.runs
    );
    println!(
        "| run | firings (all robots got) | firings/s | p50 ms | p99 ms | max ms | supervisor CPU % | robot CPU % (median, max) | wall s |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    let mut results = Vec::new();
    for k in 0..o.runs {
        let r = run_once(&o, &bin, k);
        let rc_med = median(r.robot_cpu.clone()) * 100.0;
        let rc_max = r.robot_cpu.iter().copied().fold(0.0, f64::max) * 100.0;
        println!(
            "| {} | {}{} | {:.0} | {:.2} | {:.2} | {:.2} | {:.1} | {:.1}, {:.1} | {:.1} |",
            k + 1,
            r.firings,
            if r.complete { "" } else { " (incomplete)" },
            r.rate,
            r.p50_ms,
            r.p99_ms,
            r.max_ms,
            r.sup_cpu * 100.0,
            rc_med,
            rc_max,
            r.wall
        );
        results.push(r);
    }
    println!(
        "median over runs: p50 {:.2} ms, p99 {:.2} ms, supervisor CPU {:.1} %, robot CPU {:.1} %",
        median(results.iter().map(|r| r.p50_ms).collect()),
        median(results.iter().map(|r| r.p99_ms).collect()),
        median(results.iter().map(|r| r.sup_cpu * 100.0).collect()),
        median(
            results
                .iter()
                .map(|r| median(r.robot_cpu.clone()) * 100.0)
                .collect()
        ),
    );
}
