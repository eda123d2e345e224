//! The supervisor's publications: every firing on `/gspn/firings` (reliable, keep-all), the
//! current marking on `/gspn/marking` (reliable, transient-local, depth 1) and the run's
//! state on `/gspn/run` ([`RunStatePublisher`], same QoS as the marking); the live
//! monitor's drifts (`run --monitor`) on `/gspn/drift` as `gspn_msgs/Drift` (same QoS as the
//! firings, [`drift_message`]); and
//! [`FiringListener`], a subscriber to them for robots, tests and tools.

use std::sync::Arc;

use futures::StreamExt;
use ros2_client::qos::{Durability, History, Reliability, WhenFull};
use ros2_client::{Node, Publisher, QosProfile, Subscription};

use super::Ros2Error;
use super::msgs::{
    self as msgs, DRIFT_TOPIC, FIRINGS_TOPIC, Firing, Header, MARKING_TOPIC, Marking, RUN_TOPIC,
    RunState, drift_type, firing_type, marking_type, run_state_type,
};
use crate::net::Net;
use crate::runtime::{Drift, EventKind, Events, Monitored, Received};

/// QoS of `/gspn/firings`: reliable, keep-all, volatile.
pub fn firings_qos() -> QosProfile {
    QosProfile::publisher_default()
        .reliability(Reliability::Reliable {
            when_full: WhenFull::Wait(std::time::Duration::from_secs(1)),
        })
        .durability(Durability::Volatile)
        .history(History::KeepAll)
}

/// QoS of `/gspn/marking`: reliable, transient-local, depth 1.
pub fn marking_qos() -> QosProfile {
    QosProfile::publisher_default()
        .durability(Durability::TransientLocal)
        .history(History::KeepLast { depth: 1 })
}

/// A publisher on the topic `name` of type `ty` with `qos`.
fn publisher<M: serde::Serialize>(
    node: &mut Node,
    name: &str,
    ty: ros2_client::MessageTypeName,
    qos: QosProfile,
) -> Result<Publisher<M>, Ros2Error> {
    let name = super::names::topic(node, name)?;
    let topic = node.create_topic(&name, ty, &qos).map_err(Ros2Error::dds)?;
    node.create_publisher(&topic, Some(qos))
        .map_err(Ros2Error::dds)
}

/// A subscription to the topic `name` of type `ty` with `qos`.
fn subscription<M: serde::de::DeserializeOwned + 'static>(
    node: &mut Node,
    name: &str,
    ty: ros2_client::MessageTypeName,
    qos: QosProfile,
) -> Result<Subscription<M>, Ros2Error> {
    let name = super::names::topic(node, name)?;
    let topic = node.create_topic(&name, ty, &qos).map_err(Ros2Error::dds)?;
    node.create_subscription(&topic, Some(qos))
        .map_err(Ros2Error::dds)
}

/// Publishes a run's firings and markings.
pub struct FiringPublisher {
    firings: Publisher<Firing>,
    marking: Publisher<Marking>,
    drift: Publisher<msgs::Drift>,
    net: Arc<Net>,
}

/// The `/gspn/drift` message of a drift found at model time `time`.
pub fn drift_message(net: &Net, time: f64, d: &Drift) -> msgs::Drift {
    let (transition, place) = match d.of {
        Monitored::Transition(t) => (net.transition(t).name.clone(), String::new()),
        Monitored::Place(p) => (String::new(), net.place(p).name.clone()),
    };
    msgs::Drift {
        header: Header::now(""),
        model_time: time,
        transition,
        place,
        observed: d.observed,
        predicted: d.predicted,
        interval_low: d.interval[0],
        interval_high: d.interval[1],
        n: d.n,
        p_value: d.p_value,
        text: d.describe(net),
    }
}

impl std::fmt::Debug for FiringPublisher {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("FiringPublisher")
            .field("net", &self.net.name())
            .finish()
    }
}

/// What the publisher did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Published {
    /// Firings published (the last `seq`).
    pub firings: u64,
    /// Events the bus dropped before the publisher read them (0 unless it fell behind).
    pub lagged: u64,
    /// Publications that failed.
    pub errors: u64,
}

