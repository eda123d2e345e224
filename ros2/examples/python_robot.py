#!/usr/bin/env python3
"""A gspn robot that is not gspn: Eclipse Cyclone DDS (the PyPI `cyclonedds` package, no ROS
installation) serving the ExecPlace action of gspn_msgs (ros2/gspn_msgs/action/ExecPlace.action)
to a `plan-runner run` supervisor.

    python_robot.py --id R --domain D [--server exec_place] [--delay 0.05]

It speaks the DDS topics a ROS 2 action server uses, for the action /R/<server>:

  rq/R/<server>/_action/send_goalRequest   -> rr/R/<server>/_action/send_goalReply
  rq/R/<server>/_action/get_resultRequest  -> rr/R/<server>/_action/get_resultReply
  rq/R/<server>/_action/cancel_goalRequest -> rr/R/<server>/_action/cancel_goalReply
  rt/R/<server>/_action/feedback, rt/R/<server>/_action/status

with the request ids in a 16-byte header before each request and reply, as ROS 2's
rmw_cyclonedds_cpp writes them (the plan's `[ros2] service_mapping = "cyclone"`). Types are
gspn_msgs interfaces v2 (tests/ros2/interfaces.rs checks them against the .msg files). It
publishes a gspn heartbeat on rt/gspn/heartbeat unless `--heartbeat 0` (then the supervisor
watches it through DDS discovery, as any ROS 2 action server), and leaves when the supervisor
says on rt/gspn/run that the run is over.

Its action: every goal takes --delay seconds, then succeeds with an empty transition ("let
the supervisor decide": the policy, or the net's race). A cancel request ends the goal as
CANCELED. Each goal is logged on stderr (`goal PLACE agent A: started`, `... succeeded`);
the last line says how many goals it served.

On loopback only, set CYCLONEDDS_URI as docs/ros2.md shows.
"""

import argparse
import signal
import sys
import time
from dataclasses import dataclass

from cyclonedds.core import Policy, Qos
from cyclonedds.domain import DomainParticipant
from cyclonedds.idl import IdlStruct
from cyclonedds.idl.types import array, float64, int8, int32, sequence, uint8, uint32, uint64
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration

# action_msgs/msg/GoalStatus values.
SUCCEEDED, CANCELED, EXECUTING = 4, 5, 2
# gspn_msgs/action/ExecPlace result outcomes and gspn_msgs/msg/RunState states (v2).
FIRE, DECIDE, FAILED, CANCELLED = 0, 1, 2, 3
RUN_OVER = 2


@dataclass
class Time(IdlStruct, typename="builtin_interfaces::msg::dds_::Time_"):
    sec: int32
    nanosec: uint32


@dataclass
class UUID(IdlStruct, typename="unique_identifier_msgs::msg::dds_::UUID_"):
    uuid: array[uint8, 16]


@dataclass
class GoalInfo(IdlStruct, typename="action_msgs::msg::dds_::GoalInfo_"):
    goal_id: UUID
    stamp: Time


@dataclass
class GoalStatus(IdlStruct, typename="action_msgs::msg::dds_::GoalStatus_"):
    goal_info: GoalInfo
    status: int8


@dataclass
class GoalStatusArray(IdlStruct, typename="action_msgs::msg::dds_::GoalStatusArray_"):
    status_list: sequence[GoalStatus]


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
class KeyValue(IdlStruct, typename="diagnostic_msgs::msg::dds_::KeyValue_"):
    key: str
    value: str


@dataclass
class Goal(IdlStruct, typename="gspn_msgs::action::dds_::ExecPlace_Goal_"):
    place: str
    agent: uint64
    has_target: bool
    target: PoseStamped
    args: sequence[KeyValue]


@dataclass
class Result(IdlStruct, typename="gspn_msgs::action::dds_::ExecPlace_Result_"):
    outcome: uint8
    transition: str
    message: str


@dataclass
class Feedback(IdlStruct, typename="gspn_msgs::action::dds_::ExecPlace_Feedback_"):
    elapsed: float64


# Requests and replies: the rmw_cyclonedds_cpp header (the client's GUID, last 8 bytes, and
# the request's sequence number) and then the ROS 2 message. A reply repeats its request's
# header, which is how the client pairs them.
@dataclass
class SendGoalRequest(IdlStruct, typename="gspn_msgs::action::dds_::ExecPlace_SendGoal_Request_"):
    client: array[uint8, 8]
    seq_high: int32
    seq_low: uint32
    goal_id: UUID
    goal: Goal


@dataclass
class SendGoalReply(IdlStruct, typename="gspn_msgs::action::dds_::ExecPlace_SendGoal_Response_"):
    client: array[uint8, 8]
    seq_high: int32
    seq_low: uint32
    accepted: bool
    stamp: Time


@dataclass
class GetResultRequest(
    IdlStruct, typename="gspn_msgs::action::dds_::ExecPlace_GetResult_Request_"
):
    client: array[uint8, 8]
    seq_high: int32
    seq_low: uint32
    goal_id: UUID


