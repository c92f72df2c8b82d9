"""External peer ``ompl_lazyprm``: OMPL's LazyPRM searching our explicit graph, scored by edge checks.

OMPL runs in a child process (:mod:`drd_planner.bench.ompl_worker`) because its Python bindings can
crash at interpreter exit; requests and results cross as ``.npz`` (``allow_pickle=False``) and JSON
lines. A crash after every world's result was written is harmless and only noted; a crash before
is an :class:`OmplPeerError` that says how far the worker got.

Scoring per test world: ``checks`` = the number of distinct graph edges LazyPRM asked the motion
validator about (answered from the world's row of X); ``success`` = OMPL reported an exact solution
**and** the returned vertex sequence is a start-to-goal path of graph edges that are all free in X
(verified here, independently of OMPL).

:func:`run_ompl_lazyprm_live` runs the same search with a **live checker** instead of X: the worker
rebuilds the domain from its spec and answers each edge with the domain's edge checker on each world
(:class:`~drd_planner.bench.world_recipes.WorldRecipe`), timing every answer; a world counts as a success
only when every edge of the returned path was checked free there by that checker.
"""

from __future__ import annotations

import functools
import importlib.metadata
import importlib.util
import json
import os
import subprocess
import sys
import tempfile
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import numpy as np
import numpy.typing as npt

from drd_planner.arrays import BoolArray, IntArray
from drd_planner.bench.extras import install_hint
from drd_planner.bench.world_recipes import WorldRecipe
from drd_planner.core.graph import ExplicitGraph
from drd_planner.core.problem import Problem
from drd_planner.exceptions import DrdError, ProblemError

EmbeddingName = Literal["auto", "coords", "index"]

PEER_NAME = "ompl_lazyprm"
SKIP_MESSAGE = f"ompl_lazyprm skipped: OMPL not installed (the 'peer' extra): {install_hint('peer')}"
WORKER_MODULE = "drd_planner.cli.ompl_worker"

#: How much shorter than the straight line (length units) an edge may be for the coords embedding: the
#: authors' files round coordinates to 5 significant digits and lengths to 6 decimals (errors ~1e-5).
LENGTH_TOLERANCE = 1e-4

#: Connector edges LazyPRM adds per query: start copy -> start vertex, goal copy -> goal vertex.
CONNECTOR_EDGES = 2


class OmplPeerError(DrdError):
    """OMPL is unavailable, the worker failed, or the problem cannot be handed to LazyPRM."""


@dataclass(frozen=True)
class PathCheck:
    """Result of verifying a returned vertex path against one world.

    Attributes:
        ok: the path runs from start to goal over graph edges (in a traversable direction) all free.
        edges: (L,) int64 edge ids along the path (empty when the path is not a graph path).
        reason: empty when ``ok``, otherwise why not.
    """

    ok: bool
    edges: IntArray
    reason: str


def _worker_env() -> dict[str, str]:
    env = dict(os.environ)
    package_root = str(Path(__file__).resolve().parents[2])
    env["PYTHONPATH"] = os.pathsep.join(p for p in (package_root, env.get("PYTHONPATH", "")) if p)
    return env


def _tail(text: str, lines: int = 5) -> str:
    return " | ".join(text.strip().splitlines()[-lines:]) or "(no output)"


@functools.lru_cache(maxsize=1)
def ompl_available() -> tuple[bool, str]:
    """Whether OMPL with LazyPRM can be used, and a one-line message (the skip reason when not).

    Probes in a child process (about a second, cached), so a broken install cannot crash the caller.
    """
    if importlib.util.find_spec("ompl") is None:
        return False, SKIP_MESSAGE
    try:
        version = importlib.metadata.version("ompl")
    except importlib.metadata.PackageNotFoundError:
        version = "(unknown version)"
    try:
        proc = subprocess.run(
            [sys.executable, "-m", WORKER_MODULE, "--probe"],
            capture_output=True,
            text=True,
            timeout=120,
            env=_worker_env(),
            check=False,
        )
    except subprocess.TimeoutExpired:
        return False, f"ompl_lazyprm skipped: importing OMPL {version} took over 120 s"
    try:
        probe = json.loads(proc.stdout.strip().splitlines()[-1])
    except (IndexError, json.JSONDecodeError):
        return False, f"ompl_lazyprm skipped: OMPL {version} cannot be imported: {_tail(proc.stderr)}"
    if not probe.get("has_lazyprm") or not probe.get("has_planner_data"):
        return (
            False,
            f"ompl_lazyprm skipped: OMPL {version} has no LazyPRM/PlannerData; pip install 'ompl==1.7.0'",
        )
    return True, f"OMPL {version}"


