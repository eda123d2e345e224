//! Whether a robot is there, as the supervisor sees it: any ROS 2 node with an ExecPlace
//! action server is a robot. Its presence comes from DDS discovery — the supervisor's goal
//! clients stay matched with the robot's servers while the robot's participant lives (a
//! killed process is dropped when its participant's lease ends) — and, for robots that
//! publish one (`plan-runner robot`), from the gspn heartbeat too, which notices a killed
//! robot within `lost_after` instead of a lease.
//!
//! ```text
//! Unknown ──(server matched or heartbeat heard)──▶ Alive
//! Alive ──(heartbeats stop for lost_after)──▶ Lost ──(heartbeats again)──▶ Alive
//! Alive ──(no ExecPlace server matched: the participant left)──▶ Gone ──(matched again)──▶ Alive
//! ```

use std::collections::HashMap;
use std::sync::Arc;
use std::time::Duration;

use tokio::sync::watch;

use super::heartbeat::Liveness;

/// Counts the robot's ExecPlace servers matched now (one per server it should have).
pub type ServerCounter = Box<dyn Fn() -> usize + Send + Sync>;

/// The presence of each robot: a [`Liveness`] per robot from its heartbeat (if it sends
/// one) and its servers' discovery.
#[derive(Clone, Debug)]
pub struct Presence {
    states: Arc<HashMap<String, watch::Receiver<Liveness>>>,
}

impl Presence {
    /// Watches each robot of `robots`: `(id, its heartbeat's liveness, counters of its
    /// servers)`, checking discovery every `check`. Tasks end when every receiver is gone.
    pub fn start(
        robots: Vec<(String, watch::Receiver<Liveness>, Vec<ServerCounter>)>,
        check: Duration,
    ) -> Presence {
        let mut states = HashMap::new();
        for (robot, heartbeat, servers) in robots {
            let (tx, rx) = watch::channel(combine(*heartbeat.borrow(), &servers));
            tokio::spawn(follow(robot.clone(), heartbeat, servers, tx, check));
            states.insert(robot, rx);
        }
        Presence {
            states: Arc::new(states),
        }
    }

    /// The presence of `robot` (a receiver that follows its changes), when it is watched.
    pub fn liveness(&self, robot: &str) -> Option<watch::Receiver<Liveness>> {
        self.states.get(robot).cloned()
    }
}

/// One robot's presence: the heartbeat's verdict when it has one (it is the faster), else
/// discovery's; a robot whose servers are no longer all matched is [`Liveness::Gone`].
fn combine(heartbeat: Liveness, servers: &[ServerCounter]) -> Liveness {
    let matched = servers.iter().all(|count| count() > 0);
    match heartbeat {
        Liveness::Lost => Liveness::Lost,
        _ if !matched => Liveness::Gone,
        _ => Liveness::Alive,
    }
}

async fn follow(
    robot: String,
    mut heartbeat: watch::Receiver<Liveness>,
    servers: Vec<ServerCounter>,
    tx: watch::Sender<Liveness>,
    check: Duration,
) {
    let mut tick = tokio::time::interval(check);
    tick.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Skip);
    let mut beats = true;
    loop {
        tokio::select! {
            c = heartbeat.changed(), if beats => beats = c.is_ok(),
            _ = tick.tick() => {}
            _ = tx.closed() => return,
        }
        let now = combine(*heartbeat.borrow(), &servers);
        let was = *tx.borrow();
        if now != was {
            if now == Liveness::Gone {
                tracing::warn!(
                    "robot `{robot}`: its ExecPlace server left DDS discovery (participant gone or its lease ended): lost"
                );
            }
            let _ = tx.send(now);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::{AtomicUsize, Ordering};

    #[tokio::test(start_paused = true)]
    async fn a_robot_without_heartbeat_is_gone_when_its_server_leaves_discovery() {
        let matched = Arc::new(AtomicUsize::new(1));
        let m = Arc::clone(&matched);
        let (_hb_tx, hb) = watch::channel(Liveness::Unknown);
        let p = Presence::start(
            vec![(
                "r1".into(),
                hb,
                vec![Box::new(move || m.load(Ordering::SeqCst))],
            )],
            Duration::from_millis(250),
        );
        let mut live = p.liveness("r1").unwrap();
        assert_eq!(*live.borrow(), Liveness::Alive);
        matched.store(0, Ordering::SeqCst);
        tokio::time::timeout(
            Duration::from_secs(1),
            live.wait_for(|s| *s == Liveness::Gone),
        )
        .await
        .expect("gone within one check")
        .unwrap();
        matched.store(1, Ordering::SeqCst);
        tokio::time::timeout(
            Duration::from_secs(1),
            live.wait_for(|s| *s == Liveness::Alive),
        )
        .await
        .expect("back within one check")
        .unwrap();
        assert!(p.liveness("r2").is_none());
    }

    #[tokio::test(start_paused = true)]
    async fn a_stopped_heartbeat_wins_over_a_still_matched_server() {
        let (hb_tx, hb) = watch::channel(Liveness::Alive);
        let p = Presence::start(
            vec![("r1".into(), hb, vec![Box::new(|| 1)])],
            Duration::from_secs(10),
        );
        let mut live = p.liveness("r1").unwrap();
        hb_tx.send(Liveness::Lost).unwrap();
        tokio::time::timeout(
            Duration::from_millis(10),
            live.wait_for(|s| *s == Liveness::Lost),
        )
        .await
        .expect("at once, not at the next check")
        .unwrap();
    }
}
