"""What the node reports about itself on ``/diagnostics``: status names, the maps it holds, its heartbeat.

Status names are ``<node name>: <topic>`` (``drd_planner: plan``, ``drd_planner: maps``, ...), so two
planners in one system are told apart and a map error is not filed under plans.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from drd_planner.planning.map_state import MapSnapshot

__all__ = ["HEARTBEAT_PERIOD_S", "LastPlan", "heartbeat_values", "map_values", "status_name"]

#: Seconds between two heartbeat statuses (diagnostic aggregators call a status stale after a few).
HEARTBEAT_PERIOD_S = 1.0


def status_name(node_name: str, topic: str) -> str:
    """The ``DiagnosticStatus.name`` of ``topic`` (``plan``, ``maps``, ``map update``, ``node``, ``heartbeat``)."""
    return f"{node_name}: {topic}"


def map_values(snapshot: MapSnapshot) -> dict[str, Any]:
    """Key/values describing ``snapshot``: its version and what each map holds (sizes in cells, parts, joints)."""
    values: dict[str, Any] = {"map_version": snapshot.version}
    terrain = snapshot.terrain
    if terrain is None:
        values["terrain"] = "none"
    else:
        rows, cols = terrain.shape
        values["terrain"] = f"{rows} x {cols} cells of {terrain.cell_size:g} m"
    values["obstacles"] = len(snapshot.obstacles) if snapshot.obstacle_map or snapshot.obstacles else "none"
    values["obstacle_parts"] = sum(len(parts) for parts in snapshot.obstacles.values())
    robot = snapshot.robot
    values["robot_description"] = (
        "prior's own model" if robot is None else f"{robot.chain.robot_name}, {robot.dof} joints"
    )
    return values


@dataclass(frozen=True)
class LastPlan:
    """The newest served request, as the heartbeat shows it.

    Attributes:
        result: its outcome (:attr:`SessionPlan.outcome <drd_planner.planning.session_plan.SessionPlan.outcome>`:
            ``found``, ``no_path``, ``budget_exhausted: check_budget``, ...).
        request: where it came from (``goal_pose``, ``get_plan``, ``map_update``, ...).
        finished: ``time.monotonic()`` when it was answered, seconds.
    """

    result: str
    request: str
    finished: float


def heartbeat_values(
    *,
    state: str,
    snapshot: MapSnapshot,
    priors: int,
    published: bool,
    pending: int,
    errors: int,
    last: LastPlan | None,
    now: float,
) -> dict[str, Any]:
    """The heartbeat's key/values: lifecycle state, priors loaded, maps known, published plan, last plan, its age (s).

    ``priors`` counts the loaded priors (``trees``: the same, a deprecated key kept for one release).
    """
    values: dict[str, Any] = {"state": state, "priors": priors, "trees": priors, **map_values(snapshot)}
    values["maps_known"] = snapshot.has_maps
    values["plan_published"] = published
    values["pending_requests"] = pending
    values["errors"] = errors
    if last is None:
        values["last_plan"] = "none"
    else:
        values["last_plan"] = f"{last.result} ({last.request})"
        values["last_plan_age_s"] = f"{max(0.0, now - last.finished):.1f}"
    return values
