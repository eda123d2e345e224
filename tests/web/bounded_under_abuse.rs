//! Regressions (issue 32, items 1, 4 and 5): the viewer's routes amplified a 119 KiB
//! question into a 390 MB answer, 1,100 idle connections against a 1,024-file limit made the
//! page unreachable for as long as they were held, and a token-game `step` of a million
//! firings ran inside its request handler (the server's threads busy, the state unreadable
//! until it ended). Real `plan-runner serve` processes on the loopback.

use crate::support as common;

use std::io::{BufRead, BufReader, Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::os::unix::process::CommandExt;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use gspn::net::Servers;
use gspn::web::{WebState, serve};
use serde_json::{Value, json};

use crate::security::{JSON, request};

/// `plan-runner serve` of cyc3 on a free loopback port with at most `files` open files;
/// the process and its address.
fn serve_cyc3(files: u64) -> (Child, SocketAddr) {
    let net = common::fixture("greatspn/cyc3/cyc3.PNPRO");
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_plan-runner"));
    cmd.args(["serve", net.to_str().unwrap(), "--addr", "127.0.0.1:0"])
        .stdout(Stdio::piped())
        .stderr(Stdio::null());
    // SAFETY: setrlimit is async-signal-safe; nothing else runs between fork and exec.
    unsafe {
        cmd.pre_exec(move || {
            let l = libc::rlimit {
                rlim_cur: files,
                rlim_max: files,
            };
            if libc::setrlimit(libc::RLIMIT_NOFILE, &l) != 0 {
                return Err(std::io::Error::last_os_error());
            }
            Ok(())
        });
    }
    let mut child = cmd.spawn().unwrap();
    let mut line = String::new();
    BufReader::new(child.stdout.take().unwrap())
        .read_line(&mut line)
        .unwrap();
    let addr = line
        .trim()
        .rsplit("http://")
        .next()
        .and_then(|a| a.trim_end_matches('/').parse().ok())
        .unwrap_or_else(|| panic!("no address in {line:?}"));
    (child, addr)
}

/// Kilobytes of the process's peak resident memory (`VmHWM`).
fn peak_rss_kb(pid: u32) -> u64 {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).unwrap();
    status
        .lines()
        .find_map(|l| l.strip_prefix("VmHWM:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse().ok())
        .unwrap()
}

/// One request, blocking (std), with `Connection: close`; the status and the body.
fn blocking_request(addr: SocketAddr, method: &str, path: &str, body: &str) -> (u16, Value) {
    let mut s = TcpStream::connect(addr).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(60))).unwrap();
    write!(
        s,
        "{method} {path} HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\n\
         Content-Type: application/json\r\nContent-Length: {}\r\n\r\n{body}",
        body.len()
    )
    .unwrap();
    let mut res = Vec::new();
    s.read_to_end(&mut res).unwrap();
    let res = String::from_utf8_lossy(&res);
    let (head, body) = res.split_once("\r\n\r\n").unwrap();
    (
        head[9..12].parse().unwrap(),
        serde_json::from_str(body).unwrap_or(Value::String(body.into())),
    )
}

#[test]
fn the_amplifying_question_is_refused_naming_its_limit_and_the_server_stays_small() {
    let (mut child, addr) = serve_cyc3(1024);
    let (status, v) = blocking_request(addr, "GET", "/api/analysis", "");
    assert_eq!(status, 200, "{v}");
    // Issue 32's question: 4,000 time points, a 99 KB predicate (119 KiB in all).
    let long = format!("P1 >= 0{}", " || P2 >= 0".repeat(9_900));
    let times: Vec<f64> = (1..=4_000).map(|i| f64::from(i) / 100.0).collect();
    let q = json!({ "transient": times, "prob": [long] }).to_string();
    assert!(q.len() > 119 << 10, "{} bytes", q.len());
    let (status, v) = blocking_request(addr, "POST", "/api/analysis/query", &q);
    assert_eq!(status, 422, "{v}");
    assert_eq!(
        v["error"],
        "transient: 4000 time points: at most 1000 per question"
    );
    let q = json!({ "transient": &times[..1_000], "prob": [long] }).to_string();
    let (status, v) = blocking_request(addr, "POST", "/api/analysis/query", &q);
    assert_eq!(status, 422, "{v}");
    assert_eq!(
        v["error"],
        format!(
            "prob #1: {} characters: at most 4096 per predicate",
            long.len()
        )
    );
    // Within every per-item limit, but 64 predicates of 4,000 characters at 1,000 points.
    let wide: Vec<String> = (0..64)
        .map(|i| format!("P1 >= {i}{}", " ".repeat(3_990)))
        .collect();
    let q = json!({ "transient": &times[..1_000], "prob": wide }).to_string();
    let (status, v) = blocking_request(addr, "POST", "/api/analysis/query", &q);
    assert_eq!(status, 413, "{v}");
    assert!(
        v["error"]
            .as_str()
            .unwrap()
            .ends_with("at most 16 MB per question (ask fewer time points or predicates)"),
        "{v}"
    );
    // The largest question a page can ask of one long predicate is answered.
    let q = json!({ "transient": &times[..1_000], "prob": [&wide[3]] }).to_string();
    let (status, v) = blocking_request(addr, "POST", "/api/analysis/query", &q);
    assert_eq!(status, 200, "{v}");
    assert_eq!(v["transient"].as_array().unwrap().len(), 1_000);
    let peak = peak_rss_kb(child.id());
    child.kill().unwrap();
    child.wait().unwrap();
    assert!(peak < 300 << 10, "the server's peak RSS was {peak} kB");
}

