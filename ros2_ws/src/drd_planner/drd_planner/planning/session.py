"""One world prior, ready to plan any query on map snapshots: from where the robot is to any goal.

:class:`QuerySession` is the online side's one planning session: for a whole
:class:`~drd_planner.planner.WorldPrior` (a legacy tree file loads as the prior of its one query) it rebuilds
the prior's domain (graph and FCL checker) from the stored spec, refuses a prior whose stored graph differs
from the spec's, and serves ``plan(snapshot, start, goal)`` through a :class:`~drd_planner.planner.Planner`
(the precomputed tree of a query when there is one, DiRECt online otherwise, the graph fallback when the
library is exhausted), returning a :class:`~drd_planner.planning.session_plan.SessionPlan`.

- ``start`` and ``goal`` are vertex ids or states (helicopter: x, y, z in metres and heading in rad; arm:
  joint angles in rad). A state snaps to a vertex only within ``snap_tolerance`` (default 1e-6: only the
  vertex itself), so a plan from the robot's state starts *at* that state: the new motions joining it to
  the graph are checked like every edge, and nothing unchecked lies between the robot and the path.
- Checks run on the snapshot's FCL checker; outcomes are cached per snapshot (graph edges by id, motions
  by their session id), so repeated requests on one map answer from the cache.
- Motion edges get session-wide ids from E on (:class:`~drd_planner.planning.session_motions.MotionRegistry`):
  ``edge_states`` answers them for the last plans, and :func:`~drd_planner.planning.replan.recheck_plan`
  re-checks a published plan's motions after a map update like its graph edges.
- With an ``improve_budget`` (:class:`~drd_planner.planner.anytime.ImproveBudget`) a plan goes on after its
  first verified path, checking on the same snapshot for shorter ones, and returns the shortest it verified
  (``improvements`` shorter paths after the first, ``improve_stop`` why it stopped).
- Every returned path is re-verified independently of the planner's bookkeeping: each edge, motions
  included, was answered free by this session's oracle on this snapshot (in this plan or from the
  snapshot's cache), and its dense states join up from the start to the goal; otherwise
  :class:`~drd_planner.exceptions.UnverifiedPathError` (edges of a grown roadmap too).
"""

from __future__ import annotations

import time
from typing import Any, TypedDict

import numpy as np
import numpy.typing as npt

from drd_planner.arrays import FloatArray, IntArray
from drd_planner.core.status import PlanStatus
from drd_planner.exceptions import PlanningError, UnverifiedPathError
from drd_planner.geometry.robot import RobotModel
from drd_planner.planner.anytime import ImproveBudget, as_improve_budget, check_budgets
from drd_planner.planner.endpoints import Endpoint
from drd_planner.planner.planner import Planner
from drd_planner.planner.prior import WorldPrior
from drd_planner.planner.result import PlanResult as PlannerResult
from drd_planner.planning.cancel import Cancel
from drd_planner.planning.domain_view import DomainSession, state_positions, straight_edge_states
from drd_planner.planning.map_state import MapSnapshot
from drd_planner.planning.prior_domain import rebuild_domain
from drd_planner.planning.session_motions import DEFAULT_MOTIONS_KEPT, MotionRegistry, join_pieces
from drd_planner.planning.session_plan import SessionCheck, SessionPlan
from drd_planner.planning.snapshot_oracle import SnapshotOracle

#: How far (state units) a start or goal state may lie from a vertex and still be that vertex.
DEFAULT_SNAP_TOLERANCE = 1e-6
#: How far (m) an arm's end-effector goal may lie from the nearest roadmap vertex's end effector.
DEFAULT_POSITION_TOLERANCE = 0.05


class SessionBudgets(TypedDict):
    """The budget arguments of :class:`QuerySession` (the node builds them from its parameters)."""

    max_checks: int | None
    time_budget_s: float | None
    improve_budget: ImproveBudget | None