impl FiringPublisher {
    /// Creates the two publishers on `node` for runs of `net`.
    pub fn new(node: &mut Node, net: Arc<Net>) -> Result<FiringPublisher, Ros2Error> {
        Ok(FiringPublisher {
            drift: publisher(node, DRIFT_TOPIC, drift_type(), firings_qos())?,
            firings: publisher(node, FIRINGS_TOPIC, firing_type(), firings_qos())?,
            marking: publisher(node, MARKING_TOPIC, marking_type(), marking_qos())?,
            net,
        })
    }

    /// Matched subscribers of `/gspn/firings` (needs the node's spinner).
    pub fn firing_subscribers(&self, node: &Node) -> usize {
        self.firings.get_subscription_count(node)
    }

    /// Waits (at most `limit`) until every matched subscriber has acknowledged every firing
    /// and marking published; false if some had not by then.
    pub async fn acknowledged(&self, limit: std::time::Duration) -> bool {
        let both = async {
            let f = self.firings.async_wait_for_acknowledgments().await;
            let m = self.marking.async_wait_for_acknowledgments().await;
            matches!((f, m), (Ok(true), Ok(true)))
        };
        tokio::time::timeout(limit, both).await.unwrap_or(false)
    }

    /// Publishes the initial marking, then every firing of `events` until the run is over.
    pub async fn run(&self, events: Events) -> Published {
        publish_run(&self.net, events, self).await
    }
}

impl RunSink for FiringPublisher {
    async fn send(&self, m: RunMessage) -> bool {
        match m {
            RunMessage::Marking(m) => self.marking.async_publish(m).await.is_ok(),
            RunMessage::Firing(f) => self.firings.async_publish(f).await.is_ok(),
            RunMessage::Drift(d) => self.drift.async_publish(d).await.is_ok(),
        }
    }
}

/// A message of the run's topics, whatever the transport (DDS here, Zenoh in
/// `crate::zenoh`).
pub(crate) enum RunMessage {
    /// On `/gspn/marking`.
    Marking(Marking),
    /// On `/gspn/firings`.
    Firing(Firing),
    /// On `/gspn/drift`.
    Drift(msgs::Drift),
}

/// Where [`publish_run`] sends the run's messages; `false`: that one was not sent.
pub(crate) trait RunSink {
    async fn send(&self, m: RunMessage) -> bool;
}

fn marking_msg(net: &Net, seq: u64, time: f64, tokens: &[u32]) -> Marking {
    Marking {
        header: Header::now(""),
        model_time: time,
        seq,
        places: net.places().iter().map(|p| p.name.clone()).collect(),
        tokens: tokens.to_vec(),
    }
}

/// The run's topics from its events, the one home of their content: the initial marking
/// (seq 0), then per firing a `Firing` (seq 1, 2, … without gaps) and the marking after it,
/// and every drift of the live monitor, until the run is over.
pub(crate) async fn publish_run(net: &Net, mut events: Events, sink: &impl RunSink) -> Published {
    let mut out = Published::default();
    let initial = net.initial_marking();
    let mut sent = |ok: bool| out.errors += u64::from(!ok);
    sent(
        sink.send(RunMessage::Marking(marking_msg(net, 0, 0.0, &initial)))
            .await,
    );
    let mut firings = 0;
    let mut lagged = 0;
    while let Some(r) = events.recv().await {
        let e = match r {
            Received::Event(e) => e,
            Received::Lagged(n) => {
                tracing::error!("firing publisher fell behind: {n} events lost");
                lagged += n;
                continue;
            }
        };
        if let EventKind::Drift(d) = &e.kind {
            sent(
                sink.send(RunMessage::Drift(drift_message(net, e.time, d)))
                    .await,
            );
            continue;
        }
        let EventKind::Fired {
            transition,
            marking,
            robots,
            ..
        } = e.kind
        else {
            continue;
        };
        firings += 1;
        let msg = Firing {
            header: Header::now(""),
            model_time: e.time,
            seq: firings,
            transition: net.transition(transition).name.clone(),
            marking: marking.to_vec(),
            robots: robots.iter().map(|r| r.to_string()).collect(),
        };
        sent(sink.send(RunMessage::Firing(msg)).await);
        sent(
            sink.send(RunMessage::Marking(marking_msg(
                net, firings, e.time, &marking,
            )))
            .await,
        );
    }
    Published {
        firings,
        lagged,
        ..out
    }
}

/// Publishes the run's [`RunState`] on `/gspn/run`.
pub struct RunStatePublisher {
    run: Publisher<RunState>,
}

