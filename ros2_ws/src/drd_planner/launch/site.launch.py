"""Launch the map server and the planner node on one site prior, and bring the planner to *active*.

::

    ros2 launch drd_planner site.launch.py                                # heli_lines: maps and planner
    ros2 launch drd_planner site.launch.py prior:=/path/my_site.npz namespace:=heli
    ros2 launch drd_planner site.launch.py autostart:=false               # planner stays unconfigured

Arguments:
- ``prior``: the site prior both nodes load (a ``corridors`` prior: a path or a shipped name; default
  ``heli_lines``): ``drd_map_server`` publishes its site as the latched ``terrain`` and ``obstacles``, the
  planner plans with it (its ``prior_paths``);
- ``config``: the planner's parameter file (default ``share/drd_planner/config/heli_wires.yaml``; its
  ``prior_paths`` and ``frame_id`` are replaced by this file's arguments);
- ``frame_id``: the planning frame of both nodes (default ``map``);
- ``namespace``: namespace of both nodes (the map topics are relative, so they meet inside it);
- ``autostart``: ``true`` (default) configures the planner, then activates it once it is *inactive*;
- ``log_level``: ``debug``, ``info`` (default), ``warn``, ``error``, ``fatal``.

The map server publishes once at start; its maps are latched (transient_local), so the planner gets them
whenever its subscriptions start (at ``activate``). The planner's lifecycle is driven as in
``planner.launch.py`` (launch events, which Jazzy's ``LifecycleNode`` action needs).
"""

from __future__ import annotations

from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, EmitEvent, RegisterEventHandler
from launch.conditions import IfCondition
from launch.events import matches_action
from launch.substitutions import LaunchConfiguration, PathJoinSubstitution
from launch_ros.actions import LifecycleNode, Node
from launch_ros.event_handlers import OnStateTransition
from launch_ros.events.lifecycle import ChangeState
from launch_ros.substitutions import FindPackageShare
from lifecycle_msgs.msg import Transition

PACKAGE = "drd_planner"
EXECUTABLE = "planner_node"
NODE_NAME = "drd_planner"
MAP_SERVER_EXECUTABLE = "drd_map_server"
MAP_SERVER_NAME = "drd_map_server"
DEFAULT_CONFIG = "heli_wires.yaml"
DEFAULT_PRIOR = "heli_lines"


def _transition(node: LifecycleNode, transition: int) -> EmitEvent:
    """The launch event asking ``node`` for a lifecycle ``transition``."""
    return EmitEvent(event=ChangeState(lifecycle_node_matcher=matches_action(node), transition_id=transition))


def generate_launch_description() -> LaunchDescription:
    """The launch description: six arguments, the map server, the planner and the planner's two transitions."""
    prior = LaunchConfiguration("prior")
    config = LaunchConfiguration("config")
    frame_id = LaunchConfiguration("frame_id")
    namespace = LaunchConfiguration("namespace")
    autostart = LaunchConfiguration("autostart")
    log_level = LaunchConfiguration("log_level")

    map_server = Node(
        package=PACKAGE,
        executable=MAP_SERVER_EXECUTABLE,
        name=MAP_SERVER_NAME,
        namespace=namespace,
        parameters=[{"prior": prior, "frame_id": frame_id}],
        ros_arguments=["--log-level", log_level],
        output="screen",
    )
    planner = LifecycleNode(
        package=PACKAGE,
        executable=EXECUTABLE,
        name=NODE_NAME,
        namespace=namespace,
        # The file first, then the overrides (later parameter sources win); [[prior]]: a list of one string.
        parameters=[config, {"prior_paths": [[prior]], "frame_id": frame_id, "autostart": False}],
        ros_arguments=["--log-level", log_level],
        output="screen",
    )
    configure = EmitEvent(
        event=ChangeState(
            lifecycle_node_matcher=matches_action(planner), transition_id=Transition.TRANSITION_CONFIGURE
        ),
        condition=IfCondition(autostart),
    )
    activate_when_inactive = RegisterEventHandler(
        OnStateTransition(
            target_lifecycle_node=planner,
            start_state="configuring",
            goal_state="inactive",
            entities=[_transition(planner, Transition.TRANSITION_ACTIVATE)],
        ),
        condition=IfCondition(autostart),
    )
    return LaunchDescription(
        [
            DeclareLaunchArgument(
                "prior", default_value=DEFAULT_PRIOR, description="site prior of both nodes (path or shipped name)"
            ),
            DeclareLaunchArgument(
                "config",
                default_value=PathJoinSubstitution([FindPackageShare(PACKAGE), "config", DEFAULT_CONFIG]),
                description="ROS 2 parameter file of the planner (prior_paths and frame_id replaced)",
            ),
            DeclareLaunchArgument("frame_id", default_value="map", description="planning frame of both nodes"),
            DeclareLaunchArgument("namespace", default_value="", description="namespace of both nodes"),
            DeclareLaunchArgument(
                "autostart",
                default_value="true",
                choices=["true", "false"],
                description="configure and activate the planner after it starts",
            ),
            DeclareLaunchArgument(
                "log_level",
                default_value="info",
                choices=["debug", "info", "warn", "error", "fatal"],
                description="logging level of both nodes",
            ),
            map_server,
            # Registered before the planner starts, so its first transition is never missed.
            activate_when_inactive,
            planner,
            configure,
        ]
    )
