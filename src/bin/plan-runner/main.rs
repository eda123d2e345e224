//! `plan-runner`: check, analyse, simulate, run and convert GSPN plans.
//!
//! Exit codes: 0 ok, 1 failure, 2 bad input, 130 interrupted (SIGINT), 143 terminated
//! (SIGTERM), 129 hung up (SIGHUP); the last three stop a run cleanly (see docs/reliability.md).

mod analyze;
mod backends;
mod check;
mod common;
mod conform;
mod convert;
mod export;
mod import_thesis;
mod progress;
mod repeats;
mod replay;
#[cfg(feature = "ros2")]
mod ros2;
mod run;
#[cfg(feature = "web")]
mod serve;
mod simulate;
#[cfg(feature = "ros2")]
mod supervisor_run;
mod synthesize;
#[cfg(feature = "zenoh")]
mod zenoh;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// Multi-robot plans as generalized stochastic Petri nets.
#[derive(Parser, Debug)]
#[command(name = "plan-runner", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Load a net or a plan, print a summary and warnings.
    Check(check::Args),
    /// Compare a run's journal with its model's predictions; --fit learns the net back.
    Conform(conform::Args),
    /// Analyse the state space, steady state and transient behaviour of a net.
    Analyze(analyze::Args),
    /// Play the token game: one seeded trace, or Monte-Carlo estimates over many runs.
    Simulate(simulate::Args),
    /// Execute a plan (or a bare net) on agents.
    Run(run::Args),
    /// The optimal policy of a net with rewards: decision model, objective, `[[policy]]` rules.
    Synthesize(synthesize::Args),
    /// Convert a net between formats (chosen by the output's extension).
    Convert(convert::Args),
    /// Write a run's journal as MCAP (ROS 2 messages; feature `ros2`).
    Export(export::Args),
    /// Turn a thesis framework execution input (JSON) into a plan.toml next to its net.
    ImportThesis(import_thesis::Args),
    /// Open the viewer for a net or a plan: drawing, token game, analysis (feature `web`).
    #[cfg(feature = "web")]
    Serve(serve::Args),
    /// Play a run's journal back: print its firings, or show them with --web (feature `web`).
    Replay(replay::Args),
    /// Serve a plan's `ros2` places as one robot: ExecPlace action servers at /<ID>/<server>
    /// with net-timed local actions, a heartbeat, the firings (feature `ros2`).
    #[cfg(feature = "ros2")]
    Robot(ros2::RobotArgs),
    /// Simulated robots of a plan's map serving Nav2's NavigateToPose over DDS, in a process
    /// of their own: a stand-in for a real Nav2 fleet that `run --nav2` drives (features
    /// `ros2` and `sim`).
    #[cfg(all(feature = "ros2", feature = "sim"))]
    SimNav2(ros2::SimNav2Args),
    /// Host many robots of a plan in one process over Zenoh (feature `zenoh`): each serves
    /// its ExecPlace action and declares its own liveliness token, as `robot --zenoh` does.
    #[cfg(feature = "zenoh")]
    Fleet(zenoh::FleetArgs),
    /// Run a Zenoh router (feature `zenoh`): supervisors and robots connect to it as
    /// clients; routers join each other with --connect (sites across networks).
    #[cfg(feature = "zenoh")]
    Router(zenoh::RouterArgs),
}

fn main() -> ExitCode {
    restore_sigpipe();
    init_logging();
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Check(a) => check::main(a),
        Command::Analyze(a) => analyze::main(a),
        Command::Conform(a) => conform::main(a),
        Command::Simulate(a) => simulate::main(a),
        Command::Run(a) => run::main(a),
        Command::Synthesize(a) => synthesize::main(a),
        Command::Convert(a) => convert::main(a),
        Command::Export(a) => export::main(a),
        Command::ImportThesis(a) => import_thesis::main(a),
        #[cfg(feature = "web")]
        Command::Serve(a) => serve::main(a),
        Command::Replay(a) => replay::main(a),
        #[cfg(feature = "ros2")]
        Command::Robot(a) => ros2::robot(a),
        #[cfg(all(feature = "ros2", feature = "sim"))]
        Command::SimNav2(a) => ros2::sim_nav2_main(a),
        #[cfg(feature = "zenoh")]
        Command::Fleet(a) => zenoh::fleet(a),
        #[cfg(feature = "zenoh")]
        Command::Router(a) => zenoh::router(a),
    };
    // No program an action started outlives plan-runner (a stop already ended them; this
    // catches the ones a runtime dropped mid-run).
    #[cfg(unix)]
    gspn::actions::terminate_all();
    match result {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::from(common::exit_code_for(&e))
        }
    }
}

/// The default log filter. RustDDS's writer warns "No locators" for every same-host reader
/// reached over loopback (it does reach it), ros2-client that `ROS_DISTRO` is unset, and its
/// service server that a request has no related sample identity (its own client never
/// sends one in the Enhanced mapping; the server then uses the request's own identity, as
/// it should): all three would flood stderr, so only their errors show.
const DEFAULT_LOG: &str = "warn,gspn=info,rustdds::rtps::writer=error,\
     ros2_client::distributions=error,ros2_client::service::wrappers=error,\
     zenoh::api::handlers::fifo=off";

/// Warnings and errors of the library and of its dependencies (RustDDS and ros2-client log
/// through `log`, bridged) go to stderr; `RUST_LOG` overrides the default filter
/// (`DEFAULT_LOG`: the library's notices, everyone's warnings but three noisy ones), at
/// most five lines per place in the code per 10 s ([`repeats`]: a flood of the same warning
/// is counted, not printed). With
/// feature `ros2`, a second layer with its own filter hands the ROS 2 layer's warnings and
/// errors to `/rosout` once a node forwards them (`--ros2-rosout`; it does nothing before).
fn init_logging() {
    use tracing_subscriber::Layer as _;
    use tracing_subscriber::filter::FilterExt as _;
    use tracing_subscriber::layer::SubscriberExt as _;
    use tracing_subscriber::util::SubscriberInitExt as _;
    let filter = tracing_subscriber::EnvFilter::try_from_default_env()
        .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new(DEFAULT_LOG));
    let stderr = tracing_subscriber::fmt::layer()
        .with_writer(std::io::stderr)
        .with_ansi(std::io::IsTerminal::is_terminal(&std::io::stderr()))
        .with_target(true)
        .without_time()
        .with_filter(filter.and(repeats::RateLimit::default()));
    let registry = tracing_subscriber::registry().with(stderr);
    #[cfg(feature = "ros2")]
    let registry = registry.with(gspn::ros2::rosout::RosoutLayer::filtered());
    let _ = registry.try_init();
}

/// Rust ignores SIGPIPE, so printing to a closed pipe (`plan-runner … | head`) would panic;
/// a Unix tool is expected to end quietly instead.
fn restore_sigpipe() {
    #[cfg(unix)]
    // SAFETY: called first thing in `main`, before any thread is spawned; SIG_DFL is a valid
    // disposition for SIGPIPE.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}
