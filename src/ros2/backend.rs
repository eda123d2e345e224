//! [`Ros2Backend`]: the supervisor's ROS 2 side of `plan-runner run`.
//!
//! ```text
//! connect   node `/gspn/supervisor`, its own heartbeat (robots leave when it stops), the
//!           robots' heartbeat watch (optional for robots), /gspn/firings + /gspn/marking
//!           publishers, one ExecPlace client per (robot, server); waits (≤ startup) for
//!           every robot's servers and for the wanted firing subscribers, then follows
//!           each robot's presence (discovery and heartbeat: `presence`)
//! attach    registers the `ros2` action (RemotePlaces) on the runtime builder
//!           then says the run is `running` on /gspn/run
//! publish   a task that publishes every firing and the marking from the run's events
//! finish    waits for the publisher and the subscribers' acknowledgements (≤ linger), says
//!           the run is `over` (robots leave), waits for that to be acknowledged (≤ linger)
//! ```

use std::collections::HashMap;
use std::sync::Arc;
use std::time::Duration;

use ros2_client::action::ActionClientQosPolicies;
use ros2_client::qos::{Durability, History};
use ros2_client::{Node, QosProfile};
use tokio::task::JoinHandle;

use super::Ros2Error;
use super::config::DdsConfig;
use super::firings::{FiringPublisher, Published, RunStatePublisher};
use super::heartbeat::{self, Liveness, RobotWatch};
use super::msgs::{ExecPlaceFeedback, ExecPlaceGoal, ExecPlaceResult, RunState, exec_place_type};
use super::nav2::Nav2Client;
use super::presence::{Presence, ServerCounter};
use super::remote_place::{ExecPlaceClient, Nav2Link, RemotePlaces, RobotLink};
use super::settings::{NAV2_SERVER, ROS2_ACTION, Ros2Settings};
use crate::net::Net;
use crate::runtime::{Events, RuntimeBuilder};

/// The supervisor's ROS 2 side: links to the robots and the firing publisher.
pub struct Ros2Backend {
    node: Node,
    spin: JoinHandle<()>,
    /// The supervisor's heartbeat.
    beat: AbortOnDrop,
    publisher: Arc<FiringPublisher>,
    task: Option<JoinHandle<Published>>,
    places: RemotePlaces,
    /// The robots' heartbeats (for [`Ros2Backend::presence`], and to know at the end which
    /// robots listen for the end of the run).
    watch: RobotWatch,
    presence: Presence,
    run_state: RunStatePublisher,
    /// The `/rosout` forwarder, when asked.
    rosout: Option<super::rosout::Forwarder>,
}

impl std::fmt::Debug for Ros2Backend {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Ros2Backend")
            .field("places", &self.places)
            .finish()
    }
}

fn client_qos() -> ActionClientQosPolicies {
    let service = QosProfile::publisher_default()
        .durability(Durability::Volatile)
        .history(History::KeepAll);
    ActionClientQosPolicies {
        goal_service: service.clone(),
        result_service: service.clone(),
        cancel_service: service,
        feedback_subscription: QosProfile::publisher_default()
            .durability(Durability::Volatile)
            .history(History::KeepLast { depth: 1 }),
        status_subscription: QosProfile::publisher_default()
            .durability(Durability::TransientLocal)
            .history(History::KeepLast { depth: 1 }),
    }
}

