//! [`Backend`]: what a run drives besides its own actors — the simulated robot world, ROS 2,
//! the live viewer, and later command actions or a conformance monitor. [`Backends`] is the
//! list a runner keeps: it attaches every backend to the builder, tells each when the run
//! has started, and after the run collects each one's [`Section`] of the summary.
//!
//! ```
//! use std::sync::Arc;
//!
//! use gspn::net::{NetBuilder, Servers};
//! use gspn::runtime::{
//!     Backend, BackendFuture, Backends, EventKind, Received, Runtime, Section, Start, Started,
//!     Summary,
//! };
//!
//! /// Counts the firings it observes; reports them under `"counter"`.
//! #[derive(Debug, Default)]
//! struct Counter {
//!     task: Option<tokio::task::JoinHandle<u64>>,
//! }
//!
//! impl Backend for Counter {
//!     fn name(&self) -> &'static str {
//!         "counter"
//!     }
//!     fn observes_events(&self) -> bool {
//!         true
//!     }
//!     fn started<'a>(&'a mut self, start: Start<'a>) -> Started<'a> {
//!         let mut events = start.events.expect("it observes events");
//!         self.task = Some(tokio::spawn(async move {
//!             let mut n = 0;
//!             while let Some(r) = events.recv().await {
//!                 if let Received::Event(e) = r
//!                     && matches!(e.kind, EventKind::Fired { .. })
//!                 {
//!                     n += 1;
//!                 }
//!             }
//!             n
//!         }));
//!         Box::pin(async { Ok(()) })
//!     }
//!     fn finish<'a>(&'a mut self, _summary: &'a Summary) -> BackendFuture<'a, Option<Section>> {
//!         Box::pin(async move {
//!             let n = self.task.take()?.await.ok()?;
//!             Some(Section::new(serde_json::json!({ "fired": n }), format!("fired {n}")))
//!         })
//!     }
//! }
//!
//! # #[tokio::main(flavor = "current_thread")]
//! # async fn main() {
//! let mut b = NetBuilder::new("ping");
//! let idle = b.place("idle", 1);
//! let busy = b.place("busy", 0);
//! let go = b.exponential("go", 1.0, Servers::Single);
//! let back = b.exponential("back", 1.0, Servers::Single);
//! b.input(idle, go, 1);
//! b.output(go, busy, 1);
//! b.input(busy, back, 1);
//! b.output(back, idle, 1);
//! let run = Runtime::builder(b.build().unwrap()).seed(7).max_firings(10);
//! let mut backends = Backends::default();
//! backends.push(Counter::default());
//! let (summary, sections) = backends.run(run).await.unwrap();
//! assert_eq!(summary.firings, 10);
//! assert_eq!(sections[0].0, "counter");
//! assert_eq!(sections[0].1.json["fired"], 10);
//! # }
//! ```

use std::future::Future;
use std::pin::Pin;
use std::sync::Arc;

use super::{Events, RuntimeBuilder, RuntimeError, RuntimeHandle, Summary};

/// A boxed future a [`Backend`] returns (backends are kept as `Box<dyn Backend>`).
pub type BackendFuture<'a, T> = Pin<Box<dyn Future<Output = T> + Send + 'a>>;

/// What [`Backend::started`] returns.
pub type Started<'a> = BackendFuture<'a, Result<(), BackendError>>;

/// What [`Backend::started`] is given: the running run, and its event stream when the
/// backend [observes events](Backend::observes_events).
#[derive(Debug)]
pub struct Start<'a> {
    /// The run's handle.
    pub run: &'a Arc<RuntimeHandle>,
    /// The run's events (`None` unless the backend observes events).
    pub events: Option<Events>,
}

/// Why a backend could not join a run.
#[derive(Debug, thiserror::Error)]
#[error("{backend}: {source}")]
pub struct BackendError {
    /// The backend's [`Backend::name`].
    pub backend: &'static str,
    /// What went wrong.
    pub source: Box<dyn std::error::Error + Send + Sync>,
}

impl BackendError {
    /// An error of backend `backend`.
    pub fn new(
        backend: &'static str,
        source: impl Into<Box<dyn std::error::Error + Send + Sync>>,
    ) -> Self {
        BackendError {
            backend,
            source: source.into(),
        }
    }
}

/// A backend's part of a run's summary: JSON (under the backend's name) and text.
#[derive(Clone, Debug, PartialEq)]
pub struct Section {
    /// Added to the JSON summary under [`Backend::name`].
    pub json: serde_json::Value,
    /// Printed after the text summary (nothing when empty).
    pub text: String,
}

impl Section {
    /// A section with both forms.
    pub fn new(json: serde_json::Value, text: impl Into<String>) -> Self {
        Section {
            json,
            text: text.into(),
        }
    }
}

