"""One MoveIt request planned in one MoveIt scene with a prior and the real checker (``drd plan --scene``).

:func:`plan_moveit_request` rebuilds the prior's domain from its stored spec (as the node does), makes the
collision scene of a MoveIt PlanningScene file (its box, sphere and cylinder primitives, named by their
objects, with the domain's margin), reads the start state and the first joint goal of a MotionPlanRequest file
in the robot's joint order, and plans with :class:`~drd_planner.planner.Planner` from exactly those states
(snap tolerance 1e-6: a state off the roadmap is joined to it by motions that are checked like every edge;
roadmap growth when the roadmap has no free path). The domain's edge checker on the scene is the oracle.

A found path is then **re-verified** independently of the planner's bookkeeping: its dense states (graph
edges sampled at the check resolution, motions as planned) are checked as one motion by a fresh checker on
the same scene (static rules and scene); a path that fails it is a bug (:class:`UnverifiedPathError`).

:meth:`ScenePlan.to_json` is what ``drd plan --scene ... --json FILE`` writes.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from drd_planner.arrays import FloatArray
from drd_planner.data.scene_source import scene_of, scene_primitives
from drd_planner.domains.online import OnlineDomain
from drd_planner.exceptions import DrdError, GeometryError, UnverifiedPathError
from drd_planner.geometry.moveit_request import joint_vector, read_motion_plan_request
from drd_planner.planner.planner import Planner
from drd_planner.planner.prior import WorldPrior
from drd_planner.planner.result import PlanResult
from drd_planner.planning.domain_view import straight_edge_states
from drd_planner.planning.prior_domain import rebuild_domain

__all__ = ["SCENE_SNAP_TOLERANCE", "ScenePlan", "SceneRequest", "plan_moveit_request"]

#: How far (rad) a request's state may be from a roadmap vertex and still be that vertex: only itself.
SCENE_SNAP_TOLERANCE = 1e-6


@dataclass(frozen=True)
class SceneRequest:
    """What to plan: the files and the budgets.

    Attributes:
        scene: a MoveIt PlanningScene YAML file (the obstacles).
        request: a MoveIt MotionPlanRequest YAML file (start state and joint goals; the first goal is planned).
        seed: the plan's seed.
        max_checks: the most checks (None: no limit).
        time_budget_s: the most seconds of the plan (None: no limit but the growth's own).
    """

    scene: Path
    request: Path
    seed: int = 0
    max_checks: int | None = None
    time_budget_s: float | None = None


@dataclass(frozen=True)
class ScenePlan:
    """One planned MoveIt request.

    Attributes:
        request: what was planned.
        start: (D,) start state (rad, the robot's joint order).
        goal: (D,) goal state (rad).
        result: the planner's result.
        wall_s: seconds of the plan (wall clock), the scene and checker built before it not included.
        cpu_s: CPU seconds of the plan (this process).
        path_states: (K, D) dense states of the found path, start to goal (empty unless found); every one was
            checked free again by a fresh checker.
    """

    request: SceneRequest
    start: FloatArray
    goal: FloatArray
    result: PlanResult
    wall_s: float
    cpu_s: float
    path_states: FloatArray

    def to_json(self) -> dict[str, Any]:
        """``{"status", "checks", "path_edges", "time_s", "reason", ...}`` (see ``drd plan --help``)."""
        result, growth = self.result, self.result.growth
        return {
            "status": result.status.value,
            "checks": result.num_checks,
            "path_edges": [int(e) for e in result.edges],
            "time_s": self.wall_s,
            "reason": result.reason,
            "cpu_s": self.cpu_s,
            "blocked_checks": sum(not c.free for c in result.checks),
            "stage": "" if result.stage is None else result.stage.value,
            "cost_rad": result.cost,
            "scene": str(self.request.scene),
            "request": str(self.request.request),
            "start": self.start.tolist(),
            "goal": self.goal.tolist(),
            "path_vertices": [int(v) for v in result.vertices],
            "path_states": self.path_states.tolist(),
            "growth": None
            if growth is None
            else {
                "rounds": growth.rounds,
                "vertices_added": growth.vertices_added,
                "edges_added": growth.edges_added,
                "checks": growth.checks,
                "stop": growth.stop,
            },
            "seed": self.request.seed,
        }


def _states(request: Path, joint_names: tuple[str, ...]) -> tuple[FloatArray, FloatArray]:
    """(start, first goal) of a request file in the robot's joint order (DrdError naming what is wrong)."""
    if not joint_names:
        raise DrdError("--scene/--request plan joint-space MoveIt requests; this prior's domain has no joints")
    try:
        states = read_motion_plan_request(request)
        if states.start is None:
            raise DrdError(f"{request}: no start_state.joint_state (the request must give the start)")
        start = joint_vector(states.start, joint_names, where=f"{request} start_state", allow_extra=True)
        goal = joint_vector(states.goals[0], joint_names, where=f"{request} goal_constraints[0]")
    except GeometryError as exc:
        raise DrdError(str(exc)) from exc
    return start, goal


def plan_moveit_request(
    prior: WorldPrior, request: SceneRequest, *, label: str = "prior", domain: OnlineDomain[Any] | None = None
) -> ScenePlan:
    """Plan ``request`` with ``prior`` and the real checker (see the module docstring).

    Args:
        prior: the world prior.
        request: the files and budgets.
        label: the prior's name in messages.
        domain: the prior's domain, already rebuilt (:func:`rebuild_domain`; None: rebuilt here).

    Raises:
        DrdError: unreadable or unsupported files, a prior whose domain cannot be rebuilt or has no joints.
        UnverifiedPathError: a found path whose dense states a fresh checker does not find free (a bug).
    """
    domain = domain if domain is not None else rebuild_domain(prior, label)
    start, goal = _states(request.request, domain.joint_names)
    try:
        data = request.scene.read_bytes()
    except OSError as exc:
        raise DrdError(f"cannot read scene {request.scene}: {exc}") from exc
    scene = scene_of(scene_primitives(str(request.scene), data), domain.margin)
    planner = Planner(prior, snap_tolerance=SCENE_SNAP_TOLERANCE)
    checker = domain.scene_checker(scene)
    wall0, cpu0 = time.perf_counter(), time.process_time()
    result = planner.plan(
        start,
        goal,
        checker,
        seed=request.seed,
        max_checks=request.max_checks,
        time_budget_s=request.time_budget_s,
    )
    wall, cpu = time.perf_counter() - wall0, time.process_time() - cpu0
    dense = np.zeros((0, start.size))
    if result.found:
        dense = path_states(domain, prior, result)
        fresh = getattr(domain.scene_checker(scene), "check_motion", None)
        if fresh is None or not fresh(dense):
            raise UnverifiedPathError(f"{request.scene}: the found path is not free when checked again")
    return ScenePlan(request, start, goal, result, wall, cpu, dense)


def path_states(domain: OnlineDomain[Any], prior: WorldPrior, result: PlanResult) -> FloatArray:
    """(K, D) dense states of a found path: graph edges sampled at the domain's resolution, motions as planned."""
    graph = prior.graph if result.growth is None else result.growth.query.graph
    states = graph.vertex_states
    assert states is not None

    def state(vertex: int) -> FloatArray:
        known = result.new_states.get(vertex)
        return np.asarray(states[vertex] if known is None else known, dtype=np.float64)

    pieces: list[FloatArray] = []
    for k, e in enumerate(int(x) for x in result.edges):
        tail, head = state(int(result.vertices[k])), state(int(result.vertices[k + 1]))
        motion = result.motions.get(e)
        if motion is None:
            piece = straight_edge_states(domain, tail, head)
        else:
            piece = motion if np.allclose(motion[0], tail) else motion[::-1]
        pieces.append(piece if not pieces else piece[1:])
    return np.concatenate(pieces) if pieces else state(int(result.vertices[0]))[None]
