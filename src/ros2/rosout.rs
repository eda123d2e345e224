//! `/rosout`: the ROS 2 layer's warnings and errors published by the process's node, as ROS 2
//! nodes publish their log (`rcl_interfaces/msg/Log` on `rt/rosout`).
//!
//! Two halves, joined by a bounded channel:
//! - [`RosoutLayer`] (added once to the program's `tracing` subscriber, next to the stderr
//!   output, which it does not change): each event it is given ([`RosoutLayer::targets`]:
//!   `gspn::ros2…` at WARN and ERROR, `rustdds` and `ros2_client` at ERROR) becomes a
//!   [`Record`] sent with `try_send`: the layer never blocks, and while no node forwards (or
//!   its queue of [`QUEUE`] records is full) the record is dropped and counted
//!   ([`dropped`]).
//! - [`forward`]: called with a node when `/rosout` is asked (`--ros2-rosout`, the plan's
//!   `[ros2] rosout = true`): a publisher on `rt/rosout` with rcl's QoS (reliable,
//!   transient local, keep last 1000, lifespan 10 s) and a task that publishes every record
//!   with the node's logger name (`gspn.supervisor`: the fully qualified name without the
//!   leading `/`, `/` → `.`, as rcl names a node's logger). Events before that are not sent;
//!   [`Forwarder::finish`] sends the last ones before the process leaves.

use std::cell::Cell;
use std::fmt::Write as _;
use std::future::Future;
use std::pin::Pin;
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::task::{Context, Poll};
use std::time::Duration;

use ros2_client::builtin_interfaces::Time;
use ros2_client::log::Log;
use ros2_client::qos::{Durability, History};
use ros2_client::{MessageTypeName, Name, Node, QosProfile};
use tokio::sync::mpsc;
use tokio::task::JoinHandle;
use tracing::field::{Field, Visit};
use tracing::{Event, Level, Subscriber};
use tracing_log::NormalizeEvent;
use tracing_subscriber::filter::Targets;
use tracing_subscriber::layer::{Context as LayerContext, Layer};

use super::Ros2Error;

/// How many records wait for the node's task at most; more are dropped (and counted).
pub const QUEUE: usize = 1000;

/// One forwarded event: everything of `rcl_interfaces/msg/Log` but the logger name, which is
/// the forwarding node's.
#[derive(Clone, Debug, PartialEq)]
pub struct Record {
    /// When the event happened.
    pub stamp: Time,
    /// The ROS 2 level: 30 (warn) or 40 (error).
    pub level: u8,
    /// The event's message, then its other fields as ` key=value`.
    pub msg: String,
    /// The source file of the event.
    pub file: String,
    /// Its module path (`gspn::ros2::heartbeat`): `tracing` knows no function names.
    pub function: String,
    /// Its line.
    pub line: u32,
}

/// Set while a node forwards: the layer does nothing else before that.
static ACTIVE: AtomicBool = AtomicBool::new(false);
/// Where records go (the forwarding node's channel).
static SINK: Mutex<Option<mpsc::Sender<Record>>> = Mutex::new(None);
/// Records that could not be queued while a node forwards.
static DROPPED: AtomicU64 = AtomicU64::new(0);

thread_local! {
    /// Set while this thread publishes a record: what DDS logs then is not forwarded again.
    static PUBLISHING: Cell<bool> = const { Cell::new(false) };
}

/// The records dropped because the node's queue was full.
pub fn dropped() -> u64 {
    DROPPED.load(Ordering::Relaxed)
}

/// The `tracing` layer that hands the ROS 2 layer's warnings and errors to the node that
/// [`forward`]s them; add it with its filter: [`RosoutLayer::filtered`].
#[derive(Clone, Copy, Debug, Default)]
pub struct RosoutLayer;

impl RosoutLayer {
    /// What is forwarded: `gspn::ros2…` at WARN and ERROR, `rustdds…` and `ros2_client…` at
    /// ERROR.
    pub fn targets() -> Targets {
        Targets::new()
            .with_target("gspn::ros2", Level::WARN)
            .with_target("rustdds", Level::ERROR)
            .with_target("ros2_client", Level::ERROR)
    }

    /// The layer with its own filter ([`RosoutLayer::targets`]), independent of the stderr
    /// output's.
    pub fn filtered<S>() -> impl Layer<S>
    where
        S: Subscriber + for<'a> tracing_subscriber::registry::LookupSpan<'a>,
    {
        RosoutLayer.with_filter(RosoutLayer::targets())
    }
}

impl<S: Subscriber> Layer<S> for RosoutLayer {
    fn on_event(&self, event: &Event<'_>, _: LayerContext<'_, S>) {
        if !ACTIVE.load(Ordering::Relaxed) || PUBLISHING.with(Cell::get) {
            return;
        }
        let Some(record) = record(event) else {
            return;
        };
        let Ok(sink) = SINK.lock() else {
            return;
        };
        if let Some(tx) = sink.as_ref()
            && tx.try_send(record).is_err()
        {
            DROPPED.fetch_add(1, Ordering::Relaxed);
        }
    }
}

