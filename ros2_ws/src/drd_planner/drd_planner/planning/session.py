"""One loaded tree, ready to plan on map snapshots: lazy, cached FCL checks driven by the tree.

:class:`PlanningSession` rebuilds the tree's domain (graph, start, goal, checker) from the spec
stored in the tree file, refuses a file whose stored graph does not match that spec, and serves
requests: :meth:`PlanningSession.plan` walks the tree, checks each asked edge on the snapshot's
scene only when asked (results cached per map snapshot), switches to BiSECt at the leaf and
returns a :class:`PlanResult`. The returned path is re-verified against the check log before it
is handed out: every one of its edges was checked free on that snapshot (the safety invariant).
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt

from drd_planner.arrays import FloatArray
from drd_planner.core.episode import EpisodeStatus, run_episode
from drd_planner.core.policies import POLICIES, PolicyContext
from drd_planner.data.tree_file import TreeBundle
from drd_planner.domains.base import EdgeChecker
from drd_planner.exceptions import PlanningError, TreeFileError, UnverifiedPathError
from drd_planner.planner.result import PlanStatus as PlannerStatus
from drd_planner.planning.domain_view import (
    DomainSession,
    domain_from_stored_spec,
    state_positions,
    straight_edge_states,
)
from drd_planner.planning.map_state import MapSnapshot

#: How far (metres, in x, y, z) a requested goal position may be from the tree's goal position.
DEFAULT_GOAL_TOLERANCE = 1.0
#: How far (radians, per joint) a requested goal configuration may be from the tree's goal (arm).
DEFAULT_JOINT_TOLERANCE = 0.05


@dataclass(frozen=True)
class SessionCheck:
    """One check of a plan.

    Attributes:
        step: 1-based order.
        edge: edge id; ``endpoints`` its (u, v) vertices.
        free: outcome.
        stage: ``tree`` or ``bisect``.
        check_ms: collision-check wall time, ms (0 when answered from the cache).
        select_ms: time the policy took to choose the edge, ms.
        cached: answered from the cache of this map snapshot.
    """

    step: int
    edge: int
    endpoints: tuple[int, int]
    free: bool
    stage: str
    check_ms: float
    select_ms: float
    cached: bool


@dataclass(frozen=True)
class PlanResult:
    """The outcome of one request.

    Attributes:
        ok: a path was proven free.
        status: ``path_found``, ``no_free_path``, ``max_checks`` or ``policy_gave_up``.
        message: one line for logs and diagnostics.
        map_version: the snapshot planned on.
        prior: name of the prior that planned it (its file stem; a tree file loads as a prior).
        path_edges: edge ids of the path, in order (empty unless ok).
        path_vertices: its vertex ids (start ... goal).
        states: (K, d) the path's states (trajectory samples; x, y, z metres first, or joint angles).
        checks: every check, in order.
        seconds: wall times in seconds: ``prepare`` (the snapshot's FCL scene and checker, when
            :meth:`PlanningSession.prepare` had not built them already), ``checks`` (in FCL),
            ``selection`` (the policy choosing edges), ``policy`` (the policy's whole work in the
            episode: choosing, and updating its beliefs after each outcome), ``total``.
        cause: why it failed, as a value (:class:`~drd_planner.planner.cause.PlanCause`'s: ``start_outside``,
            ``goal_outside``, ``start_blocked``, ``goal_blocked``), where the planner can tell; "" otherwise.
    """

    ok: bool
    status: str
    message: str
    map_version: int
    prior: str
    path_edges: tuple[int, ...] = ()
    path_vertices: tuple[int, ...] = ()
    states: FloatArray = field(default_factory=lambda: np.zeros((0, 3)))
    checks: tuple[SessionCheck, ...] = ()
    seconds: dict[str, float] = field(default_factory=dict)
    cause: str = ""

    @property
    def tree(self) -> str:
        """Deprecated alias of :attr:`prior` (read-only; removed in the next release)."""
        return self.prior

    @property
    def num_blocked(self) -> int:
        """Checks that found the edge in collision."""
        return sum(not c.free for c in self.checks)


#: The :attr:`PlanResult.status` of each planner status (a budget's status depends on the budget).
PLANNER_STATUS = {
    PlannerStatus.FOUND: "path_found",
    PlannerStatus.NO_PATH: "no_free_path",
    PlannerStatus.REFUSED: "refused",
}


class _CachingOracle:
    """Edge oracle over one snapshot's checker, remembering outcomes for that map version."""

    def __init__(self, checker: EdgeChecker, cache: dict[int, bool]) -> None:
        self._checker = checker
        self._cache = cache
        self.timings: dict[int, tuple[float, bool]] = {}

    def check(self, edge: int) -> bool:
        known = self._cache.get(edge)
        if known is not None:
            self.timings[edge] = (0.0, True)
            return known
        t0 = time.perf_counter()
        free = bool(self._checker.check(edge))
        self.timings[edge] = ((time.perf_counter() - t0) * 1e3, False)
        self._cache[edge] = free
        return free


