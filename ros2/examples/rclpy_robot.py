#!/usr/bin/env python3
"""A gspn robot in rclpy: nothing but an ExecPlace action server (no gspn code, no heartbeat).

    ros2 run <your_pkg> rclpy_robot.py --ros-args -r __node:=r1   # serves /r1/exec_place

Needs ROS 2 (Humble or later) and gspn_msgs (ros2/gspn_msgs) built in your workspace. The
supervisor finds the server through DDS discovery and notices when it goes (docs/ros2.md,
"rclpy robot in 5 minutes"). Replace `act` with what your robot does for each place.
"""
import time

import rclpy
from rclpy.action import ActionServer, CancelResponse
from rclpy.executors import MultiThreadedExecutor
from rclpy.node import Node

from gspn_msgs.action import ExecPlace


class Robot(Node):
    def __init__(self):
        super().__init__("r1")  # the robot's id: its server is /<node name>/exec_place
        ActionServer(self, ExecPlace, f"/{self.get_name()}/exec_place", self.act,
                     cancel_callback=lambda _goal: CancelResponse.ACCEPT)

    def act(self, handle):
        goal = handle.request
        args = {kv.key: kv.value for kv in goal.args}
        self.get_logger().info(f"{goal.place} for agent {goal.agent} {args}")
        time.sleep(float(args.get("seconds", "0.5")))  # the place's work goes here
        result = ExecPlace.Result()
        if handle.is_cancel_requested:
            handle.canceled()
            result.outcome = ExecPlace.Result.CANCELLED
            return result
        handle.succeed()
        result.outcome = ExecPlace.Result.DECIDE  # or FIRE with result.transition = "t3"
        result.message = "done"
        return result


def main():
    rclpy.init()
    rclpy.spin(Robot(), executor=MultiThreadedExecutor())


if __name__ == "__main__":
    main()
