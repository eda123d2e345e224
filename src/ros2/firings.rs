//! The supervisor's publications: every firing on `/gspn/firings` (reliable, keep-all), the
//! current marking on `/gspn/marking` (reliable, transient-local, depth 1) and the run's
//! state on `/gspn/run` ([`RunStatePublisher`], same QoS as the marking); and
//! [`FiringListener`], a subscriber to them for robots, tests and tools.

use std::sync::Arc;

use futures::StreamExt;
use ros2_client::qos::{Durability, History, Reliability, WhenFull};
use ros2_client::{Name, Node, Publisher, QosProfile, Subscription};

use super::Ros2Error;
use super::msgs::{
    FIRINGS_TOPIC, Firing, MARKING_TOPIC, Marking, RUN_TOPIC, RunState, Time, firing_type,
    marking_type, run_state_type,
};
use crate::net::Net;
use crate::runtime::{EventKind, Events, Received};

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

fn topic(
    node: &Node,
    name: &str,
    ty: ros2_client::MessageTypeName,
    qos: &QosProfile,
) -> Result<ros2_client::dds::rustdds::Topic, Ros2Error> {
    let name = Name::parse(name).map_err(Ros2Error::dds)?;
    node.create_topic(&name, ty, qos).map_err(Ros2Error::dds)
}

/// Publishes a run's firings and markings.
pub struct FiringPublisher {
    firings: Publisher<Firing>,
    marking: Publisher<Marking>,
    net: Arc<Net>,
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
        let fq = firings_qos();
        let mq = marking_qos();
        let ft = topic(node, FIRINGS_TOPIC, firing_type(), &fq)?;
        let mt = topic(node, MARKING_TOPIC, marking_type(), &mq)?;
        Ok(FiringPublisher {
            firings: node
                .create_publisher(&ft, Some(fq))
                .map_err(Ros2Error::dds)?,
            marking: node
                .create_publisher(&mt, Some(mq))
                .map_err(Ros2Error::dds)?,
            net,
        })
    }

    /// Matched subscribers of `/gspn/firings` (needs the node's spinner).
    pub fn firing_subscribers(&self, node: &Node) -> usize {
        self.firings.get_subscription_count(node)
    }

    fn marking_msg(&self, seq: u64, tokens: &[u32]) -> Marking {
        Marking {
            seq,
            places: self.net.places().iter().map(|p| p.name.clone()).collect(),
            tokens: tokens.to_vec(),
        }
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
    pub async fn run(&self, mut events: Events) -> Published {
        let mut out = Published::default();
        let initial = self.net.initial_marking();
        if self
            .marking
            .async_publish(self.marking_msg(0, &initial))
            .await
            .is_err()
        {
            out.errors += 1;
        }
        while let Some(r) = events.recv().await {
            let e = match r {
                Received::Event(e) => e,
                Received::Lagged(n) => {
                    tracing::error!("firing publisher fell behind: {n} events lost");
                    out.lagged += n;
                    continue;
                }
            };
            let EventKind::Fired {
                transition,
                marking,
                robots,
                ..
            } = e.kind
            else {
                continue;
            };
            out.firings += 1;
            let msg = Firing {
                seq: out.firings,
                transition: self.net.transition(transition).name.clone(),
                marking: marking.to_vec(),
                robots: robots.iter().map(|r| r.to_string()).collect(),
                stamp: Time::now(),
            };
            if self.firings.async_publish(msg).await.is_err() {
                out.errors += 1;
            }
            if self
                .marking
                .async_publish(self.marking_msg(out.firings, &marking))
                .await
                .is_err()
            {
                out.errors += 1;
            }
        }
        out
    }
}

/// Publishes the run's [`RunState`] on `/gspn/run`.
pub struct RunStatePublisher {
    run: Publisher<RunState>,
}

impl std::fmt::Debug for RunStatePublisher {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("RunStatePublisher")
    }
}

impl RunStatePublisher {
    /// Creates the publisher on `node`.
    pub fn new(node: &mut Node) -> Result<RunStatePublisher, Ros2Error> {
        let q = marking_qos();
        let t = topic(node, RUN_TOPIC, run_state_type(), &q)?;
        Ok(RunStatePublisher {
            run: node.create_publisher(&t, Some(q)).map_err(Ros2Error::dds)?,
        })
    }

    /// Publishes `state`.
    pub async fn publish(&self, state: RunState) -> Result<(), Ros2Error> {
        self.run.async_publish(state).await.map_err(Ros2Error::dds)
    }

    /// Waits (at most `limit`) until every matched subscriber has acknowledged the states
    /// published; false if some had not by then.
    pub async fn acknowledged(&self, limit: std::time::Duration) -> bool {
        let acked = self.run.async_wait_for_acknowledgments();
        matches!(tokio::time::timeout(limit, acked).await, Ok(Ok(true)))
    }
}

/// A subscriber to `/gspn/firings`, `/gspn/marking` and `/gspn/run`.
pub struct FiringListener {
    firings: Subscription<Firing>,
    marking: Subscription<Marking>,
    run: Subscription<RunState>,
}

impl std::fmt::Debug for FiringListener {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("FiringListener")
    }
}

impl FiringListener {
    /// Subscribes on `node`.
    pub fn new(node: &mut Node) -> Result<FiringListener, Ros2Error> {
        let fq = firings_qos();
        let mq = marking_qos();
        let ft = topic(node, FIRINGS_TOPIC, firing_type(), &fq)?;
        let mt = topic(node, MARKING_TOPIC, marking_type(), &mq)?;
        let rt = topic(node, RUN_TOPIC, run_state_type(), &mq)?;
        Ok(FiringListener {
            run: node
                .create_subscription(&rt, Some(mq.clone()))
                .map_err(Ros2Error::dds)?,
            firings: node
                .create_subscription(&ft, Some(fq))
                .map_err(Ros2Error::dds)?,
            marking: node
                .create_subscription(&mt, Some(mq))
                .map_err(Ros2Error::dds)?,
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