/// The record of `event` (its real target, file and line for a `log` record), `None` below
/// WARN.
fn record(event: &Event<'_>) -> Option<Record> {
    let normalized = event.normalized_metadata();
    let meta = normalized.as_ref().unwrap_or_else(|| event.metadata());
    let level = match *meta.level() {
        Level::ERROR => 40,
        Level::WARN => 30,
        _ => return None,
    };
    let mut fields = Fields::default();
    event.record(&mut fields);
    let stamp = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .ok()
        .and_then(|d| i64::try_from(d.as_nanos()).ok())
        .map(Time::from_nanos)
        .unwrap_or(Time::ZERO);
    Some(Record {
        stamp,
        level,
        msg: fields.msg + &fields.rest,
        file: meta.file().unwrap_or_default().to_string(),
        function: meta
            .module_path()
            .unwrap_or_else(|| meta.target())
            .to_string(),
        line: meta.line().unwrap_or(0),
    })
}

/// An event's message and its other fields (`log.*`, the bridged record's metadata, left
/// out).
#[derive(Default)]
struct Fields {
    msg: String,
    rest: String,
}

impl Visit for Fields {
    fn record_str(&mut self, field: &Field, value: &str) {
        if field.name() == "message" {
            self.msg.push_str(value);
        } else if !field.name().starts_with("log.") {
            let _ = write!(self.rest, " {}={value}", field.name());
        }
    }

    fn record_debug(&mut self, field: &Field, value: &dyn std::fmt::Debug) {
        if field.name() == "message" {
            let _ = write!(self.msg, "{value:?}");
        } else if !field.name().starts_with("log.") {
            let _ = write!(self.rest, " {}={value:?}", field.name());
        }
    }
}

/// The logger name rcl gives node `fqn` (`/gspn/supervisor` → `gspn.supervisor`).
pub fn logger_name(fqn: &str) -> String {
    fqn.trim_start_matches('/').replace('/', ".")
}

/// rcl's `/rosout` QoS: reliable, transient local, keep last 1000, lifespan 10 s.
pub fn qos() -> QosProfile {
    let mut q = QosProfile::publisher_default()
        .durability(Durability::TransientLocal)
        .history(History::KeepLast { depth: 1000 });
    q.lifespan = Some(Duration::from_secs(10));
    q
}

/// The node's side of `/rosout` ([`forward`]): its task publishes what [`RosoutLayer`]
/// gives; dropped, the task is aborted.
#[derive(Debug)]
pub struct Forwarder {
    task: Option<JoinHandle<()>>,
}

/// Starts publishing on `/rosout` what [`RosoutLayer`] gives from now on, with `node`'s
/// logger name, until [`Forwarder::finish`] (or the forwarder is dropped). A second call
/// takes the records from the first.
pub fn forward(node: &mut Node) -> Result<Forwarder, Ros2Error> {
    let name = Name::parse("/rosout").map_err(Ros2Error::dds)?;
    let topic = node
        .create_topic(&name, MessageTypeName::new("rcl_interfaces", "Log"), &qos())
        .map_err(Ros2Error::dds)?;
    let publisher = node
        .create_publisher::<Log>(&topic, Some(qos()))
        .map_err(Ros2Error::dds)?;
    let name = logger_name(&node.fully_qualified_name());
    let (tx, mut rx) = mpsc::channel::<Record>(QUEUE);
    if let Ok(mut sink) = SINK.lock() {
        *sink = Some(tx);
    }
    ACTIVE.store(true, Ordering::Relaxed);
    let task = tokio::spawn(Quiet(Box::pin(async move {
        while let Some(r) = rx.recv().await {
            let log = Log {
                stamp: r.stamp,
                level: r.level,
                name: name.clone(),
                msg: r.msg,
                file: r.file,
                function: r.function,
                line: r.line,
            };
            // Not logged: a warning about /rosout would come back here.
            let _ = publisher.async_publish(log).await;
        }
        // The queue is closed (`finish`): the subscribers get the last records before the
        // process leaves (bounded by the caller).
        let _ = publisher.async_wait_for_acknowledgments().await;
    })));
    Ok(Forwarder { task: Some(task) })
}

impl Forwarder {
    /// Stops taking records, publishes those queued and waits (at most `limit`) until the
    /// subscribers of `/rosout` acknowledged them: the warnings of a leaving process reach
    /// `/rosout` before it exits.
    pub async fn finish(mut self, limit: Duration) {
        ACTIVE.store(false, Ordering::Relaxed);
        if let Ok(mut sink) = SINK.lock() {
            *sink = None;
        }
        if let Some(t) = self.task.take() {
            let abort = t.abort_handle();
            if tokio::time::timeout(limit, t).await.is_err() {
                abort.abort();
            }
        }
    }
}

