//! The simulated world's side of Nav2 (feature `sim`): [`SimNav2`] serves
//! `NavigateToPose` for each simulated robot and publishes its pose, and
//! [`Nav2Navigator`] sends a built-in action's `goto` steps there. The two sides are two
//! DDS participants, as they would be two processes with real robots. A goal whose pose is
//! at no location of the map (farther than [`AT_LOCATION`]) is rejected, as Nav2 rejects a
//! goal it cannot plan for.

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Duration;

use ros2_client::Node;
use ros2_client::action::{AsyncActionServer, GoalEndStatus};
use tokio::task::JoinHandle;

use super::{
    Nav2Client, Nav2Error, client, feedback_qos, navigate, robot_name, server_qos, wait_for_server,
};
use crate::ros2::Ros2Error;
use crate::ros2::config::DdsConfig;
use crate::ros2::msgs::PoseStamped;
use crate::ros2::msgs::common::pose_stamped_type;
use crate::ros2::msgs::nav2::{
    ACTION, Duration as RosDuration, NavigateToPoseFeedback, NavigateToPoseGoal,
    NavigateToPoseResult, navigate_to_pose_type,
};
use crate::runtime::{Backend, BackendFuture, Section, Summary};
use crate::world::map::Map;
use crate::world::{DriveError, Navigator, WorldHandle, WorldView};

/// A goal pose this close to a location (m) means that location.
pub const AT_LOCATION: f64 = 0.5;
/// How often poses and feedback are published (wall clock).
const POSE_PERIOD: Duration = Duration::from_millis(100);
/// How long the end of a run waits for its given-up goals to be cancelled.
const SETTLE: Duration = Duration::from_secs(2);
type Nav2Server =
    AsyncActionServer<NavigateToPoseGoal, NavigateToPoseResult, NavigateToPoseFeedback>;

/// A location's pose in frame `map` (facing +x: the map gives locations no heading).
fn location_pose(map: &Map, location: usize) -> PoseStamped {
    let l = &map.locations[location];
    PoseStamped::on_map(l.x, l.y, 0.0)
}

/// The location `pose` means: the nearest within [`AT_LOCATION`].
fn location_at(map: &Map, pose: &PoseStamped) -> Option<usize> {
    let (x, y) = (pose.pose.position.x, pose.pose.position.y);
    map.locations
        .iter()
        .enumerate()
        .map(|(i, l)| (i, (l.x - x).hypot(l.y - y)))
        .filter(|&(_, d)| d <= AT_LOCATION)
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(i, _)| i)
}

/// `robot`'s pose in `view`, in frame `map`.
fn robot_pose(view: &WorldView, robot: &str) -> Option<PoseStamped> {
    let r = view.robots.iter().find(|r| &*r.id == robot)?;
    Some(PoseStamped::on_map(r.x, r.y, 0.0))
}

/// The simulated world's Nav2 side: a `NavigateToPose` server and a pose publisher per
/// robot. Its tasks end when it is dropped.
pub struct SimNav2 {
    tasks: Vec<JoinHandle<()>>,
    counts: Arc<Counts>,
}

/// Goals the world's servers received, and how they ended.
#[derive(Debug, Default)]
struct Counts {
    goals: AtomicU64,
    succeeded: AtomicU64,
    aborted: AtomicU64,
    cancelled: AtomicU64,
    rejected: AtomicU64,
}

impl std::fmt::Debug for SimNav2 {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SimNav2")
            .field("tasks", &self.tasks.len())
            .finish()
    }
}

impl Drop for SimNav2 {
    fn drop(&mut self) {
        for t in &self.tasks {
            t.abort();
        }
    }
}

/// The world's Nav2 side as a backend of the run: its summary section counts the goals
/// (`"nav2": {"goals", "succeeded", "aborted", "cancelled", "rejected"}`).
impl Backend for SimNav2 {
    fn name(&self) -> &'static str {
        "nav2"
    }

    fn finish<'a>(&'a mut self, _summary: &'a Summary) -> BackendFuture<'a, Option<Section>> {
        Box::pin(async move { Some(self.counts.section().await) })
    }

    fn stop(&mut self) {
        for t in &self.tasks {
            t.abort();
        }
    }
}

