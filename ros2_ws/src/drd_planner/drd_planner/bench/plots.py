"""Benchmark figures (matplotlib, Agg canvas, PNG + SVG): checked edges, normalised costs, training size.

Each ``plot_*`` function takes data and an output path (its suffix is replaced by ``.png`` and ``.svg``)
and returns the written paths. Each ``draw_*`` function draws on a given axes and returns what it drew,
so tests can compare the figure's data with its source. No pyplot: figures are plain
:class:`matplotlib.figure.Figure` objects, so nothing global (backend, open figures) is touched.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import LineCollection
from matplotlib.container import ErrorbarContainer
from matplotlib.figure import Figure

from drd_planner.arrays import FloatArray, IntArray
from drd_planner.bench.learning_curve import TrainingCurve
from drd_planner.bench.stats import Table1
from drd_planner.core.episode import EpisodeResult
from drd_planner.core.problem import Problem
from drd_planner.exceptions import ProblemError

#: Colours of the checked-edges figure (matplotlib colour specs).
COLOURS = {"unchecked": "#c8c8c8", "free": "#2ca02c", "blocked": "#d62728", "path": "#1f4fd8"}
#: Line widths in points.
WIDTHS = {"unchecked": 0.6, "free": 1.6, "blocked": 1.6, "path": 3.5}
#: Policies of the paper's Fig. 3, left to right.
FIG3_POLICIES = ("lazysp", "lazysp_set", "bisect", "direct_bisect")


def save_figure(fig: Figure, out: str | Path) -> list[Path]:
    """Write ``fig`` as PNG (150 dpi) and SVG next to ``out`` (suffix replaced); return both paths."""
    base = Path(out)
    base.parent.mkdir(parents=True, exist_ok=True)
    FigureCanvasAgg(fig)
    paths = [base.with_suffix(".png"), base.with_suffix(".svg")]
    for path in paths:
        fig.savefig(path, dpi=150, bbox_inches="tight")
    return paths


# --------------------------------------------------------------------------------------------------
# (a) checked edges on the graph (Fig. 3)
# --------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class EdgeLayers:
    """The edges of one episode by how they are drawn.

    Attributes:
        free: (a,) edges checked free, in check order.
        blocked: (b,) edges checked blocked, in check order.
        unchecked: (c,) library edges never checked, sorted.
        path: (d,) edges of the verified path (empty when the episode failed).
    """

    free: IntArray
    blocked: IntArray
    unchecked: IntArray
    path: IntArray


def edge_layers(problem: Problem, result: EpisodeResult) -> EdgeLayers:
    """Split the library edges and the check log of ``result`` into the four drawn layers."""
    free = np.array([c.edge for c in result.checks if c.free], dtype=np.int64)
    blocked = np.array([c.edge for c in result.checks if not c.free], dtype=np.int64)
    checked = np.array([c.edge for c in result.checks], dtype=np.int64)
    unchecked = np.setdiff1d(problem.library.library_edges, checked).astype(np.int64)
    path = np.zeros(0, np.int64) if result.path_edges is None else np.asarray(result.path_edges, np.int64)
    return EdgeLayers(free, blocked, unchecked, path)


def vertex_xy(problem: Problem) -> FloatArray:
    """(V, 2) planar vertex coordinates (first two state components, e.g. x, y from ``coord_set.dat``).

    Raises:
        ProblemError: the problem has no graph or its vertices have no (at least 2-D) coordinates.
    """
    graph = problem.graph
    if graph is None or graph.vertex_states is None or graph.vertex_states.shape[1] < 2:
        raise ProblemError(
            f"{problem.name}: the checked-edges figure needs 2-D vertex coordinates "
            "(coord_set.dat or vertex_coordinates.txt), and this dataset has none"
        )
    return np.asarray(graph.vertex_states[:, :2], dtype=np.float64)


def has_vertex_xy(problem: Problem) -> bool:
    """True when :func:`vertex_xy` can draw this problem."""
    graph = problem.graph
    return graph is not None and graph.vertex_states is not None and graph.vertex_states.shape[1] >= 2


def edge_segments(problem: Problem, edges: npt.ArrayLike) -> FloatArray:
    """(k, 2, 2) straight segments (endpoint, xy) of ``edges`` (k,) between their vertices."""
    xy = vertex_xy(problem)
    assert problem.graph is not None
    ends = problem.graph.edges[np.asarray(edges, dtype=np.int64).ravel()]
    return np.stack([xy[ends[:, 0]], xy[ends[:, 1]]], axis=1)


def draw_checked_edges(ax: Axes, problem: Problem, result: EpisodeResult, *, title: str) -> dict[str, LineCollection]:
    """Draw one episode: unchecked library edges grey, free green, blocked red, the path thick blue.

    Start and goal are marked (black circle, black star). Returns the line collection of each layer
    (keys ``unchecked``, ``free``, ``blocked``, ``path``) in drawing order.
    """
    layers = edge_layers(problem, result)
    drawn: dict[str, LineCollection] = {}
    for key in ("unchecked", "free", "blocked", "path"):
        coll = LineCollection(
            list(edge_segments(problem, getattr(layers, key))),
            colors=COLOURS[key],
            linewidths=WIDTHS[key],
            zorder=len(drawn) + 1,
            label=key,
        )
        coll.set_gid(f"{key}_edges")
        ax.add_collection(coll)
        drawn[key] = coll
    xy = vertex_xy(problem)
    if problem.start is not None:
        ax.plot(*xy[problem.start], "o", color="black", markersize=7, zorder=6, label="start")
    if problem.goal is not None:
        ax.plot(*xy[problem.goal], "*", color="black", markersize=11, zorder=6, label="goal")
    ax.autoscale_view()
    ax.set_aspect("equal")
    ax.set_xticks([])
    ax.set_yticks([])
    ax.set_title(title, fontsize=10)
    return drawn


def episode_title(name: str, result: EpisodeResult) -> str:
    """``name: N checks`` (plus the failure status, and its cause when it has one, when no path was verified)."""
    text = f"{name}: {result.num_checks} checks"
    if result.success:
        return text
    cause = f": {result.cause.value}" if result.cause is not None else ""
    return f"{text} ({result.status.value}{cause})"


def plot_checked_edges(
    problem: Problem, episodes: Mapping[str, EpisodeResult], out: str | Path, *, world: int | None = None
) -> list[Path]:
    """The paper's Fig. 3: one panel per policy with the edges it checked on one test world.

    Args:
        problem: the dataset (needs vertex coordinates, see :func:`vertex_xy`).
        episodes: policy name -> its episode on the same world (panel order = mapping order).
        out: output path; ``.png`` and ``.svg`` are written.
        world: the world row, for the figure title.
    """
    if not episodes:
        raise ProblemError("the checked-edges figure needs at least one episode")
    vertex_xy(problem)
    fig = Figure(figsize=(3.6 * len(episodes), 3.9))
    axes = fig.subplots(1, len(episodes), squeeze=False)[0]
    for ax, (name, result) in zip(axes, episodes.items(), strict=True):
        draw_checked_edges(ax, problem, result, title=episode_title(name, result))
    suffix = "" if world is None else f", world {world}"
    fig.suptitle(f"{problem.name}{suffix}: free (green), blocked (red), path (blue)", fontsize=11)
    return save_figure(fig, out)


# --------------------------------------------------------------------------------------------------
# (b) normalised cost per dataset
# --------------------------------------------------------------------------------------------------


def draw_normalised_costs(
    ax: Axes,
    table: Table1,
    baselines: Sequence[str],
    *,
    filtered: bool = True,
    title: str = "",
    failures: Mapping[str, int] | None = None,
) -> ErrorbarContainer:
    """Median relative extra cost per baseline with [P40, P60] error bars and a line at 0.

    Baselines that were not run are left empty (NaN). A baseline with failed episodes gets
    ``(k failed)`` under its name (failed episodes count with the checks they made, so its bar is
    optimistic). Returns the error bar container (its data line holds the medians).
    """
    med, low, high = [], [], []
    for name in baselines:
        rel = table.policies.get(name)
        s = None if rel is None else (rel.filtered if filtered else rel.unfiltered)
        med.append(np.nan if s is None else s.median)
        low.append(np.nan if s is None else s.median - s.p40)
        high.append(np.nan if s is None else s.p60 - s.median)
    x = np.arange(len(baselines), dtype=np.float64)
    ax.axhline(0.0, color="black", linewidth=0.8)
    bars = ax.errorbar(x, med, yerr=np.array([low, high]), fmt="o", capsize=4, color="#1f4fd8")
    fails = failures or {}
    labels = [f"{name} ({fails[name]} failed)" if fails.get(name) else name for name in baselines]
    ax.set_xticks(x, labels, rotation=45, ha="right", fontsize=8)
    ax.set_ylabel(f"(c - c_ref) / c_ref, ref = {table.reference}", fontsize=8)
    ax.set_title(title, fontsize=10)
    return bars


def plot_normalised_costs(
    tables: Mapping[str, Table1],
    baselines: Sequence[str],
    out: str | Path,
    *,
    filtered: bool = True,
    failures: Mapping[str, Mapping[str, int]] | None = None,
) -> list[Path]:
    """One panel per dataset: median extra cost over the reference with [P40, P60] bars per baseline.

    Args:
        tables: dataset name -> its Table-1 statistics (panel order = mapping order).
        baselines: the policies on the x axis.
        out: output path; ``.png`` and ``.svg`` are written.
        filtered: use the tie-filtered worlds (the paper's protocol) or all test worlds.
        failures: dataset name -> policy name -> failed episodes, shown in the tick labels.
    """
    if not tables:
        raise ProblemError("the normalised-cost figure needs at least one dataset")
    cols = min(4, len(tables))
    rows = -(-len(tables) // cols)
    fig = Figure(figsize=(3.4 * cols, 3.2 * rows), layout="constrained")
    axes = fig.subplots(rows, cols, squeeze=False).ravel()
    for k, (ax, (name, table)) in enumerate(zip(axes, tables.items(), strict=False)):
        n = table.num_kept if filtered else table.kept.size
        fails = None if failures is None else failures.get(name)
        draw_normalised_costs(ax, table, baselines, filtered=filtered, title=f"{name} (n={n})", failures=fails)
        if k % cols:
            ax.set_ylabel("")
    for ax in axes[len(tables) :]:
        ax.set_visible(False)
    return save_figure(fig, out)


# --------------------------------------------------------------------------------------------------
# (c) checks versus training-set size (Fig. 4)
# --------------------------------------------------------------------------------------------------


def draw_training_curve(ax: Axes, curve: TrainingCurve) -> dict[str, Any]:
    """Mean checks per policy against training size, ``direct_only`` failure rate on a twin axis.

    Returns ``{policy: Line2D, ..., "failure_rate": Line2D}``.
    """
    drawn: dict[str, Any] = {}
    styles = {"direct_bisect": "o-", "bisect": "s--", "direct_only": "^:"}
    for name, values in curve.mean_checks.items():
        (drawn[name],) = ax.plot(curve.sizes, values, styles.get(name, "o-"), label=name)
    ax.set_xlabel("training worlds")
    ax.set_ylabel("mean checks")
    twin = ax.twinx()
    (drawn["failure_rate"],) = twin.plot(
        curve.sizes, curve.failure_rate, "x-", color="#d62728", label="direct_only failure rate"
    )
    twin.set_ylabel("direct_only failure rate", color="#d62728")
    twin.set_ylim(0.0, 1.0)
    handles = [*ax.get_legend_handles_labels()[0], drawn["failure_rate"]]
    ax.legend(handles=handles, fontsize=8, loc="best")
    ax.set_title(f"{curve.dataset}: checks vs training size ({curve.num_test} test worlds)", fontsize=10)
    return drawn


def plot_training_curve(curve: TrainingCurve, out: str | Path) -> list[Path]:
    """The paper's Fig. 4 for one dataset; writes ``.png`` and ``.svg``."""
    fig = Figure(figsize=(6.0, 4.0), layout="constrained")
    draw_training_curve(fig.add_subplot(), curve)
    return save_figure(fig, out)
