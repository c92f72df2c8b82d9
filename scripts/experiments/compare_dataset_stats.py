#!/usr/bin/env python3
"""Compare the statistics of our planar / SE(2) worlds with the authors' released datasets.

For every 2D world model (graph sizes as in the authors' datasets: N = 100 OneWall, 200 TwoWall / Forest /
Maze, 150 MovingWall / Baffle / Bugtrap) and the SE(2) models OneWall, MovingWall, Baffle, Bugtrap it
generates worlds through the Domain protocol, checks every edge, builds the path library like the
authors (Yen k = 5 per world on its free edges, union, seeded subsample to 500 paths) and reports

  * the fraction of free edges (mean of X),
  * the fraction of worlds whose free edges connect start to goal (independent of the library),
  * the fraction of worlds with at least one free library path (R has a 1 in the row),
  * the mean number of free library paths per world (row sums of R),

next to the same numbers computed from the authors' folder (``load_gccd_folder``; 1000 worlds each).
Prints a markdown table (and optionally writes it as JSON).

The library numbers depend on the number of worlds: the union of 5 paths per world is subsampled to 500,
so with fewer worlds than the authors' 1000 a larger share of every world's own paths survives and worlds
look more solvable. Use ``--worlds 1000`` for a like-for-like library, or ``--max-paths`` to scale the cap.
``--authors-graph`` checks our 2D worlds on the authors' own random geometric graph (``coord_set.dat``),
which removes the graph as a source of difference (the SE(2) lattice is the authors' one anyway).

Usage: python scripts/experiments/compare_dataset_stats.py [--worlds 200] [--se2-worlds 100] [--only one_wall,...]
       [--domains planar,se2] [--authors-graph] [--gccd ../shared/data/gccd] [--seed 0] [--json out.json]
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
from scipy.sparse import coo_array
from scipy.sparse.csgraph import breadth_first_order

from drd_planner.core.graph import ExplicitGraph
from drd_planner.data.gccd import load_gccd_folder
from drd_planner.data.library_builder import build_path_library
from drd_planner.domains.base import Domain, domain_from_spec
from drd_planner.domains.planar import PlanarChecker
from drd_planner.exceptions import ProblemError

REPO_ROOT = Path(__file__).resolve().parents[2]
DEFAULT_GCCD = Path(os.environ.get("DRD_SHARED_DATA", REPO_ROOT.parent / "shared" / "data")) / "gccd"


@dataclass(frozen=True)
class Case:
    """One row: our domain + model, and the authors' folder it mirrors."""

    label: str
    domain: str
    model: str
    num_vertices: int | None
    folder: str


CASES: tuple[Case, ...] = (
    Case("2D OneWall", "planar", "one_wall", 100, "dataset_2d_1"),
    Case("2D TwoWall", "planar", "two_wall", 200, "dataset_2d_2"),
    Case("2D Forest", "planar", "forest", 200, "dataset_2d_3"),
    Case("2D MovingWall", "planar", "moving_wall", 150, "dataset_2d_4"),
    Case("2D Maze", "planar", "maze", 200, "dataset_2d_5"),
    Case("2D Baffle", "planar", "baffle", 150, "dataset_2d_6"),
    Case("2D Bugtrap", "planar", "bugtrap", 150, "dataset_2d_7"),
    Case("SE(2) OneWall", "se2", "one_wall", None, "dataset_xyh_1"),
    Case("SE(2) MovingWall", "se2", "moving_wall", None, "dataset_xyh_3"),
    Case("SE(2) Baffle", "se2", "baffle", None, "dataset_xyh_4"),
    Case("SE(2) Bugtrap", "se2", "bugtrap", None, "dataset_xyh_5"),
)


@dataclass(frozen=True)
class Stats:
    """The compared numbers of one dataset (ours or theirs)."""

    vertices: int
    edges: int
    worlds: int
    paths: int
    free_edges: float
    connected: float
    solvable: float
    mean_valid_paths: float


def connected_fraction(graph: ExplicitGraph, x: np.ndarray, start: int, goal: int) -> float:
    """Share of the worlds (rows of X (n, E)) whose free edges lead from start to goal."""
    hits = 0
    for row in x:
        e = graph.edges[row]
        adj = coo_array((np.ones(e.shape[0]), (e[:, 0], e[:, 1])), shape=(graph.num_vertices,) * 2).tocsr()
        reached = breadth_first_order(adj, start, directed=graph.directed, return_predecessors=False)
        hits += bool(np.isin(goal, reached))
    return float(hits / max(1, x.shape[0]))


def _stats(graph: ExplicitGraph, x: np.ndarray, r: np.ndarray | None, start: int, goal: int, paths: int) -> Stats:
    """Stats of X (n, E) and R (n, m) (R None when no library could be built)."""
    n, e = x.shape
    solvable = float(r.any(axis=1).mean()) if r is not None and r.size else 0.0
    mean_valid = float(r.sum(axis=1).mean()) if r is not None and r.size else 0.0
    connected = connected_fraction(graph, x, start, goal)
    return Stats(graph.num_vertices, e, n, paths, float(x.mean()), connected, solvable, mean_valid)


