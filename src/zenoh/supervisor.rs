//! [`ZenohBackend`]: the supervisor's side of `plan-runner run --zenoh`, the Zenoh twin of
//! [`crate::ros2::Ros2Backend`].
//!
//! ```text
//! connect   the supervisor's node token (robots leave when it is gone), the robots'
//!           presence from their tokens, publishers of /gspn/firings, /gspn/marking,
//!           /gspn/run, /gspn/drift; waits (≤ startup) for every robot's token and, when
//!           asked, for a firings subscriber
//! attach    registers the `ros2` action (ZenohPlaces), says the run is `running`
//! publish   a task that publishes every firing and the marking from the run's events
//! finish    waits for the publisher, says the run is `over` (robots leave), lingers so
//!           the last samples leave the process
//! ```
//!
//! Publications block rather than drop when the network is congested: a firing is never
//! lost between the supervisor and the router.

use std::collections::HashMap;
use std::sync::Arc;
use std::time::Duration;

use serde::Serialize;
use tokio::task::JoinHandle;
use zenoh::Session;
use zenoh::liveliness::LivelinessToken;
use zenoh::pubsub::Publisher;
use zenoh::qos::CongestionControl;

use super::keys::{self, EntityIds, EntityKind, NodeKey, Topic};
use super::presence::Presence;
use super::remote_place::{RobotLink, ZenohPlaces};
use super::robot::declare_token;
use super::wire::{self, Source};
use super::{ZenohConfig, ZenohError};
use crate::net::Net;
use crate::ros2::firings::{Published, RunMessage, RunSink, publish_run};
use crate::ros2::msgs::RunState;
use crate::ros2::settings::{NAV2_SERVER, ROS2_ACTION, Ros2Settings};
use crate::runtime::{Events, RuntimeBuilder};

/// A publisher and its rmw_zenoh attachment (GID, sequence numbers).
struct TopicPublisher {
    publisher: Publisher<'static>,
    source: Source,
}

impl TopicPublisher {
    async fn new(session: &Session, domain: u16, topic: Topic) -> Result<Self, ZenohError> {
        let publisher = session
            .declare_publisher(topic.key(domain)?)
            .congestion_control(CongestionControl::Block)
            .await
            .map_err(ZenohError::zenoh)?;
        Ok(TopicPublisher {
            publisher,
            source: Source::new(topic.name()),
        })
    }

    async fn put<M: Serialize>(&self, m: &M) -> bool {
        self.publisher
            .put(wire::encode(m))
            .attachment(self.source.next().to_bytes())
            .await
            .is_ok()
    }
}

/// The four topics of a run.
struct RunTopics {
    firings: TopicPublisher,
    marking: TopicPublisher,
    run: TopicPublisher,
    drift: TopicPublisher,
    net: Arc<Net>,
}

impl RunTopics {
    /// Publishes the initial marking, then every firing of `events` until the run is over
    /// (the same messages as the DDS publisher).
    async fn run(&self, events: Events) -> Published {
        publish_run(&self.net, events, self).await
    }
}

impl RunSink for RunTopics {
    async fn send(&self, m: RunMessage) -> bool {
        match m {
            RunMessage::Marking(m) => self.marking.put(&m).await,
            RunMessage::Firing(f) => self.firings.put(&f).await,
            RunMessage::Drift(d) => self.drift.put(&d).await,
        }
    }
}

/// The supervisor's Zenoh side: its session, links to the robots and the publishers.
pub struct ZenohBackend {
    session: Session,
    /// The node's and its endpoints' liveliness tokens, withdrawn when it is dropped.
    _tokens: Vec<LivelinessToken>,
    topics: Arc<RunTopics>,
    task: Option<JoinHandle<Published>>,
    places: ZenohPlaces,
    presence: Presence,
}

impl std::fmt::Debug for ZenohBackend {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ZenohBackend")
            .field("places", &self.places)
            .finish()
    }
}