class QuerySession(DomainSession):
    """Plans any query of one world prior on map snapshots (see the module docstring).

    Args:
        prior: the loaded prior (``load_prior``; a legacy tree file serves its own query only).
        name: a label for logs (the file stem).
        max_checks: cap on checks per plan (None: none).
        time_budget_s: cap on a plan's planner time in seconds (None: none); the snapshot's scene and
            checker (:meth:`prepare`) are not counted.
        improve_budget: after a plan's first verified path, look for shorter verified ones within this
            budget (an int n is ``ImproveBudget(checks=n)``; None: stop at the first path); ``max_checks``
            and ``time_budget_s`` bound it too.
        snap_tolerance: how far a state may be from a vertex and be that vertex (state units); None uses
            the planner's default (a quarter of the median edge length: the path may then start up to
            that far from the given state).
        cache_size: queries whose library and tree the planner keeps.
        motions_kept: motions remembered for :meth:`edge_states` and re-checks.

    Raises:
        PriorFileError: the prior has no domain spec, the spec cannot be rebuilt, or its stored graph
            differs from the graph its spec builds.
        ProblemError: a budget that is not positive, or an ``improve_budget`` of another kind.
    """

    def __init__(
        self,
        prior: WorldPrior,
        *,
        name: str,
        max_checks: int | None = None,
        time_budget_s: float | None = None,
        improve_budget: ImproveBudget | int | None = None,
        snap_tolerance: float | None = DEFAULT_SNAP_TOLERANCE,
        cache_size: int = 16,
        motions_kept: int = DEFAULT_MOTIONS_KEPT,
    ) -> None:
        domain = rebuild_domain(prior, name)
        super().__init__(domain, name)
        self._prior = prior
        self.set_budgets(max_checks, time_budget_s)
        self._improve_budget = as_improve_budget(improve_budget)
        self._planner = Planner(prior, cache_size=cache_size, snap_tolerance=snap_tolerance)
        self._endpoints = self._planner.endpoints
        self._num_edges = prior.graph.num_edges
        self._motions = MotionRegistry(self._num_edges, capacity=motions_kept)
        self._trajectories = domain.edge_trajectories()
        self._tool_positions: tuple[RobotModel | None, FloatArray] | None = None
        for qt in prior.trees[:cache_size]:  # first use costs ~80 ms (bias, query graph): pay it here
            self._planner.query_model(qt.start, qt.goal)
        self._planner.warm_up()  # the per-prior work of new queries, here rather than in the first one

    def set_check_cost_ms(self, cost_ms: float | None) -> None:
        """Tell the planner what one check costs (None: not stated) and measure the lead's price now.

        See :attr:`drd_planner.planner.Planner.check_cost_ms`; ProblemError for a value that is not a finite
        number >= 0.
        """
        self._planner.check_cost_ms = cost_ms
        self._planner.warm_up()  # the library's price is measured here, not in the first request

    # ------------------------------------------------------------------------------------------------
    # What the node reads

    @property
    def prior(self) -> WorldPrior:
        """The world prior."""
        return self._prior

    @property
    def planner(self) -> Planner:
        """The planner over the prior."""
        return self._planner

    @property
    def state_dim(self) -> int:
        """D, the length of a state."""
        states = self._prior.graph.vertex_states
        return 0 if states is None else int(states.shape[1])

    @property
    def max_checks(self) -> int | None:
        """Cap on checks per plan (None: none)."""
        return self._max_checks

    @property
    def time_budget_s(self) -> float | None:
        """Cap on a plan's planner time in seconds (None: none)."""
        return self._time_budget_s

    @property
    def improve_budget(self) -> ImproveBudget | None:
        """The anytime improvement after each plan's first verified path (None: off)."""
        return self._improve_budget

    def set_budgets(self, max_checks: int | None, time_budget_s: float | None) -> None:
        """Use these caps from the next plan on (a runtime parameter change).

        Raises:
            ProblemError: a cap that is not positive.
        """
        check_budgets(max_checks, time_budget_s)
        self._max_checks = max_checks
        self._time_budget_s = None if time_budget_s is None else float(time_budget_s)

    @property
    def goal_state(self) -> FloatArray:
        """(D,) the goal state of the prior's stored query (the dataset's goal)."""
        return self.vertex_state(int(self._domain.goal))

    @property
    def goal_position(self) -> FloatArray:
        """(3,) the stored goal's position (m): the helicopter's, or the arm's end effector there."""
        position: FloatArray = self.positions(self.goal_state)[0]
        return position

    def vertex_state(self, vertex: int) -> FloatArray:
        """(D,) state of a graph vertex."""
        states = self._prior.graph.vertex_states
        if states is None:
            raise PlanningError(f"{self._name}: the graph has no vertex states")
        return np.array(states[int(vertex)], dtype=np.float64)

    def positions(self, states: npt.ArrayLike, snapshot: MapSnapshot | None = None) -> FloatArray:
        """(K, 3) positions (m, planning frame) of (K, D) states: x, y, z, or the arm's end effector.

        The arm uses ``snapshot.robot`` when the snapshot carries a ``robot_description``.
        """
        return state_positions(self._domain, states, self.state_dim, snapshot)

    def edge_states(self, edge: int) -> FloatArray:
        """(K, D) states along a graph edge (first vertex to second) or a remembered motion (tail first).

        Graph edges without stored trajectories (the arm) are straight lines sampled so that no
        coordinate moves more than the domain's check resolution per step.

        Raises:
            PlanningError: neither a graph edge nor a motion this session remembers.
        """
        e = int(edge)
        if 0 <= e < self._num_edges:
            if self._trajectories is not None:
                return np.asarray(self._trajectories[e], dtype=np.float64)
            u, v = self._prior.graph.edges[e]
            return straight_edge_states(self._domain, self.vertex_state(int(u)), self.vertex_state(int(v)))
        states = self._motions.states(e)
        if states is None:
            forgotten = " (forgotten: older than the motions kept)" if self._motions.is_motion_id(e) else ""
            raise PlanningError(
                f"{self._name}: edge {e} is neither a graph edge [0, {self._num_edges}) nor a motion "
                f"this session remembers{forgotten}"
            )
        return states

    def motion_states(self, edge: int) -> FloatArray | None:
        """(K, D) states of a remembered motion id, tail first; None for graph edges and unknown ids."""
        return self._motions.states(int(edge)) if int(edge) >= self._num_edges else None

    def library_edges(self) -> IntArray:
        """Edge ids of the precomputed trees' libraries (sorted, each once; empty without trees)."""
        parts = [np.asarray(qt.library.library_edges, dtype=np.int64) for qt in self._prior.trees]
        return np.unique(np.concatenate(parts)) if parts else np.zeros(0, dtype=np.int64)

    # ------------------------------------------------------------------------------------------------
    # Goals

    def goal_state_from_position(
        self,
        xyz: npt.ArrayLike,
        *,
        yaw: float = 0.0,
        snapshot: MapSnapshot | None = None,
        tolerance: float = DEFAULT_POSITION_TOLERANCE,
    ) -> FloatArray:
        """(D,) the goal state for a goal position (m, planning frame).

        Helicopter: the state at ``xyz`` with heading ``yaw`` (the goal pose's yaw; :func:`state_from_pose`).
        Arm: the state of the roadmap vertex whose end effector (with ``snapshot.robot`` when given) is
        nearest to ``xyz``, when it is within ``tolerance`` metres.

        Raises:
            PlanningError: a malformed position, no vertex within ``tolerance`` (the distance and the
                tolerance named), or a domain without position goals.
        """
        goals = self._domain.position_goals
        if goals == "pose":
            return self._domain.state_from_position(xyz, yaw)
        if goals != "vertex":
            raise PlanningError(f"{self._name}: the {self._domain.name} domain has no position goals")
        want = np.asarray(xyz, dtype=np.float64).ravel()
        if want.shape != (3,) or not np.all(np.isfinite(want)):
            raise PlanningError(f"a goal position must be three finite numbers (m), got {want.tolist()}")
        vertex, distance = self.nearest_vertex_to_position(want, snapshot)
        if not distance <= tolerance:
            raise PlanningError(
                f"{self._name}: goal position {np.round(want, 3).tolist()} is {distance:.3f} m from the nearest "
                f"end-effector position of the roadmap (vertex {vertex}), farther than the tolerance "
                f"{tolerance:.3f} m"
            )
        return self.vertex_state(vertex)

    def nearest_vertex_to_position(self, xyz: npt.ArrayLike, snapshot: MapSnapshot | None = None) -> tuple[int, float]:
        """(vertex, distance in m) of the vertex whose position (:meth:`positions`) is nearest to ``xyz``."""
        robot = snapshot.robot if snapshot is not None and self._domain.needs_robot_description else None
        cached = self._tool_positions
        if cached is None or cached[0] is not robot:
            states = self._prior.graph.vertex_states
            if states is None:
                raise PlanningError(f"{self._name}: the graph has no vertex states")
            cached = (robot, self.positions(states, snapshot if robot is not None else None))
            self._tool_positions = cached
        distances = np.linalg.norm(cached[1] - np.asarray(xyz, dtype=np.float64).ravel(), axis=1)
        vertex = int(np.argmin(distances))
        return vertex, float(distances[vertex])

    # ------------------------------------------------------------------------------------------------
    # Planning

    def plan(
        self, snapshot: MapSnapshot, start: Endpoint, goal: Endpoint, *, seed: int = 0, cancel: Cancel = None
    ) -> SessionPlan:
        """Plan from ``start`` to ``goal`` (vertex ids or (D,) states) on ``snapshot``; ``cancel`` stops it.

        Returns:
            ``ok`` only with a verified path (status FOUND); otherwise status NO_PATH, BUDGET_EXHAUSTED
            (``cause`` CHECK_BUDGET or TIME_BUDGET) or REFUSED (a malformed or unreachable start or goal, or a
            query a legacy tree file cannot serve) and the reason in ``message``.

        Raises:
            PlanningError: the snapshot has no terrain and no obstacles yet (no maps).
            PlanCancelled: ``cancel`` was set; the plan stopped before its next check.
            UnverifiedPathError: never, unless the bookkeeping is broken (then nothing is returned).
        """
        t0 = time.perf_counter()
        cache = self._outcomes(snapshot)
        oracle = SnapshotOracle(self.checker(snapshot), cache, self._motions, cancel)
        t_prepared = time.perf_counter()
        result = self._planner.plan(
            start,
            goal,
            oracle,
            seed=seed,
            max_checks=self._max_checks,
            time_budget_s=self._time_budget_s,
            improve_budget=self._improve_budget,
        )
        query = self._query_edges(result, start, goal)
        checks = self._session_checks(result, oracle, query)
        timings = result.timings
        check_s = sum(c.check_ms for c in checks) / 1e3
        seconds = {
            "prepare": t_prepared - t0,
            "checks": check_s,
            "selection": timings.selection_s,
            "library": timings.library_s,
            "policy": max(timings.total_s - timings.library_s - timings.checks_s, 0.0),
        }
        common: dict[str, Any] = {
            "map_version": snapshot.version,
            "prior": self._name,
            "checks": checks,
            "query": result.query,
            "query_cached": result.query_cached,
            "library_size": result.library_size,
            "cause": result.cause,
        }
        blocked = sum(not c.free for c in checks)
        if not result.found:
            seconds["total"] = time.perf_counter() - t0
            refused = result.status is PlanStatus.REFUSED
            message = result.reason if refused else f"{result.reason} ({blocked} blocked)"
            return SessionPlan(status=result.status, message=message, seconds=seconds, **common)
        path, states = self._verified_path(result, query)
        motions = sum(e >= self._num_edges for e in path)
        stage = result.stage.value if result.stage is not None else ""
        seconds["total"] = time.perf_counter() - t0
        return SessionPlan(
            status=PlanStatus.FOUND,
            message=(
                f"path of {len(path)} edges ({motions} new motions) proven by the {stage} stage after "
                f"{len(checks)} checks ({blocked} blocked){_improvement_text(result)}"
            ),
            path_edges=path,
            path_vertices=tuple(int(v) for v in result.vertices),
            states=states,
            seconds=seconds,
            stage=stage,
            cost=result.cost,
            first_cost=result.improvements[0].cost if result.improvements else 0.0,
            improvements=max(len(result.improvements) - 1, 0),
            improve_stop=result.improve_stop,
            **common,
        )

    def _query_edges(
        self, result: PlannerResult, start: Endpoint, goal: Endpoint
    ) -> tuple[IntArray, dict[int, FloatArray]]:
        """The query graph's (E', 2) edges and its motions (query id -> states) when the plan used motions."""
        graph_edges = self._prior.graph.edges
        used = [c.edge for c in result.checks] + [int(e) for e in result.edges]
        if not any(e >= self._num_edges for e in used):
            return graph_edges, {}
        if result.growth is not None:  # the plan grew the query's graph: grown edges are its motions too
            return result.growth.query.graph.edges, dict(result.growth.query.motions)
        # The planner's cached model of this query (the same snapping, so the same cache key).
        model = self._planner.query_model(self._endpoints.snap(start, "start"), self._endpoints.snap(goal, "goal"))
        if (model.start, model.goal) != (result.start, result.goal):
            raise UnverifiedPathError(f"{self._name}: the query's model does not match the plan's endpoints")
        return model.query.graph.edges, dict(model.query.motions)

    def _session_id(self, edge: int, motions: dict[int, FloatArray]) -> int:
        if edge < self._num_edges:
            return edge
        return self._motions.id_for(motions[edge])

    def _session_checks(
        self,
        result: PlannerResult,
        oracle: SnapshotOracle,
        query: tuple[IntArray, dict[int, FloatArray]],
    ) -> tuple[SessionCheck, ...]:
        edges, motions = query
        ids = [self._session_id(c.edge, motions) for c in result.checks]
        checked_motions = [sid for sid in ids if sid >= self._num_edges]
        if checked_motions != oracle.motion_calls:  # what the log names is what was checked
            raise UnverifiedPathError(f"{self._name}: the plan's motion checks do not match the motions checked")
        return tuple(
            SessionCheck(
                step=c.step + 1,  # the runner counts from 0
                edge=sid,
                endpoints=(int(edges[c.edge, 0]), int(edges[c.edge, 1])),
                free=c.free,
                stage=c.stage,
                check_ms=oracle.timings[sid][0],
                select_ms=c.select_ms,
                cached=oracle.timings[sid][1],
            )
            for c, sid in zip(result.checks, ids, strict=True)
        )

    def _verified_path(
        self, result: PlannerResult, query: tuple[IntArray, dict[int, FloatArray]]
    ) -> tuple[tuple[int, ...], FloatArray]:
        """Session ids and dense states of a found path, after the independent safety check."""
        edges, motions = query
        vertices = [int(v) for v in result.vertices]
        checked_free = {self._session_id(c.edge, motions) for c in result.checks if c.free}
        path: list[int] = []
        pieces: list[FloatArray] = []
        directed = self._prior.graph.directed
        for k, e in enumerate(int(x) for x in result.edges):
            sid = self._session_id(e, motions)
            if sid not in checked_free or self._cache.get(sid) is not True:
                raise UnverifiedPathError(f"{self._name}: path edge {sid} was not checked free on this snapshot")
            u, v = int(edges[e, 0]), int(edges[e, 1])
            states = self.edge_states(sid)
            if (u, v) == (vertices[k], vertices[k + 1]):
                pieces.append(states)
            elif not directed and (v, u) == (vertices[k], vertices[k + 1]):
                pieces.append(states[::-1])
            else:
                raise UnverifiedPathError(f"{self._name}: path edge {sid} does not join vertices {vertices[k : k + 2]}")
            path.append(sid)
        if not pieces:  # start and goal are one vertex
            return (), self._endpoint_state(vertices[0], result)[None, :]
        return tuple(path), join_pieces(pieces, dim=self.state_dim, periodic=self._domain.periodic_dims)

    def _endpoint_state(self, vertex: int, result: PlannerResult) -> FloatArray:
        state = result.new_states.get(vertex)
        return np.array(state, dtype=np.float64) if state is not None else self.vertex_state(vertex)


def _improvement_text(result: PlannerResult) -> str:
    """What the anytime improvement did, for a found plan's message ("" without an improve budget)."""
    if not result.improve_stop:
        return ""
    found = max(len(result.improvements) - 1, 0)
    first = result.improvements[0].cost if result.improvements else result.cost
    return (
        f"; {found} shorter path(s) after the first (cost {first:.4g} -> {result.cost:.4g}), "
        f"improvement stopped: {result.improve_stop}"
    )