def ours(case: Case, worlds: int, seed: int, k: int, max_paths: int, authors: Path | None) -> Stats:
    """Generate ``worlds`` worlds of the case, check every edge, build the library, measure.

    With ``authors`` (a 2D folder) the edges are those of the authors' graph instead of our own RGG.
    """
    spec = {} if case.num_vertices is None else {"num_vertices": case.num_vertices, "seed": seed}
    dom: Domain = domain_from_spec(case.domain, spec)
    graph, start, goal = dom.graph, dom.start, dom.goal
    if authors is not None:
        problem = load_gccd_folder(authors)
        assert problem.graph is not None and problem.start is not None and problem.goal is not None
        graph, start, goal = problem.graph, problem.start, problem.goal
    all_edges = np.arange(graph.num_edges)
    world_seeds = np.random.SeedSequence(seed).generate_state(worlds).tolist()
    rows = []
    for s in world_seeds:
        world = dom.make_world(case.model, s)
        checker = dom.checker(world) if authors is None else PlanarChecker(graph, world)
        rows.append(checker.check_many(all_edges))
    x = np.array(rows)
    try:
        library = build_path_library(graph, x, start, goal, k=k, max_paths=max_paths, seed=seed)
    except ProblemError:
        return _stats(graph, x, None, start, goal, 0)
    return _stats(graph, x, library.valid_paths(x), start, goal, library.num_paths)


def theirs(folder: Path) -> Stats | None:
    """The same numbers from the authors' folder, or None when it is absent."""
    if not folder.is_dir():
        return None
    problem = load_gccd_folder(folder)
    w = problem.require_worlds()
    assert problem.graph is not None and problem.start is not None and problem.goal is not None
    return _stats(problem.graph, w.X, w.R, problem.start, problem.goal, problem.num_paths)


def _pair(a: float | int | None, b: float | int | None, fmt: str) -> str:
    """``a / b`` with a dash for missing values."""
    return " / ".join("—" if v is None else format(v, fmt) for v in (a, b))


def table(rows: list[tuple[Case, Stats, Stats | None]]) -> str:
    """Markdown table: ours / authors' per column."""
    head = (
        "| dataset (authors' folder) | V | E | worlds | library m | free edges | start-goal connected "
        "| worlds with >=1 free path | mean free paths / world |"
    )
    lines = [head, "|" + "---|" * 9]
    for case, o, t in rows:
        g = None if t is None else t
        lines.append(
            f"| {case.label} ({case.folder}) | {_pair(o.vertices, None if g is None else g.vertices, 'd')} "
            f"| {_pair(o.edges, None if g is None else g.edges, 'd')} | "
            f"{_pair(o.worlds, None if g is None else g.worlds, 'd')} "
            f"| {_pair(o.paths, None if g is None else g.paths, 'd')} | "
            f"{_pair(o.free_edges, None if g is None else g.free_edges, '.3f')} "
            f"| {_pair(o.connected, None if g is None else g.connected, '.3f')} "
            f"| {_pair(o.solvable, None if g is None else g.solvable, '.3f')} "
            f"| {_pair(o.mean_valid_paths, None if g is None else g.mean_valid_paths, '.1f')} |"
        )
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--worlds", type=int, default=200, help="worlds per 2D model (default 200)")
    p.add_argument("--se2-worlds", type=int, default=None, help="worlds per SE(2) model (default: --worlds)")
    p.add_argument("--seed", type=int, default=0, help="graph, world and library seed (default 0)")
    p.add_argument("--k", type=int, default=5, help="Yen's k per world (default 5)")
    p.add_argument("--max-paths", type=int, default=500, help="library size cap (default 500)")
    p.add_argument("--only", default="", help="comma-separated model names to keep (e.g. maze,bugtrap)")
    p.add_argument("--domains", default="planar,se2", help="comma-separated domains (planar, se2)")
    p.add_argument("--gccd", type=Path, default=DEFAULT_GCCD, help="folder of the authors' datasets")
    p.add_argument(
        "--authors-graph",
        action="store_true",
        help="check our 2D worlds on the authors' graph instead of ours",
    )
    p.add_argument("--json", type=Path, default=None, help="also write the numbers as JSON here")
    args = p.parse_args(argv)
    if args.worlds < 1 or (args.se2_worlds is not None and args.se2_worlds < 1):
        p.error("--worlds / --se2-worlds must be positive")
    only = {m for m in args.only.split(",") if m}
    domains = {d for d in args.domains.split(",") if d}
    rows: list[tuple[Case, Stats, Stats | None]] = []
    for case in CASES:
        if case.domain not in domains or (only and case.model not in only):
            continue
        n = args.worlds if case.domain == "planar" or args.se2_worlds is None else args.se2_worlds
        t0 = time.perf_counter()
        folder = args.gccd / case.folder
        use_authors = args.authors_graph and case.domain == "planar" and folder.is_dir()
        o = ours(case, n, args.seed, args.k, args.max_paths, folder if use_authors else None)
        t1 = time.perf_counter()
        t = theirs(folder)
        print(f"{case.label}: {n} worlds in {t1 - t0:.1f} s", file=sys.stderr)
        rows.append((case, o, t))
    graph_note = "the authors' 2D graphs" if args.authors_graph else f"our own graphs (seed {args.seed})"
    print(
        f"Ours / authors'. Ours: {graph_note}, world seeds from SeedSequence({args.seed}), Yen k={args.k}, "
        f"library cap {args.max_paths}.\n"
    )
    print(table(rows))
    if args.json is not None:
        payload = [
            {"case": asdict(c), "ours": asdict(o), "authors": None if t is None else asdict(t)} for c, o, t in rows
        ]
        args.json.write_text(json.dumps(payload, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
