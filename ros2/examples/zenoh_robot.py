#!/usr/bin/env python3
"""A gspn robot that is not gspn, over Zenoh: the PyPI `eclipse-zenoh` package (no ROS
installation, none of our code) serving the ExecPlace action of gspn_msgs
(ros2/gspn_msgs/action/ExecPlace.action) to a `plan-runner run --zenoh` supervisor, laid out
as rmw_zenoh lays out a ROS 2 action server (docs/zenoh.md).

    zenoh_robot.py --id R --router tcp/127.0.0.1:7447 [--domain 0] [--server exec_place]
                   [--delay 0.05]

For the action /R/<server> it declares three queryables, one per service of the action:

  <domain>/R/<server>/_action/send_goal/<type>/<hash>
  <domain>/R/<server>/_action/get_result/<type>/<hash>
  <domain>/R/<server>/_action/cancel_goal/<type>/<hash>

(any type and hash: the queryables end in `/**`), answers with CDR payloads (little endian,
header 00 01 00 00) and echoes each request's attachment (sequence number and client GID,
a fresh timestamp; zenoh-ext serialized), as rmw_zenoh's service servers do. Then it
declares its node's liveliness token, `@ros2_lv/<domain>/<zid>/0/0/NN/%/%R/gspn_robot`: the
supervisor counts the robot ready when it sees it. It leaves when the supervisor says on
`/gspn/run` that the run is over.

Its action: every goal takes --delay seconds, then succeeds with outcome DECIDE ("let
the supervisor decide": the policy, or the net's race). A cancel request ends the goal as
CANCELED. Each goal is logged on stderr (`goal PLACE agent A: started`, its target and
args when the plan gives the place some, `... succeeded`);
the last line says how many goals it served.
"""

import argparse
import json
import signal
import struct
import sys
import time

import zenoh
from zenoh.ext import Int64, UInt8, z_deserialize, z_serialize

# action_msgs/msg/GoalStatus values; action_msgs/srv/CancelGoal return codes.
EXECUTING, SUCCEEDED, CANCELED = 2, 4, 5
CANCEL_NONE, CANCEL_UNKNOWN_GOAL = 0, 2
# gspn_msgs/action/ExecPlace result outcomes; gspn_msgs/msg/RunState states.
FIRE, DECIDE, FAILED, OUTCOME_CANCELLED = 0, 1, 2, 3
RUN_OVER = 2
CDR_LE = b"\x00\x01\x00\x00"