#[test]
fn idle_connections_past_the_file_limit_do_not_lock_out_the_page() {
    let (mut child, addr) = serve_cyc3(1024);
    // 1,100 connections that never send a byte (this process may hold them: its own
    // limit is raised to its hard limit for the test).
    raise_own_file_limit(1_300);
    let idle: Vec<TcpStream> = (0..1_100)
        .map(|_| TcpStream::connect(addr).unwrap())
        .collect();
    // Past the cap (1,024 − 128 = 896) a connection is answered 503 at once, limit named.
    let mut last = idle.last().unwrap();
    last.set_read_timeout(Some(Duration::from_secs(10)))
        .unwrap();
    let mut refused = String::new();
    let _ = last.read_to_string(&mut refused);
    assert!(
        refused.starts_with("HTTP/1.1 503 Service Unavailable"),
        "{refused:?}"
    );
    assert!(
        refused.contains("the viewer holds 896 connections, its limit"),
        "{refused}"
    );
    // The page answers within 15 s while the connections are still held open by us.
    let start = Instant::now();
    let answered = loop {
        assert!(
            start.elapsed() < Duration::from_secs(15),
            "the page did not answer within 15 s"
        );
        if let Ok(mut s) = TcpStream::connect(addr) {
            s.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
            let _ = write!(
                s,
                "GET / HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\n\r\n"
            );
            let mut res = String::new();
            let _ = s.read_to_string(&mut res);
            if res.starts_with("HTTP/1.1 200") {
                break start.elapsed();
            }
        }
        std::thread::sleep(Duration::from_millis(250));
    };
    eprintln!("the page answered after {answered:?}");
    drop(idle);
    child.kill().unwrap();
    child.wait().unwrap();
}

#[cfg(unix)]
fn raise_own_file_limit(want: u64) {
    let mut l = libc::rlimit {
        rlim_cur: 0,
        rlim_max: 0,
    };
    // SAFETY: getrlimit and setrlimit read and write only the struct given.
    unsafe {
        assert_eq!(libc::getrlimit(libc::RLIMIT_NOFILE, &mut l), 0);
        if l.rlim_cur < want {
            l.rlim_cur = want.min(l.rlim_max);
            assert_eq!(libc::setrlimit(libc::RLIMIT_NOFILE, &l), 0);
        }
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_million_firings_leave_the_state_readable_while_they_run() {
    let state = WebState::new(common::cyc3(Servers::Single), None, 3);
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let addr = listener.local_addr().unwrap();
    let server = tokio::spawn(serve(listener, state));
    // While a step runs, other requests are answered and see the firings so far. A loaded
    // machine may end a step before a read lands inside it: up to three steps are tried.
    let mut seen_mid_step = None;
    for round in 0..3u64 {
        let step = tokio::spawn(async move {
            request(addr, "POST", "/api/sim/step", &[JSON], r#"{"n": 1000000}"#).await
        });
        let start = Instant::now();
        while seen_mid_step.is_none() && !step.is_finished() {
            let (status, _, mode) = request(addr, "GET", "/api/mode", &[], "").await;
            assert_eq!((status, mode["live"].as_bool()), (200, Some(false)));
            let (_, _, v) = request(addr, "GET", "/api/sim/state?trace=1", &[], "").await;
            let k = v["firings"].as_u64().unwrap();
            if k > round * 1_000_000 && k < (round + 1) * 1_000_000 {
                seen_mid_step = Some(k);
            }
            assert!(start.elapsed() < Duration::from_secs(300));
        }
        let (status, _, done) = step.await.unwrap();
        assert_eq!(status, 200, "{done}");
        assert_eq!(done["fired"], 1_000_000);
        assert_eq!(done["firings"], (round + 1) * 1_000_000);
        if seen_mid_step.is_some() {
            break;
        }
    }
    let k = seen_mid_step.expect("a state was read while a step ran");
    // The step holds the token game a chunk (10,000 firings) at a time.
    assert_eq!(k % 10_000, 0, "{k} firings seen mid-step");
    server.abort();
}
