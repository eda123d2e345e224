//! Actions as programs, measured: a ring of 4 action places with N agents, every action
//! answered by a program — one `sh` process per action (`--kind command`) or one Python
//! worker for the whole run (`--kind worker`, python/gspn/worker.py), many requests in flight.
//!
//! ```text
//! cargo bench --bench actions -- --kind worker --agents 1000 --firings 100000
//! cargo bench --bench actions -- --kind command --agents 50 --firings 2000
//! ```
//!
//! Prints one JSON line: `{kind, agents, firings, seconds, actions_per_s}` (each firing ends
//! one action, so actions/s = firings/s).

#[path = "support/args.rs"]
mod bench_args;

use std::path::Path;
use std::time::Instant;

use gspn::actions::{CommandAction, CommandSpec, Worker, WorkerSpec};
use gspn::net::{NetBuilder, Servers};
use gspn::runtime::{AgentMode, Runtime};

const WORKER: &str = r#"
from gspn.worker import action, run

@action("step")
def step(ctx):
    return ctx.outputs[0]

run()
"#;

fn arg(name: &str, default: &str) -> String {
    let args: Vec<String> = bench_args::args().collect();
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1).cloned())
        .unwrap_or_else(|| default.to_string())
}

#[tokio::main]
async fn main() {
    let kind = arg("--kind", "worker");
    let agents: u32 = arg("--agents", "1000").parse().unwrap();
    let firings: u64 = arg("--firings", "100000").parse().unwrap();
    let mut b = NetBuilder::new("ring4");
    let places: Vec<_> = (0..4)
        .map(|i| b.place(format!("p{i}"), agents / 4 + u32::from(i < agents % 4)))
        .collect();
    for i in 0..4 {
        let t = b.exponential(format!("t{i}"), 1.0, Servers::Infinite);
        b.input(places[i], t, 1);
        b.output(t, places[(i + 1) % 4], 1);
    }
    let net = b.build().unwrap();
    let dir = std::env::temp_dir().join(format!("gspn-bench-actions-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut builder = Runtime::builder(net)
        .agent_mode(AgentMode::Light)
        .max_firings(firings)
        .seed(1)
        .subscribe_at_start(false);
    let action_name = "step";
    builder = match kind.as_str() {
        "command" => builder.action(
            action_name,
            CommandAction::new(CommandSpec::new(["sh", "-c", "echo $GSPN_OUTPUTS"])),
        ),
        _ => {
            let script = dir.join("bench_worker.py");
            std::fs::write(&script, WORKER).unwrap();
            let python = Path::new(env!("CARGO_MANIFEST_DIR")).join("python");
            let mut spec = WorkerSpec::new(["python3", script.to_str().unwrap()]);
            spec.env
                .push(("PYTHONPATH".into(), python.display().to_string()));
            builder.action(action_name, Worker::start(spec).action("step"))
        }
    };
    for i in 0..4 {
        builder = builder.bind(format!("p{i}"), action_name);
    }
    let start = Instant::now();
    let h = builder.spawn().unwrap();
    let s = h.wait().await;
    let secs = start.elapsed().as_secs_f64();
    assert!(s.errors.is_empty(), "{:?}", s.errors);
    println!(
        "{{\"kind\":\"{kind}\",\"agents\":{agents},\"firings\":{},\"seconds\":{secs:.3},\"actions_per_s\":{:.0}}}",
        s.firings,
        s.firings as f64 / secs
    );
    let _ = std::fs::remove_dir_all(&dir);
}
