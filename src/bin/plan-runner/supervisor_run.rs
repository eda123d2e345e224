//! The supervisor's transport side of `run` — DDS ([`gspn::ros2::Ros2Backend`]) or Zenoh
//! ([`gspn::zenoh::ZenohBackend`]) — as one backend: it registers the `ros2` action,
//! publishes the run's firings and marking, and after the run tells the robots it is over
//! and lingers so subscribers get the last ones.

use std::future::Future;
use std::time::Duration;

use gspn::ros2::firings::Published;
use gspn::runtime::{
    Backend, BackendError, BackendFuture, Events, RuntimeBuilder, Section, Start, Started, Summary,
};

/// What `run` needs of a transport's supervisor side.
pub(crate) trait Transport: std::fmt::Debug + Send + Sized + 'static {
    /// The backend's name, and the prefix of its line on stderr.
    const NAME: &'static str;
    /// Registers the `ros2` action on the run.
    fn attach(&self, run: RuntimeBuilder) -> RuntimeBuilder;
    /// Starts publishing the run's events.
    fn publish(&mut self, events: Events) -> impl Future<Output = ()> + Send + '_;
    /// Says the run is over (why: `stopped`), lets the publisher finish, lingers.
    fn finish(self, linger: Duration, stopped: String) -> impl Future<Output = Published> + Send;
}

impl Transport for gspn::ros2::Ros2Backend {
    const NAME: &'static str = "ros2";

    fn attach(&self, run: RuntimeBuilder) -> RuntimeBuilder {
        gspn::ros2::Ros2Backend::attach(self, run)
    }

    fn publish(&mut self, events: Events) -> impl Future<Output = ()> + Send + '_ {
        gspn::ros2::Ros2Backend::publish(self, events);
        std::future::ready(())
    }

    async fn finish(self, linger: Duration, stopped: String) -> Published {
        gspn::ros2::Ros2Backend::finish(self, linger, &stopped).await
    }
}

#[cfg(feature = "zenoh")]
impl Transport for gspn::zenoh::ZenohBackend {
    const NAME: &'static str = "zenoh";

    fn attach(&self, run: RuntimeBuilder) -> RuntimeBuilder {
        gspn::zenoh::ZenohBackend::attach(self, run)
    }

    fn publish(&mut self, events: Events) -> impl Future<Output = ()> + Send + '_ {
        gspn::zenoh::ZenohBackend::publish(self, events)
    }

    async fn finish(self, linger: Duration, stopped: String) -> Published {
        gspn::zenoh::ZenohBackend::finish(self, linger, &stopped).await
    }
}

/// A transport's supervisor side as a backend of `run`.
#[derive(Debug)]
pub(crate) struct SupervisorRun<T: Transport> {
    backend: Option<T>,
    linger: Duration,
}

impl<T: Transport> SupervisorRun<T> {
    /// `backend`, lingering `linger` seconds (clamped to 0–60) after the run.
    pub(crate) fn new(backend: T, linger: f64) -> Self {
        SupervisorRun {
            backend: Some(backend),
            linger: Duration::from_secs_f64(linger.clamp(0.0, 60.0)),
        }
    }
}

impl<T: Transport> Backend for SupervisorRun<T> {
    fn name(&self) -> &'static str {
        T::NAME
    }

    fn attach(&mut self, run: RuntimeBuilder) -> Result<RuntimeBuilder, BackendError> {
        Ok(match &self.backend {
            Some(b) => b.attach(run),
            None => run,
        })
    }

    fn observes_events(&self) -> bool {
        true
    }

    fn started<'a>(&'a mut self, start: Start<'a>) -> Started<'a> {
        Box::pin(async move {
            if let (Some(b), Some(events)) = (&mut self.backend, start.events) {
                b.publish(events).await;
            }
            Ok(())
        })
    }

    /// The counts go to stderr.
    fn finish<'a>(&'a mut self, summary: &'a Summary) -> BackendFuture<'a, Option<Section>> {
        Box::pin(async move {
            let backend = self.backend.take()?;
            let stopped = serde_json::to_value(&summary.stopped)
                .ok()
                .and_then(|v| v.as_str().map(str::to_string))
                .unwrap_or_default();
            let p = backend.finish(self.linger, stopped).await;
            eprintln!(
                "{}: published {} firings ({} events lost, {} publish errors)",
                T::NAME,
                p.firings,
                p.lagged,
                p.errors
            );
            None
        })
    }
}
