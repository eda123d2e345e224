#!/usr/bin/env python3
"""Watches a `plan-runner run --robots N --ros2` from the Nav2 side with Eclipse Cyclone DDS
(the PyPI `cyclonedds` package, not ours): the NavigateToPose goals sent to
/<robot>/navigate_to_pose and the poses on /<robot>/pose, under the DDS topic and type names
ROS 2 gives them. The IDL below is nav2_msgs/action/NavigateToPose as Nav2 defines it
(navigation2, branch main / lyrical) and geometry_msgs/PoseStamped.

    nav2_watcher.py DOMAIN ROBOTS     (ROBOTS: r1,r2,...)

Prints `ready` on stderr once the readers exist, reads until its stdin closes, then prints one JSON
object on stdout: per robot, the goals (their pose and frame, behavior_tree) and the poses
(count, frame, first and last x/y). Set CYCLONEDDS_URI to the loopback-only configuration.
"""

import json
import sys
import threading
import time
from dataclasses import dataclass

from cyclonedds.core import Policy, Qos
from cyclonedds.domain import DomainParticipant
from cyclonedds.idl import IdlStruct
from cyclonedds.idl.types import array, float64, int32, uint8, uint32
from cyclonedds.internal import InvalidSample
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration


@dataclass
class Time(IdlStruct, typename="builtin_interfaces::msg::dds_::Time_"):
    sec: int32
    nanosec: uint32


@dataclass
class Header(IdlStruct, typename="std_msgs::msg::dds_::Header_"):
    stamp: Time
    frame_id: str


@dataclass
class Point(IdlStruct, typename="geometry_msgs::msg::dds_::Point_"):
    x: float64
    y: float64
    z: float64


@dataclass
class Quaternion(IdlStruct, typename="geometry_msgs::msg::dds_::Quaternion_"):
    x: float64
    y: float64
    z: float64
    w: float64


@dataclass
class Pose(IdlStruct, typename="geometry_msgs::msg::dds_::Pose_"):
    position: Point
    orientation: Quaternion


@dataclass
class PoseStamped(IdlStruct, typename="geometry_msgs::msg::dds_::PoseStamped_"):
    header: Header
    pose: Pose


@dataclass
class UUID(IdlStruct, typename="unique_identifier_msgs::msg::dds_::UUID_"):
    uuid: array[uint8, 16]


@dataclass
class NavigateToPoseGoal(IdlStruct, typename="nav2_msgs::action::dds_::NavigateToPose_Goal_"):
    pose: PoseStamped
    behavior_tree: str


@dataclass
class SendGoalRequest(
    IdlStruct, typename="nav2_msgs::action::dds_::NavigateToPose_SendGoal_Request_"
):
    goal_id: UUID
    goal: NavigateToPoseGoal


def main() -> int:
    domain, robots = int(sys.argv[1]), sys.argv[2].split(",")
    closed = threading.Event()
    threading.Thread(target=lambda: (sys.stdin.read(), closed.set()), daemon=True).start()
    dp = DomainParticipant(domain)
    qos = Qos(
        Policy.Reliability.Reliable(duration(seconds=1)),
        Policy.History.KeepAll,
        Policy.Durability.Volatile,
    )
    readers = {}
    for r in robots:
        goals = Topic(dp, f"rq/{r}/navigate_to_pose/_action/send_goalRequest", SendGoalRequest)
        poses = Topic(dp, f"rt/{r}/pose", PoseStamped)
        readers[r] = (DataReader(dp, goals, qos=qos), DataReader(dp, poses, qos=qos))
    print("ready", file=sys.stderr, flush=True)
    out = {
        r: {"goals": [], "poses": 0, "pose_frames": [], "first": None, "last": None}
        for r in robots
    }
    last = False
    while not last:
        # One more round after stdin closed: what arrived meanwhile.
        last = closed.is_set()
        for r, (goals, poses) in readers.items():
            for g in goals.take(N=64):
                if isinstance(g, InvalidSample):
                    continue
                p = g.goal.pose
                out[r]["goals"].append(
                    {
                        "frame": p.header.frame_id,
                        "x": p.pose.position.x,
                        "y": p.pose.position.y,
                        "w": p.pose.orientation.w,
                        "behavior_tree": g.goal.behavior_tree,
                    }
                )
            for p in poses.take(N=256):
                if isinstance(p, InvalidSample):
                    continue
                o = out[r]
                o["poses"] += 1
                if p.header.frame_id not in o["pose_frames"]:
                    o["pose_frames"].append(p.header.frame_id)
                xy = [p.pose.position.x, p.pose.position.y]
                o["first"] = o["first"] or xy
                o["last"] = xy
        time.sleep(0.02)
    types = {
        "goal": SendGoalRequest.__idl_typename__,
        "pose": PoseStamped.__idl_typename__,
    }
    print(json.dumps({"types": types, "robots": out}), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