impl RunStatePublisher {
    /// Creates the publisher on `node`.
    pub fn new(node: &mut Node) -> Result<RunStatePublisher, Ros2Error> {
        Ok(RunStatePublisher {
            run: publisher(node, RUN_TOPIC, run_state_type(), marking_qos())?,
        })
    }

    /// Publishes `state`.
    pub async fn publish(&self, state: RunState) -> Result<(), Ros2Error> {
        self.run.async_publish(state).await.map_err(Ros2Error::dds)
    }

    /// Waits (at most `limit`) until at least `n` subscribers are matched; false if fewer
    /// were by then.
    pub async fn matched(&self, node: &Node, n: usize, limit: std::time::Duration) -> bool {
        let start = tokio::time::Instant::now();
        loop {
            if self.run.get_subscription_count(node) >= n {
                return true;
            }
            if start.elapsed() >= limit {
                return false;
            }
            tokio::time::sleep(std::time::Duration::from_millis(20)).await;
        }
    }

    /// Waits (at most `limit`) until every matched subscriber has acknowledged the states
    /// published; false if some had not by then.
    pub async fn acknowledged(&self, limit: std::time::Duration) -> bool {
        let acked = self.run.async_wait_for_acknowledgments();
        matches!(tokio::time::timeout(limit, acked).await, Ok(Ok(true)))
    }
}

/// `Debug` naming the type only: its DDS handles have none.
macro_rules! debug_by_name {
    ($($t:ident),*) => {$(
        impl std::fmt::Debug for $t {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str(stringify!($t))
            }
        }
    )*};
}

debug_by_name!(RunStatePublisher, FiringListener);

/// A subscriber to `/gspn/firings`, `/gspn/marking` and `/gspn/run`.
pub struct FiringListener {
    firings: Subscription<Firing>,
    marking: Subscription<Marking>,
    run: Subscription<RunState>,
}

impl FiringListener {
    /// Subscribes on `node`.
    pub fn new(node: &mut Node) -> Result<FiringListener, Ros2Error> {
        Ok(FiringListener {
            run: subscription(node, RUN_TOPIC, run_state_type(), marking_qos())?,
            firings: subscription(node, FIRINGS_TOPIC, firing_type(), firings_qos())?,
            marking: subscription(node, MARKING_TOPIC, marking_type(), marking_qos())?,
        })
    }

    /// The firings as they arrive.
    pub fn firings(&self) -> impl futures::Stream<Item = Firing> + '_ {
        self.firings
            .async_stream()
            .filter_map(|r| async move { r.ok().map(|(f, _)| f) })
    }

    /// The run's states as they arrive (the current one first, for a late joiner).
    pub fn run_states(&self) -> impl futures::Stream<Item = RunState> + '_ {
        self.run
            .async_stream()
            .filter_map(|r| async move { r.ok().map(|(m, _)| m) })
    }

    /// The markings as they arrive (the current one first, for a late joiner).
    pub fn markings(&self) -> impl futures::Stream<Item = Marking> + '_ {
        self.marking
            .async_stream()
            .filter_map(|r| async move { r.ok().map(|(m, _)| m) })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::net::{NetBuilder, Servers};

    #[test]
    fn a_drift_is_published_naming_the_transition_or_place() {
        let mut b = NetBuilder::new("n");
        let p = b.place("Check", 1);
        let t = b.exponential("Done", 1.0, Servers::Single);
        b.input(p, t, 1);
        let net = b.build().unwrap();
        let d = Drift {
            of: Monitored::Transition(t),
            observed: 0.25,
            predicted: 1.0,
            interval: [0.2, 0.3],
            n: 60,
            p_value: 1e-9,
        };
        let m = drift_message(&net, 12.5, &d);
        assert_eq!(m.transition, "Done");
        assert_eq!(m.place, "");
        assert_eq!(m.model_time, 12.5);
        assert_eq!(m.observed, 0.25);
        assert_eq!((m.interval_low, m.interval_high), (0.2, 0.3));
        assert_eq!(m.n, 60);
        let d = Drift {
            of: Monitored::Place(p),
            ..d
        };
        let m = drift_message(&net, 1.0, &d);
        assert_eq!((m.transition.as_str(), m.place.as_str()), ("", "Check"));
        assert!(m.text.starts_with("Check: 0.2500 mean tokens"));
    }
}