impl Drop for Forwarder {
    fn drop(&mut self) {
        if let Some(t) = self.task.take() {
            t.abort();
        }
    }
}

/// A future during whose polls [`RosoutLayer`] ignores the thread's events.
struct Quiet<F>(F);

impl<F: Future + Unpin> Future for Quiet<F> {
    type Output = F::Output;

    fn poll(mut self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<F::Output> {
        PUBLISHING.with(|p| p.set(true));
        let out = Pin::new(&mut self.0).poll(cx);
        PUBLISHING.with(|p| p.set(false));
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn logger_names_are_rcl_s() {
        assert_eq!(logger_name("/gspn/supervisor"), "gspn.supervisor");
        assert_eq!(logger_name("/gspn/robot_r1"), "gspn.robot_r1");
        assert_eq!(logger_name("/talker"), "talker");
    }

    #[test]
    fn the_targets_are_the_ros2_layer_s_warnings_and_the_dds_crates_errors() {
        let t = RosoutLayer::targets();
        assert!(t.would_enable("gspn::ros2::heartbeat", &Level::WARN));
        assert!(t.would_enable("gspn::ros2", &Level::ERROR));
        assert!(!t.would_enable("gspn::ros2::heartbeat", &Level::INFO));
        assert!(!t.would_enable("gspn::runtime", &Level::WARN));
        assert!(t.would_enable("rustdds::rtps::writer", &Level::ERROR));
        assert!(!t.would_enable("rustdds::rtps::writer", &Level::WARN));
        assert!(t.would_enable("ros2_client::service", &Level::ERROR));
        assert!(!t.would_enable("ros2_client::service", &Level::WARN));
        let q = qos();
        assert_eq!(q.history, History::KeepLast { depth: 1000 });
        assert_eq!(q.durability, Durability::TransientLocal);
        assert_eq!(q.lifespan, Some(Duration::from_secs(10)));
    }

    #[test]
    fn the_layer_queues_matching_events_without_blocking_and_counts_what_it_drops() {
        use tracing_subscriber::layer::SubscriberExt as _;
        let (tx, mut rx) = mpsc::channel::<Record>(3);
        *SINK.lock().unwrap() = Some(tx);
        ACTIVE.store(true, Ordering::Relaxed);
        let dropped_before = dropped();
        // RustDDS and ros2-client log through `log`, bridged as in `plan-runner`.
        let _ = tracing_log::LogTracer::init();
        let subscriber = tracing_subscriber::registry().with(RosoutLayer::filtered());
        let (line, log_line) = tracing::subscriber::with_default(subscriber, || {
            tracing::info!(target: "gspn::ros2::heartbeat", "not forwarded: info");
            tracing::warn!(target: "gspn::runtime", "not forwarded: not the ROS 2 layer");
            tracing::warn!(target: "rustdds::rtps", "not forwarded: a DDS warning");
            let line = line!() + 1;
            tracing::warn!(target: "gspn::ros2::heartbeat", robot = "r2", "lost {}", 1);
            tracing::error!(target: "rustdds::rtps", "an error");
            tracing_log::log::warn!(target: "rustdds::rtps", "not forwarded: a bridged warning");
            let log_line = line!() + 1;
            tracing_log::log::error!(target: "rustdds::rtps::writer", "a bridged error");
            tracing::error!(target: "ros2_client::x", "a fourth: the queue (3) is full");
            (line, log_line)
        });
        ACTIVE.store(false, Ordering::Relaxed);
        *SINK.lock().unwrap() = None;
        let first = rx.try_recv().unwrap();
        assert_eq!(first.level, 30);
        assert_eq!(first.msg, "lost 1 robot=r2");
        assert!(first.file.ends_with("src/ros2/rosout.rs"), "{first:?}");
        assert_eq!(first.line, line);
        assert_eq!(first.function, "gspn::ros2::rosout::tests");
        assert!(first.stamp.to_nanos() > 1_700_000_000_000_000_000);
        let second = rx.try_recv().unwrap();
        assert_eq!((second.level, second.msg.as_str()), (40, "an error"));
        // A `log` record: its own target, file and line, not the bridge's.
        let third = rx.try_recv().unwrap();
        assert_eq!((third.level, third.msg.as_str()), (40, "a bridged error"));
        assert_eq!(third.function, "gspn::ros2::rosout::tests");
        assert!(third.file.ends_with("src/ros2/rosout.rs"), "{third:?}");
        assert_eq!(third.line, log_line);
        assert!(rx.try_recv().is_err());
        assert_eq!(dropped() - dropped_before, 1);
    }
}
