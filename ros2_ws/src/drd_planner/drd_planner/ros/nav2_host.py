"""Where the node's Nav2 interface lives: a companion node spun in threads of its own.

Nav2's planner interface (``compute_path_to_pose``, :mod:`drd_planner.ros.nav2_planner_action`;
``is_path_valid``, :mod:`drd_planner.ros.nav2_path_validity`) is offered by a plain node named
``<node name>_nav2`` in the planner node's namespace, so that the names resolve as on the planner node
(``/compute_path_to_pose`` for a node in ``/``). It has its own
:class:`~rclpy.executors.MultiThreadedExecutor` (:data:`NAV2_THREADS` threads, reentrant callbacks) in a
daemon thread: a goal plans in its callback while another thread hears its cancel request and the next
``is_path_valid``, and the planner node's own executor (single-threaded, maps and topic requests) is never
blocked by a Nav2 client. Plans stay one at a time (the service's planning lock).

The interfaces come from ``nav2_msgs``: a ROS install's where it is importable, else the two interfaces
``scripts/tools/build_nav2_msgs.sh`` builds into the venv (``scripts/run.sh`` runs it). Without either, the node
runs without the Nav2 interface and says why.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any

import rclpy
from rclpy.callback_groups import ReentrantCallbackGroup
from rclpy.executors import ExternalShutdownException, MultiThreadedExecutor

from drd_planner.planning.path_validity import ServedPaths
from drd_planner.planning.service import PlannerService
from drd_planner.ros.nav2_path_validity import PathValidityService
from drd_planner.ros.nav2_planner_action import PlannerActionServer

__all__ = ["NAV2_THREADS", "Nav2Host", "nav2_interfaces"]

#: Executor threads of the companion node: a running goal, a cancel request, an ``is_path_valid``.
NAV2_THREADS = 3
#: Seconds :meth:`Nav2Host.stop` waits for the executor's callbacks (a running plan is cancelled first).
STOP_WAIT_S = 5.0


def nav2_interfaces() -> tuple[Any, Any]:
    """``(nav2_msgs.action.ComputePathToPose, nav2_msgs.srv.IsPathValid)``.

    Raises:
        ImportError: nav2_msgs is not importable, or lacks one of them.
    """
    from nav2_msgs.action import ComputePathToPose  # optional: a ROS install's, or the venv's
    from nav2_msgs.srv import IsPathValid

    return ComputePathToPose, IsPathValid


class Nav2Host:
    """The companion node with the Nav2 interface, spinning until :meth:`stop` (see the module docstring).

    Use :meth:`start`. ``served`` remembers the paths ``compute_path_to_pose`` returned, for
    ``is_path_valid``; ``cancel_all`` is set by the action server (it cancels the running plans).
    """

    def __init__(self, node: Any, executor: MultiThreadedExecutor, served: ServedPaths) -> None:
        self.node = node
        self.served = served
        self.cancel_all: Callable[[], None] = lambda: None
        self._executor = executor
        self._thread = threading.Thread(target=self._spin, name="drd_planner-nav2", daemon=True)

    @classmethod
    def start(cls, planner: Any, service: PlannerService, *, report: Callable[[str], None]) -> Nav2Host | None:
        """Offer ``compute_path_to_pose`` and ``is_path_valid`` for ``planner`` (None: nav2_msgs missing, logged)."""
        try:
            action_type, service_type = nav2_interfaces()
        except ImportError as exc:
            planner.get_logger().warning(
                f"Nav2 interface off (compute_path_to_pose, is_path_valid): nav2_msgs is not importable ({exc}); "
                "scripts/tools/build_nav2_msgs.sh builds it into the venv"
            )
            return None
        node = rclpy.create_node(
            f"{planner.get_name()}_nav2",
            namespace=planner.get_namespace(),
            context=planner.context,
            use_global_arguments=False,  # a ``__node:=`` remap of the planner must not rename this one too
            start_parameter_services=False,
        )
        host = cls(
            node,
            MultiThreadedExecutor(NAV2_THREADS, context=planner.context),
            ServedPaths(service.planning_lock),
        )
        group = ReentrantCallbackGroup()
        action = PlannerActionServer(node, action_type, service, host.served, group=group, report=report)
        validity = PathValidityService(node, service_type, service, host.served, group=group, report=report)
        host.cancel_all = action.cancel_all
        host._executor.add_node(node)
        host._thread.start()
        planner.get_logger().info(f"Nav2 interface on {node.get_name()}: action {action.name}, service {validity.name}")
        return host

    def _spin(self) -> None:
        try:
            self._executor.spin()
        except ExternalShutdownException:  # the context was shut down (the process ends)
            pass

    def stop(self) -> Nav2Host | None:
        """Cancel the running plans, stop the executor and destroy the companion node.

        Returns None, so that ``host = host.stop()`` forgets it.
        """
        self.cancel_all()
        self._executor.shutdown(timeout_sec=STOP_WAIT_S)
        self._thread.join(timeout=STOP_WAIT_S)
        self.node.destroy_node()
        return None