impl Counts {
    /// The `nav2` summary section, once every goal has ended (or [`SETTLE`] passed).
    async fn section(&self) -> Section {
        let n = |a: &AtomicU64| a.load(Ordering::SeqCst);
        // The run's last drives were given up when it stopped: their cancel requests are on
        // their way. Wait (a little) for them to be answered and counted.
        let settled = async {
            while n(&self.succeeded) + n(&self.aborted) + n(&self.cancelled) + n(&self.rejected)
                < n(&self.goals)
            {
                tokio::time::sleep(Duration::from_millis(20)).await;
            }
        };
        if tokio::time::timeout(SETTLE, settled).await.is_err() {
            tracing::warn!("nav2: goals still driving {SETTLE:?} after the run stopped");
        }
        let json = serde_json::json!({
            "goals": n(&self.goals),
            "succeeded": n(&self.succeeded),
            "aborted": n(&self.aborted),
            "cancelled": n(&self.cancelled),
            "rejected": n(&self.rejected),
        });
        let text = format!(
            "nav2: {} NavigateToPose goals ({} succeeded, {} aborted, {} cancelled, {} rejected)",
            n(&self.goals),
            n(&self.succeeded),
            n(&self.aborted),
            n(&self.cancelled),
            n(&self.rejected)
        );
        Section::new(json, text)
    }
}

/// The goals a [`Nav2Navigator`] sent and how they ended, as the run's `nav2` summary
/// section (the same as [`SimNav2`]'s, counted on the client's side): the backend of a run
/// on real Nav2 robots (`run --nav2`).
#[derive(Debug)]
pub struct Nav2Goals {
    counts: Arc<Counts>,
}

impl Backend for Nav2Goals {
    fn name(&self) -> &'static str {
        "nav2"
    }

    fn finish<'a>(&'a mut self, _summary: &'a Summary) -> BackendFuture<'a, Option<Section>> {
        Box::pin(async move { Some(self.counts.section().await) })
    }
}

/// Counts one goal: sent when made, its end when [`Tally::end`] is called, cancelled when
/// dropped first (the step was given up).
struct Tally {
    counts: Arc<Counts>,
    ended: bool,
}

impl Tally {
    fn new(counts: Arc<Counts>) -> Tally {
        counts.goals.fetch_add(1, Ordering::SeqCst);
        Tally {
            counts,
            ended: false,
        }
    }

    fn end(mut self, r: Result<(), &Nav2Error>) {
        self.ended = true;
        let c = &self.counts;
        let ended = match r {
            Ok(()) => &c.succeeded,
            Err(Nav2Error::Rejected { .. }) => &c.rejected,
            Err(Nav2Error::Cancelled) => &c.cancelled,
            Err(Nav2Error::Ended { status, .. }) if status == "Canceled" => &c.cancelled,
            Err(_) => &c.aborted,
        };
        ended.fetch_add(1, Ordering::SeqCst);
    }
}

impl Drop for Tally {
    fn drop(&mut self) {
        if !self.ended {
            self.counts.cancelled.fetch_add(1, Ordering::SeqCst);
        }
    }
}

