"""External peer ``rrt_connect``: OMPL's RRT-Connect on MoveIt requests, every query answered by our checker.

OMPL runs in a child process (:mod:`drd_planner.bench.rrt_connect_worker`; its Python bindings can crash at
interpreter exit). :func:`run_rrt_connect` hands it the domain (registry name and spec: the worker rebuilds the
same checker as ours), the tasks (a MoveIt scene file, start and goal states in rad) and a time limit per
task; it reads one JSON line per task back. Each solution is then **re-verified here**, independently of
OMPL: its waypoints joined by straight motions at the domain's check resolution must be free for a fresh
checker of the same scene (:func:`verify_waypoints`). A task counts as solved only then.
"""

from __future__ import annotations

import itertools
import json
import os
import subprocess
import sys
import tempfile
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from drd_planner.arrays import FloatArray
from drd_planner.bench.ompl_peer import OmplPeerError, ompl_available, read_worker_results
from drd_planner.data.scene_source import scene_of, scene_primitives
from drd_planner.domains.online import OnlineDomain
from drd_planner.planning.domain_view import straight_edge_states

__all__ = ["PEER_NAME", "RrtTask", "run_rrt_connect", "verify_waypoints"]

PEER_NAME = "rrt_connect"
WORKER_MODULE = "drd_planner.cli.rrt_connect_worker"


@dataclass(frozen=True)
class RrtTask:
    """One request for RRT-Connect.

    Attributes:
        key: a label (e.g. ``table_pick_panda/0081``).
        scene: the MoveIt PlanningScene file.
        start: (D,) start state (rad).
        goal: (D,) goal state (rad).
    """

    key: str
    scene: Path
    start: FloatArray
    goal: FloatArray

    def to_json(self) -> dict[str, Any]:
        """The task as the worker reads it."""
        return {
            "key": self.key,
            "scene": str(self.scene),
            "start": self.start.tolist(),
            "goal": self.goal.tolist(),
        }


def _worker_env() -> dict[str, str]:
    """The environment of the worker: this one, with this package importable."""
    env = dict(os.environ)
    package_root = str(Path(__file__).resolve().parents[2])
    env["PYTHONPATH"] = os.pathsep.join(p for p in (package_root, env.get("PYTHONPATH", "")) if p)
    return env


def verify_waypoints(domain: OnlineDomain[Any], scene_file: Path, waypoints: Sequence[Sequence[float]]) -> bool:
    """Whether the straight motions between consecutive (K, D) waypoints are free for a fresh checker of the scene.

    Each motion is sampled at the domain's check resolution (no joint moves more than it between samples)
    and the whole dense path is one ``check_motion`` (static rules and scene).
    """
    points = np.asarray(waypoints, dtype=np.float64)
    if points.ndim != 2 or points.shape[0] < 2:
        return False
    scene = scene_of(scene_primitives(str(scene_file), scene_file.read_bytes()), domain.margin)
    pieces = [straight_edge_states(domain, a, b) for a, b in itertools.pairwise(points)]
    dense = np.concatenate([pieces[0]] + [p[1:] for p in pieces[1:]])
    check_motion = getattr(domain.scene_checker(scene), "check_motion", None)
    return bool(check_motion is not None and check_motion(dense))


def run_rrt_connect(
    domain: OnlineDomain[Any],
    spec: dict[str, Any],
    tasks: Sequence[RrtTask],
    *,
    time_limit_s: float,
    seed: int = 0,
) -> list[dict[str, Any]]:
    """RRT-Connect on every task in one child process; one record per task, in order.

    Args:
        domain: the domain (for re-verification here; the worker rebuilds it from ``spec``).
        spec: the domain's JSON-able spec (a prior's ``domain_spec``).
        tasks: the requests.
        time_limit_s: OMPL's time limit per task (s).
        seed: OMPL's seed of the first task (task n uses ``seed + n + 1``).

    Returns:
        Per task ``{"key", "status", "solved" (exact solution and re-verified), "ompl_solved", "verified",
        "wall_s", "cpu_s", "state_checks", "motion_checks", "waypoints", "range"}``.

    Raises:
        OmplPeerError: OMPL is unavailable, or the worker failed.
    """
    available, message = ompl_available()
    if not available:
        raise OmplPeerError(message.replace("ompl_lazyprm", PEER_NAME))
    config = {
        "domain": domain.name,
        "spec": spec,
        "seed": int(seed),
        "time_limit_s": float(time_limit_s),
        "tasks": [task.to_json() for task in tasks],
    }
    with tempfile.TemporaryDirectory(prefix="drd_rrt_") as tmp:
        folder = Path(tmp)
        (folder / "config.json").write_text(json.dumps(config))
        result = folder / "result.jsonl"
        cmd = [
            sys.executable,
            "-m",
            WORKER_MODULE,
            "--config",
            str(folder / "config.json"),
            "--result",
            str(result),
        ]
        timeout = 300.0 + len(tasks) * (time_limit_s + 30.0)
        t0 = time.perf_counter()
        try:
            proc = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, env=_worker_env(), check=False)
        except subprocess.TimeoutExpired:
            raise OmplPeerError(f"RRT-Connect worker did not finish within {timeout:.0f} s") from None
        records = read_worker_results(result, len(tasks), proc.returncode, proc.stderr)
    out = []
    for task, record in zip(tasks, records, strict=True):
        verified = bool(record["solved"]) and verify_waypoints(domain, task.scene, record["path"])
        out.append(
            {
                "key": task.key,
                "status": record["status"],
                "solved": verified,
                "ompl_solved": bool(record["solved"]),
                "verified": verified,
                "wall_s": float(record["wall_s"]),
                "cpu_s": float(record["cpu_s"]),
                "state_checks": int(record["state_checks"]),
                "motion_checks": int(record["motion_checks"]),
                "waypoints": len(record["path"]),
                "range": float(record["range"]),
                "worker_s": time.perf_counter() - t0,
            }
        )
    return out
