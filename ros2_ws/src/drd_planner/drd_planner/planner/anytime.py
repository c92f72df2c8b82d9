"""Anytime shorter paths after the first verified one (the paper's Q2), by posterior sampling.

The library stage stops at the first path it proves free, which can be much longer than the shortest
free path of the world. With an :class:`ImproveBudget` the plan goes on, in the spirit of posterior
sampling motion planning (PSMP):

1. draw a world from the posterior: a training world consistent with every outcome so far (weighted by
   its prior weight), or, with probability ``tail_probability`` and always when no training world is
   consistent, a world outside the database: every unchecked edge free independently with the
   probability of :func:`~drd_planner.planner.graph_fallback.posterior_free_probability` (the consistent
   worlds' free fraction shrunk toward the training marginal by kappa pseudo-worlds, mixed with 1/2 by
   1 - alpha); checked edges keep their outcome in every draw;
2. the shortest start-goal path (graph lengths) over the edges free in that world;
3. if it is shorter than the best verified path, check its unchecked edges, least likely free first
   (posterior probability; a blocked edge ends the proposal at once, so the likely blocker goes first);
   when every one is free it is a new, shorter verified path.

It stops at the first of: the best path is provably the shortest (its cost equals the shortest path of
the optimistic graph, every unchecked edge free and every blocked one deleted: ``optimal``); the
budget's checks or seconds are spent (``checks``, ``seconds``); the plan's own ``max_checks`` or
``time_budget_s`` (``plan_checks``, ``plan_time``); ``patience`` consecutive draws proposed nothing
(``patience``). A draw proposes nothing when its shortest path is not shorter than the best, or when it
needs more checks than the budget has left (a path that cannot be finished is not started). The loop
always ends: every draw that proposes something checks a new edge or records a shorter path.

Every recorded path has each edge checked free in this plan (re-verified before it is kept); the
sampler's random stream is derived from the plan's seed only (same seed, same checks).

Measured on the dataset's own query of the authors' SE(2) and helicopter sets (``scripts/experiments/bench_anytime.py``,
100 test worlds each, extra budget = the first path's checks): the mean gap of the path cost ratio to 1
falls by 72 % (xyh_1), 97 % (xyh_3), 91 % (xyh_4), 63 % (xyh_5) and 84 % (heli_canyon_1). Most draws that
propose nothing need more checks than are left (on xyh_5 about 11 unchecked edges with 6 left), so a
patience of 100 instead of 30 gains at most 4 points (heli 88 %) for up to a third more checks; half the plans
on xyh_5 end with no consistent training world left, where only the tail proposes.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from drd_planner.arrays import BoolArray, FloatArray, IntArray
from drd_planner.core.episode import CheckRecord, EdgeOracle, verify_path
from drd_planner.core.lazysp import GraphArcs
from drd_planner.exceptions import ProblemError
from drd_planner.planner.graph_fallback import DEFAULT_FALLBACK_KAPPA
from drd_planner.planner.prior import WorldPrior
from drd_planner.planner.query_library import ShortestPaths, vertex_sequence
from drd_planner.planner.query_model import QueryModel
from drd_planner.planner.result import Improvement, PlanResult, PlanStage

__all__ = ["ImproveBudget", "PlanLimits", "WorldSampler", "as_improve_budget", "improve_path"]

#: Consecutive draws that propose nothing before the improvement stops.
DEFAULT_PATIENCE = 30
#: Probability that a draw comes from the Bernoulli tail rather than a consistent training world.
DEFAULT_TAIL_PROBABILITY = 0.1
#: Stage label of the improvement's checks in the check log.
IMPROVE_STAGE = "improve"
#: Second word of the sampler's seed, so that its stream differs from the policy's (same plan seed).
_SAMPLER_STREAM = 0xA17
#: Relative tolerance of "shorter" and "equal to the optimistic bound".
_RTOL = 1e-9


@dataclass(frozen=True)
class ImproveBudget:
    """How long a plan goes on looking for shorter paths after its first verified one.

    Attributes:
        checks: the most checks after the first path (None: no check limit).
        seconds: the most wall-clock seconds after the first path (None: no time limit).
        patience: stop after this many consecutive draws that propose nothing.
        tail_probability: probability in [0, 1] of drawing a world outside the database (Bernoulli tail).

    At least one of ``checks`` and ``seconds`` must be given. :meth:`Planner.plan` also takes a plain
    int as ``ImproveBudget(checks=n)``.
    """

    checks: int | None = None
    seconds: float | None = None
    patience: int = DEFAULT_PATIENCE
    tail_probability: float = DEFAULT_TAIL_PROBABILITY

    def __post_init__(self) -> None:
        if self.checks is None and self.seconds is None:
            raise ProblemError("an improve budget needs checks (an int >= 1) or seconds (> 0), or both")
        if self.checks is not None and (not _is_int(self.checks) or self.checks < 1):
            raise ProblemError(f"improve budget checks must be an int >= 1 or None, got {self.checks!r}")
        if self.seconds is not None and not (_is_real(self.seconds) and 0 < self.seconds < np.inf):
            raise ProblemError(f"improve budget seconds must be a positive finite number or None, got {self.seconds!r}")
        if not _is_int(self.patience) or self.patience < 1:
            raise ProblemError(f"improve budget patience must be an int >= 1, got {self.patience!r}")
        if not (_is_real(self.tail_probability) and 0.0 <= self.tail_probability <= 1.0):
            raise ProblemError(f"tail_probability must lie in [0, 1], got {self.tail_probability!r}")


@dataclass(frozen=True)
class PlanLimits:
    """The plan's own settings that bound its improvement.

    Attributes:
        seed: the plan's seed (the sampler's stream is derived from it).
        max_checks: the plan's check limit, its first path's checks included (None: none).
        deadline: the plan's deadline on ``time.perf_counter()`` (None: none).
    """

    seed: int = 0
    max_checks: int | None = None
    deadline: float | None = None


def as_improve_budget(value: object) -> ImproveBudget | None:
    """``improve_budget`` of :meth:`Planner.plan` as a budget: None, an :class:`ImproveBudget`, or an int (checks).

    Raises:
        ProblemError: any other value (a float, a bool, a negative int, ...), naming what is valid.
    """
    if value is None or isinstance(value, ImproveBudget):
        return value
    if _is_int(value):
        return ImproveBudget(checks=int(value))  # type: ignore[call-overload]
    raise ProblemError(
        f"improve_budget must be None, an int (extra checks >= 1) or an ImproveBudget(checks=..., "
        f"seconds=...), got {value!r}"
    )


def _is_int(value: object) -> bool:
    return isinstance(value, int | np.integer) and not isinstance(value, bool | np.bool_)


def _is_real(value: object) -> bool:
    return isinstance(value, int | float | np.integer | np.floating) and not isinstance(value, bool | np.bool_)


class WorldSampler:
    """Worlds drawn from the posterior over the training worlds, with a Bernoulli tail (see the module doc).

    Args:
        worlds: (n, E) bool training worlds (True = free), or None (then every draw is a tail draw at 1/2).
        weights: (n,) positive prior weights, or None for uniform.
        outcomes: edges checked so far and their outcome.
        alpha: weight of the data term of the tail's probabilities.
        pseudo_count: kappa > 0, in worlds, of the tail's shrinkage toward the training marginal.
        tail_probability: probability of a tail draw while training worlds are consistent.
        rng: the random stream.
    """

    def __init__(
        self,
        worlds: BoolArray | None,
        weights: FloatArray | None,
        outcomes: Mapping[int, bool],
        *,
        num_edges: int,
        alpha: float,
        pseudo_count: float,
        tail_probability: float,
        rng: np.random.Generator,
    ) -> None:
        self._x = worlds
        n = 0 if worlds is None else int(worlds.shape[0])
        w = np.ones(n) if weights is None else np.asarray(weights, dtype=np.float64)
        self._w = w / w.mean() if n else w
        self._uniform = weights is None
        self._all = np.arange(n)
        self._marginal: FloatArray | None = None  # (E,) training marginal, computed on the first tail draw
        self._alpha, self._kappa, self._tail, self._rng = alpha, pseudo_count, tail_probability, rng
        self._state = np.full(num_edges, -1, dtype=np.int8)  # -1 unchecked, 0 blocked, 1 free
        self._consistent = np.ones(n, dtype=bool)
        self._theta: FloatArray | None = None
        for edge, free in outcomes.items():
            self.observe(edge, free)

    @property
    def num_consistent(self) -> int:
        """How many training worlds agree with every outcome so far."""
        return int(self._consistent.sum())

    def observe(self, edge: int, free: bool) -> None:
        """Record an outcome: the training worlds that disagree are no longer drawn."""
        self._state[edge] = 1 if free else 0
        if self._x is not None:
            self._consistent &= self._x[:, edge] == free
        self._theta = None

    def free_probability(self, edges: IntArray | None = None) -> FloatArray:
        """P(free | outcomes) of ``edges`` (all when None): the tail's probabilities, 1 or 0 when checked."""
        if edges is None and self._theta is not None:
            return self._theta
        cols = None if edges is None else np.asarray(edges, dtype=np.int64)
        state = self._state if cols is None else self._state[cols]
        if self._x is None:
            theta = np.full(state.size, 0.5)
        else:
            rows = np.flatnonzero(self._consistent)
            mass = float(self._w[rows].sum())
            data = (self._free_mass(rows, cols) + self._kappa * self._marginal_of(cols)) / (mass + self._kappa)
            theta = self._alpha * data + (1.0 - self._alpha) * 0.5
        theta = np.asarray(np.where(state == 1, 1.0, np.where(state == 0, 0.0, theta)), dtype=np.float64)
        if edges is None:
            self._theta = theta
        return theta

    def _free_mass(self, rows: IntArray, cols: IntArray | None) -> FloatArray:
        """(k,) weighted count of the worlds ``rows`` in which each edge of ``cols`` (None: all) is free."""
        assert self._x is not None
        if rows.size == 0:
            return np.zeros(self._state.size if cols is None else cols.size)
        block = self._x[rows] if cols is None else self._x[np.ix_(rows, cols)]
        if self._uniform:  # a count: no (rows, cols) float copy of the worlds
            return np.asarray(block.sum(axis=0, dtype=np.float64), dtype=np.float64)
        return np.asarray(self._w[rows] @ block, dtype=np.float64)

    def _marginal_of(self, cols: IntArray | None) -> FloatArray:
        """(k,) the weighted free fraction of each edge of ``cols`` (None: all) over every training world."""
        if self._marginal is None and cols is None:
            self._marginal = self._free_mass(self._all, None) / float(self._w.sum())
        if self._marginal is not None:
            return self._marginal if cols is None else self._marginal[cols]
        return self._free_mass(self._all, cols) / float(self._w.sum())

    def draw(self) -> BoolArray:
        """(E,) one sampled world (True = free); every checked edge at its outcome."""
        rows = np.flatnonzero(self._consistent)
        tail = self._rng.random() < self._tail
        if self._x is None or rows.size == 0 or tail:
            world = self._rng.random(self._state.size) < self.free_probability()
        else:
            p = self._w[rows] / self._w[rows].sum()
            world = self._x[int(self._rng.choice(rows, p=p))].copy()
        world[self._state == 1] = True
        world[self._state == 0] = False
        return np.asarray(world, dtype=bool)