@dataclass(frozen=True)
class Embedding:
    """Where the graph's vertices sit in LazyPRM's RealVectorStateSpace(d).

    Attributes:
        kind: ``coords`` (the vertex coordinates) or ``index`` (vertex i at ``i * spacing`` in R^1).
        states: (V, d) float64 vertex positions, all distinct.
        connect_radius: LazyPRM's connection range: 1e-3 of the smallest distance between vertices,
            so only copies of a vertex's state (the query's start and goal) connect to it.
    """

    kind: Literal["coords", "index"]
    states: npt.NDArray[np.float64]
    connect_radius: float


def coords_unusable(graph: ExplicitGraph) -> str | None:
    """Why the vertex coordinates cannot serve as LazyPRM's state space, or None when they can.

    They can when every vertex has finite coordinates, no two vertices coincide, and no edge is
    shorter than the straight line between its endpoints by more than :data:`LENGTH_TOLERANCE` (so
    OMPL's Euclidean A* heuristic is admissible up to rounding).
    """
    states = graph.vertex_states
    if states is None:
        return "the graph has no vertex coordinates"
    if not np.all(np.isfinite(states)):
        return "some vertex coordinates are not finite"
    if graph.num_vertices > 1 and _min_separation(states) <= 0.0:
        return "two vertices share the same coordinates"
    if graph.num_edges:
        straight = np.linalg.norm(states[graph.edges[:, 0]] - states[graph.edges[:, 1]], axis=1)
        short = straight - graph.lengths
        if np.any(short > LENGTH_TOLERANCE):
            return (
                f"edges are up to {short.max():.3g} shorter than the straight line between their "
                f"endpoints (tolerance {LENGTH_TOLERANCE:g})"
            )
    return None


def _min_separation(states: npt.NDArray[np.float64]) -> float:
    from scipy.spatial import cKDTree

    dist, _ = cKDTree(states).query(states, k=2)
    return float(np.min(dist[:, 1]))


def embed_vertices(graph: ExplicitGraph, requested: EmbeddingName = "auto") -> Embedding:
    """The state-space positions of the vertices.

    ``coords`` uses the vertex coordinates (OMPL's A* then has its Euclidean heuristic); ``index``
    puts vertex i at ``i * spacing`` with ``spacing = (smallest positive edge length) / (2 V)``, so the
    A* heuristic ``spacing * |i - goal|`` never exceeds one edge's length: it is consistent and the
    search is Dijkstra on the edge lengths in all but tie-breaking. ``auto`` picks ``coords`` when
    :func:`coords_unusable` finds nothing wrong, else ``index``.

    Raises:
        OmplPeerError: ``coords`` was requested but cannot work, or ``requested`` is unknown.
    """
    if requested not in ("auto", "coords", "index"):
        raise OmplPeerError(f"unknown embedding {requested!r}; use auto, coords or index")
    if requested != "index":
        reason = coords_unusable(graph)
        if reason is None and graph.vertex_states is not None:
            states = np.asarray(graph.vertex_states, dtype=np.float64)
            sep = _min_separation(states) if graph.num_vertices > 1 else 1.0
            return Embedding("coords", states, 1e-3 * sep)
        if requested == "coords":
            raise OmplPeerError(f"the coords embedding cannot be used: {reason}")
    positive = graph.lengths[graph.lengths > 0]
    spacing = (float(positive.min()) if positive.size else 1.0) / (2 * max(graph.num_vertices, 1))
    states = spacing * np.arange(graph.num_vertices, dtype=np.float64).reshape(-1, 1)
    return Embedding("index", states, 1e-3 * spacing)


