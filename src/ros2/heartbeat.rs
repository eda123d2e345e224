//! Heartbeats: every robot process publishes one on `/gspn/heartbeat` a few times a second;
//! the supervisor's [`RobotWatch`] marks a robot lost when its heartbeats stop for
//! `lost_after` (a killed process sends nothing, so DDS alone would notice only when the
//! participant's lease ends, tens of seconds later). The supervisor publishes its own on
//! `/gspn/supervisor_heartbeat`, which each robot watches the same way
//! ([`RobotWatch::supervisor`]): a robot that missed the end of the run still leaves when its
//! supervisor falls silent.

use std::collections::HashMap;
use std::sync::Arc;
use std::time::Duration;

use futures::StreamExt;
use ros2_client::qos::{Durability, History};
use ros2_client::{Node, Publisher, QosProfile, Subscription};
use tokio::sync::watch;
use tokio::time::Instant;

use super::Ros2Error;
use super::msgs::{HEARTBEAT_TOPIC, Heartbeat, SUPERVISOR_HEARTBEAT_TOPIC, heartbeat_type};

/// The sender name of the supervisor's heartbeats.
pub const SUPERVISOR: &str = "supervisor";

/// What the supervisor knows of a robot.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Liveness {
    /// No heartbeat seen yet.
    Unknown,
    /// Heartbeats arrive.
    Alive,
    /// Heartbeats stopped: no heartbeat for `lost_after`.
    Lost,
    /// Its ExecPlace server left DDS discovery ([`super::presence`]).
    Gone,
}

impl Liveness {
    /// Lost or gone: its goals fail.
    pub fn is_lost(self) -> bool {
        matches!(self, Liveness::Lost | Liveness::Gone)
    }
}

fn qos() -> QosProfile {
    QosProfile::subscription_default()
        .durability(Durability::Volatile)
        .history(History::KeepLast { depth: 64 })
}

fn topic(node: &Node, name: &str) -> Result<ros2_client::dds::rustdds::Topic, Ros2Error> {
    let name = super::names::topic(node, name)?;
    node.create_topic(&name, heartbeat_type(), &qos())
        .map_err(Ros2Error::dds)
}

/// Publishes `robot`'s heartbeat every `period` until the task is aborted.
pub fn publish(
    node: &mut Node,
    robot: &str,
    period: Duration,
) -> Result<tokio::task::JoinHandle<()>, Ros2Error> {
    publish_on(node, HEARTBEAT_TOPIC, robot, period)
}

/// Publishes the supervisor's heartbeat every `period` until the task is aborted.
pub fn publish_supervisor(
    node: &mut Node,
    period: Duration,
) -> Result<tokio::task::JoinHandle<()>, Ros2Error> {
    publish_on(node, SUPERVISOR_HEARTBEAT_TOPIC, SUPERVISOR, period)
}

fn publish_on(
    node: &mut Node,
    topic_name: &str,
    robot: &str,
    period: Duration,
) -> Result<tokio::task::JoinHandle<()>, Ros2Error> {
    let t = topic(node, topic_name)?;
    let publisher: Publisher<Heartbeat> =
        node.create_publisher(&t, None).map_err(Ros2Error::dds)?;
    let robot = robot.to_string();
    Ok(tokio::spawn(async move {
        let mut tick = tokio::time::interval(period);
        tick.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Skip);
        for seq in 0.. {
            tick.tick().await;
            let _ = publisher.publish(Heartbeat {
                robot: robot.clone(),
                seq,
            });
        }
    }))
}

/// The supervisor's view of its robots' heartbeats (one [`Liveness`] per robot), or a
/// robot's view of its supervisor's.
#[derive(Clone, Debug)]
pub struct RobotWatch {
    states: Arc<HashMap<String, watch::Receiver<Liveness>>>,
}

impl RobotWatch {
    /// Subscribes to the heartbeats of `robots`; a robot silent for `lost_after` becomes
    /// [`Liveness::Lost`] (and `Alive` again if its heartbeats come back).
    pub fn start(
        node: &mut Node,
        robots: &[String],
        lost_after: Duration,
    ) -> Result<RobotWatch, Ros2Error> {
        RobotWatch::start_on(node, HEARTBEAT_TOPIC, "robot", robots, lost_after)
    }