class Cdr:
    """Little-endian CDR, alignment counted from the end of the encapsulation header."""

    def __init__(self, data: bytes = b""):
        self.buf = bytearray(data)
        self.pos = 0

    # -- reading
    def _align(self, n: int):
        self.pos += (-self.pos) % n

    def read(self, fmt: str, size: int):
        self._align(size)
        (v,) = struct.unpack_from("<" + fmt, self.buf, self.pos)
        self.pos += size
        return v

    def raw(self, n: int) -> bytes:
        b = bytes(self.buf[self.pos : self.pos + n])
        self.pos += n
        return b

    def string(self) -> str:
        n = self.read("I", 4)
        s = self.raw(n)
        return s[:-1].decode()

    def header(self) -> str:
        """std_msgs/Header: the stamp (skipped), then the frame id."""
        self.read("i", 4), self.read("I", 4)
        return self.string()

    def goal(self):
        """gspn_msgs/action/ExecPlace goal: place, agent, has_target, target
        (geometry_msgs/PoseStamped), args (diagnostic_msgs/KeyValue[])."""
        place, agent = self.string(), self.read("Q", 8)
        has_target = self.read("?", 1)
        frame = self.header()
        pose = [self.read("d", 8) for _ in range(7)]  # position xyz, orientation xyzw
        args = {}
        for _ in range(self.read("I", 4)):
            k = self.string()
            args[k] = self.string()
        target = (pose[0], pose[1], frame) if has_target else None
        return place, agent, target, args

    # -- writing
    def _pad(self, n: int):
        self.buf += b"\x00" * ((-len(self.buf)) % n)

    def put(self, fmt: str, size: int, v) -> "Cdr":
        self._pad(size)
        self.buf += struct.pack("<" + fmt, v)
        return self

    def put_raw(self, b: bytes) -> "Cdr":
        self.buf += b
        return self

    def put_string(self, s: str) -> "Cdr":
        b = s.encode() + b"\x00"
        return self.put("I", 4, len(b)).put_raw(b)

    def put_time(self, ns: int) -> "Cdr":
        return self.put("i", 4, ns // 1_000_000_000).put("I", 4, ns % 1_000_000_000)


def body(payload) -> Cdr:
    """The CDR body of a request (its header must be little-endian plain CDR)."""
    b = payload.to_bytes() if payload is not None else b""
    if b[:4] != CDR_LE:
        raise ValueError(f"not little-endian CDR: {b[:4]!r}")
    return Cdr(b[4:])


class Goal:
    def __init__(self, goal_id: bytes, place: str, agent: int, ends: float):
        self.goal_id, self.place, self.agent, self.ends = goal_id, place, agent, ends
        self.status = EXECUTING
        self.stamp = time.time_ns()
        self.ended_at = None
        self.waiting = []  # get_result queries to answer when the goal ends


class ExecPlaceServer:
    """The ExecPlace action at /<robot>/<server>, as three queryables."""

    def __init__(self, session, domain: int, robot: str, server: str, delay: float):
        base = f"{domain}/{robot}/{server}/_action"
        self.delay = delay
        self.goals = {}  # goal id -> Goal
        self.served = self.cancelled = 0
        self.send_goal = session.declare_queryable(f"{base}/send_goal/**")
        self.get_result = session.declare_queryable(f"{base}/get_result/**")
        self.cancel_goal = session.declare_queryable(f"{base}/cancel_goal/**")

    @staticmethod
    def reply(query, cdr: Cdr):
        """Answers `query`, echoing its attachment's sequence number and client GID."""
        att = None
        if query.attachment is not None:
            seq, _stamp, gid = z_deserialize(tuple[Int64, Int64, list[UInt8]], query.attachment)
            att = z_serialize((Int64(seq), Int64(time.time_ns()), [UInt8(g) for g in gid]))
        query.reply(query.key_expr, CDR_LE + bytes(cdr.buf), attachment=att)
        query.drop()

    @staticmethod
    def result(status: int, outcome: int, message: str) -> Cdr:
        """status (int8), then ExecPlace_Result {outcome (uint8), transition, message}."""
        return Cdr().put("b", 1, status).put("B", 1, outcome).put_string("").put_string(message)

    def answer(self, g: Goal):
        for q in g.waiting:
            if g.status == SUCCEEDED:
                self.reply(q, self.result(g.status, DECIDE, "python robot"))
            else:
                self.reply(q, self.result(g.status, OUTCOME_CANCELLED, "cancelled"))
        g.waiting = []

    def step(self) -> bool:
        """Serves what arrived and ends what is due; True when something happened."""
        busy = False
        while (q := self.send_goal.try_recv()) is not None:
            busy = True
            c = body(q.payload)
            goal_id = c.raw(16)
            place, agent, target, args = c.goal()
            g = Goal(goal_id, place, agent, time.monotonic() + self.delay)
            self.goals[goal_id] = g
            self.served += 1
            log(f"goal {place} agent {agent}: started")
            if target or args:
                where = f"target ({target[0]:g}, {target[1]:g}) in {target[2]}" if target else "no target"
                kv = " ".join(f"{k}={v}" for k, v in sorted(args.items()))
                log(f"goal {place} agent {agent}: {where}, args {kv}")
            # accepted (bool), stamp (builtin_interfaces/Time).
            self.reply(q, Cdr().put("?", 1, True).put_time(g.stamp))
        while (q := self.get_result.try_recv()) is not None:
            busy = True
            goal_id = body(q.payload).raw(16)
            g = self.goals.get(goal_id)
            if g is None:
                # Unknown goal: ROS 2 answers UNKNOWN (0) at once.
                self.reply(q, self.result(0, FAILED, "unknown goal"))
                continue
            g.waiting.append(q)
            if g.status != EXECUTING:
                self.answer(g)
        while (q := self.cancel_goal.try_recv()) is not None:
            busy = True
            goal_id = body(q.payload).raw(16)
            g = self.goals.get(goal_id)
            out = Cdr()
            if g is not None and g.status == EXECUTING:
                g.status, g.ended_at = CANCELED, time.monotonic()
                self.cancelled += 1
                log(f"goal {g.place} agent {g.agent}: cancelled")
                self.answer(g)
                # return_code, then goals_canceling: one GoalInfo {uuid, stamp}.
                out.put("b", 1, CANCEL_NONE).put("I", 4, 1).put_raw(goal_id).put_time(g.stamp)
            else:
                out.put("b", 1, CANCEL_UNKNOWN_GOAL).put("I", 4, 0)
            self.reply(q, out)
        t = time.monotonic()
        for g in self.goals.values():
            if g.status == EXECUTING and t >= g.ends:
                g.status, g.ended_at = SUCCEEDED, t
                busy = True
                log(f"goal {g.place} agent {g.agent}: succeeded")
                self.answer(g)
        # Forget goals long over (their results were asked for by now).
        for k in [k for k, g in self.goals.items() if g.ended_at and t - g.ended_at > 60.0]:
            del self.goals[k]
        return busy


def log(msg: str):
    print(f"python robot {ROBOT}: {msg}", file=sys.stderr, flush=True)


ROBOT = "?"


def main() -> int:
    global ROBOT
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--id", required=True, help="the robot's id, as in the plan's robots")
    ap.add_argument("--router", default="tcp/127.0.0.1:7447", help="the Zenoh router")
    ap.add_argument("--domain", type=int, default=0, help="the ROS domain id")
    ap.add_argument("--server", action="append", help="ExecPlace servers (default exec_place)")
    ap.add_argument("--delay", type=float, default=0.05, help="seconds each goal takes")
    args = ap.parse_args()
    ROBOT = args.id
    stop = []
    signal.signal(signal.SIGTERM, lambda *_: stop.append("SIGTERM"))
    signal.signal(signal.SIGINT, lambda *_: stop.append("SIGINT"))

    conf = zenoh.Config()
    conf.insert_json5("mode", '"client"')
    conf.insert_json5("connect/endpoints", json.dumps([args.router]))
    conf.insert_json5("scouting/multicast/enabled", "false")
    with zenoh.open(conf) as session:
        servers = [
            ExecPlaceServer(session, args.domain, args.id, s, args.delay)
            for s in (args.server or ["exec_place"])
        ]
        run = session.declare_subscriber(f"{args.domain}/gspn/run/**")
        # Last: the token says the robot is ready.
        token = session.liveliness().declare_token(
            f"@ros2_lv/{args.domain}/{session.zid()}/0/0/NN/%/%{args.id}/gspn_robot"
        )
        log(f"serving {', '.join('/' + args.id + '/' + s for s in (args.server or ['exec_place']))} via {args.router}")
        why = None
        while why is None:
            if stop:
                why = stop[0]
                break
            busy = False
            for s in servers:
                busy |= s.step()
            while (sample := run.try_recv()) is not None:
                # gspn_msgs/RunState: state (uint8), stopped (string), firings (uint64).
                c = body(sample.payload)
                state, stopped, firings = c.read("B", 1), c.string(), c.read("Q", 8)
                if state == RUN_OVER:
                    why = f"the supervisor's run is over ({stopped} after {firings} firings)"
            if not busy:
                time.sleep(0.002)
        token.undeclare()
        log(f"{why}: leaving")
        served = sum(s.served for s in servers)
        cancelled = sum(s.cancelled for s in servers)
        log(f"{served} goals served, {cancelled} cancelled")
    return 0


if __name__ == "__main__":
    sys.exit(main())
