"""Launch a gspn plan on ROS 2: a supervisor and N robots in one namespace.

    ros2 launch ros2/launch/patrol.launch.py namespace:=/fleet_a robots:=3 \
        plan:=plans/temperature_patrol_ros2.toml

Each process is `plan-runner` (built with `--features ros2`, on PATH) given the namespace and
its node name with --ros-args, so two launches with different namespaces share a domain
without a crossed message (docs/ros2.md, "Names as ROS does them"). Swap the robots for your
own ExecPlace servers (ros2/examples/rclpy_robot.py) started under the same namespace.
"""

from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, ExecuteProcess, OpaqueFunction
from launch.substitutions import LaunchConfiguration


def processes(context):
    ns = LaunchConfiguration("namespace").perform(context)
    plan = LaunchConfiguration("plan").perform(context)
    n = int(LaunchConfiguration("robots").perform(context))
    ros_args = ["--ros-args", "-r", f"__ns:={ns}"]
    out = [
        ExecuteProcess(
            cmd=["plan-runner", "run", plan, "--max-firings", "1000", *ros_args,
                 "-r", "__node:=supervisor"],
            output="screen",
        )
    ]
    for i in range(1, n + 1):
        out.append(
            ExecuteProcess(
                cmd=["plan-runner", "robot", "--plan", plan, *ros_args, "-r", f"__node:=r{i}"],
                output="screen",
            )
        )
    return out


def generate_launch_description():
    return LaunchDescription(
        [
            DeclareLaunchArgument("namespace", default_value="/fleet_a"),
            DeclareLaunchArgument("plan", default_value="plans/temperature_patrol_ros2.toml"),
            DeclareLaunchArgument("robots", default_value="3"),
            OpaqueFunction(function=processes),
        ]
    )