def verify_path(
    graph: ExplicitGraph, outcomes: npt.ArrayLike, start: int, goal: int, vertices: Sequence[int]
) -> PathCheck:
    """Check a vertex path (L + 1,) against one world's outcomes (E,) bool (True = free)."""
    row = np.asarray(outcomes, dtype=bool).ravel()
    empty = np.zeros(0, dtype=np.int64)
    if len(vertices) < 2:
        return PathCheck(False, empty, "the path has fewer than two vertices")
    if vertices[0] != start or vertices[-1] != goal:
        return PathCheck(False, empty, f"the path runs {vertices[0]} -> {vertices[-1]}, not {start} -> {goal}")
    try:
        edges = graph.vertex_path_to_edges(vertices)
    except ProblemError as exc:
        return PathCheck(False, empty, f"not a graph path: {exc}")
    blocked = edges[~row[edges]]
    if blocked.size:
        return PathCheck(False, edges, f"edges {blocked.tolist()} on the path are in collision")
    return PathCheck(True, edges, "")


def read_worker_results(result_file: Path, expected: int, returncode: int, stderr: str) -> list[dict[str, Any]]:
    """Parse the worker's JSON-lines result file.

    Returns:
        the ``expected`` per-world records, in request order.

    Raises:
        OmplPeerError: the worker reported an error, or stopped (crashed) before writing every world.
    """
    records: list[dict[str, Any]] = []
    done = False
    lines = result_file.read_text().splitlines() if result_file.is_file() else []
    for line in lines:
        try:
            item = json.loads(line)
        except json.JSONDecodeError:
            break  # a line cut short by a crash
        if "error" in item:
            raise OmplPeerError(f"OMPL worker failed: {item['error']}")
        if item.get("done"):
            done = True
            break
        records.append(item)
    if not done or len(records) != expected:
        raise OmplPeerError(
            f"OMPL worker crashed (exit code {returncode}) after {len(records)} of {expected} worlds: {_tail(stderr)}"
        )
    return records


def _check_problem(problem: Problem, test_ids: Sequence[int]) -> tuple[ExplicitGraph, int, int, IntArray]:
    graph, start, goal = problem.graph, problem.start, problem.goal
    if graph is None or start is None or goal is None:
        raise OmplPeerError(f"{PEER_NAME} needs a graph with start and goal; problem {problem.name!r} has none")
    worlds = problem.require_worlds()
    ids = np.asarray(test_ids, dtype=np.int64).ravel()
    if ids.size and (ids.min() < 0 or ids.max() >= worlds.num_worlds):
        raise OmplPeerError(f"world ids must lie in [0, {worlds.num_worlds})")
    return graph, start, goal, ids


def _worker_config(
    graph: ExplicitGraph, embedded: Embedding, start: int, goal: int, seed: int, time_limit_s: float
) -> dict[str, Any]:
    """The worker's settings every run shares: roadmap size, embedding radius, query, seed, time limit (s)."""
    return {
        "connect_radius": embedded.connect_radius,
        "seed": int(seed),
        "time_limit_s": float(time_limit_s),
        "num_vertices": graph.num_vertices,
        "directed": graph.directed,
        "start": int(start),
        "goal": int(goal),
    }


def _run_worker(
    graph: ExplicitGraph,
    states: npt.NDArray[np.float64],
    rows: BoolArray,
    config: dict[str, Any],
    timeout_s: float,
    expected: int | None = None,
) -> tuple[list[dict[str, Any]], int]:
    """Run the worker on one request; ``expected`` worlds (default: one per row of ``rows``)."""
    with tempfile.TemporaryDirectory(prefix="drd_ompl_") as tmp:
        folder = Path(tmp)
        np.savez(folder / "request.npz", edges=graph.edges, lengths=graph.lengths, states=states, X=rows)
        (folder / "config.json").write_text(json.dumps(config))
        result = folder / "result.jsonl"
        cmd = [sys.executable, "-m", WORKER_MODULE, "--request", str(folder / "request.npz")]
        cmd += ["--config", str(folder / "config.json"), "--result", str(result)]
        try:
            proc = subprocess.run(
                cmd, capture_output=True, text=True, timeout=timeout_s, env=_worker_env(), check=False
            )
        except subprocess.TimeoutExpired:
            raise OmplPeerError(f"OMPL worker did not finish within {timeout_s:.0f} s") from None
        count = rows.shape[0] if expected is None else expected
        records = read_worker_results(result, count, proc.returncode, proc.stderr)
        return records, proc.returncode


