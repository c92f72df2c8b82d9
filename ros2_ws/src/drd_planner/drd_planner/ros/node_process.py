"""The ``planner_node`` process: one :class:`~drd_planner.ros.node.PlannerNode` spun until a signal ends it.

The ``planner_node`` console script (:mod:`drd_planner.ros.planner_node`) installs the signal handlers and
parses ``--help`` before it imports this module. Without ``autostart`` the node waits for the lifecycle
services (``ros2 lifecycle set``). One executor thread takes maps and requests while the node's planning
thread plans (and Nav2's interface has an executor of its own: :mod:`drd_planner.ros.nav2_host`).
"""

from __future__ import annotations

import sys

import rclpy
from rclpy.exceptions import ParameterException
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.impl.implementation_singleton import rclpy_implementation
from rclpy.lifecycle import TransitionCallbackReturn
from rclpy.utilities import ok, try_shutdown

from drd_planner.ros.guard import shorten
from drd_planner.ros.node import PlannerNode

__all__ = ["SPIN_TIMEOUT_S", "main"]

#: Longest executor wait (seconds) of the spin loop.
SPIN_TIMEOUT_S = 0.25


def main(args: list[str] | None = None) -> int:
    """Run the lifecycle node until SIGINT / SIGTERM (``autostart:=true`` configures and activates it).

    Returns the exit status: 0, 2 when the parameters given on the command line are refused, or 130 when a
    signal shut rclpy down while the node was being made.
    """
    rclpy.init(args=args)
    executor: SingleThreadedExecutor | None = None
    node: PlannerNode | None = None
    try:
        executor = SingleThreadedExecutor()
        node = PlannerNode()
        executor.add_node(node)
    except Exception as exc:
        if not ok():
            # rclpy's own signal handler shuts the context down before Python's handler runs: making the node
            # or its executor on that context then fails (an RCLError, rclpy's NotInitializedException, ...).
            # That is the end a signal asked for, not an error; what was made goes with the process.
            return 130
        if node is not None or not isinstance(exc, (ParameterException, ValueError, TypeError)):
            raise
        # an override outside its range or type
        print(f"planner_node: error: {shorten(str(exc))}", file=sys.stderr)
        if executor is not None:
            executor.shutdown()
        try_shutdown()
        return 2
    try:
        if bool(node.get_parameter("autostart").value):
            if node.trigger_configure() == TransitionCallbackReturn.SUCCESS:
                node.trigger_activate()
            else:
                node.get_logger().error("autostart: configure failed; the node waits unconfigured")
        context = node.context
        while context.ok():  # short waits: a signal that only Python saw still ends the loop soon
            executor.spin_once(timeout_sec=SPIN_TIMEOUT_S)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except rclpy_implementation.RCLError:  # a signal shut the context down mid-transition: the end asked for
        if node.context.ok():
            raise
    finally:
        executor.shutdown()
        node.destroy_node()
        try_shutdown()
    return 0
