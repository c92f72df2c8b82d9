"""Child process running OMPL's RRT-Connect on MoveIt requests with our checker (:mod:`~drd_planner.bench.rrt_connect`).

OMPL 1.7.0's Python bindings can crash while the interpreter tears down, so everything OMPL touches lives in
this process (as :mod:`drd_planner.bench.ompl_worker`). It reads ``config.json`` (the domain's registry name and
spec, the seed, the time limit and the tasks: scene file, start and goal states), writes one JSON line per task
to the result file (flushed after each, then ``{"done": true}``) and leaves with ``os._exit``.

The search space is a ``RealVectorStateSpace`` bounded by the arm's joint limits (rad). **Our checker decides
everything**: a state is valid when the domain's edge checker on the task's scene says the one-state motion
through it is free (``check_motion``: joint limits, self-collision, floor rule, scene), and a motion between
two states is valid when the straight motion sampled at the domain's check resolution (no joint moves more than
``resolution`` rad between samples) is free (``check_motion`` of those samples). RRT-Connect keeps OMPL's
defaults (range: 0.2 of the space's extent) and stops at its first exact solution, which is not simplified.
Times: wall and CPU of ``solve`` (the scene and checker are built and warmed up before).
"""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import IO, Any

import numpy as np

from drd_planner.arrays import FloatArray


def _import_ompl() -> tuple[Any, Any, Any]:
    from ompl import base as ob  # imported in this process only
    from ompl import geometric as og
    from ompl import util as ou

    return ob, og, ou


class _Counter:
    """Answers OMPL's state and motion queries with one checker and counts them."""

    def __init__(self, checker: Any, resolution: float, dim: int) -> None:
        self.checker = checker
        self.resolution = resolution
        self.dim = dim
        self.states = 0
        self.motions = 0

    def vector(self, state: Any) -> FloatArray:
        return np.array([float(state[k]) for k in range(self.dim)])

    def state_valid(self, state: Any) -> bool:
        self.states += 1
        return bool(self.checker.check_motion(self.vector(state)[None]))

    def motion_valid(self, a: Any, b: Any) -> bool:
        self.motions += 1
        qa, qb = self.vector(a), self.vector(b)
        steps = max(1, int(np.ceil(np.max(np.abs(qb - qa)) / self.resolution)))
        return bool(self.checker.check_motion(qa + np.linspace(0.0, 1.0, steps + 1)[:, None] * (qb - qa)))


def _task_checker(domain: Any, scene_path: str) -> Any:
    from drd_planner.data.scene_source import scene_of, scene_primitives

    scene = scene_of(scene_primitives(scene_path, Path(scene_path).read_bytes()), domain.margin)
    return domain.scene_checker(scene)


def _solve(ob: Any, og: Any, space: Any, counter: _Counter, task: dict[str, Any], limit: float) -> dict[str, Any]:
    """One RRT-Connect solve: the JSON record of the task."""
    si = ob.SpaceInformation(space)

    def check_motion(self: Any, s1: Any, s2: Any, *last_valid: Any) -> bool:
        return counter.motion_valid(s1, s2)

    validator_class = type("OurMotionValidator", (ob.MotionValidator,), {"checkMotion": check_motion})
    si.setStateValidityChecker(ob.StateValidityCheckerFn(counter.state_valid))
    validator = validator_class(si)
    si.setMotionValidator(validator)
    si.setup()
    start, goal = ob.State(space), ob.State(space)
    for k in range(counter.dim):
        start[k] = float(task["start"][k])
        goal[k] = float(task["goal"][k])
    pdef = ob.ProblemDefinition(si)
    pdef.setStartAndGoalStates(start, goal)
    planner = og.RRTConnect(si)
    planner.setProblemDefinition(pdef)
    planner.setup()
    wall0, cpu0 = time.perf_counter(), time.process_time()
    status = planner.solve(limit)
    wall, cpu = time.perf_counter() - wall0, time.process_time() - cpu0
    solved = bool(pdef.hasExactSolution())
    path: list[list[float]] = []
    if solved:
        solution = pdef.getSolutionPath()
        path = [counter.vector(solution.getState(i)).tolist() for i in range(solution.getStateCount())]
    del validator
    return {
        "key": task["key"],
        "status": str(status),
        "solved": solved,
        "wall_s": wall,
        "cpu_s": cpu,
        "state_checks": counter.states,
        "motion_checks": counter.motions,
        "path": path,
        "range": float(planner.getRange()),
    }


def run_tasks(config_path: Path, out: IO[str]) -> None:
    """Run every task of ``config_path`` (JSON: MoveIt requests, limits), one JSON line per task to ``out``."""
    ob, og, ou = _import_ompl()
    from drd_planner.domains.base import domain_from_spec

    config = json.loads(config_path.read_text())
    domain = domain_from_spec(str(config["domain"]), config.get("spec") or {})
    robot = domain.robot
    if robot is None:
        raise RuntimeError(f"domain {config['domain']!r} has no arm: RRT-Connect here plans joint-space requests")
    ou.setLogLevel(ou.LOG_ERROR)
    dim = robot.dof
    space = ob.RealVectorStateSpace(dim)
    bounds = ob.RealVectorBounds(dim)
    for k in range(dim):
        bounds.setLow(k, float(robot.lower[k]))
        bounds.setHigh(k, float(robot.upper[k]))
    space.setBounds(bounds)
    for n, task in enumerate(config["tasks"]):
        checker = _task_checker(domain, str(task["scene"]))
        checker.check_motion(np.asarray(task["start"], dtype=np.float64)[None])  # first use: not in the time
        ou.RNG.setSeed(int(config["seed"]) + n + 1)  # OMPL seeds must be > 0
        counter = _Counter(checker, float(domain.resolution), dim)
        out.write(json.dumps(_solve(ob, og, space, counter, task, float(config["time_limit_s"]))) + "\n")
        out.flush()
    out.write(json.dumps({"done": True}) + "\n")
    out.flush()
