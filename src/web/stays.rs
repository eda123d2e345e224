//! Which robot was in which place when: the robot timeline of a replay, and the history a
//! page that joins a live run late receives. Built from the run's events alone, so a journal
//! and a live run give the same rows.
//!
//! A robot is bound to the agent it was spawned with (`agent_spawned` names it); an agent
//! keeps its id through the firings that move it (`fired` lists it in `consumed`, then in
//! `produced`), and learns its new place from the `action_started` that follows.

use std::collections::HashMap;
use std::sync::Arc;

use serde::Serialize;
use serde_json::Value;
use serde_json::value::RawValue;

use crate::net::{Net, PlaceId};
use crate::runtime::{AgentId, Event, EventKind};

/// One stay of a robot in a place; `place` is `None` between a firing and the action that
/// tells where the agent went.
#[derive(Clone, Debug, PartialEq)]
struct Stay {
    t0: f64,
    t1: Option<f64>,
    place: Option<PlaceId>,
    agent: AgentId,
}

/// Every robot's stays so far (see the module).
#[derive(Clone, Debug, Default)]
pub(crate) struct RobotStays {
    robot_of: HashMap<AgentId, Arc<str>>,
    stays: HashMap<Arc<str>, Vec<Stay>>,
    /// The time of the last event seen: the end of the stays still open.
    now: f64,
}

impl RobotStays {
    /// The stays of every robot in `events`.
    pub(crate) fn of(events: &[Event]) -> RobotStays {
        let mut s = RobotStays::default();
        for e in events {
            s.push(e);
        }
        s
    }

    /// Takes one event into account.
    pub(crate) fn push(&mut self, e: &Event) {
        self.now = self.now.max(e.time);
        match &e.kind {
            EventKind::AgentSpawned {
                agent,
                place,
                robot: Some(robot),
            } => {
                self.robot_of.insert(*agent, robot.clone());
                self.stays.entry(robot.clone()).or_default().push(Stay {
                    t0: e.time,
                    t1: None,
                    place: Some(*place),
                    agent: *agent,
                });
            }
            EventKind::Fired {
                consumed, produced, ..
            } => {
                for a in consumed {
                    if let Some(last) = self.last_mut(*a) {
                        last.t1 = Some(e.time);
                    }
                }
                for a in produced {
                    let Some(robot) = self.robot_of.get(a) else {
                        continue;
                    };
                    self.stays.entry(robot.clone()).or_default().push(Stay {
                        t0: e.time,
                        t1: None,
                        place: None,
                        agent: *a,
                    });
                }
            }
            EventKind::ActionStarted { agent, place, .. } => {
                if let Some(last) = self.last_mut(*agent)
                    && last.t1.is_none()
                    && last.place.is_none()
                {
                    last.place = Some(*place);
                }
            }
            EventKind::AgentEnded { agent } => {
                if let Some(last) = self.last_mut(*agent) {
                    last.t1.get_or_insert(e.time);
                }
            }
            _ => {}
        }
    }

    fn last_mut(&mut self, agent: AgentId) -> Option<&mut Stay> {
        let robot = self.robot_of.get(&agent)?;
        self.stays.get_mut(robot)?.last_mut()
    }

    /// `[{robot, stays: [{t0, t1, place, agent}]}]`, robots in natural order (`r2` before
    /// `r10`), a stay still open ending at the last event's time; a stay whose place no
    /// event told is left out.
    pub(crate) fn json(&self, net: &Net) -> Value {
        serde_json::to_value(self.rows(net)).unwrap_or_else(|_| Value::Array(Vec::new()))
    }

    /// [`RobotStays::json`] as its text (a replay keeps it so: a tenth of the memory).
    pub(crate) fn raw_json(&self, net: &Net) -> Box<RawValue> {
        serde_json::value::to_raw_value(&self.rows(net))
            .unwrap_or_else(|_| RawValue::from_string("[]".into()).expect("valid JSON"))
    }

    fn rows<'a>(&'a self, net: &'a Net) -> Vec<RobotRow<'a>> {
        let mut robots: Vec<&Arc<str>> = self.stays.keys().collect();
        robots.sort_by(|a, b| natural(a).cmp(&natural(b)));
        robots
            .into_iter()
            .map(|r| RobotRow {
                robot: r,
                stays: self.stays[r]
                    .iter()
                    .filter_map(|s| {
                        Some(StayRow {
                            t0: s.t0,
                            t1: s.t1.unwrap_or(self.now),
                            place: &net.place(s.place?).name,
                            agent: s.agent.0,
                        })
                    })
                    .collect(),
            })
            .collect()
    }
}

/// One robot's row of [`RobotStays::json`].
#[derive(Serialize)]
struct RobotRow<'a> {
    robot: &'a str,
    stays: Vec<StayRow<'a>>,
}

/// One stay of [`RobotRow`].
#[derive(Serialize)]
struct StayRow<'a> {
    t0: f64,
    t1: f64,
    place: &'a str,
    agent: u64,
}

/// A name split into its text and its number (`r10` → ("r", 10)), for sorting.
fn natural(name: &str) -> (&str, u64, &str) {
    let digits = name.trim_end_matches(|c: char| c.is_ascii_digit());
    (digits, name[digits.len()..].parse().unwrap_or(0), name)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::net::{Marking, NetBuilder, Servers};
    use serde_json::json;

    #[test]
    fn a_robot_moves_with_its_agent_and_learns_its_place_from_the_action() {
        let mut b = NetBuilder::new("two");
        let (p, q) = (b.place("p", 1), b.place("q", 0));
        let tr = b.exponential("t", 1.0, Servers::Single);
        b.input(p, tr, 1);
        b.output(tr, q, 1);
        let net = b.build().unwrap();
        let ev = |seq, time, kind| Event { seq, time, kind };
        let a = AgentId(0);
        let events = vec![
            ev(
                0,
                0.0,
                EventKind::AgentSpawned {
                    agent: a,
                    place: p,
                    robot: Some("r1".into()),
                },
            ),
            ev(
                1,
                2.5,
                EventKind::Fired {
                    transition: tr,
                    consumed: vec![a],
                    produced: vec![a],
                    marking: Marking::from(vec![0, 1]),
                    robots: vec!["r1".into()],
                },
            ),
            ev(
                2,
                2.5,
                EventKind::ActionStarted {
                    agent: a,
                    place: q,
                    attempt: 0,
                },
            ),
            ev(
                3,
                4.0,
                EventKind::Warning {
                    message: "later".into(),
                },
            ),
        ];
        let rows = RobotStays::of(&events).json(&net);
        assert_eq!(
            rows,
            json!([{"robot": "r1", "stays": [
                {"t0": 0.0, "t1": 2.5, "place": "p", "agent": 0},
                {"t0": 2.5, "t1": 4.0, "place": "q", "agent": 0},
            ]}])
        );
        assert!(natural("r2") < natural("r10"));
    }
}
