"""MoveIt's interface on the planner node: the scene topic and ``plan_kinematic_path``.

- ``monitored_planning_scene`` (``moveit_msgs/msg/PlanningScene``, full scenes and diffs; reliable, volatile, as
  MoveIt's planning scene monitor publishes it) is subscribed on the planner node itself, so a scene is
  applied on the node's executor in order with its other maps
  (:meth:`~drd_planner.planning.map_store.MapStore.apply_planning_scene`; an octomap is refused and says why).
- ``plan_kinematic_path`` (``moveit_msgs/srv/GetMotionPlan``) is served by a plain companion node
  ``<node name>_moveit`` in the planner's namespace with an executor thread of its own (a plan never blocks
  the planner node's executor): start state and joint goal constraints
  (:mod:`~drd_planner.planning.moveit_plan`) -> the arm prior's plan on the current maps, every edge checked
  free, as a ``moveit_msgs/RobotTrajectory`` with ``time_from_start``, and MoveIt's error code.

The interfaces come from ``moveit_msgs``: a ROS install's where it is importable, else the subset
``scripts/tools/build_moveit_msgs.sh`` builds into the venv (``scripts/run.sh`` runs it). Without either, or without
an arm prior, the node runs without MoveIt's interface and says why.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from typing import Any

import rclpy
from builtin_interfaces.msg import Duration
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from trajectory_msgs.msg import JointTrajectoryPoint

from drd_planner.planning.moveit_plan import MoveItError, moveit_error, read_motion_request, timed_waypoints
from drd_planner.planning.service import PlannerService

__all__ = ["SCENE_QOS", "SCENE_TOPIC", "SERVICE_NAME", "MoveItHost", "duration_of", "moveit_interfaces"]

#: The scene topic and the service, relative to the node's namespace (MoveIt's move_group names).
SCENE_TOPIC = "monitored_planning_scene"
SERVICE_NAME = "plan_kinematic_path"
#: QoS of the scene subscription (MoveIt publishes scenes reliable and volatile).
SCENE_QOS = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.VOLATILE)
#: Seconds :meth:`MoveItHost.stop` waits for a running callback.
STOP_WAIT_S = 5.0


def moveit_interfaces() -> tuple[Any, Any]:
    """``(moveit_msgs.msg.PlanningScene, moveit_msgs.srv.GetMotionPlan)`` (ImportError: not importable)."""
    from moveit_msgs.msg import PlanningScene  # optional: a ROS install's, or the venv's
    from moveit_msgs.srv import GetMotionPlan

    return PlanningScene, GetMotionPlan


def duration_of(seconds: float) -> Duration:
    """A ``builtin_interfaces/Duration`` of ``seconds`` (>= 0)."""
    ns = round(max(seconds, 0.0) * 1e9)
    return Duration(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)


class MoveItHost:
    """The scene subscription and the companion node serving ``plan_kinematic_path`` (module docstring).

    Use :meth:`start`; :meth:`stop` removes both.
    """

    def __init__(self, planner: Any, node: Any, service: PlannerService, report: Callable[[str], None]) -> None:
        self.planner = planner
        self.node = node
        self.subscription: Any = None
        self._service = service
        self._report = report
        self._executor = SingleThreadedExecutor(context=planner.context)
        self._thread = threading.Thread(target=self._spin, name="drd_planner-moveit", daemon=True)

    @classmethod
    def start(
        cls,
        planner: Any,
        service: PlannerService,
        *,
        on_scene: Callable[[Any], None],
        report: Callable[[str], None],
    ) -> MoveItHost | None:
        """Subscribe ``on_scene`` to the scenes and offer ``plan_kinematic_path`` (None: off, logged why)."""
        try:
            scene_type, service_type = moveit_interfaces()
        except ImportError as exc:
            planner.get_logger().warning(
                f"MoveIt interface off ({SCENE_TOPIC}, {SERVICE_NAME}): moveit_msgs is not importable ({exc}); "
                "scripts/tools/build_moveit_msgs.sh builds it into the venv"
            )
            return None
        if service.joint_goal_session is None:
            planner.get_logger().info(f"MoveIt interface off ({SCENE_TOPIC}, {SERVICE_NAME}): no arm prior loaded")
            return None
        node = rclpy.create_node(
            f"{planner.get_name()}_moveit",
            namespace=planner.get_namespace(),
            context=planner.context,
            use_global_arguments=False,  # a ``__node:=`` remap of the planner must not rename this one too
            start_parameter_services=False,
        )
        host = cls(planner, node, service, report)
        host.subscription = planner.create_subscription(scene_type, SCENE_TOPIC, on_scene, SCENE_QOS)
        server = node.create_service(service_type, SERVICE_NAME, host._on_plan)
        host._executor.add_node(node)
        host._thread.start()
        planner.get_logger().info(
            f"MoveIt interface: scenes on {host.subscription.topic_name}, service {server.srv_name} "
            f"on {node.get_name()}"
        )
        return host

    def _spin(self) -> None:
        try:
            self._executor.spin()
        except ExternalShutdownException:  # the context was shut down (the process ends)
            pass

    def _on_plan(self, request: Any, response: Any) -> Any:
        """Answer one GetMotionPlan: a timed trajectory with SUCCESS, or an empty one with MoveIt's code."""
        started = time.perf_counter()
        out = response.motion_plan_response
        out.group_name = request.motion_plan_request.group_name
        try:
            error = self._plan(request.motion_plan_request, out)
        except Exception as exc:  # a bug must not end the node: answered FAILURE, the error reported
            self._report(f"{SERVICE_NAME}: internal error: {type(exc).__name__}: {exc}")
            error = MoveItError("FAILURE", f"internal error: {exc}")
        out.error_code.val = error.code
        out.error_code.message = error.text
        out.error_code.source = "drd_planner"
        out.planning_time = time.perf_counter() - started
        return response

    def _plan(self, request: Any, out: Any) -> MoveItError:
        arm = self._service.joint_goal_session
        assert arm is not None  # checked at start
        names = list(arm.joint_names)
        parsed = read_motion_request(request, names)
        if isinstance(parsed, MoveItError):
            return parsed
        outcome = self._service.serve_request(parsed.goal, parsed.start, SERVICE_NAME)
        error = moveit_error(outcome)
        if error.name != "SUCCESS":
            return error
        assert outcome.result is not None
        states = outcome.result.states
        seconds = timed_waypoints(states, parsed.velocity_scaling)
        out.trajectory_start.joint_state.name = names
        out.trajectory_start.joint_state.position = [float(v) for v in states[0]]
        trajectory = out.trajectory.joint_trajectory
        trajectory.header.frame_id = self._service.frame_id
        trajectory.joint_names = names
        trajectory.points = [
            JointTrajectoryPoint(positions=[float(v) for v in q], time_from_start=duration_of(t))
            for q, t in zip(states, seconds, strict=True)
        ]
        return error

    def stop(self) -> MoveItHost | None:
        """Remove the subscription, stop the executor and destroy the companion node (returns None)."""
        if self.subscription is not None:
            self.planner.destroy_subscription(self.subscription)
        self._executor.shutdown(timeout_sec=STOP_WAIT_S)
        self._thread.join(timeout=STOP_WAIT_S)
        self.node.destroy_node()
        return None