@dataclass
class GetResultReply(
    IdlStruct, typename="gspn_msgs::action::dds_::ExecPlace_GetResult_Response_"
):
    client: array[uint8, 8]
    seq_high: int32
    seq_low: uint32
    status: int8
    result: Result


@dataclass
class CancelRequest(IdlStruct, typename="action_msgs::srv::dds_::CancelGoal_Request_"):
    client: array[uint8, 8]
    seq_high: int32
    seq_low: uint32
    goal_info: GoalInfo


@dataclass
class CancelReply(IdlStruct, typename="action_msgs::srv::dds_::CancelGoal_Response_"):
    client: array[uint8, 8]
    seq_high: int32
    seq_low: uint32
    return_code: int8
    goals_canceling: sequence[GoalInfo]


@dataclass
class FeedbackMessage(
    IdlStruct, typename="gspn_msgs::action::dds_::ExecPlace_FeedbackMessage_"
):
    goal_id: UUID
    feedback: Feedback


@dataclass
class Heartbeat(IdlStruct, typename="gspn_msgs::msg::dds_::Heartbeat_"):
    robot: str
    seq: uint64


@dataclass
class RunState(IdlStruct, typename="gspn_msgs::msg::dds_::RunState_"):
    state: uint8
    stopped: str
    firings: uint64