def _world_block(record: dict[str, Any], graph: ExplicitGraph, row: BoolArray, start: int, goal: int) -> dict[str, Any]:
    check = verify_path(graph, row, start, goal, record["path_vertices"]) if record["solved"] else None
    success = check is not None and check.ok
    reason = "" if success else (f"OMPL found no path ({record['status']})" if check is None else check.reason)
    vertices_added = record["milestones_after"] - record["milestones_before"]
    edges_added = record["edges_after"] - (record["edges_before"] - record["edges_removed"])
    return {
        "world": record["world"],
        "checks": len(record["checked_edges"]),
        "checked_edges": record["checked_edges"],
        "checked_free": record.get("checked_free", []),
        "check_s": record.get("check_s", 0.0),
        "success": success,
        "ompl_solved": record["solved"],
        "ompl_status": record["status"],
        "failure_reason": reason,
        "path_vertices": record["path_vertices"],
        "path_edges": [] if check is None else check.edges.tolist(),
        "wall_s": record["wall_s"],
        "state_checks": record["state_checks"],
        "motion_calls": record["motion_calls"],
        "connector_calls": record["connector_calls"],
        "reverse_rejections": record["reverse_rejections"],
        "roadmap": {
            "iterations": record["iterations"],
            "vertices_added": vertices_added,
            "edges_added": edges_added,
            "edges_removed": record["edges_removed"],
            # Only the start/goal copies with their connectors and isolated samples were added.
            "exact": edges_added == CONNECTOR_EDGES and vertices_added == 2 + record["iterations"],
        },
    }


def run_ompl_lazyprm(
    problem: Problem,
    test_ids: Sequence[int] | npt.ArrayLike,
    *,
    seed: int,
    time_limit_s: float,
    embedding: EmbeddingName = "auto",
) -> dict[str, Any]:
    """Run LazyPRM on ``problem.graph`` once per world in ``test_ids`` (rows of X) in one child process.

    Args:
        problem: a problem with a graph, start, goal and world database.
        test_ids: (k,) world row indices.
        seed: OMPL's RNG seed (LazyPRM's samples stay isolated, so results do not depend on it).
        time_limit_s: wall-clock limit of one world's solve, in seconds.
        embedding: ``auto``, ``coords`` or ``index`` (see :func:`embed_vertices`).

    Returns:
        ``{"peer", "dataset", "ompl", "embedding", "seed", "time_limit_s", "test_ids", "checks" (k ints),
        "mean_checks", "median_checks", "failures", "mean_wall_ms", "total_wall_s", "worker_returncode",
        "worlds": [per-world blocks: checks, success, path_edges, wall_s, state_checks, roadmap, ...]}``.

    Raises:
        OmplPeerError: OMPL is unavailable (message :data:`SKIP_MESSAGE`), the problem lacks a graph,
            start, goal or worlds, or the worker failed.
    """
    ids = np.asarray(test_ids, dtype=np.int64).ravel()
    graph, start, goal, ids = _check_problem(problem, ids.tolist())
    available, message = ompl_available()
    if not available:
        raise OmplPeerError(message)
    embedded = embed_vertices(graph, embedding)
    rows = problem.require_worlds().X[ids]
    config = {**_worker_config(graph, embedded, start, goal, seed, time_limit_s), "world_ids": ids.tolist()}
    t0 = time.perf_counter()
    records, returncode = _run_worker(
        graph, embedded.states, rows, config, timeout_s=60.0 + ids.size * (time_limit_s + 5.0)
    )
    total = time.perf_counter() - t0
    worlds = [_world_block(rec, graph, row, start, goal) for rec, row in zip(records, rows, strict=True)]
    checks = np.array([w["checks"] for w in worlds], dtype=np.float64)
    return {
        "peer": PEER_NAME,
        "dataset": problem.name,
        "ompl": message,
        "embedding": embedded.kind,
        "seed": int(seed),
        "time_limit_s": float(time_limit_s),
        "test_ids": ids.tolist(),
        "checks": [int(c) for c in checks],
        "mean_checks": float(checks.mean()) if checks.size else float("nan"),
        "median_checks": float(np.median(checks)) if checks.size else float("nan"),
        "failures": sum(not w["success"] for w in worlds),
        "mean_wall_ms": 1e3 * float(np.mean([w["wall_s"] for w in worlds])) if worlds else 0.0,
        "total_wall_s": total,
        "worker_returncode": returncode,
        "worlds": worlds,
    }