    /// Subscribes to the supervisor's heartbeats: [`RobotWatch::liveness`] of
    /// [`SUPERVISOR`] follows it.
    pub fn supervisor(node: &mut Node, lost_after: Duration) -> Result<RobotWatch, Ros2Error> {
        let who = [SUPERVISOR.to_string()];
        RobotWatch::start_on(node, SUPERVISOR_HEARTBEAT_TOPIC, "", &who, lost_after)
    }

    /// Watches the senders `names` on `topic_name`; `kind` names them in the warning
    /// (`robot `r2`: no heartbeat …`; empty: `supervisor: no heartbeat …`).
    fn start_on(
        node: &mut Node,
        topic_name: &str,
        kind: &'static str,
        names: &[String],
        lost_after: Duration,
    ) -> Result<RobotWatch, Ros2Error> {
        let robots = names;
        let t = topic(node, topic_name)?;
        let sub: Subscription<Heartbeat> =
            node.create_subscription(&t, None).map_err(Ros2Error::dds)?;
        let mut senders = HashMap::new();
        let mut states = HashMap::new();
        for r in robots {
            let (tx, rx) = watch::channel(Liveness::Unknown);
            senders.insert(r.clone(), (tx, None::<Instant>));
            states.insert(r.clone(), rx);
        }
        let check = (lost_after / 4).max(Duration::from_millis(10));
        tokio::spawn(async move {
            let stream = sub.async_stream();
            futures::pin_mut!(stream);
            let mut tick = tokio::time::interval(check);
            loop {
                tokio::select! {
                    m = stream.next() => match m {
                        Some(Ok((hb, _))) => {
                            if let Some((tx, seen)) = senders.get_mut(&hb.robot) {
                                *seen = Some(Instant::now());
                                tx.send_if_modified(|s| {
                                    let changed = *s != Liveness::Alive;
                                    *s = Liveness::Alive;
                                    changed
                                });
                            }
                        }
                        Some(Err(e)) => tracing::warn!("heartbeat: {e:?}"),
                        None => break,
                    },
                    _ = tick.tick() => {
                        let now = Instant::now();
                        for (robot, (tx, seen)) in &senders {
                            if let Some(t) = seen
                                && now.duration_since(*t) > lost_after
                                && *tx.borrow() == Liveness::Alive
                            {
                                if kind.is_empty() {
                                    tracing::warn!("{robot}: no heartbeat for {lost_after:?}: lost");
                                } else {
                                    tracing::warn!("{kind} `{robot}`: no heartbeat for {lost_after:?}: lost");
                                }
                                let _ = tx.send(Liveness::Lost);
                            }
                        }
                        if senders.values().all(|(tx, _)| tx.is_closed()) {
                            break;
                        }
                    }
                }
            }
        });
        Ok(RobotWatch {
            states: Arc::new(states),
        })
    }

    /// The liveness of `robot` (a receiver that follows its changes), when it is watched.
    pub fn liveness(&self, robot: &str) -> Option<watch::Receiver<Liveness>> {
        self.states.get(robot).cloned()
    }

    /// How many watched robots are [`Liveness::Alive`] now.
    pub fn alive_count(&self) -> usize {
        self.states
            .values()
            .filter(|rx| *rx.borrow() == Liveness::Alive)
            .count()
    }

    /// Waits until every watched robot is [`Liveness::Alive`]; the robots still missing at
    /// `deadline` are returned as the error.
    pub async fn all_alive(&self, deadline: Duration) -> Result<(), Vec<String>> {
        all_alive(self.states.iter(), deadline).await
    }
}

/// Waits until every one of `states` (name, liveness) is [`Liveness::Alive`]; the names
/// still missing at `deadline`, sorted, are the error. Heartbeats (DDS) and liveliness
/// tokens (Zenoh) alike.
pub(crate) async fn all_alive<'a>(
    states: impl Iterator<Item = (&'a String, &'a watch::Receiver<Liveness>)> + Clone,
    deadline: Duration,
) -> Result<(), Vec<String>> {
    let wait = async {
        for (_, rx) in states.clone() {
            let mut rx = rx.clone();
            let _ = rx.wait_for(|s| *s == Liveness::Alive).await;
        }
    };
    if tokio::time::timeout(deadline, wait).await.is_ok() {
        return Ok(());
    }
    let mut missing: Vec<String> = states
        .filter(|(_, rx)| *rx.borrow() != Liveness::Alive)
        .map(|(r, _)| r.clone())
        .collect();
    missing.sort();
    Err(missing)
}