/// Something a run drives besides its own actors. Every method but [`name`](Backend::name)
/// has a default that does nothing, so a backend implements only what it needs. The order:
///
/// 1. [`attach`](Backend::attach) before the run is spawned: register action handlers by
///    name ([`RuntimeBuilder::action`]), bind robots, change options;
/// 2. [`started`](Backend::started) once it runs, with the handle and — when
///    [`observes_events`](Backend::observes_events) — its own event stream;
/// 3. [`finish`](Backend::finish) after the run: wait for what is in flight and give a
///    [`Section`] of the summary;
/// 4. [`stop`](Backend::stop) last: release what it holds.
pub trait Backend: Send + std::fmt::Debug {
    /// A short name: the key of its summary section, the prefix of its errors.
    fn name(&self) -> &'static str;

    /// Prepares the run before it is spawned: register actions, bind robots, set options.
    fn attach(&mut self, run: RuntimeBuilder) -> Result<RuntimeBuilder, BackendError> {
        Ok(run)
    }

    /// True when [`started`](Backend::started) wants the run's events.
    fn observes_events(&self) -> bool {
        false
    }

    /// The run is spawned: its handle, and its event stream when the backend observes events.
    fn started<'a>(&'a mut self, start: Start<'a>) -> Started<'a> {
        let _ = start;
        Box::pin(async { Ok(()) })
    }

    /// The run is over: wait for what is in flight, then give this backend's part of the
    /// summary (`None`: nothing to add).
    fn finish<'a>(&'a mut self, summary: &'a Summary) -> BackendFuture<'a, Option<Section>> {
        let _ = summary;
        Box::pin(async { None })
    }

    /// Releases what the backend holds (tasks, a world, sockets); called after
    /// [`finish`](Backend::finish).
    fn stop(&mut self) {}
}

/// The backends of a run, in the order they are attached, started and finished.
#[derive(Debug, Default)]
pub struct Backends {
    list: Vec<Box<dyn Backend>>,
}

impl Backends {
    /// Adds a backend at the end.
    pub fn push(&mut self, backend: impl Backend + 'static) {
        self.list.push(Box::new(backend));
    }

    /// True when there is none.
    pub fn is_empty(&self) -> bool {
        self.list.is_empty()
    }

    /// The backends' names, in order.
    pub fn names(&self) -> Vec<&'static str> {
        self.list.iter().map(|b| b.name()).collect()
    }

    /// Attaches every backend to `run`, in order; the run keeps its events from the start
    /// when one of them observes events.
    pub fn attach(&mut self, mut run: RuntimeBuilder) -> Result<RuntimeBuilder, BackendError> {
        for b in &mut self.list {
            run = b.attach(run)?;
        }
        if self.list.iter().any(|b| b.observes_events()) {
            run = run.subscribe_at_start(true);
        }
        Ok(run)
    }

    /// Tells every backend that `handle`'s run has started. The first observing backend gets
    /// the events from the run's start, the others a stream subscribed now.
    pub async fn start(
        &mut self,
        mut handle: RuntimeHandle,
    ) -> Result<Arc<RuntimeHandle>, BackendError> {
        let streams: Vec<Option<Events>> = self
            .list
            .iter()
            .map(|b| b.observes_events().then(|| handle.events()))
            .collect();
        let handle = Arc::new(handle);
        for (b, events) in self.list.iter_mut().zip(streams) {
            b.started(Start {
                run: &handle,
                events,
            })
            .await?;
        }
        Ok(handle)
    }

    /// After the run: every backend's section, in order, by backend name.
    pub async fn finish(&mut self, summary: &Summary) -> Vec<(&'static str, Section)> {
        let mut sections = Vec::new();
        for b in &mut self.list {
            if let Some(s) = b.finish(summary).await {
                sections.push((b.name(), s));
            }
        }
        sections
    }

    /// Stops every backend, in order.
    pub fn stop(&mut self) {
        for b in &mut self.list {
            b.stop();
        }
    }

    /// Runs `run` to its end with these backends: attach, spawn, start, wait, finish, stop.
    pub async fn run(
        &mut self,
        run: RuntimeBuilder,
    ) -> Result<(Summary, Vec<(&'static str, Section)>), RunError> {
        let run = self.attach(run)?;
        let handle = match self.start(run.spawn()?).await {
            Ok(h) => h,
            Err(e) => {
                self.stop();
                return Err(e.into());
            }
        };
        let summary = handle.wait().await;
        let sections = self.finish(&summary).await;
        self.stop();
        Ok((summary, sections))
    }
}

/// Why [`Backends::run`] could not run.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RunError {
    /// A backend refused the run.
    #[error(transparent)]
    Backend(#[from] BackendError),
    /// The runtime refused it.
    #[error(transparent)]
    Runtime(#[from] RuntimeError),
}
