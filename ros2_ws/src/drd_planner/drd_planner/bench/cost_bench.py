"""The time-to-a-verified-plan benchmark at stated check costs: run every policy, summarize, tabulate.

Each query runs once per check cost C and policy (:mod:`~drd_planner.bench.cost_episodes`), each episode
with a fresh oracle (a live checker may cache its answers). The summary keeps, per policy and C, the median
and mean CPU time (and the wall time beside) over the queries of each kind that **every** policy timed on
that kind verified at every C (so the medians compare the same queries), and over all such queries of all
kinds; the verified counts say how many each policy verified on its own.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
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
    "check_cost_policies",
    "cost_markdown",
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


def run_cost_episodes(
    planner: Planner,
    queries: Sequence[CostQuery],
    oracle_of: OracleOf,
    costs: Sequence[float],
    *,
    policies: Sequence[str] = DEFAULT_COST_POLICIES,
    seed: int = 0,
    progress: bool | None = None,
    rows: dict[int, FullRow] | None = None,
) -> list[EpisodeTime]:
    """Every policy on every query at every cost; ``oracle_of(world)`` makes a fresh oracle of a world.

    Query i's library policies use seed ``seed + i`` (same seed, same checks at every cost). ``rows``: the
    worlds' :class:`FullRow` already made (``check_all`` makes the others).
    """
    check_cost_policies(policies)
    planner.warm_up()
    if LEAD_POLICY in policies:  # the lead's price, measured before anything is timed
        planner.library_cost_ms()
        planner.library_cost_ms(joined=True)
    rows = dict(rows or {})
    out: list[EpisodeTime] = []
    if queries:  # first use of every code path (imports, caches) before anything is timed
        first = queries[0]
        for name in policies:
            if name not in GRAPH_POLICIES:
                plan_episode(planner, first, 0, oracle_of(first.world), 0.0, name, seed)
        lazysp_episode(planner, first, 0, oracle_of(first.world), 0.0)
    bar = Progress(len(queries) * len(costs) * len(policies), "check-cost episodes", unit="episode", enabled=progress)
    for i, query in enumerate(queries):
        for cost in costs:
            for name in policies:
                oracle = oracle_of(query.world)
                if name == "check_all":
                    if query.world not in rows:
                        rows[query.world] = full_row(oracle_of(query.world), planner.prior.graph.num_edges)
                    out.append(check_all_episode(planner, query, i, oracle, cost, rows[query.world]))
                elif name == "lazysp":
                    out.append(lazysp_episode(planner, query, i, oracle, cost))
                else:
                    out.append(plan_episode(planner, query, i, oracle, cost, name, seed + i))
                bar.update(1)
    bar.close()
    return out


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
        {kind: count}, "queries": {kind: count}}}``; ``checks``, ``verified`` and ``queries`` at the first C
        (a planner told the check cost, :data:`LEAD_POLICY`, may check differently at each C: ``checks_at``).
    """
    common = {kind: _common(episodes, kind) for kind in QUERY_KINDS}
    out: dict[str, Any] = {}
    for name in dict.fromkeys(e.policy for e in episodes):
        mine = [e for e in episodes if e.policy == name]
        block: dict[str, Any] = {"time_ms": {}, "checks": {}, "checks_at": {}, "verified": {}, "queries": {}}
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
