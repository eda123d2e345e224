//! Soaks the live viewer's websocket (issue 32, item 6): a `plan-runner run --web` process
//! follows a real-time run of cyc3 while ROUNDS rounds of CLIENTS websocket clients connect
//! at once, each read the net and one state, and leave. The server's resident memory is read
//! from `/proc` before the first round and after each round (once its connections are
//! closed), so growth across rounds — a leak, or memory the allocator keeps — shows.
//!
//! ```text
//! cargo build --release --bin plan-runner
//! cargo bench --bench ws_soak -- target/release/plan-runner [CLIENTS] [ROUNDS]
//! ```

#[path = "support/args.rs"]
mod bench_args;

use std::io::{BufRead, BufReader};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use futures_util::{SinkExt, StreamExt};
use tokio_tungstenite::tungstenite::Message;

fn rss_kb(pid: u32, key: &str) -> u64 {
    std::fs::read_to_string(format!("/proc/{pid}/status"))
        .unwrap()
        .lines()
        .find_map(|l| l.strip_prefix(key))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse().ok())
        .unwrap()
}

fn raise_file_limit(want: u64) {
    let mut l = libc::rlimit {
        rlim_cur: 0,
        rlim_max: 0,
    };
    // SAFETY: getrlimit and setrlimit read and write only the struct given.
    unsafe {
        libc::getrlimit(libc::RLIMIT_NOFILE, &mut l);
        l.rlim_cur = want.min(l.rlim_max).max(l.rlim_cur);
        libc::setrlimit(libc::RLIMIT_NOFILE, &l);
    }
}

/// One client: connect, read the net and the first state, close.
async fn visit(url: String) -> bool {
    let Ok((mut ws, _)) = tokio_tungstenite::connect_async(url).await else {
        return false;
    };
    let mut got = 0;
    while got < 2 {
        match tokio::time::timeout(Duration::from_secs(30), ws.next()).await {
            Ok(Some(Ok(Message::Text(_)))) => got += 1,
            Ok(Some(Ok(_))) => {}
            _ => return false,
        }
    }
    let _ = ws.send(Message::Close(None)).await;
    true
}

#[tokio::main(flavor = "multi_thread", worker_threads = 2)]
async fn main() {
    let mut args = bench_args::args().skip(1);
    let bin = args.next().expect("the plan-runner binary");
    let clients: usize = args.next().and_then(|s| s.parse().ok()).unwrap_or(2_000);
    let rounds: usize = args.next().and_then(|s| s.parse().ok()).unwrap_or(12);
    raise_file_limit(clients as u64 + 256);
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    // The fixtures live beside the repository (`GSPN_FIXTURES` overrides, as in the tests).
    let fixtures = std::env::var("GSPN_FIXTURES")
        .unwrap_or_else(|_| concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/fixtures").into());
    let net = format!("{fixtures}/greatspn/cyc3/cyc3.PNPRO");
    let mut server = Command::new(&bin)
        .args([
            "run",
            &net,
            "--time-scale",
            "0.001",
            "--seed",
            "1",
            "--quiet",
        ])
        .arg("--web")
        .arg(format!("127.0.0.1:{port}"))
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("plan-runner runs");
    let pid = server.id();
    // It says where on stderr (`watch the run at http://…/`).
    let mut out = BufReader::new(server.stderr.take().unwrap());
    let mut line = String::new();
    while !line.contains("http://") {
        line.clear();
        if out.read_line(&mut line).unwrap() == 0 {
            panic!("plan-runner ended before serving");
        }
    }
    std::thread::spawn(move || std::io::copy(&mut out, &mut std::io::sink()));
    let url = format!("ws://127.0.0.1:{port}/api/live/ws");
    tokio::time::sleep(Duration::from_secs(1)).await;
    println!("before: RSS {} kB", rss_kb(pid, "VmRSS:"));
    let mut after = Vec::new();
    for round in 1..=rounds {
        let start = Instant::now();
        let visits: Vec<_> = (0..clients)
            .map(|_| tokio::spawn(visit(url.clone())))
            .collect();
        let mut ok = 0;
        for v in visits {
            ok += usize::from(v.await.unwrap_or(false));
        }
        let peak = rss_kb(pid, "VmRSS:");
        tokio::time::sleep(Duration::from_secs(2)).await;
        let rss = rss_kb(pid, "VmRSS:");
        after.push(rss);
        println!(
            "round {round:>2}: {ok}/{clients} clients in {:.2} s, RSS {peak} kB at the end of \
             the round, {rss} kB 2 s later",
            start.elapsed().as_secs_f64()
        );
    }
    let first = after[0] as f64;
    let last = *after.last().unwrap() as f64;
    println!(
        "after the last round {last} kB = {:+.1} % of after the first ({first} kB); peak RSS \
         {} kB",
        (last / first - 1.0) * 100.0,
        rss_kb(pid, "VmHWM:")
    );
    let _ = server.kill();
    let _ = server.wait();
}