impl SimNav2 {
    /// Serves `/<robot>/navigate_to_pose` and publishes `/<robot>/pose` for every robot of
    /// `world` (on `map`), from a node `sim_world` of its own.
    pub fn serve(
        world: &WorldHandle,
        map: Arc<Map>,
        cfg: &DdsConfig,
    ) -> Result<SimNav2, Ros2Error> {
        let mut node = cfg.node("sim_world", None)?;
        let spinner = node.spinner().map_err(Ros2Error::dds)?;
        let mut tasks = vec![tokio::spawn(async move {
            if let Err(e) = spinner.spin().await {
                tracing::warn!("ROS 2 spinner (sim_world): {e:?}");
            }
        })];
        let counts = Arc::new(Counts::default());
        let mut poses = Vec::new();
        for robot in world.robots() {
            let name = robot_name(&node, robot, ACTION)?;
            let server = node
                .create_action_server::<NavigateToPoseGoal, NavigateToPoseResult, NavigateToPoseFeedback>(
                    cfg.service_mapping,
                    &name,
                    &navigate_to_pose_type(),
                    server_qos(),
                )
                .map_err(Ros2Error::dds)?;
            let server = Arc::new(AsyncActionServer::new(server));
            tasks.push(tokio::spawn(serve_goals(
                server,
                Arc::clone(robot),
                world.clone(),
                Arc::clone(&map),
                Arc::clone(&counts),
            )));
            let topic = node
                .create_topic(
                    &robot_name(&node, robot, "pose")?,
                    pose_stamped_type(),
                    &feedback_qos(),
                )
                .map_err(Ros2Error::dds)?;
            let publisher = node
                .create_publisher::<PoseStamped>(&topic, None)
                .map_err(Ros2Error::dds)?;
            poses.push((Arc::clone(robot), publisher));
        }
        let mut view = world.view();
        tasks.push(tokio::spawn(async move {
            // Keeps the node (and so its participant) alive as long as the publishers.
            let _node = node;
            let mut tick = tokio::time::interval(POSE_PERIOD);
            loop {
                tick.tick().await;
                let now = view.borrow_and_update().clone();
                for (robot, publisher) in &poses {
                    if let Some(p) = robot_pose(&now, robot)
                        && let Err(e) = publisher.async_publish(p).await
                    {
                        tracing::warn!("publishing /{robot}/pose: {e:?}");
                    }
                }
            }
        }));
        Ok(SimNav2 { tasks, counts })
    }
}

/// A goal being driven, and the sender that cancels it.
type Running = (
    ros2_client::action::GoalId,
    tokio::sync::oneshot::Sender<()>,
);

/// Receives one robot's goals and cancel requests; each goal drives the robot in its own
/// task (a new goal preempts nothing: the world queues the robot's drives).
async fn serve_goals(
    server: Arc<Nav2Server>,
    robot: Arc<str>,
    world: WorldHandle,
    map: Arc<Map>,
    counts: Arc<Counts>,
) {
    let running: Arc<std::sync::Mutex<Vec<Running>>> = Arc::default();
    loop {
        tokio::select! {
            g = server.receive_new_goal() => match g {
                Ok(handle) => {
                    let (tx, rx) = tokio::sync::oneshot::channel();
                    if let Ok(mut r) = running.lock() {
                        r.retain(|(_, tx)| !tx.is_closed());
                        r.push((handle.goal_id(), tx));
                    }
                    tokio::spawn(run_goal(
                        Arc::clone(&server),
                        handle,
                        Arc::clone(&robot),
                        world.clone(),
                        Arc::clone(&map),
                        rx,
                        Arc::clone(&counts),
                    ));
                }
                Err(e) => tracing::warn!("/{robot}/navigate_to_pose: receiving a goal: {e:?}"),
            },
            c = server.receive_cancel_request() => match c {
                Ok(cancel) => {
                    let ours: Vec<_> = match running.lock() {
                        Ok(mut r) => {
                            let (hit, keep) = std::mem::take(&mut *r)
                                .into_iter()
                                .partition(|(id, _)| cancel.contains_goal(id));
                            *r = keep;
                            hit.into_iter().map(|(id, tx): Running| {
                                let _ = tx.send(());
                                id
                            }).collect()
                        }
                        Err(_) => Vec::new(),
                    };
                    let _ = server.respond_to_cancel_requests(&cancel, ours.into_iter()).await;
                }
                Err(e) => tracing::warn!("/{robot}/navigate_to_pose: receiving a cancel: {e:?}"),
            },
        }
    }
}

