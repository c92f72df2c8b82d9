"""Child process that runs OMPL's LazyPRM on an explicit graph; started by :mod:`drd_planner.bench.ompl_peer`.

OMPL 1.7.0's Python bindings can crash while the interpreter tears down, so everything OMPL touches
lives in this process. It reads a request (``request.npz`` with the graph and the worlds' rows of X,
``config.json`` with the scalars), writes one JSON line per world to the result file (flushed after
each line, then a final ``{"done": true}`` line) and leaves with ``os._exit`` so that no teardown
runs. ``--probe`` only imports OMPL and prints one JSON line. Its entry point (argv) is
:mod:`drd_planner.cli.ompl_worker`.

**Live mode** (``config["live"]``: a domain name, its spec and a list of
:class:`~drd_planner.bench.world_recipes.WorldRecipe` dicts): instead of rows of X, the motion validator
answers each graph edge with the domain's own edge checker on each world, built here from the spec (the
domain's graph must equal the request's, edge for edge; one edge is checked once, untimed, before the first
world, so that first use costs fall in no world). Every answer is timed, so a world's ``wall_s`` is
LazyPRM's time to a path including the collision checks it asked for.

How LazyPRM is made to search exactly our graph:

* The roadmap is handed to ``LazyPRM(PlannerData)``: one vertex per graph vertex (each its own
  ``State`` object, since PlannerData merges vertices that share a state pointer) and one edge per
  graph edge weighted with the graph's length.
* Vertices live in a RealVectorStateSpace(d) at the positions the parent chose
  (:func:`drd_planner.bench.ompl_peer.embed_vertices`: coordinates, or the scaled vertex index).
  LazyPRM keeps its default path-length objective (created in C++, so no Python call per A* step)
  with an infinite cost threshold, so its first path is final.
* LazyPRM still adds the start and goal states of the query as new milestones, and samples one
  milestone per solve iteration. The connection radius (far below the smallest distance between
  two vertices) and one neighbour at most make the start and goal copies connect only to their
  own graph vertex (a zero-length "connector" edge, answered free without a check) and leave the
  samples isolated.
* The motion validator maps both states to graph vertices, and the vertex pair to a graph edge id;
  it answers from the world's row of X and records every distinct edge asked. On a directed graph
  a request to traverse an edge backwards is refused without a check (LazyPRM's roadmap is
  undirected, so it may try).
"""

from __future__ import annotations

import functools
import json
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any

import numpy as np
import numpy.typing as npt

from drd_planner.core.graph import ExplicitGraph
from drd_planner.exceptions import ProblemError

#: Answers whether one graph edge (by id) is free.
EdgeAnswer = Callable[[int], bool]


def _import_ompl() -> tuple[Any, Any, Any]:
    from ompl import base as ob  # imported in this process only
    from ompl import geometric as og
    from ompl import util as ou

    return ob, og, ou


class _Bookkeeper:
    """Answers checks for one world at a time and records what was asked."""

    def __init__(self, graph: ExplicitGraph) -> None:
        self.graph = graph
        self.reset(lambda _edge: False)

    def reset(self, answer: EdgeAnswer) -> None:
        """Start a new world whose edges ``answer`` decides (True where free)."""
        self.answer = answer
        self.check_s = 0.0
        self.checked: dict[int, bool] = {}
        self.motion_calls = 0
        self.connector_calls = 0
        self.reverse_rejections = 0
        self.state_checks = 0
        self.removed = 0

    def motion(self, u: int, v: int) -> bool:
        """Outcome of moving from graph vertex ``u`` to ``v``."""
        self.motion_calls += 1
        if u == v:
            self.connector_calls += 1
            return True
        try:
            eid = self.graph.edge_id(u, v)
        except ProblemError:
            self.graph.edge_id(v, u)  # raises when (u, v) is no edge in either direction
            # A directed edge traversed backwards: refused without a check.
            self.reverse_rejections += 1
            self.removed += 1
            return False
        free = self.checked.get(eid)
        if free is None:
            t0 = time.perf_counter()
            free = bool(self.answer(eid))
            self.check_s += time.perf_counter() - t0
            self.checked[eid] = free
        if not free:
            self.removed += 1
        return free


def _space(ob: Any, coords: npt.NDArray[np.float64]) -> Any:
    dim = coords.shape[1]
    space = ob.RealVectorStateSpace(dim)
    bounds = ob.RealVectorBounds(dim)
    for k in range(dim):
        bounds.setLow(k, float(coords[:, k].min()) - 1.0)
        bounds.setHigh(k, float(coords[:, k].max()) + 1.0)
    space.setBounds(bounds)
    return space


