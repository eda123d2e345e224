#!/usr/bin/env python3
"""Reads an MCAP file with the PyPI `mcap` and `mcap-ros2-support` readers (not ours) and
prints what it holds as one JSON document on stdout:

    mcap_reader.py FILE.mcap

{"topics": {topic: {"schema": name, "encoding": enc, "count": n}},
 "firings": [[seq, transition, robots, model_time, stamp_ns], ...],
 "poses": {topic: {"count": n, "frames": [...], "first": [x, y, z, w]}},
 "markings": [[seq, tokens], ...]}
"""
import json
import sys

from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory


def main() -> int:
    topics, firings, poses, markings = {}, [], {}, []
    with open(sys.argv[1], "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        for schema, channel, message, msg in reader.iter_decoded_messages():
            t = topics.setdefault(
                channel.topic,
                {"schema": schema.name, "encoding": channel.message_encoding, "count": 0},
            )
            t["count"] += 1
            if schema.name == "gspn_msgs/msg/Firing":
                stamp = msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec
                firings.append(
                    [msg.seq, msg.transition, list(msg.robots), msg.model_time, stamp]
                )
            elif schema.name == "gspn_msgs/msg/Marking":
                markings.append([msg.seq, list(msg.tokens)])
            elif schema.name == "geometry_msgs/msg/PoseStamped":
                p = poses.setdefault(channel.topic, {"count": 0, "frames": [], "first": None})
                p["count"] += 1
                if msg.header.frame_id not in p["frames"]:
                    p["frames"].append(msg.header.frame_id)
                if p["first"] is None:
                    q = msg.pose.orientation
                    p["first"] = [msg.pose.position.x, msg.pose.position.y, q.z, q.w]
    json.dump(
        {"topics": topics, "firings": firings, "poses": poses, "markings": markings},
        sys.stdout,
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
