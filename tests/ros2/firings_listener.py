#!/usr/bin/env python3
"""Subscribes to the gspn supervisor's firings with Eclipse Cyclone DDS (the PyPI
`cyclonedds` package) — a DDS implementation not written by us — and prints each firing as
one JSON line on stdout.

    firings_listener.py DOMAIN COUNT TIMEOUT_SECS

Prints `ready` on stderr once the reader exists; exits 0 after COUNT firings, 1 on timeout.
Set CYCLONEDDS_URI to the loopback-only configuration (tests/ros2/interop.rs does).
The IDL below is gspn_msgs/msg/Firing (ros2/gspn_msgs/msg/Firing.msg) under the DDS names
ROS 2 gives it.
"""

import json
import sys
import time
from dataclasses import dataclass

from cyclonedds.core import Policy, Qos
from cyclonedds.domain import DomainParticipant
from cyclonedds.idl import IdlStruct
from cyclonedds.idl.types import float64, int32, sequence, uint32, uint64
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
class Firing(IdlStruct, typename="gspn_msgs::msg::dds_::Firing_"):
    header: Header
    model_time: float64
    seq: uint64
    transition: str
    marking: sequence[uint32]
    robots: sequence[str]


def main() -> int:
    domain, count, timeout = int(sys.argv[1]), int(sys.argv[2]), float(sys.argv[3])
    dp = DomainParticipant(domain)
    topic = Topic(dp, "rt/gspn/firings", Firing)
    qos = Qos(
        Policy.Reliability.Reliable(duration(seconds=1)),
        Policy.History.KeepAll,
        Policy.Durability.Volatile,
    )
    reader = DataReader(dp, topic, qos=qos)
    print("ready", file=sys.stderr, flush=True)
    got = 0
    end = time.monotonic() + timeout
    while got < count and time.monotonic() < end:
        for f in reader.take(N=256):
            if isinstance(f, InvalidSample):
                # No valid data: the writer left (the instance has no writers). Say so and
                # keep waiting: a missing firing then shows as a count short at the timeout.
                print(f"after {got} firings: {f.sample_info.instance_state!r}", file=sys.stderr)
                continue
            got += 1
            print(
                json.dumps(
                    {
                        "seq": f.seq,
                        "transition": f.transition,
                        "marking": list(f.marking),
                        "robots": list(f.robots),
                        "model_time": f.model_time,
                        "stamp_ns": f.header.stamp.sec * 1_000_000_000 + f.header.stamp.nanosec,
                    }
                ),
                flush=True,
            )
        time.sleep(0.01)
    return 0 if got >= count else 1


if __name__ == "__main__":
    sys.exit(main())