def run_request(request: Path, config_path: Path, out: IO[str]) -> None:
    """Solve ``request`` (.npz) with the ``config_path`` (JSON) settings; one JSON line per world to ``out``."""
    ob, og, ou = _import_ompl()
    config = json.loads(config_path.read_text())
    with np.load(request, allow_pickle=False) as data:
        edges = np.asarray(data["edges"], dtype=np.int64)
        lengths = np.asarray(data["lengths"], dtype=np.float64)
        coords = np.asarray(data["states"], dtype=np.float64)
        rows = np.asarray(data["X"], dtype=bool)
    graph = ExplicitGraph(edges, lengths, int(config["num_vertices"]), bool(config["directed"]))
    vertex_of = {tuple(row): i for i, row in enumerate(coords.tolist())}
    if coords.shape[0] != graph.num_vertices or len(vertex_of) != graph.num_vertices:
        raise RuntimeError(f"need {graph.num_vertices} distinct vertex states, got {coords.shape[0]}")
    ou.setLogLevel(ou.LOG_ERROR)
    ou.RNG.setSeed(int(config["seed"]))

    space = _space(ob, coords)
    dim = coords.shape[1]
    book = _Bookkeeper(graph)

    def vertex(state: Any) -> int:
        return vertex_of[tuple(float(state[k]) for k in range(dim))]

    si, validator = _space_information(ob, space, book, vertex)
    roadmap, keep_alive = _roadmap(ob, space, si, coords, (edges, lengths))
    if roadmap.numVertices() != graph.num_vertices or roadmap.numEdges() != graph.num_edges:
        raise RuntimeError(
            f"PlannerData holds {roadmap.numVertices()} vertices / {roadmap.numEdges()} edges, "
            f"graph has {graph.num_vertices} / {graph.num_edges}"
        )
    start_state, goal_state = ob.State(space), ob.State(space)
    for k in range(dim):
        start_state[k] = float(coords[int(config["start"]), k])
        goal_state[k] = float(coords[int(config["goal"]), k])
    session = _Session(ob, og, si, roadmap, (start_state, goal_state), vertex, book, config)
    answers = list(_live_answers(graph, config["live"]) if "live" in config else _table_answers(config, rows))
    costs = [float(c) for c in config.get("check_costs_ms", [0.0])]
    if "check_costs_ms" in config and answers:  # an untimed first solve: its one-off work in no record
        session.solve(answers[0][0], answers[0][1]())
    for world, answer_of in answers:
        for cost in costs:  # a fresh answer (a fresh checker: they may cache) per check cost
            record = session.solve(world, _with_cost(answer_of(), cost))
            out.write(json.dumps({**record, "check_cost_ms": cost}) + "\n")
            out.flush()
    out.write(json.dumps({"done": True}) + "\n")
    out.flush()
    del validator, keep_alive  # OMPL held them (the validator, the roadmap's states) until here


def _with_cost(answer: EdgeAnswer, cost_ms: float) -> EdgeAnswer:
    """``answer`` after ``cost_ms`` ms of CPU per call (:func:`drd_planner.bench.check_cost.burn_cpu_ms`)."""
    if cost_ms <= 0.0:
        return answer
    from drd_planner.bench.check_cost import burn_cpu_ms

    def costly(edge: int) -> bool:
        burn_cpu_ms(cost_ms)
        return answer(edge)

    return costly


def _table_answers(
    config: dict[str, Any], rows: npt.NDArray[np.bool_]
) -> Iterator[tuple[int, Callable[[], EdgeAnswer]]]:
    """``(world id, answer maker)`` per requested world, answered from its (E,) row of X."""
    for world, row in zip(config["world_ids"], rows, strict=True):
        yield int(world), functools.partial(_row_answer, row)


def _row_answer(row: npt.NDArray[np.bool_]) -> EdgeAnswer:
    """The answer of one (E,) row of X (True where the edge is free)."""

    def answer(edge: int) -> bool:
        return bool(row[edge])

    return answer


def _live_answers(graph: ExplicitGraph, live: dict[str, Any]) -> Iterator[tuple[int, Callable[[], EdgeAnswer]]]:
    """``(world index, answer maker)`` per world recipe: each answer a new edge checker of the domain there."""
    from drd_planner.bench.world_recipes import WorldRecipe
    from drd_planner.domains.base import domain_from_spec

    domain = domain_from_spec(str(live["domain"]), live.get("spec") or {})
    own = domain.graph
    if own.num_edges != graph.num_edges or not np.array_equal(own.edges, graph.edges):
        raise RuntimeError(f"the live domain's graph ({own.num_edges} edges) is not the request's ({graph.num_edges})")
    worlds = [WorldRecipe.from_json(recipe).make(domain) for recipe in live["worlds"]]
    if worlds and graph.num_edges:  # first use in this process (imports, caches): not in any world's time
        domain.checker(worlds[0]).check(0)
    for index, world in enumerate(worlds):
        yield index, functools.partial(_checker_answer, domain, world)


def _checker_answer(domain: Any, world: Any) -> EdgeAnswer:
    """The ``check`` of a new edge checker of ``domain`` on ``world``."""
    answer: EdgeAnswer = domain.checker(world).check
    return answer