async fn run_goal(
    server: Arc<Nav2Server>,
    handle: ros2_client::action::NewGoalHandle<NavigateToPoseGoal>,
    robot: Arc<str>,
    world: WorldHandle,
    map: Arc<Map>,
    cancelled: tokio::sync::oneshot::Receiver<()>,
    counts: Arc<Counts>,
) {
    let Some(goal) = server.get_new_goal(handle.clone()) else {
        return;
    };
    counts.goals.fetch_add(1, Ordering::SeqCst);
    let Some(location) = location_at(&map, &goal.pose) else {
        tracing::warn!(
            "/{robot}/navigate_to_pose: goal ({:.2}, {:.2}) is at no location of the map: rejected",
            goal.pose.pose.position.x,
            goal.pose.pose.position.y
        );
        counts.rejected.fetch_add(1, Ordering::SeqCst);
        let _ = server.reject_goal(handle).await;
        return;
    };
    let Ok(accepted) = server.accept_goal(handle).await else {
        return;
    };
    let Ok(executing) = server.start_executing_goal(accepted).await else {
        return;
    };
    let started = std::time::Instant::now();
    let drive = world.drive(Arc::clone(&robot), location);
    tokio::pin!(drive);
    tokio::pin!(cancelled);
    let mut view = world.view();
    let mut tick = tokio::time::interval(POSE_PERIOD);
    let (status, result) = loop {
        tokio::select! {
            r = &mut drive => break match r {
                Ok(()) => (GoalEndStatus::Succeeded, NavigateToPoseResult::default()),
                Err(e) => (GoalEndStatus::Aborted, NavigateToPoseResult {
                    error_code: NavigateToPoseResult::UNKNOWN,
                    error_msg: e.to_string(),
                }),
            },
            _ = &mut cancelled => break (GoalEndStatus::Canceled, NavigateToPoseResult::default()),
            _ = tick.tick() => {
                let now = view.borrow_and_update().clone();
                if let Some(current_pose) = robot_pose(&now, &robot) {
                    let target = &goal.pose.pose.position;
                    let left = (target.x - current_pose.pose.position.x)
                        .hypot(target.y - current_pose.pose.position.y);
                    let feedback = NavigateToPoseFeedback {
                        current_pose,
                        navigation_time: RosDuration::from_std(started.elapsed()),
                        distance_remaining: left as f32,
                        ..NavigateToPoseFeedback::default()
                    };
                    let _ = server.publish_feedback(executing.clone(), feedback).await;
                }
            }
        }
    };
    let ended = match status {
        GoalEndStatus::Succeeded => &counts.succeeded,
        GoalEndStatus::Aborted => &counts.aborted,
        GoalEndStatus::Canceled => &counts.cancelled,
    };
    ended.fetch_add(1, Ordering::SeqCst);
    let send = server.send_result_response(executing, status, result);
    if tokio::time::timeout(Duration::from_secs(5), send)
        .await
        .is_err()
    {
        tracing::warn!("/{robot}/navigate_to_pose: nobody asked for the result");
    }
}

/// The Nav2 client side of `goto`: one `NavigateToPose` client per robot, in a node
/// `nav2_client` of its own. A robot drives one goal at a time, so each client has at most
/// one call of each kind in flight.
pub struct Nav2Navigator {
    map: Arc<Map>,
    clients: Vec<(Arc<str>, Arc<Nav2Client>)>,
    /// The mirror world of robots that drive themselves (`run --nav2`), told each robot's
    /// departures, arrivals and feedback poses.
    mirror: Option<WorldHandle>,
    counts: Arc<Counts>,
    /// The node the clients belong to (its spinner runs in `_spin`).
    _node: std::sync::Mutex<Node>,
    _spin: AbortOnDrop,
}

impl std::fmt::Debug for Nav2Navigator {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Nav2Navigator")
            .field("robots", &self.clients.len())
            .finish()
    }
}

struct AbortOnDrop(JoinHandle<()>);

impl Drop for AbortOnDrop {
    fn drop(&mut self) {
        self.0.abort();
    }
}

impl Nav2Navigator {
    /// Clients of `/<robot>/navigate_to_pose` for every robot of `robots`; waits (at most
    /// `cfg.startup`) until each server is matched.
    pub async fn connect(
        robots: &[Arc<str>],
        map: Arc<Map>,
        cfg: &DdsConfig,
    ) -> Result<Nav2Navigator, Ros2Error> {
        let mut node = cfg.node("nav2_client", None)?;
        let spinner = node.spinner().map_err(Ros2Error::dds)?;
        let spin = AbortOnDrop(tokio::spawn(async move {
            if let Err(e) = spinner.spin().await {
                tracing::warn!("ROS 2 spinner (nav2_client): {e:?}");
            }
        }));
        let mut clients = Vec::new();
        for robot in robots {
            let client = client(&mut node, cfg, robot)?;
            clients.push((Arc::clone(robot), Arc::new(client)));
        }
        let deadline = tokio::time::Instant::now() + cfg.startup;
        for (robot, c) in &clients {
            let found = wait_for_server(c, &node);
            if tokio::time::timeout_at(deadline, found).await.is_err() {
                return Err(Ros2Error::Startup(format!(
                    "no NavigateToPose server at /{robot}/{ACTION} within {:?}",
                    cfg.startup
                )));
            }
        }
        Ok(Nav2Navigator {
            map,
            clients,
            mirror: None,
            counts: Arc::default(),
            _node: std::sync::Mutex::new(node),
            _spin: spin,
        })
    }