impl ZenohBackend {
    /// Joins through `session` and links to every robot of `robots` for the `ros2` places
    /// of `settings`; waits (at most `cfg.startup`) for every robot's token and, when
    /// `subscribers` > 0, for a subscriber of `/gspn/firings` (Zenoh tells whether one
    /// matches, not how many).
    pub async fn connect(
        session: Session,
        net: &Net,
        settings: &Ros2Settings,
        robots: &[String],
        cfg: &ZenohConfig,
        subscribers: usize,
    ) -> Result<ZenohBackend, ZenohError> {
        let d = cfg.domain;
        if let Some((p, _)) = settings.servers.iter().find(|(_, s)| s == NAV2_SERVER) {
            return Err(ZenohError::Nav2Place(net.place(*p).name.clone()));
        }
        // The node's token first, as rmw_zenoh declares a node before its endpoints.
        let ids = EntityIds::default();
        let node = NodeKey {
            domain: d,
            zid: session.zid().to_string(),
            id: ids.next(),
            namespace: keys::SUPERVISOR_NS.to_string(),
            name: keys::SUPERVISOR_NODE.to_string(),
        };
        let mut tokens = vec![declare_token(&session, node.token()).await?];
        let presence = Presence::robots(&session, d, robots, cfg.lost_after).await?;
        let topics = RunTopics {
            firings: TopicPublisher::new(&session, d, Topic::Firings).await?,
            marking: TopicPublisher::new(&session, d, Topic::Marking).await?,
            run: TopicPublisher::new(&session, d, Topic::Run).await?,
            drift: TopicPublisher::new(&session, d, Topic::Drift).await?,
            net: Arc::new(net.clone()),
        };
        for topic in [Topic::Firings, Topic::Marking, Topic::Run, Topic::Drift] {
            let key = node.endpoint(
                ids.next(),
                EntityKind::Publisher,
                topic.name(),
                topic.ty(),
                topic.qos(),
            )?;
            tokens.push(declare_token(&session, key).await?);
        }
        let mut servers: Vec<&str> = settings.servers.iter().map(|(_, s)| s.as_str()).collect();
        servers.sort_unstable();
        servers.dedup();
        let mut links = Vec::new();
        for robot in robots {
            let (Some(live), Some(present)) = (presence.liveness(robot), presence.present(robot))
            else {
                return Err(ZenohError::Unwatched(robot.clone()));
            };
            for &server in &servers {
                let link = RobotLink::new(
                    session.clone(),
                    d,
                    robot.clone(),
                    server,
                    live.clone(),
                    present.clone(),
                )?;
                links.push((server.to_string(), Arc::new(link)));
                for key in keys::action_client_tokens(&node, &ids, robot, server)? {
                    tokens.push(declare_token(&session, key).await?);
                }
            }
        }
        let startup = cfg.startup;
        presence
            .all_alive(startup)
            .await
            .map_err(|missing| ZenohError::RobotsMissing {
                missing,
                within: startup,
                endpoint: cfg.endpoint.clone(),
                domain: d,
            })?;
        if subscribers > 0 {
            let matched = async {
                loop {
                    if let Ok(m) = topics.firings.publisher.matching_status().await
                        && m.matching()
                    {
                        break;
                    }
                    tokio::time::sleep(Duration::from_millis(20)).await;
                }
            };
            tokio::time::timeout(startup, matched)
                .await
                .map_err(|_| ZenohError::NoSubscriber(startup))?;
        }
        let servers: HashMap<_, _> = settings.servers.iter().cloned().collect();
        let args: HashMap<_, _> = settings.args.iter().cloned().collect();
        Ok(ZenohBackend {
            session,
            _tokens: tokens,
            topics: Arc::new(topics),
            task: None,
            places: ZenohPlaces::new(servers, args, links),
            presence,
        })
    }

    /// Registers the `ros2` action on `b`.
    pub fn attach(&self, b: RuntimeBuilder) -> RuntimeBuilder {
        b.action(ROS2_ACTION, self.places.clone())
    }

    /// Says the run is `running` and starts publishing its firings and marking from
    /// `events`.
    pub async fn publish(&mut self, events: Events) {
        let running = RunState {
            state: RunState::RUNNING,
            stopped: String::new(),
            firings: 0,
        };
        self.topics.run.put(&running).await;
        if self.task.is_none() {
            let t = Arc::clone(&self.topics);
            self.task = Some(tokio::spawn(async move { t.run(events).await }));
        }
    }

    /// The robots' presence.
    pub fn presence(&self) -> &Presence {
        &self.presence
    }

    /// The session.
    pub fn session(&self) -> &Session {
        &self.session
    }

    /// Waits for the publisher to have sent every firing (the run must be over), says the
    /// run is over (`stopped`: why) so robots leave, then lingers `linger` so the last
    /// samples leave the process before it exits.
    pub async fn finish(mut self, linger: Duration, stopped: &str) -> Published {
        let mut published = match self.task.take() {
            Some(t) => t.await.unwrap_or_default(),
            None => Published::default(),
        };
        let over = RunState {
            state: RunState::OVER,
            stopped: stopped.to_string(),
            firings: published.firings,
        };
        if !self.topics.run.put(&over).await {
            published.errors += 1;
        }
        tokio::time::sleep(linger).await;
        published
    }
}
