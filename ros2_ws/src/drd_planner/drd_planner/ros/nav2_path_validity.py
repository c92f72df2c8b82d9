"""Nav2's ``is_path_valid`` service (``nav2_msgs/srv/IsPathValid``, Jazzy) on the planner.

Request: ``path`` (nav_msgs/Path in the planning frame). Response: ``is_valid`` and
``invalid_pose_indices`` (the poses found blocked; Nav2 Jazzy's planner server leaves it empty). A path
``compute_path_to_pose`` returned is answered by re-checking only its edges that the map changes since it
was last known free can reach (:mod:`drd_planner.planning.path_validity`); another path is checked pose by
pose. An empty path, or one in another frame, is not valid (as in Nav2).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from drd_planner.domains.pose_states import yaw_from_quaternion
from drd_planner.planning.path_validity import ServedPaths
from drd_planner.planning.service import PlannerService

__all__ = ["SERVICE_NAME", "PathValidityService", "path_arrays"]

#: The service's name, relative to the node's namespace (Nav2's planner server's).
SERVICE_NAME = "is_path_valid"


def path_arrays(
    path: Any,
) -> tuple[np.ndarray[Any, np.dtype[np.float64]], np.ndarray[Any, np.dtype[np.float64]]]:
    """``(positions (K, 3) m, yaws (K,) rad)`` of a ``nav_msgs/Path``'s poses."""
    positions = np.zeros((len(path.poses), 3))
    yaws = np.zeros(len(path.poses))
    for i, stamped in enumerate(path.poses):
        p, q = stamped.pose.position, stamped.pose.orientation
        positions[i] = (p.x, p.y, p.z)
        yaws[i] = yaw_from_quaternion((q.x, q.y, q.z, q.w)) if (q.x, q.y, q.z, q.w) != (0, 0, 0, 0) else 0.0
    return positions, yaws


class PathValidityService:
    """Serves ``is_path_valid`` on ``node`` (see the module docstring; arguments as the action server's)."""

    def __init__(
        self,
        node: Any,
        service_type: Any,
        service: PlannerService,
        served: ServedPaths,
        *,
        group: Any,
        report: Callable[[str], None],
    ) -> None:
        self._node = node
        self._service = service
        self._served = served
        self._report = report
        self._server = node.create_service(service_type, SERVICE_NAME, self._on_request, callback_group=group)
        self.name = f"{node.get_namespace().rstrip('/')}/{SERVICE_NAME}"

    def _on_request(self, request: Any, response: Any) -> Any:
        path = request.path
        frame = str(path.header.frame_id)
        if frame not in ("", self._service.frame_id):
            response.is_valid = False
            self._node.get_logger().warning(f"{SERVICE_NAME}: a path in frame {frame[:80]!r} is not valid here")
            return response
        try:
            positions, yaws = path_arrays(path)
            answer = self._served.validity(positions, yaws, self._service.sessions, self._service.snapshot)
        except Exception as exc:  # a bad path or a bug: not valid, reported, the node goes on
            self._report(f"{SERVICE_NAME}: {type(exc).__name__}: {exc}")
            response.is_valid = False
            return response
        response.is_valid = answer.valid
        response.invalid_pose_indices = list(answer.invalid)
        self._node.get_logger().info(f"{SERVICE_NAME}: {'valid' if answer.valid else 'not valid'}: {answer.text}")
        return response