impl Ros2Backend {
    /// Joins DDS and links to every robot of `robots` for the `ros2` places of `settings`
    /// (places of `net`); waits (at most `cfg.startup`) until each robot's servers are
    /// matched (any ROS 2 node serving ExecPlace is a robot; heartbeats are optional) and
    /// `/gspn/firings` has at least `subscribers` matched subscriptions.
    pub async fn connect(
        net: &Net,
        settings: &Ros2Settings,
        robots: &[String],
        cfg: &DdsConfig,
        subscribers: usize,
    ) -> Result<Ros2Backend, Ros2Error> {
        let mut node = cfg.node("supervisor", None)?;
        // From here on the ROS 2 layer's warnings reach /rosout too, when asked.
        let rosout = cfg
            .rosout
            .then(|| super::rosout::forward(&mut node))
            .transpose()?;
        let spinner = node.spinner().map_err(Ros2Error::dds)?;
        let spin = tokio::spawn(async move {
            if let Err(e) = spinner.spin().await {
                tracing::warn!("ROS 2 spinner: {e:?}");
            }
        });
        // Aborted when connecting fails too: robots then see the supervisor leave.
        let beat = AbortOnDrop(heartbeat::publish_supervisor(&mut node, cfg.heartbeat)?);
        let watch = RobotWatch::start(&mut node, robots, cfg.lost_after)?;
        let publisher = FiringPublisher::new(&mut node, Arc::new(net.clone()))?;
        let run_state = RunStatePublisher::new(&mut node)?;
        let clients = Clients::create(&mut node, settings, robots, cfg)?;
        clients.wait_for_servers(&node, cfg).await?;
        let presence = clients.presence(&node, robots, &watch, cfg);
        let (links, nav2) = clients.links(&presence)?;
        let startup = cfg.startup;
        let subs = async {
            while publisher.firing_subscribers(&node) < subscribers {
                tokio::time::sleep(Duration::from_millis(20)).await;
            }
        };
        tokio::time::timeout(startup, subs).await.map_err(|_| {
            Ros2Error::Startup(format!(
                "{} of {subscribers} subscriber(s) of /gspn/firings matched within {startup:?}",
                publisher.firing_subscribers(&node)
            ))
        })?;
        let servers: HashMap<_, _> = settings.servers.iter().cloned().collect();
        run_state
            .publish(RunState {
                state: RunState::RUNNING,
                stopped: String::new(),
                firings: 0,
            })
            .await?;
        Ok(Ros2Backend {
            run_state,
            node,
            spin,
            beat,
            publisher: Arc::new(publisher),
            task: None,
            places: RemotePlaces::new(
                servers,
                settings.args.iter().cloned().collect(),
                links,
                nav2,
            ),
            watch,
            presence,
            rosout,
        })
    }

    /// Registers the `ros2` action on `b`.
    pub fn attach(&self, b: RuntimeBuilder) -> RuntimeBuilder {
        b.action(ROS2_ACTION, self.places.clone())
    }

    /// Starts publishing the run's firings and marking from `events` (take them before the
    /// first firing: `handle.events()` right after `spawn`).
    pub fn publish(&mut self, events: Events) {
        if self.task.is_none() {
            let p = Arc::clone(&self.publisher);
            self.task = Some(tokio::spawn(async move { p.run(events).await }));
        }
    }

    /// The robots' presence (discovery of their servers, and their heartbeats).
    pub fn presence(&self) -> &Presence {
        &self.presence
    }

    /// The node, for extra entities.
    pub fn node(&mut self) -> &mut Node {
        &mut self.node
    }

    /// Waits for the publisher to have sent every firing (the run must be over) and for
    /// every subscriber to acknowledge them, says the run is over (`stopped`: why) so robots
    /// leave, and waits for that to be acknowledged too. Each wait takes at most `linger` (a
    /// lost sample is repaired in that time; a subscriber that never answers, such as a
    /// killed robot whose reader DDS still counts, costs the whole of it). The second wait
    /// has its own `linger`, not what the first left: the end of the run is written to the
    /// DDS event loop, which sends it after `publish` returns, so with no time left the
    /// process could exit before the live robots were ever sent it. The `/rosout` records
    /// (`--ros2-rosout`) get a last `linger` too.
    pub async fn finish(mut self, linger: Duration, stopped: &str) -> Published {
        let mut published = match self.task.take() {
            Some(t) => t.await.unwrap_or_default(),
            None => Published::default(),
        };
        if !self.publisher.acknowledged(linger).await {
            tracing::warn!(
                "not every subscriber acknowledged every firing within {linger:?} (--ros2-linger)"
            );
        }
        // Robots that send heartbeats are gspn robots, which listen for the end of the run.
        // A run of a few firings can end before discovery has matched their readers with
        // the run-state writer (the supervisor starts once the robots' servers are
        // discovered, not their readers): wait for them, so the transient-local end of the
        // run reaches every one before this process exits.
        let listeners = self.watch.alive_count();
        if !self.run_state.matched(&self.node, listeners, linger).await {
            tracing::warn!(
                "not every robot's reader of the run state was matched within {linger:?} (--ros2-linger)"
            );
        }
        let over = RunState {
            state: RunState::OVER,
            stopped: stopped.to_string(),
            firings: published.firings,
        };
        if let Err(e) = self.run_state.publish(over).await {
            tracing::warn!("publishing the end of the run: {e}");
            published.errors += 1;
        }
        if !self.run_state.acknowledged(linger).await {
            tracing::warn!(
                "not every subscriber acknowledged the end of the run within {linger:?} (--ros2-linger)"
            );
        }
        if let Some(r) = self.rosout.take() {
            r.finish(linger).await;
        }
        self.beat.0.abort();
        self.spin.abort();
        published
    }
}

/// A task aborted when its handle is dropped.
struct AbortOnDrop(JoinHandle<()>);

impl Drop for AbortOnDrop {
    fn drop(&mut self) {
        self.0.abort();
    }
}