def improve_path(
    result: PlanResult,
    model: QueryModel,
    oracle: EdgeOracle,
    budget: ImproveBudget,
    *,
    prior: WorldPrior,
    limits: PlanLimits,
) -> PlanResult:
    """The plan's FOUND ``result`` after the anytime improvement (see the module doc).

    Args:
        result: the FOUND result of the plan's first verified path.
        model: the query it planned (graph, training worlds, start and goal).
        oracle: the plan's edge oracle (the same one that checked the first path).
        budget: the improvement's budget.
        prior: the planner's prior (world weights, alpha and kappa of the tail).
        limits: the plan's seed, check limit and deadline.

    Returns:
        The result with the shortest path verified (the first one when none was shorter), the improvement
        checks appended to the check log (stage ``improve``) and every verified path in ``improvements``.
    """
    run = _Improvement(result, model, oracle, budget, prior, limits)
    stop = run.loop()
    return run.result(stop)


class _Improvement:
    """The state of one :func:`improve_path`: outcomes, check log, best path and the budget left."""

    def __init__(
        self,
        result: PlanResult,
        model: QueryModel,
        oracle: EdgeOracle,
        budget: ImproveBudget,
        prior: WorldPrior,
        limits: PlanLimits,
    ) -> None:
        self.t0 = time.perf_counter()
        self.first, self.model, self.oracle, self.budget = result, model, oracle, budget
        graph = model.query.graph
        self.lengths = graph.lengths
        self.search = ShortestPaths(GraphArcs(graph), graph.lengths)
        self.outcome = {c.edge: c.free for c in result.checks}
        self.blocked = np.zeros(graph.num_edges, dtype=bool)
        self.blocked[[e for e, free in self.outcome.items() if not free]] = True
        self.sampler = WorldSampler(
            None if model.query.worlds is None else model.query.worlds.dense,
            prior.world_weights,
            self.outcome,
            num_edges=graph.num_edges,
            alpha=prior.alpha,
            pseudo_count=prior.pseudo_count or DEFAULT_FALLBACK_KAPPA,
            tail_probability=budget.tail_probability,
            rng=np.random.default_rng([int(limits.seed) % (1 << 64), _SAMPLER_STREAM]),
        )
        self.checks = list(result.checks)
        self.best = Improvement(
            len(self.checks),
            np.asarray(result.edges, dtype=np.int64),
            float(result.cost),
            result.timings.total_s,
        )
        self.found = [self.best]
        plan_left = None if limits.max_checks is None else limits.max_checks - len(self.checks)
        self.check_limit = min((c for c in (budget.checks, plan_left) if c is not None), default=None)
        self.check_reason = (
            "checks" if budget.checks is not None and self.check_limit == budget.checks else "plan_checks"
        )
        own = None if budget.seconds is None else self.t0 + budget.seconds
        self.deadline = min((d for d in (own, limits.deadline) if d is not None), default=None)
        self.time_reason = "seconds" if own is not None and self.deadline == own else "plan_time"
        self.bound: float | None = None  # the optimistic graph's shortest path length (None: stale)
        self.since = self.t0  # when the selection of the next check began (draws and searches count)

    @property
    def used(self) -> int:
        """Checks made by the improvement so far."""
        return len(self.checks) - len(self.first.checks)

    def checks_left(self) -> float:
        """Checks the improvement may still make (inf without a limit)."""
        return np.inf if self.check_limit is None else self.check_limit - self.used

    def out_of_time(self) -> bool:
        """True once the improvement's (or the plan's) deadline has passed."""
        return self.deadline is not None and time.perf_counter() >= self.deadline

    def provably_shortest(self) -> bool:
        """True when no path of the optimistic graph (unchecked edges free, blocked deleted) is shorter."""
        if self.bound is None:
            path = self.search.path(self.model.start, self.model.goal, ~self.blocked)
            self.bound = np.inf if path is None else float(self.lengths[path].sum())
        return self.best.cost <= self.bound * (1 + _RTOL)

    def loop(self) -> str:
        """Draw, propose and check until a stopping rule applies; returns its name."""
        idle = 0
        while True:
            if self.provably_shortest():
                return "optimal"
            if self.checks_left() <= 0:
                return self.check_reason
            if self.out_of_time():
                return self.time_reason
            if idle >= self.budget.patience:
                return "patience"
            path = self.propose()
            if path is None:
                idle += 1
                continue
            idle = 0
            self.verify(path)

    def propose(self) -> IntArray | None:
        """The shortest path of one drawn world when it is shorter and affordable, else None."""
        limit = self.best.cost * (1 - _RTOL)
        path = self.search.path(self.model.start, self.model.goal, self.sampler.draw(), limit=limit)
        if path is None or float(self.lengths[path].sum()) >= limit:
            return None
        unchecked = sum(e not in self.outcome for e in path.tolist())
        return path if unchecked <= self.checks_left() else None

    def verify(self, path: IntArray) -> None:
        """Check the path's unchecked edges, least likely free first, up to the first blocked one.

        A path found free becomes the best one; a blocked edge is deleted from the optimistic graph.
        """
        unknown = np.array([e for e in path.tolist() if e not in self.outcome], dtype=np.int64)
        order = unknown[np.argsort(self.sampler.free_probability(unknown), kind="stable")]
        for edge in order.tolist():
            if self.out_of_time():
                return
            t_check = time.perf_counter()
            free = bool(self.oracle.check(edge))
            t_done = time.perf_counter()
            select_ms, check_ms = (t_check - self.since) * 1e3, (t_done - t_check) * 1e3
            self.checks.append(CheckRecord(len(self.checks), edge, free, IMPROVE_STAGE, select_ms, check_ms))
            self.since = t_done
            self.outcome[edge] = free
            self.sampler.observe(edge, free)
            if not free:
                self.blocked[edge] = True
                self.bound = None
                return
        verify_path(path, self.outcome)
        elapsed = self.first.timings.total_s + time.perf_counter() - self.t0
        self.best = Improvement(len(self.checks), path, float(self.lengths[path].sum()), elapsed)
        self.found.append(self.best)

    def result(self, stop: str) -> PlanResult:
        """The plan's result with the best path, the whole check log and every improvement."""
        first, best, query = self.first, self.best, self.model.query
        improved = len(self.found) > 1
        timings = dataclasses.replace(
            first.timings,
            selection_s=first.timings.selection_s + sum(c.select_ms for c in self.checks[len(first.checks) :]) / 1e3,
            checks_s=first.timings.checks_s + sum(c.check_ms for c in self.checks[len(first.checks) :]) / 1e3,
            total_s=first.timings.total_s + time.perf_counter() - self.t0,
        )
        reason = (
            f"path of {best.path_edges.size} edges (cost {best.cost:.4g}) verified free after "
            f"{len(self.checks)} checks; {len(self.found) - 1} shorter path(s) after the first (cost "
            f"{first.cost:.4g}, {len(first.checks)} checks), improvement stopped: {stop}"
        )
        return dataclasses.replace(
            first,
            reason=reason,
            vertices=vertex_sequence(query.graph.edges, self.model.start, best.path_edges),
            edges=best.path_edges,
            checks=tuple(self.checks),
            cost=best.cost,
            stage=PlanStage.IMPROVE if improved else first.stage,
            timings=timings,
            motions={e: query.motions[e] for e in best.path_edges.tolist() if e in query.motions},
            improvements=tuple(self.found),
            improve_stop=stop,
        )


def check_budgets(max_checks: int | None, time_budget_s: float | None) -> None:
    """ProblemError for a plan budget that is not positive (None: no budget of that kind).

    Args:
        max_checks: cap on a plan's checks (count).
        time_budget_s: cap on a plan's time (s).
    """
    if max_checks is not None and max_checks < 1:
        raise ProblemError(f"max_checks must be at least 1, got {max_checks}")
    if time_budget_s is not None and not (np.isfinite(time_budget_s) and time_budget_s > 0):
        raise ProblemError(f"time_budget_s must be a positive number of seconds, got {time_budget_s}")
