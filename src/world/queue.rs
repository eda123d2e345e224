//! [`Queues`]: how robots line up at each location, first come, first served.
//!
//! A location's queue is its robots in the order they joined (a robot joins when its `goto`
//! to the location starts). The k-th robot ever to join takes lane `k mod lanes`; its row is
//! the number of robots ahead of it in that lane. Slot (lane, row) lies `row × spacing`
//! behind the location's point, along the location's queue direction, and
//! `(lane − (lanes − 1)/2) × spacing` to its side. When the front robot leaves, the robots
//! behind it in its lane move up one row — a queue, not a car park — so the robot at the
//! front of a lane always has a free way out.

use std::collections::VecDeque;

use super::room::Vec2;
use crate::world::map::Map;

/// The queues of every location.
#[derive(Debug)]
pub(crate) struct Queues {
    lanes: u64,
    spacing: f32,
    fronts: Vec<Vec2>,
    back: Vec<Vec2>,
    side: Vec<Vec2>,
    /// Per location: (robot, join number) in join order.
    queues: Vec<VecDeque<(usize, u64)>>,
    joined: Vec<u64>,
}

impl Queues {
    /// Empty queues at the map's locations.
    pub(crate) fn new(map: &Map) -> Queues {
        let n = map.locations.len();
        let mut q = Queues {
            lanes: u64::from(map.queue.lanes),
            spacing: map.queue.spacing as f32,
            fronts: Vec::with_capacity(n),
            back: Vec::with_capacity(n),
            side: Vec::with_capacity(n),
            queues: vec![VecDeque::new(); n],
            joined: vec![0; n],
        };
        for l in &map.locations {
            let d = Vec2::new(l.queue_dir[0] as f32, l.queue_dir[1] as f32);
            q.fronts.push(Vec2::new(l.x as f32, l.y as f32));
            q.back.push(d);
            q.side.push(Vec2::new(-d.y, d.x));
        }
        q
    }

    /// `robot` joins the back of `loc`'s queue.
    pub(crate) fn join(&mut self, loc: usize, robot: usize) {
        let k = self.joined[loc];
        self.joined[loc] += 1;
        self.queues[loc].push_back((robot, k));
    }

    /// `robot` leaves `loc`; returns how many robots that joined before it are still there
    /// (0 = it was at the front), or `None` when it was not in the queue.
    pub(crate) fn leave(&mut self, loc: usize, robot: usize) -> Option<usize> {
        let q = &mut self.queues[loc];
        let i = q.iter().position(|&(r, _)| r == robot)?;
        q.remove(i);
        Some(i)
    }

    /// The robot at the front of `loc`'s queue.
    pub(crate) fn front(&self, loc: usize) -> Option<usize> {
        self.queues[loc].front().map(|&(r, _)| r)
    }

    /// Every robot of `loc` with the point of its slot now.
    pub(crate) fn slots(&self, loc: usize) -> Vec<(usize, Vec2)> {
        let mut rows = vec![0u32; self.lanes as usize];
        let centre = (self.lanes as f32 - 1.0) / 2.0;
        self.queues[loc]
            .iter()
            .map(|&(r, k)| {
                let lane = (k % self.lanes) as usize;
                let row = rows[lane];
                rows[lane] += 1;
                let p = self.fronts[loc]
                    + self.back[loc] * (row as f32 * self.spacing)
                    + self.side[loc] * ((lane as f32 - centre) * self.spacing);
                (r, p)
            })
            .collect()
    }

    /// The point of the location itself (the front of its queue).
    pub(crate) fn point(&self, loc: usize) -> Vec2 {
        self.fronts[loc]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::world::map::{Location, QueueSpec};

    fn map() -> Map {
        Map {
            queue: QueueSpec {
                lanes: 2,
                spacing: 0.5,
            },
            ..Map::bare(vec![Location {
                name: "L".into(),
                x: 1.0,
                y: 1.0,
                queue_dir: [0.0, 1.0],
                places: vec![],
            }])
        }
    }

    #[test]
    fn robots_fill_lanes_in_turn_and_move_up_when_the_front_leaves() {
        let mut q = Queues::new(&map());
        for r in 0..4 {
            q.join(0, r);
        }
        // Queue grows towards +y; lanes are across it (side = (-1, 0)).
        let s = q.slots(0);
        assert_eq!(s[0], (0, Vec2::new(1.25, 1.0)));
        assert_eq!(s[1], (1, Vec2::new(0.75, 1.0)));
        assert_eq!(s[2], (2, Vec2::new(1.25, 1.5)));
        assert_eq!(s[3], (3, Vec2::new(0.75, 1.5)));
        assert_eq!(q.leave(0, 0), Some(0));
        assert_eq!(q.front(0), Some(1));
        let s = q.slots(0);
        assert_eq!(
            s[1],
            (2, Vec2::new(1.25, 1.0)),
            "robot 2 moved up in lane 0"
        );
        assert_eq!(
            q.leave(0, 3),
            Some(2),
            "two robots that joined earlier are still there"
        );
        assert_eq!(q.leave(0, 9), None);
    }
}
