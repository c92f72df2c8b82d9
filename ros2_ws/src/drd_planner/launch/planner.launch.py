"""Launch the ``drd_planner`` lifecycle node and bring it to *active*.

::

    ros2 launch drd_planner planner.launch.py                        # helicopter, Wires (default config)
    ros2 launch drd_planner planner.launch.py config:=/path/arm_table_clutter.yaml namespace:=arm
    ros2 launch drd_planner planner.launch.py autostart:=false       # stay unconfigured; use ros2 lifecycle

Arguments:
- ``config``: ROS 2 parameter file (default ``share/drd_planner/config/heli_wires.yaml``);
- ``namespace``: node namespace (default none; every topic of the node is relative to it);
- ``autostart``: ``true`` (default) configures the node, then activates it once it is *inactive*;
- ``log_level``: ``debug``, ``info`` (default), ``warn``, ``error``, ``fatal``.

The transitions are launch events (``ChangeState``), so they work on Jazzy, whose ``LifecycleNode``
action has no ``autostart`` argument (that arrived in launch_ros 0.28, Kilted). The node's own
``autostart`` parameter is forced to false here so that only the launch file drives the lifecycle.
A failed ``configure`` (a bad prior file, say) leaves the node up and *unconfigured* with the reason in
its log and on ``/diagnostics``; nothing is activated.
"""

from __future__ import annotations

from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, EmitEvent, RegisterEventHandler
from launch.conditions import IfCondition
from launch.events import matches_action
from launch.substitutions import LaunchConfiguration, PathJoinSubstitution
from launch_ros.actions import LifecycleNode
from launch_ros.event_handlers import OnStateTransition
from launch_ros.events.lifecycle import ChangeState
from launch_ros.substitutions import FindPackageShare
from lifecycle_msgs.msg import Transition

PACKAGE = "drd_planner"
EXECUTABLE = "planner_node"
NODE_NAME = "drd_planner"
DEFAULT_CONFIG = "heli_wires.yaml"


def generate_launch_description() -> LaunchDescription:
    """The launch description: four arguments, the lifecycle node, and its two automatic transitions."""
    config = LaunchConfiguration("config")
    namespace = LaunchConfiguration("namespace")
    autostart = LaunchConfiguration("autostart")
    log_level = LaunchConfiguration("log_level")

    node = LifecycleNode(
        package=PACKAGE,
        executable=EXECUTABLE,
        name=NODE_NAME,
        namespace=namespace,
        # The file first, then the override: later parameter sources win.
        parameters=[config, {"autostart": False}],
        ros_arguments=["--log-level", log_level],
        output="screen",
    )
    configure = EmitEvent(
        event=ChangeState(lifecycle_node_matcher=matches_action(node), transition_id=Transition.TRANSITION_CONFIGURE),
        condition=IfCondition(autostart),
    )
    activate_when_inactive = RegisterEventHandler(
        OnStateTransition(
            target_lifecycle_node=node,
            start_state="configuring",
            goal_state="inactive",
            entities=[
                EmitEvent(
                    event=ChangeState(
                        lifecycle_node_matcher=matches_action(node),
                        transition_id=Transition.TRANSITION_ACTIVATE,
                    )
                )
            ],
        ),
        condition=IfCondition(autostart),
    )
    return LaunchDescription(
        [
            DeclareLaunchArgument(
                "config",
                default_value=PathJoinSubstitution([FindPackageShare(PACKAGE), "config", DEFAULT_CONFIG]),
                description="ROS 2 parameter file of the node",
            ),
            DeclareLaunchArgument("namespace", default_value="", description="namespace of the node"),
            DeclareLaunchArgument(
                "autostart",
                default_value="true",
                choices=["true", "false"],
                description="configure and activate the node after it starts",
            ),
            DeclareLaunchArgument(
                "log_level",
                default_value="info",
                choices=["debug", "info", "warn", "error", "fatal"],
                description="logging level of the node",
            ),
            # Registered before the node starts, so the first transition is never missed.
            activate_when_inactive,
            node,
            configure,
        ]
    )