    /// The same navigator for robots that drive themselves (real robots running Nav2):
    /// `world` (a [`crate::world::World::spawn_mirror`]) learns where each robot sets out
    /// for, where its feedback says it is and when it arrived.
    pub fn mirroring(self, world: WorldHandle) -> Nav2Navigator {
        Nav2Navigator {
            mirror: Some(world),
            ..self
        }
    }

    /// The goals sent so far and how they ended, as the run's `nav2` summary section.
    pub fn goals(&self) -> Nav2Goals {
        Nav2Goals {
            counts: Arc::clone(&self.counts),
        }
    }

    fn client(&self, robot: &str) -> Option<Arc<Nav2Client>> {
        self.clients
            .iter()
            .find(|(r, _)| &**r == robot)
            .map(|(_, c)| Arc::clone(c))
    }
}

impl Navigator for Nav2Navigator {
    fn goto(
        &self,
        robot: Arc<str>,
        location: usize,
    ) -> std::pin::Pin<Box<dyn std::future::Future<Output = Result<(), DriveError>> + Send>> {
        let client = self.client(&robot);
        let pose = location_pose(&self.map, location);
        let mirror = self.mirror.clone();
        let counts = Arc::clone(&self.counts);
        Box::pin(async move {
            let Some(client) = client else {
                return Err(format!("no Nav2 client for robot `{robot}`").into());
            };
            let tally = Tally::new(counts);
            let at = |p: &PoseStamped| {
                if let Some(world) = &mirror {
                    let (x, y) = (p.pose.position.x, p.pose.position.y);
                    world.set_pose(Arc::clone(&robot), x, y);
                }
            };
            // The step gives the drive up by dropping it (the guard cancels the goal).
            let drive = async {
                let r = navigate(client, &robot, pose, std::future::pending(), at).await;
                tally.end(r.as_ref().map(|_| ()));
                r.map_err(DriveError::from)
            };
            match &mirror {
                Some(world) => world.mirror_goto(Arc::clone(&robot), location, drive).await,
                None => drive.await,
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::world::map::Location;

    #[test]
    fn a_goal_pose_means_the_location_within_half_a_metre() {
        // Two locations 4 m apart, built here: the ROS side reads no plan file.
        let at_xy = |name: &str, x: f64, y: f64| Location {
            name: name.into(),
            x,
            y,
            queue_dir: [1.0, 0.0],
            places: vec![],
        };
        let map = Map::bare(vec![at_xy("L1", 1.0, 1.0), at_xy("L2", 5.0, 1.0)]);
        let l2 = map.location("L2").unwrap();
        let (x, y) = (map.locations[l2].x, map.locations[l2].y);
        let at = |dx: f64| location_at(&map, &PoseStamped::on_map(x + dx, y, 0.0));
        assert_eq!(at(0.0), Some(l2));
        assert_eq!(at(0.49), Some(l2));
        assert_eq!(at(0.51), None);
        let goal = location_pose(&map, l2);
        assert_eq!(goal.header.frame_id, "map");
        assert_eq!((goal.pose.position.x, goal.pose.position.y), (x, y));
        assert_eq!(location_at(&map, &goal), Some(l2));
    }

    #[test]
    fn durations_saturate() {
        let d = RosDuration::from_std(Duration::from_millis(2_500));
        assert_eq!((d.sec, d.nanosec), (2, 500_000_000));
        assert_eq!(
            RosDuration::from_std(Duration::from_secs(u64::MAX)).sec,
            i32::MAX
        );
    }
}
