//! Presence from liveliness tokens: every robot's node declares one (and the supervisor's);
//! Zenoh withdraws it when the session closes, dies or is cut off from the router. A watched
//! node is [`Liveness::Alive`] while its token is there and [`Liveness::Lost`] once it has
//! been gone for `lost_after` (a short cut does not fail its goals); it is alive again
//! when the token comes back. The same [`Liveness`] as the DDS heartbeats, so the
//! supervisor's `ros2` action treats a lost robot the same way.

use std::collections::HashMap;
use std::sync::Arc;
use std::time::Duration;

use tokio::sync::watch;
use tokio::time::Instant;
use zenoh::Session;
use zenoh::sample::SampleKind;

use super::ZenohError;
use super::keys;
pub use crate::ros2::heartbeat::Liveness;

/// The liveness of some nodes, by namespace and name.
#[derive(Clone, Debug)]
pub struct Presence {
    states: Arc<HashMap<String, Watched>>,
}

/// What is known of one watched node.
#[derive(Clone, Debug)]
struct Watched {
    /// Alive, or lost after its token has been gone for `lost_after`.
    liveness: watch::Receiver<Liveness>,
    /// Whether its token is there now (a cut shorter than `lost_after` shows here only).
    present: watch::Receiver<bool>,
}

impl Presence {
    /// Watches the robots `ids` (nodes [`keys::ROBOT_NODE`] in `/<id>`).
    pub async fn robots(
        session: &Session,
        domain: u16,
        ids: &[String],
        lost_after: Duration,
    ) -> Result<Presence, ZenohError> {
        let nodes: Vec<(String, String)> = ids
            .iter()
            .map(|id| (keys::robot_namespace(id), keys::ROBOT_NODE.to_string()))
            .collect();
        Presence::start(session, domain, ids, &nodes, lost_after).await
    }

    /// Watches the supervisor, under the name `supervisor`.
    pub async fn supervisor(
        session: &Session,
        domain: u16,
        lost_after: Duration,
    ) -> Result<Presence, ZenohError> {
        let nodes = [(
            keys::SUPERVISOR_NS.to_string(),
            keys::SUPERVISOR_NODE.to_string(),
        )];
        let names = [keys::SUPERVISOR_NODE.to_string()];
        Presence::start(session, domain, &names, &nodes, lost_after).await
    }

    /// Watches node `nodes[i]` under the name `names[i]`.
    async fn start(
        session: &Session,
        domain: u16,
        names: &[String],
        nodes: &[(String, String)],
        lost_after: Duration,
    ) -> Result<Presence, ZenohError> {
        let sub = session
            .liveliness()
            .declare_subscriber(keys::node_tokens(domain))
            .history(true)
            .await
            .map_err(ZenohError::zenoh)?;
        let mut by_node = HashMap::new();
        let mut states = HashMap::new();
        for (name, node) in names.iter().zip(nodes) {
            let (tx, liveness) = watch::channel(Liveness::Unknown);
            let (present_tx, present) = watch::channel(false);
            // (name, liveness, presence, tokens present, since when none is)
            by_node.insert(
                node.clone(),
                (name.clone(), tx, present_tx, 0usize, None::<Instant>),
            );
            states.insert(name.clone(), Watched { liveness, present });
        }
        let check = (lost_after / 4).max(Duration::from_millis(10));
        tokio::spawn(async move {
            let mut tick = tokio::time::interval(check);
            loop {
                tokio::select! {
                    s = sub.recv_async() => {
                        let Ok(s) = s else { break };
                        let Some(node) = keys::parse_node_token(s.key_expr().as_str()) else {
                            continue;
                        };
                        let Some((_, tx, present, n, gone)) = by_node.get_mut(&node) else {
                            continue;
                        };
                        match s.kind() {
                            SampleKind::Put => {
                                *n += 1;
                                *gone = None;
                                present.send_replace(true);
                                tx.send_if_modified(|l| {
                                    let changed = *l != Liveness::Alive;
                                    *l = Liveness::Alive;
                                    changed
                                });
                            }
                            SampleKind::Delete => {
                                *n = n.saturating_sub(1);
                                if *n == 0 {
                                    *gone = Some(Instant::now());
                                    present.send_replace(false);
                                }
                            }
                        }
                    }
                    _ = tick.tick() => {
                        let now = Instant::now();
                        for (name, tx, _, _, gone) in by_node.values() {
                            if let Some(t) = gone
                                && now.duration_since(*t) >= lost_after
                                && *tx.borrow() == Liveness::Alive
                            {
                                tracing::warn!("`{name}`: liveliness token gone for {lost_after:?}: lost");
                                let _ = tx.send(Liveness::Lost);
                            }
                        }
                        if by_node.values().all(|(_, tx, p, _, _)| tx.is_closed() && p.is_closed()) {
                            break;
                        }
                    }
                }
            }
        });
        Ok(Presence {
            states: Arc::new(states),
        })
    }

    /// The liveness of `name`, when it is watched.
    pub fn liveness(&self, name: &str) -> Option<watch::Receiver<Liveness>> {
        self.states.get(name).map(|w| w.liveness.clone())
    }

    /// Whether `name`'s token is there now, when it is watched.
    pub fn present(&self, name: &str) -> Option<watch::Receiver<bool>> {
        self.states.get(name).map(|w| w.present.clone())
    }

    /// How many watched nodes are alive now.
    pub fn alive(&self) -> usize {
        self.states
            .values()
            .filter(|w| *w.liveness.borrow() == Liveness::Alive)
            .count()
    }

    /// Waits until every watched node is alive; those still missing at `deadline` are the
    /// error.
    pub async fn all_alive(&self, deadline: Duration) -> Result<(), Vec<String>> {
        let states = self.states.iter().map(|(r, w)| (r, &w.liveness));
        crate::ros2::heartbeat::all_alive(states, deadline).await
    }
}
