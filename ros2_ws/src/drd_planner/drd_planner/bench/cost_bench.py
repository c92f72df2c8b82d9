"""The time-to-a-verified-plan benchmark at stated check costs: run every policy, summarize, tabulate.

Each query runs once per check cost C and policy (:mod:`~drd_planner.bench.cost_episodes`), each episode
with a fresh oracle (a live checker may cache its answers); with ``repeat`` R > 1 each episode runs R times in
a row and keeps the run of median CPU time: the same checks each time (the same seed), so only the clock's
noise differs, and a policy's median over the queries then moves less between runs of the benchmark where two
policies are within a few per cent of each other. The summary keeps, per policy and C, the median and mean CPU
time (and the wall time beside) over the queries of each kind that **every** policy timed on that kind
verified at every C (so the medians compare the same queries), and over all such queries of all kinds; the
verified counts say how many each policy verified on its own.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from drd_planner.bench.check_cost import cost_key, time_summary
from drd_planner.bench.cost_episodes import (
    LEAD_POLICY,
    QUERY_KINDS,
    CostQuery,
    EpisodeTime,
    FullRow,
    check_all_episode,
    full_row,
    lazysp_episode,
    plan_episode,
)
from drd_planner.core.episode import EdgeOracle
from drd_planner.exceptions import DrdError
from drd_planner.planner.planner import PLAN_POLICIES, Planner
from drd_planner.progress import Progress

__all__ = [
    "COST_POLICIES",
    "DEFAULT_COST_POLICIES",
    "CostRun",
    "check_cost_policies",
    "cost_markdown",
    "episode_records",
    "median_episode",
    "paired_ratios",
    "run_cost_episodes",
    "summarize_costs",
]

#: The graph baselines of the benchmark beside the Planner's library policies.
GRAPH_POLICIES = ("lazysp", "check_all")
COST_POLICIES = (*PLAN_POLICIES, LEAD_POLICY, *GRAPH_POLICIES)
DEFAULT_COST_POLICIES = ("direct_bisect", LEAD_POLICY, "bisect", "lazysp", "check_all")
#: The policies whose ratio to ``lazysp`` the markdown table shows.
RATIO_POLICIES = ("direct_bisect", LEAD_POLICY)

OracleOf = Callable[[int], EdgeOracle]


def check_cost_policies(policies: Sequence[str]) -> None:
    """DrdError naming the known policies when one of ``policies`` cannot be timed at a check cost."""
    unknown = [p for p in policies if p not in COST_POLICIES]
    if unknown:
        raise DrdError(
            f"policies that cannot be timed with --check-cost-ms: {', '.join(unknown)}; "
            f"known: {', '.join(COST_POLICIES)}"
        )


@dataclass(frozen=True)
class CostRun:
    """How :func:`run_cost_episodes` runs.

    Attributes:
        policies: the policies timed (:data:`COST_POLICIES`).
        seed: query i's library policies use seed ``seed + i`` (the same checks at every cost).
        repeat: runs of each episode, the run of median CPU time kept (:func:`median_episode`; at least 1).
        progress: show a progress bar (None: when stderr is a terminal).
    """

    policies: Sequence[str] = DEFAULT_COST_POLICIES
    seed: int = 0
    repeat: int = 1
    progress: bool | None = None


def run_cost_episodes(
    planner: Planner,
    queries: Sequence[CostQuery],
    oracle_of: OracleOf,
    costs: Sequence[float],
    run: CostRun = CostRun(),
    rows: dict[int, FullRow] | None = None,
) -> list[EpisodeTime]:
    """Every policy on every query at every cost; ``oracle_of(world)`` makes a fresh oracle of a world.

    ``rows``: the worlds' :class:`FullRow` already made (``check_all`` makes the others).
    """
    check_cost_policies(run.policies)
    if run.repeat < 1:
        raise DrdError(f"repeat must be at least 1, got {run.repeat}")
    planner.warm_up()
    if LEAD_POLICY in run.policies:  # the lead's price, measured before anything is timed
        planner.library_cost_ms()
        planner.library_cost_ms(joined=True)
    episodes = _Episodes(planner, oracle_of, dict(rows or {}), run.seed)
    if queries:  # first use of every code path (imports, caches) before anything is timed
        first = queries[0]
        for name in run.policies:
            if name not in GRAPH_POLICIES:
                plan_episode(planner, first, 0, oracle_of(first.world), 0.0, name, run.seed)
        lazysp_episode(planner, first, 0, oracle_of(first.world), 0.0)
    total = len(queries) * len(costs) * len(run.policies) * run.repeat
    bar = Progress(total, "check-cost episodes", unit="episode", enabled=run.progress)
    out: list[EpisodeTime] = []
    for i, query in enumerate(queries):
        for cost in costs:
            for name in run.policies:
                runs = []
                for _ in range(run.repeat):
                    runs.append(episodes.run(name, query, i, cost))
                    bar.update(1)
                out.append(median_episode(runs))
    bar.close()
    return out


@dataclass
class _Episodes:
    """One episode of any policy: a fresh oracle of the query's world each time."""

    planner: Planner
    oracle_of: OracleOf
    rows: dict[int, FullRow]
    seed: int

    def run(self, name: str, query: CostQuery, index: int, cost: float) -> EpisodeTime:
        """Policy ``name`` on query number ``index`` at ``cost`` ms per check."""
        oracle = self.oracle_of(query.world)
        if name == "check_all":
            if query.world not in self.rows:
                self.rows[query.world] = full_row(self.oracle_of(query.world), self.planner.prior.graph.num_edges)
            return check_all_episode(self.planner, query, index, oracle, cost, self.rows[query.world])
        if name == "lazysp":
            return lazysp_episode(self.planner, query, index, oracle, cost)
        return plan_episode(self.planner, query, index, oracle, cost, name, self.seed + index)