def now() -> Time:
    t = time.time_ns()
    return Time(sec=t // 1_000_000_000, nanosec=t % 1_000_000_000)


RELIABLE = Policy.Reliability.Reliable(duration(seconds=1))
SERVICE = Qos(RELIABLE, Policy.History.KeepAll, Policy.Durability.Volatile)
STATUS = Qos(RELIABLE, Policy.History.KeepLast(1), Policy.Durability.TransientLocal)
FEEDBACK = Qos(RELIABLE, Policy.History.KeepLast(1), Policy.Durability.Volatile)
HEARTBEAT = Qos(Policy.Reliability.BestEffort, Policy.History.KeepLast(64))
RUN = Qos(RELIABLE, Policy.History.KeepLast(1), Policy.Durability.TransientLocal)


class GoalState:
    def __init__(self, info: GoalInfo, goal: Goal, ends: float):
        self.info, self.goal, self.ends = info, goal, ends
        self.started = time.monotonic()
        self.status = EXECUTING
        self.ended_at = None
        self.result_requests = []  # headers of get_result requests waiting for the end
        self.last_feedback = self.started


class ExecPlaceServer:
    """The ExecPlace action at /<robot>/<server>."""

    def __init__(self, dp, robot: str, server: str, delay: float, namespace: str = ""):
        base = f"{namespace}/{robot}/{server}/_action".lstrip("/")
        self.delay = delay
        self.goals = {}  # bytes(uuid) -> GoalState

        def service(name, req_type, rep_type):
            rq = Topic(dp, f"rq/{base}/{name}Request", req_type)
            rr = Topic(dp, f"rr/{base}/{name}Reply", rep_type)
            return DataReader(dp, rq, qos=SERVICE), DataWriter(dp, rr, qos=SERVICE)

        self.goal_rq, self.goal_rr = service("send_goal", SendGoalRequest, SendGoalReply)
        self.result_rq, self.result_rr = service("get_result", GetResultRequest, GetResultReply)
        self.cancel_rq, self.cancel_rr = service("cancel_goal", CancelRequest, CancelReply)
        self.status = DataWriter(
            dp, Topic(dp, f"rt/{base}/status", GoalStatusArray), qos=STATUS
        )
        self.feedback = DataWriter(
            dp, Topic(dp, f"rt/{base}/feedback", FeedbackMessage), qos=FEEDBACK
        )
        self.served = 0
        self.cancelled = 0

    def publish_status(self):
        recent = [
            g
            for g in self.goals.values()
            if g.ended_at is None or time.monotonic() - g.ended_at < 10.0
        ]
        self.status.write(
            GoalStatusArray(
                status_list=[GoalStatus(goal_info=g.info, status=g.status) for g in recent]
            )
        )

    def answer_results(self, g: GoalState):
        if g.status == SUCCEEDED:
            result = Result(outcome=DECIDE, transition="", message="done")
        else:
            result = Result(outcome=CANCELLED, transition="", message="cancelled")
        for h in g.result_requests:
            self.result_rr.write(GetResultReply(*h, status=g.status, result=result))
        g.result_requests = []

    def step(self) -> bool:
        """Serves what arrived and ends what is due; True when something happened."""
        busy = False
        changed = False
        for r in self.goal_rq.take(N=64):
            if not isinstance(r, SendGoalRequest):
                continue
            busy = changed = True
            info = GoalInfo(goal_id=r.goal_id, stamp=now())
            g = GoalState(info, r.goal, time.monotonic() + self.delay)
            self.goals[bytes(r.goal_id.uuid)] = g
            self.served += 1
            where = ""
            if r.goal.has_target:
                pos = r.goal.target.pose.position
                where = f" target ({pos.x:g}, {pos.y:g}) in {r.goal.target.header.frame_id}"
            extra = "".join(f" {a.key}={a.value}" for a in r.goal.args)
            log(f"goal {r.goal.place} agent {r.goal.agent}: started{where}{extra}")
            self.goal_rr.write(
                SendGoalReply(r.client, r.seq_high, r.seq_low, accepted=True, stamp=info.stamp)
            )
        for r in self.result_rq.take(N=64):
            if not isinstance(r, GetResultRequest):
                continue
            busy = True
            header = (r.client, r.seq_high, r.seq_low)
            g = self.goals.get(bytes(r.goal_id.uuid))
            if g is None:
                # Unknown goal: ROS 2 answers UNKNOWN (0) at once.
                self.result_rr.write(
                    GetResultReply(*header, status=0, result=Result(FAILED, "", "unknown goal"))
                )
                continue
            g.result_requests.append(header)
            if g.status != EXECUTING:
                self.answer_results(g)
        for r in self.cancel_rq.take(N=64):
            if not isinstance(r, CancelRequest):
                continue
            busy = changed = True
            g = self.goals.get(bytes(r.goal_info.goal_id.uuid))
            canceling = []
            if g is not None and g.status == EXECUTING:
                g.status, g.ended_at = CANCELED, time.monotonic()
                self.cancelled += 1
                canceling.append(g.info)
                log(f"goal {g.goal.place} agent {g.goal.agent}: cancelled")
                self.answer_results(g)
            # return_code 0 = ERROR_NONE, 2 = ERROR_UNKNOWN_GOAL_ID
            code = 0 if canceling else 2
            self.cancel_rr.write(
                CancelReply(r.client, r.seq_high, r.seq_low, code, canceling)
            )
        t = time.monotonic()
        for g in self.goals.values():
            if g.status != EXECUTING:
                continue
            if t >= g.ends:
                g.status, g.ended_at = SUCCEEDED, t
                changed = True
                log(f"goal {g.goal.place} agent {g.goal.agent}: succeeded")
                self.answer_results(g)
            elif t - g.last_feedback >= 1.0:
                g.last_feedback = t
                self.feedback.write(
                    FeedbackMessage(goal_id=g.info.goal_id, feedback=Feedback(t - g.started))
                )
        if changed:
            self.publish_status()
        # Forget goals long over (their results were asked for by now).
        for k in [k for k, g in self.goals.items() if g.ended_at and t - g.ended_at > 60.0]:
            del self.goals[k]
        return busy or changed


def log(msg: str):
    print(f"python robot {ROBOT}: {msg}", file=sys.stderr, flush=True)


ROBOT = "?"


def main() -> int:
    global ROBOT
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--id", required=True, help="the robot's id, as in the plan's robots")
    ap.add_argument("--domain", type=int, default=0, help="the DDS domain id")
    ap.add_argument("--server", action="append", help="ExecPlace servers (default exec_place)")
    ap.add_argument("--delay", type=float, default=0.05, help="seconds each goal takes")
    ap.add_argument(
        "--namespace",
        default="",
        help="the run's namespace, as the supervisor's --ros-args -r __ns:=/NS (default: none)",
    )
    ap.add_argument(
        "--heartbeat",
        type=float,
        default=0.1,
        help="seconds between gspn heartbeats; 0 = none (the supervisor then watches the "
        "action server through DDS discovery)",
    )
    args = ap.parse_args()
    ROBOT = args.id
    stop = []
    signal.signal(signal.SIGTERM, lambda *_: stop.append("SIGTERM"))
    signal.signal(signal.SIGINT, lambda *_: stop.append("SIGINT"))

    dp = DomainParticipant(args.domain)
    ns = args.namespace.rstrip("/")
    servers = [
        ExecPlaceServer(dp, args.id, s, args.delay, ns) for s in args.server or ["exec_place"]
    ]
    beat = None
    if args.heartbeat > 0:
        beat = DataWriter(dp, Topic(dp, f"rt{ns}/gspn/heartbeat", Heartbeat), qos=HEARTBEAT)
    run = DataReader(dp, Topic(dp, f"rt{ns}/gspn/run", RunState), qos=RUN)
    log(f"serving {', '.join(args.server or ['exec_place'])} on domain {args.domain}")

    seq, next_beat, over = 0, 0.0, None
    while not stop and over is None:
        t = time.monotonic()
        if beat is not None and t >= next_beat:
            beat.write(Heartbeat(robot=args.id, seq=seq))
            seq, next_beat = seq + 1, t + args.heartbeat
        busy = False
        for s in servers:
            busy |= s.step()
        for r in run.take(N=8):
            if isinstance(r, RunState) and r.state == RUN_OVER:
                over = f"{r.stopped} after {r.firings} firings"
        if not busy:
            time.sleep(0.002)
    # Leaving: cancel what still runs, so a waiting supervisor hears of it.
    for s in servers:
        for g in s.goals.values():
            if g.status == EXECUTING:
                g.status, g.ended_at = CANCELED, time.monotonic()
                s.cancelled += 1
                s.answer_results(g)
        s.publish_status()
    if over is not None:
        log(f"the supervisor's run is over ({over}): leaving")
    served = sum(s.served for s in servers)
    cancelled = sum(s.cancelled for s in servers)
    log(f"{served} goals, {cancelled} cancelled")
    return 0


if __name__ == "__main__":
    sys.exit(main())