@dataclass(frozen=True)
class LiveWorlds:
    """The worlds a live run checks: the domain (registry name and JSON-able spec) and the world recipes."""

    domain: str
    spec: dict[str, Any]
    worlds: tuple[WorldRecipe, ...]


def run_ompl_lazyprm_live(
    graph: ExplicitGraph,
    start: int,
    goal: int,
    live: LiveWorlds,
    *,
    seed: int = 0,
    time_limit_s: float = 60.0,
    embedding: EmbeddingName = "auto",
    check_costs_ms: Sequence[float] = (0.0,),
) -> dict[str, Any]:
    """Run LazyPRM on ``graph`` once per world, each edge answered by the domain's live edge checker.

    Args:
        graph: the domain's graph (the worker's domain, rebuilt from ``spec``, must have the same edges).
        start: start vertex.
        goal: goal vertex.
        live: the domain (its spec, e.g. with ``collision_model`` for the arm) and the worlds, all
            rebuilt in the worker.
        seed: OMPL's RNG seed.
        time_limit_s: wall-clock limit of one world's solve, in seconds.
        embedding: ``auto``, ``coords`` or ``index`` (see :func:`embed_vertices`).
        check_costs_ms: solve each world once per cost, each distinct edge check spending that many ms of
            CPU on top of the checker (:mod:`drd_planner.bench.check_cost`), a new checker per solve, after
            one untimed solve on the first world (the first solve's one-off work is in no record).

    Returns:
        ``{"peer", "ompl", "embedding", "domain", "worlds": [per world and cost (world-major): label,
        check_cost_ms, cpu_s (the solve's CPU time), checks, checked_edges,
        checked_free, success (OMPL solved and every path edge was checked free), path_edges, wall_s
        (the solve, checks included), check_s (inside the checker), ...], "total_wall_s"}``.

    Raises:
        OmplPeerError: OMPL is unavailable, the start or goal is not a vertex, or the worker failed.
    """
    available, message = ompl_available()
    if not available:
        raise OmplPeerError(message)
    for label, vertex in (("start", start), ("goal", goal)):
        if not 0 <= int(vertex) < graph.num_vertices:
            raise OmplPeerError(f"{label} vertex {vertex} outside [0, {graph.num_vertices})")
    embedded = embed_vertices(graph, embedding)
    config = {
        **_worker_config(graph, embedded, start, goal, seed, time_limit_s),
        "live": {
            "domain": live.domain,
            "spec": dict(live.spec),
            "worlds": [w.to_json() for w in live.worlds],
        },
        "check_costs_ms": [float(c) for c in check_costs_ms],
    }
    solves = [(recipe, float(c)) for recipe in live.worlds for c in check_costs_ms]
    rows = np.zeros((0, graph.num_edges), dtype=bool)
    t0 = time.perf_counter()
    records, returncode = _run_worker(
        graph,
        embedded.states,
        rows,
        config,
        timeout_s=300.0 + len(solves) * (time_limit_s + 5.0),
        expected=len(solves),
    )
    blocks = []
    for record, (recipe, _) in zip(records, solves, strict=True):
        row = np.zeros(graph.num_edges, dtype=bool)
        row[np.asarray(record["checked_edges"], dtype=np.int64)] = np.asarray(record["checked_free"], dtype=bool)
        block = _world_block(record, graph, row, int(start), int(goal))
        extra = {"check_cost_ms": record.get("check_cost_ms", 0.0), "cpu_s": record.get("cpu_s")}
        blocks.append({"label": recipe.label, **extra, **block})
    return {
        "peer": PEER_NAME,
        "ompl": message,
        "embedding": embedded.kind,
        "domain": live.domain,
        "worlds": blocks,
        "total_wall_s": time.perf_counter() - t0,
        "worker_returncode": returncode,
    }
