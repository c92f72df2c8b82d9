"""Markdown reports of benchmark runs: the paper's Table 1 and the absolute numbers behind it.

Every table has one row per dataset. Missing entries (policy not run, reference absent, nothing left
after the tie filter) are shown as an em dash.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from drd_planner.bench.runner import BenchmarkResult, markdown_table
from drd_planner.bench.stats import Summary, Table1

_DASH = "—"


def _num(value: float, digits: int = 2) -> str:
    return _DASH if not math.isfinite(value) else f"{value:.{digits}f}"


def interval_cell(summary: Summary) -> str:
    """A Table-1 cell ``[p40, p60]`` of the relative extra cost, two decimals."""
    if summary.n == 0:
        return _DASH
    return f"[{_num(summary.p40)}, {_num(summary.p60)}]"


def mean_cell(summary: Summary) -> str:
    """``mean [low, high]`` of the relative extra cost with its bootstrap interval."""
    if summary.n == 0:
        return _DASH
    return f"{_num(summary.mean)} [{_num(summary.ci_low)}, {_num(summary.ci_high)}]"


def table1_markdown(
    results: Sequence[BenchmarkResult],
    tables: Sequence[Table1 | None],
    baselines: Sequence[str],
    *,
    filtered: bool = True,
    means: bool = False,
) -> str:
    """Relative extra cost over the reference, one row per dataset and one column per baseline.

    Args:
        results: the runs, one per dataset.
        tables: their Table-1 statistics (same order; None where the reference was not run).
        baselines: the policy columns (the reference is usually left out: its cells are all 0).
        filtered: use the tie-filtered worlds (the paper's Table 1) or every test world.
        means: cells ``mean [95% CI]`` instead of ``[p40, p60]``.
    """
    head = "| dataset | n | " + " | ".join(baselines) + " |"
    rule = "|---|---|" + "---|" * len(baselines)
    rows = [head, rule]
    for res, table in zip(results, tables, strict=True):
        if table is None:
            rows.append(f"| {res.dataset} | {len(res.test_ids)} | " + " | ".join(_DASH for _ in baselines) + " |")
            continue
        cells = []
        for name in baselines:
            rel = table.policies.get(name)
            if rel is None:
                cells.append(_DASH)
                continue
            summary = rel.filtered if filtered else rel.unfiltered
            cells.append(mean_cell(summary) if means else interval_cell(summary))
        n = table.num_kept if filtered else int(table.kept.size)
        rows.append(f"| {res.dataset} | {n} | " + " | ".join(cells) + " |")
    return "\n".join(rows) + "\n"


def select_ms_markdown(results: Sequence[BenchmarkResult], policies: Sequence[str]) -> str:
    """Mean selection time per check in milliseconds, one row per dataset."""
    head = "| dataset | " + " | ".join(policies) + " |"
    rule = "|---|" + "---|" * len(policies)
    rows = [head, rule]
    for res in results:
        cells = [_num(res.policies[p].mean_select_ms, 3) if p in res.policies else _DASH for p in policies]
        rows.append(f"| {res.dataset} | " + " | ".join(cells) + " |")
    return "\n".join(rows) + "\n"


def full_report(
    results: Sequence[BenchmarkResult],
    tables: Sequence[Table1 | None],
    policies: Sequence[str],
    *,
    reference: str,
    skipped: Sequence[tuple[str, str]] = (),
) -> str:
    """The whole markdown report: Table 1 (filtered and not), means, mean checks, selection times.

    Args:
        results: the runs, one per dataset.
        tables: their Table-1 statistics (same order).
        policies: the policies run, in column order.
        reference: the reference policy (left out of the relative tables).
        skipped: (folder, reason) of datasets that were not run.
    """
    baselines = [p for p in policies if p != reference]
    subset = next((t.tie_subset for t in tables if t is not None), ())
    parts = [
        f"## Relative extra checks over `{reference}`: [P40, P60] (Table 1 protocol)\n\n"
        f"Per test world (c - c_ref) / c_ref; MATLAB-prctile 40th and 60th percentiles after dropping "
        f"worlds where {', '.join(subset) or 'the tie subset'} all tie (n = worlds kept). Negative = "
        f"fewer checks than `{reference}`. Failed episodes count with the checks they made.\n",
        table1_markdown(results, tables, baselines, filtered=True),
        "## The same without the tie filter\n",
        table1_markdown(results, tables, baselines, filtered=False),
        "## Mean relative extra checks [95% bootstrap CI], every test world\n",
        table1_markdown(results, tables, baselines, filtered=False, means=True),
        "## Mean checks per test world (failed episodes in brackets)\n\n"
        "Oracle bound: mean cost of the cheapest valid library path (a full-graph policy such as "
        "`lazysp` may verify a path outside the library and go below it).\n",
        markdown_table(results, policies),
        "## Mean selection time per check (ms)\n",
        select_ms_markdown(results, policies),
    ]
    if skipped:
        notes = "\n".join(f"- `{folder}`: {reason}" for folder, reason in skipped)
        parts += ["## Skipped folders\n", notes + "\n"]
    return "\n".join(parts)