def median_episode(runs: Sequence[EpisodeTime]) -> EpisodeTime:
    """One episode of several runs of it: the run of median CPU time (the lower middle one of an even count).

    Its checks and times are that run's; verified only when every run was. The runs of one episode make the
    same checks (the same seed) unless a time budget cut one short (a growth's ``seconds``), so the median run
    is one that really happened rather than a mix of runs.
    """
    if not runs:
        raise DrdError("an episode needs at least one run")
    ordered = sorted(runs, key=lambda r: r.time.cpu_ms)
    middle = ordered[(len(ordered) - 1) // 2]
    return dataclasses.replace(middle, verified=all(r.verified for r in runs))


def _common(episodes: Sequence[EpisodeTime], kind: str) -> tuple[list[str], set[int]]:
    """(policies timed on ``kind``, queries of ``kind`` every one of them verified at every cost)."""
    mine = [e for e in episodes if e.kind == kind]
    names = sorted({e.policy for e in mine})
    queries = {e.query for e in mine}
    for e in mine:
        if not e.verified:
            queries.discard(e.query)
    return names, queries


def summarize_costs(episodes: Sequence[EpisodeTime], costs: Sequence[float]) -> dict[str, Any]:
    """Per policy: times in ms over the queries every policy verified (see the module docstring).

    Returns:
        ``{policy: {"time_ms": {C: {"n", "median", "mean", "wall_median", "wall_mean", "kinds": {kind: {the
        same}}}}, "checks": {kind: median checks}, "checks_at": {C: {kind: median checks}}, "verified":
        {kind: count}, "queries": {kind: count}, "paired_to_lazysp": {C: {kind: {"median", "n"}}}}}``;
        ``checks``, ``verified`` and ``queries`` at the first C (a planner told the check cost,
        :data:`LEAD_POLICY`, may check differently at each C: ``checks_at``); ``paired_to_lazysp`` (when
        ``lazysp`` ran): the median over the compared queries of the policy's CPU time over LazySP's on the
        same query (:func:`paired_ratios`).
    """
    common = {kind: _common(episodes, kind) for kind in QUERY_KINDS}
    out: dict[str, Any] = {}
    for name in dict.fromkeys(e.policy for e in episodes):
        mine = [e for e in episodes if e.policy == name]
        block: dict[str, Any] = {"time_ms": {}, "checks": {}, "checks_at": {}, "verified": {}, "queries": {}}
        block["paired_to_lazysp"] = paired_ratios(episodes, name, costs, {k: c[1] for k, c in common.items()})
        for cost in costs:
            at = [e for e in mine if e.cost_ms == cost]
            shared = [e for e in at if e.query in common[e.kind][1]]
            entry = time_summary([e.time for e in shared])
            entry["kinds"] = {
                kind: time_summary([e.time for e in shared if e.kind == kind])
                for kind in QUERY_KINDS
                if any(e.kind == kind for e in at)
            }
            block["time_ms"][cost_key(cost)] = entry
            block["checks_at"][cost_key(cost)] = {
                kind: float(np.median([e.checks for e in at if e.kind == kind]))
                for kind in QUERY_KINDS
                if any(e.kind == kind for e in at)
            }
        first = [e for e in mine if e.cost_ms == costs[0]]
        for kind in QUERY_KINDS:
            of_kind = [e for e in first if e.kind == kind]
            if of_kind:
                block["checks"][kind] = float(np.median([e.checks for e in of_kind]))
                block["verified"][kind] = sum(e.verified for e in of_kind)
                block["queries"][kind] = len(of_kind)
        out[name] = block
    return out


def paired_ratios(
    episodes: Sequence[EpisodeTime], policy: str, costs: Sequence[float], compared: dict[str, set[int]]
) -> dict[str, dict[str, dict[str, Any]]]:
    """``{C: {kind: {"median", "n"}}}``: per query, ``policy``'s CPU time over ``lazysp``'s; their median.

    A ratio of medians compares two distributions, which with a few queries of two sizes (a short plan and a long
    one) can jump between them; the per-query ratio compares each query with itself. Over the ``compared``
    queries of each kind (those every policy verified); empty when ``lazysp`` did not run.
    """
    times = {(e.policy, e.query, e.cost_ms): e.time.cpu_ms for e in episodes}
    kinds = {e.query: e.kind for e in episodes}
    out: dict[str, dict[str, dict[str, Any]]] = {}
    if not any(e.policy == "lazysp" for e in episodes):
        return out
    for cost in costs:
        row: dict[str, dict[str, Any]] = {}
        for kind in QUERY_KINDS:
            ratios = [
                times[(policy, q, cost)] / times[("lazysp", q, cost)]
                for q in sorted(compared.get(kind, set()))
                if kinds[q] == kind and (policy, q, cost) in times and times.get(("lazysp", q, cost), 0.0) > 0
            ]
            if ratios:
                row[kind] = {"median": float(np.median(ratios)), "n": len(ratios)}
        out[cost_key(cost)] = row
    return out


def episode_records(episodes: Sequence[EpisodeTime]) -> list[dict[str, Any]]:
    """Every timed episode as a JSON-ready record (policy, query, kind, cost_ms, verified, checks, cpu_ms, wall_ms)."""
    return [
        {
            "policy": e.policy,
            "query": e.query,
            "kind": e.kind,
            "cost_ms": e.cost_ms,
            "verified": e.verified,
            "checks": e.checks,
            "cpu_ms": e.time.cpu_ms,
            "wall_ms": e.time.wall_ms,
        }
        for e in episodes
    ]


def _ms(value: float | None) -> str:
    return "-" if value is None else (f"{value:.1f}" if value >= 10 else f"{value:.2f}")


def cost_markdown(summary: dict[str, Any], costs: Sequence[float], *, title: str, notes: Sequence[str] = ()) -> str:
    """A markdown table of a :func:`summarize_costs` summary.

    Per query kind and C, each policy's median CPU ms (n = queries compared) and the ratios
    ``direct_bisect / lazysp`` and ``direct_bisect_lead / lazysp``; then median checks (at the first C) and
    verified counts per kind.
    """
    names = list(summary)
    ratios = [n for n in RATIO_POLICIES if n in summary] if "lazysp" in summary else []
    head = ["kind", "C ms/check", "n", *names] + [f"{n} / lazysp" for n in ratios]
    lines = [f"## {title}", "", "Median CPU ms to a verified plan:", ""]
    lines += ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for kind in QUERY_KINDS:
        for cost in costs:
            cells = [summary[n]["time_ms"][cost_key(cost)]["kinds"].get(kind) for n in names]
            if not any(c is not None for c in cells):
                continue
            n = max(c["n"] for c in cells if c is not None)
            row = [kind, cost_key(cost), str(n)] + ["-" if c is None else _ms(c["median"]) for c in cells]
            for name in ratios:
                a = summary[name]["time_ms"][cost_key(cost)]["kinds"].get(kind)
                b = summary["lazysp"]["time_ms"][cost_key(cost)]["kinds"].get(kind)
                ok = a and b and a["median"] is not None and b["median"]
                row.append(f"{a['median'] / b['median']:.2f}" if ok else "-")  # type: ignore[index]
            lines.append("| " + " | ".join(row) + " |")
    if ratios:
        lines += ["", "Per query, the policy's CPU time over LazySP's on the same query: the median (n):", ""]
        lines += ["| kind | C ms/check | " + " | ".join(f"{n} / lazysp" for n in ratios) + " |"]
        lines += ["|" + "---|" * (len(ratios) + 2)]
        for kind in QUERY_KINDS:
            for cost in costs:
                paired = [summary[n]["paired_to_lazysp"].get(cost_key(cost), {}).get(kind) for n in ratios]
                if any(p is not None for p in paired):
                    cells = ["-" if p is None else f"{p['median']:.2f} ({p['n']})" for p in paired]
                    lines.append(f"| {kind} | {cost_key(cost)} | " + " | ".join(cells) + " |")
    lines += ["", "Median checks (verified / queries):", ""]
    lines += ["| kind | " + " | ".join(names) + " |", "|" + "---|" * (len(names) + 1)]
    for kind in QUERY_KINDS:
        if not any(kind in summary[n]["checks"] for n in names):
            continue
        cells = []
        for n in names:
            s = summary[n]
            cells.append(
                f"{s['checks'][kind]:g} ({s['verified'][kind]}/{s['queries'][kind]})" if kind in s["checks"] else "-"
            )
        lines.append(f"| {kind} | " + " | ".join(cells) + " |")
    lines += [""] + [f"note: {note}" for note in notes] + ([""] if notes else [])
    return "\n".join(lines)