def _space_information(ob: Any, space: Any, book: _Bookkeeper, vertex: Callable[[Any], int]) -> tuple[Any, Any]:
    """``(space information, motion validator)``: every state valid, motions answered by ``book``.

    The caller keeps the validator (a Python object OMPL calls back) alive while OMPL runs.
    """
    si = ob.SpaceInformation(space)

    def state_valid(state: Any) -> bool:
        book.state_checks += 1
        # Vertex validity is folded into the edge outcomes of X (docs/algorithms.md, "Worlds, the path
        # library and the split").
        return True

    def check_motion(self: Any, s1: Any, s2: Any, *last_valid: Any) -> bool:
        return book.motion(vertex(s1), vertex(s2))

    # A Python subclass of ob.MotionValidator whose checkMotion OMPL calls back.
    validator_class = type("TableMotionValidator", (ob.MotionValidator,), {"checkMotion": check_motion})
    si.setStateValidityChecker(ob.StateValidityCheckerFn(state_valid))
    validator = validator_class(si)
    si.setMotionValidator(validator)
    si.setup()
    return si, validator


def _roadmap(
    ob: Any,
    space: Any,
    si: Any,
    coords: npt.NDArray[np.float64],
    graph_edges: tuple[npt.NDArray[np.int64], npt.NDArray[np.float64]],
) -> tuple[Any, list[Any]]:
    """``(PlannerData, its states)``: a vertex per (V, d) ``coords`` row, an edge per (E, 2) edge with its length.

    Each vertex gets its own ``State``; the caller keeps the returned states alive while OMPL runs.
    """
    edges, lengths = graph_edges
    roadmap = ob.PlannerData(si)
    keep_alive = []
    for row in coords.tolist():
        st = ob.State(space)
        for k, value in enumerate(row):
            st[k] = value
        keep_alive.append(st)
        roadmap.addVertex(ob.PlannerDataVertex(st()))
    for (u, v), length in zip(edges.tolist(), lengths.tolist(), strict=True):
        roadmap.addEdge(int(u), int(v), ob.PlannerDataEdge(), ob.Cost(float(length)))
    return roadmap, keep_alive


@dataclass
class _Session:
    """Everything one LazyPRM solve per world needs: OMPL modules, space, roadmap, query and bookkeeper."""

    ob: Any
    og: Any
    si: Any
    roadmap: Any
    endpoints: tuple[Any, Any]
    vertex: Callable[[Any], int]
    book: _Bookkeeper
    config: dict[str, Any]

    def solve(self, world: int, answer: EdgeAnswer) -> dict[str, Any]:
        """The JSON record of one LazyPRM solve on world ``world`` whose edges ``answer`` decides."""
        ob, book = self.ob, self.book
        book.reset(answer)
        planner = self.og.LazyPRM(self.roadmap)
        planner.setRange(float(self.config["connect_radius"]))
        planner.setMaxNearestNeighbors(1)
        pdef = ob.ProblemDefinition(self.si)
        pdef.setStartAndGoalStates(*self.endpoints)
        planner.setProblemDefinition(pdef)
        planner.setup()
        milestones_before, edges_before = int(planner.milestoneCount()), int(planner.edgeCount())
        time_limit = float(self.config["time_limit_s"])
        t0, c0 = time.perf_counter(), time.process_time()

        def stop(t0: float = t0, planner: Any = planner) -> bool:
            # Iteration 1 runs the lazy search to a path or to a disconnected start and goal;
            # later iterations would only add isolated samples.
            return int(planner.getIterationCount()) >= 2 or time.perf_counter() - t0 > time_limit

        status = planner.solve(ob.PlannerTerminationCondition(ob.PlannerTerminationConditionFn(stop)))
        wall, cpu = time.perf_counter() - t0, time.process_time() - c0
        solved = pdef.hasExactSolution()
        return {
            "world": world,
            "status": str(status),
            "solved": bool(solved),
            "path_vertices": self._path_vertices(pdef) if solved else [],
            "checked_edges": list(book.checked),
            "checked_free": list(book.checked.values()),
            "check_s": book.check_s,
            "motion_calls": book.motion_calls,
            "connector_calls": book.connector_calls,
            "reverse_rejections": book.reverse_rejections,
            "state_checks": book.state_checks,
            "edges_removed": book.removed,
            "iterations": int(planner.getIterationCount()),
            "milestones_before": milestones_before,
            "milestones_after": int(planner.milestoneCount()),
            "edges_before": edges_before,
            "edges_after": int(planner.edgeCount()),
            "wall_s": wall,
            "cpu_s": cpu,
        }

    def _path_vertices(self, pdef: Any) -> list[int]:
        """Graph vertices of the solution path, repeats in a row merged."""
        path = pdef.getSolutionPath()
        path_vertices: list[int] = []
        for i in range(path.getStateCount()):
            v = self.vertex(path.getState(i))
            if not path_vertices or path_vertices[-1] != v:
                path_vertices.append(v)
        return path_vertices


def probe() -> dict[str, Any]:
    """Whether OMPL imports here and has LazyPRM and PlannerData (a JSON-able dict)."""
    ob, og, _ = _import_ompl()
    return {"ok": True, "has_lazyprm": hasattr(og, "LazyPRM"), "has_planner_data": hasattr(ob, "PlannerData")}