/// The supervisor's action clients: one ExecPlace client per (robot, server), and one Nav2
/// client per robot when a place is served by Nav2 (`navigate_to_pose`).
struct Clients {
    exec: Vec<(String, String, ExecPlaceClient)>,
    nav2: Vec<(String, Arc<Nav2Client>)>,
}

impl Clients {
    fn create(
        node: &mut Node,
        settings: &Ros2Settings,
        robots: &[String],
        cfg: &DdsConfig,
    ) -> Result<Clients, Ros2Error> {
        // Nav2 places go to the robots' own Nav2 (`navigate_to_pose`), the rest to ExecPlace.
        let servers = settings.exec_place_servers();
        let mut nav2 = Vec::new();
        if settings.servers.iter().any(|(_, s)| s == NAV2_SERVER) {
            for robot in robots {
                let client = super::nav2::client(node, cfg, robot)?;
                nav2.push((robot.clone(), Arc::new(client)));
            }
        }
        let mut exec = Vec::new();
        for robot in robots {
            for &server in &servers {
                let name = super::names::action(node, robot, server)?;
                let client = node
                    .create_action_client::<ExecPlaceGoal, ExecPlaceResult, ExecPlaceFeedback>(
                        cfg.service_mapping,
                        &name,
                        &exec_place_type(),
                        client_qos(),
                    )
                    .map_err(Ros2Error::dds)?;
                exec.push((robot.clone(), server.to_string(), client));
            }
        }
        Ok(Clients { exec, nav2 })
    }

    /// Waits (at most `cfg.startup` in all) until every client's server is matched: a
    /// robot is there when its servers are (heartbeats are optional).
    async fn wait_for_servers(&self, node: &Node, cfg: &DdsConfig) -> Result<(), Ros2Error> {
        let startup = cfg.startup;
        let deadline = tokio::time::Instant::now() + startup;
        let mut missing = Vec::new();
        for (robot, server, c) in &self.exec {
            let found = RobotLink::wait_for_server(c, node);
            if tokio::time::timeout_at(deadline, found).await.is_err() {
                missing.push(format!("/{robot}/{server}"));
            }
        }
        for (robot, c) in &self.nav2 {
            let found = super::nav2::wait_for_server(c, node);
            if tokio::time::timeout_at(deadline, found).await.is_err() {
                missing.push(format!("/{robot}/{NAV2_SERVER} (Nav2)"));
            }
        }
        if missing.is_empty() {
            return Ok(());
        }
        Err(Ros2Error::Startup(format!(
            "no ExecPlace server at {} within {startup:?} (domain {}): are the robots running (`plan-runner robot`, or any ROS 2 node serving gspn_msgs/action/ExecPlace)?",
            missing.join(", "),
            cfg.domain_id
        )))
    }

    /// Follows each robot's presence: its heartbeat (when it sends one) and the discovery
    /// of its servers.
    fn presence(
        &self,
        node: &Node,
        robots: &[String],
        watch: &RobotWatch,
        cfg: &DdsConfig,
    ) -> Presence {
        Presence::start(
            robots
                .iter()
                .map(|r| {
                    let heartbeat = watch
                        .liveness(r)
                        .unwrap_or_else(|| tokio::sync::watch::channel(Liveness::Unknown).1);
                    let mut counters: Vec<ServerCounter> = self
                        .exec
                        .iter()
                        .filter(|(robot, _, _)| robot == r)
                        .map(|(_, _, c)| {
                            Box::new(c.goal_client().server_counter(node)) as ServerCounter
                        })
                        .collect();
                    counters.extend(self.nav2.iter().filter(|(robot, _)| robot == r).map(
                        |(_, c)| Box::new(c.goal_client().server_counter(node)) as ServerCounter,
                    ));
                    (r.clone(), heartbeat, counters)
                })
                .collect(),
            (cfg.lost_after / 4).max(Duration::from_millis(10)),
        )
    }

    /// The clients as the remote places use them, each with its robot's presence.
    #[allow(clippy::type_complexity)]
    fn links(
        self,
        presence: &Presence,
    ) -> Result<(Vec<(String, Arc<RobotLink>)>, HashMap<String, Nav2Link>), Ros2Error> {
        let live = |robot: &str| {
            presence
                .liveness(robot)
                .ok_or_else(|| Ros2Error::Other(format!("robot `{robot}` is not watched")))
        };
        let mut links = Vec::new();
        for (robot, server, client) in self.exec {
            let liveness = live(&robot)?;
            links.push((server, Arc::new(RobotLink::new(robot, client, liveness))));
        }
        let mut nav2 = HashMap::new();
        for (robot, client) in self.nav2 {
            let liveness = live(&robot)?;
            nav2.insert(robot, Nav2Link { client, liveness });
        }
        Ok((links, nav2))
    }
}