class PlanningSession(DomainSession):
    """Plans with one tree bundle on map snapshots.

    Args:
        bundle: the loaded tree file (with ``domain_spec`` in its problem metadata).
        name: a label for logs (the file stem).
        max_checks: cap on checks per request (None: none).
        goal_tolerance: metres (per axis) within which a requested goal position matches the tree's goal
            position (the helicopter's goal, or the arm's end-effector position at its goal).
        joint_tolerance: radians (per joint) within which a requested arm configuration matches the
            tree's goal configuration.

    Raises:
        TreeFileError: the bundle has no domain spec, or its stored graph differs from the graph its
            spec builds (a corrupt or mismatched file).
    """

    def __init__(
        self,
        bundle: TreeBundle,
        *,
        name: str = "tree",
        max_checks: int | None = None,
        goal_tolerance: float = DEFAULT_GOAL_TOLERANCE,
        joint_tolerance: float = DEFAULT_JOINT_TOLERANCE,
    ) -> None:
        meta = bundle.problem.metadata
        if "domain_spec" not in meta or "domain" not in meta:
            raise TreeFileError(f"{name}: the tree file has no domain spec (built from an authors' dataset?)")
        domain = domain_from_stored_spec(str(meta["domain"]), meta["domain_spec"], label=name, error=TreeFileError)
        graph = bundle.problem.graph
        if (
            graph is None
            or not np.array_equal(domain.graph.edges, graph.edges)
            or not np.allclose(domain.graph.lengths, graph.lengths)
            or (domain.start, domain.goal) != (bundle.problem.start, bundle.problem.goal)
        ):
            raise TreeFileError(f"{name}: the stored graph does not match the graph of its domain spec")
        super().__init__(domain, name)
        self._bundle = bundle
        self._max_checks = max_checks
        self._goal_tolerance = goal_tolerance
        self._joint_tolerance = joint_tolerance
        self._trajectories = domain.edge_trajectories()
        root = bundle.tree.bias(0, alpha=bundle.alpha)
        self._context = PolicyContext(
            bundle.problem.library,
            bundle.problem.edge_costs,
            root,
            bundle.tree,
            0,
            eta=bundle.eta,
            alpha=bundle.alpha,
            pseudo_count=bundle.pseudo_count,
        )

    @property
    def bundle(self) -> TreeBundle:
        """The tree bundle."""
        return self._bundle

    def library_edges(self) -> npt.NDArray[np.int64]:
        """Edge ids of the tree's library (sorted, each once)."""
        return np.asarray(self._bundle.problem.library.library_edges, dtype=np.int64)

    def vertex_state(self, vertex: int) -> FloatArray:
        """(d,) state of a graph vertex (x, y, z, heading for the helicopter; joints for the arm)."""
        states = self._domain.graph.vertex_states
        if states is None:
            raise PlanningError(f"{self._name}: the graph has no vertex states")
        return np.asarray(states[vertex], dtype=np.float64)

    @property
    def goal_state(self) -> FloatArray:
        """(d,) the tree's goal state."""
        return self.vertex_state(self._domain.goal)

    def positions(self, states: npt.ArrayLike, snapshot: MapSnapshot | None = None) -> FloatArray:
        """(K, 3) positions (m, planning frame) of (K, d) states: x, y, z, or the arm's end effector.

        The arm uses ``snapshot.robot`` when the snapshot carries a ``robot_description``.
        """
        return state_positions(self._domain, states, self.goal_state.size, snapshot)

    @property
    def goal_position(self) -> FloatArray:
        """(3,) the goal position (m): the helicopter's goal, or the arm's end effector at its goal."""
        position: FloatArray = self.positions(self.goal_state)[0]
        return position

    def matches_goal(self, goal: npt.ArrayLike) -> bool:
        """Whether a requested goal is this tree's: a (3,) position in metres, or an arm's joint angles."""
        want = np.asarray(goal, dtype=np.float64).ravel()
        if want.size == 3:
            have, tolerance = self.goal_position, self._goal_tolerance
        else:
            have, tolerance = self.goal_state, self._joint_tolerance
        return bool(want.size == have.size and np.all(np.abs(want - have) <= tolerance))

    def edge_states(self, edge: int) -> FloatArray:
        """(K, d) the edge's trajectory samples from its first vertex to its second.

        Domains without stored trajectories (the arm) move in a straight line between the vertices;
        it is sampled so that no coordinate moves more than the domain's check resolution per step.
        """
        if self._trajectories is not None:
            return np.asarray(self._trajectories[edge], dtype=np.float64)
        u, v = self._domain.graph.edges[edge]
        return straight_edge_states(self._domain, self.vertex_state(int(u)), self.vertex_state(int(v)))

    def motion_states(self, edge: int) -> FloatArray | None:
        """None: a tree session plans on its graph's edges only (no motions off it)."""
        return None

    def path_vertices(self, edges: npt.ArrayLike) -> list[int]:
        """Vertex ids along a path of edges from the start (undirected edges may be walked backwards)."""
        graph_edges = self._domain.graph.edges
        vertices = [int(self._domain.start)]
        for e in np.asarray(edges, dtype=np.int64):
            u, v = (int(x) for x in graph_edges[e])
            vertices.append(v if u == vertices[-1] else u)
        return vertices

    def path_states(self, edges: npt.ArrayLike) -> FloatArray:
        """(K, d) states along a path of edges from the start (shared vertices once)."""
        rows = []
        graph_edges = self._domain.graph.edges
        vertices = self.path_vertices(edges)
        for k, e in enumerate(np.asarray(edges, dtype=np.int64)):
            states = self.edge_states(int(e))
            rows.append(states if int(graph_edges[e, 0]) == vertices[k] else states[::-1])
        if not rows:
            return np.zeros((0, 3))
        return np.concatenate([rows[0]] + [r[1:] for r in rows[1:]])

    def plan(self, snapshot: MapSnapshot, *, seed: int = 0, checker: EdgeChecker | None = None) -> PlanResult:
        """Serve one request on ``snapshot`` (see the module docstring).

        Args:
            snapshot: the maps to plan on; the plan never mixes versions.
            seed: seeds the policy (same seed, same maps: same checks).
            checker: the checker to use (default :meth:`checker` of the snapshot).

        Raises:
            PlanningError: the snapshot has no terrain and no obstacles yet (no maps).
            UnverifiedPathError: never, unless the bookkeeping is broken (then nothing is returned).
        """
        t0 = time.perf_counter()
        cache = self._outcomes(snapshot)
        oracle = _CachingOracle(checker or self.checker(snapshot), cache)
        t_episode = time.perf_counter()
        context = dataclasses.replace(self._context, seed=seed)
        policy = POLICIES["direct_bisect"](context)
        problem = self._bundle.problem
        episode = run_episode(problem.library, problem.edge_costs, policy, oracle, max_checks=self._max_checks)
        episode_s = time.perf_counter() - t_episode
        edges = self._domain.graph.edges
        checks = tuple(
            SessionCheck(
                step=c.step + 1,  # the runner counts from 0
                edge=c.edge,
                endpoints=(int(edges[c.edge, 0]), int(edges[c.edge, 1])),
                free=c.free,
                stage=c.stage,
                check_ms=oracle.timings[c.edge][0],
                select_ms=c.select_ms,
                cached=oracle.timings[c.edge][1],
            )
            for c in episode.checks
        )
        check_s = sum(c.check_ms for c in checks) / 1e3
        seconds = {
            "prepare": t_episode - t0,
            "checks": check_s,
            "selection": sum(c.select_ms for c in checks) / 1e3,
            "policy": max(episode_s - check_s, 0.0),
        }
        common: dict[str, Any] = {"map_version": snapshot.version, "prior": self._name, "checks": checks}
        if episode.status is not EpisodeStatus.PATH_FOUND or episode.path_edges is None:
            seconds["total"] = time.perf_counter() - t0
            reason = {
                EpisodeStatus.NO_FREE_PATH: "no library path is free on this map",
                EpisodeStatus.MAX_CHECKS: f"gave up after max_checks = {self._max_checks} checks",
                EpisodeStatus.POLICY_GAVE_UP: "the policy had nothing left to check",
            }.get(episode.status, episode.status.value)
            return PlanResult(
                ok=False,
                status=episode.status.value,
                message=f"{reason} ({len(checks)} checks, {sum(not c.free for c in checks)} blocked)",
                seconds=seconds,
                **common,
            )
        path = tuple(int(e) for e in episode.path_edges)
        checked_free = {c.edge for c in checks if c.free}
        if not set(path) <= checked_free:  # the safety invariant, independent of the runner
            raise UnverifiedPathError(f"{self._name}: path edges {sorted(set(path) - checked_free)} not checked free")
        vertices = self.path_vertices(path)
        states = self.path_states(path)
        seconds["total"] = time.perf_counter() - t0
        return PlanResult(
            ok=True,
            status=episode.status.value,
            message=f"path of {len(path)} edges after {len(checks)} checks ({sum(not c.free for c in checks)} blocked)",
            path_edges=path,
            path_vertices=tuple(vertices),
            states=states,
            seconds=seconds,
            **common,
        )
