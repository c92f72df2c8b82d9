"""The arm's two collision models side by side: edge-by-edge agreement, per-edge time, time to a verified plan.

    python scripts/experiments/bench_arm_checkers.py [--quick] [--table-clutter 10] [--clutter 10] [--scenes 20]
        [--plan-worlds 40] [--repeats 5] [--skip-edges] [--prior trees/arm_table_clutter.npz] [--no-ompl] [--json FILE]

Both checkers work on the shipped arm prior's roadmap (its domain spec, 489 vertices, 2475 edges); the mesh
domain is the same spec with ``collision_model: meshes``. Worlds: seeded ``table_clutter`` and ``clutter``
worlds (seeds 0, 1, ...) and the first ``--scenes`` MotionBenchMaker scenes of ``table_pick_panda`` and
``box_panda`` (``<shared data>/mbm``).

1. **Edges**: every roadmap edge of every world checked by both (fresh checkers, one edge after the other with
   both); how often they disagree and in which direction, and for each edge the meshes find blocked but the
   spheres call free: which mesh link, which sample, how deep, how far the spheres stay away.
2. **Sphere cover**: how far each collision mesh sticks out of the sphere model (robot only, no world).
3. **Per-edge time**: mean and median ms of one ``check`` (end vertices cached per world, as in planning).
4. **Time to a verified plan** (start 0 -> goal 1) with each checker for ``direct_bisect`` (the prior's tree),
   ``lazysp`` and ``ompl_lazyprm`` on the first ``--plan-worlds`` worlds; a plan counts only when every edge
   of its path was checked free in that run. Each plan is timed ``--repeats`` times with fresh checkers and
   the least time kept (repeats make the same checks; the machine may be loaded). Ratios are mesh / sphere over the
   worlds where both verified a plan: of the mean times, and the median of the per-world ratios.

``--quick``: 2 + 2 seeded worlds, 2 scenes per family, 400 edges each, plans on 6 worlds.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from drd_planner.bench.checker_compare import WorldComparison, compare_world, summarize
from drd_planner.bench.ompl_peer import LiveWorlds, ompl_available
from drd_planner.bench.plan_timing import PlanRun, summarize_plans, time_lazysp, time_ompl, time_planner
from drd_planner.bench.world_recipes import WorldRecipe, scene_recipes, seeded_recipes
from drd_planner.domains.arm import ArmDomain
from drd_planner.domains.arm_mesh_checker import arm_link_meshes
from drd_planner.domains.arm_robot import robot_texts
from drd_planner.geometry.mesh_cover import sphere_cover
from drd_planner.planner.planner import Planner
from drd_planner.planner.prior_file import load_prior
from drd_planner.settings import shared_data_dir

ROOT = Path(__file__).resolve().parents[2]
MODELS = ("spheres", "meshes")
QUERY = (0, 1)


def parse() -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="a small run (about a minute)")
    parser.add_argument("--table-clutter", type=int, default=10, help="seeded table_clutter worlds")
    parser.add_argument("--clutter", type=int, default=10, help="seeded clutter worlds")
    parser.add_argument("--scenes", type=int, default=20, help="MotionBenchMaker scenes per family")
    parser.add_argument("--edges", type=int, default=None, help="check only the first N edges per world")
    parser.add_argument("--plan-worlds", type=int, default=40, help="worlds timed for plans (the first N)")
    parser.add_argument("--repeats", type=int, default=5, help="times each plan is timed (the least kept)")
    parser.add_argument("--skip-edges", action="store_true", help="time the plans only")
    parser.add_argument("--prior", type=Path, default=ROOT / "trees" / "arm_table_clutter.npz")
    parser.add_argument("--no-ompl", action="store_true", help="skip ompl_lazyprm")
    parser.add_argument("--json", type=Path, default=None)
    args = parser.parse_args()
    if args.quick:
        args.table_clutter, args.clutter, args.scenes, args.edges, args.plan_worlds = 2, 2, 2, 400, 6
        args.repeats = 1
    return args


def recipes(args: argparse.Namespace) -> list[WorldRecipe]:
    mbm = shared_data_dir() / "mbm"
    out = seeded_recipes("table_clutter", range(args.table_clutter)) + seeded_recipes("clutter", range(args.clutter))
    for family in ("table_pick_panda", "box_panda"):
        if args.scenes and (mbm / family).is_dir():
            out += scene_recipes(mbm / family, args.scenes)
    # Interleave families so that --plan-worlds N takes some of each.
    by_family: dict[str, list[WorldRecipe]] = {}
    for r in out:
        by_family.setdefault(r.family, []).append(r)
    mixed: list[WorldRecipe] = []
    for i in range(max(len(v) for v in by_family.values())):
        mixed += [v[i] for v in by_family.values() if i < len(v)]
    return mixed


def compare(
    spheres: ArmDomain, meshes: ArmDomain, worlds: list[WorldRecipe], edges: int | None
) -> list[WorldComparison]:
    ids = None if edges is None else list(range(min(edges, spheres.graph.num_edges)))
    results = []
    for i, recipe in enumerate(worlds):
        t0 = time.perf_counter()
        result = compare_world(spheres, meshes, recipe, ids)
        results.append(result)
        print(
            f"  [{i + 1}/{len(worlds)}] {recipe.label}: free {int(result.free_spheres.sum())} / "
            f"{int(result.free_meshes.sum())} of {result.free_spheres.size}, spheres-only blocked "
            f"{result.spheres_only_blocked}, meshes-only blocked {result.meshes_only_blocked} "
            f"({time.perf_counter() - t0:.1f} s)",
            file=sys.stderr,
        )
    return results


def plans(
    domains: dict[str, ArmDomain], planner: Planner, worlds: list[WorldRecipe], ompl: bool, repeats: int
) -> list[PlanRun]:
    runs: list[PlanRun] = []
    first = domains["spheres"]
    planner.plan(*QUERY, first.checker(worlds[0].make(first)))  # warm the query's cached model
    for recipe in worlds:
        world = recipe.make(first)
        for _ in range(repeats):
            for model in MODELS:
                checker = domains[model].checker(world)
                runs.append(time_planner(planner, checker, QUERY, model=model, world=recipe.label))
            for model in MODELS:
                checker = domains[model].checker(world)
                runs.append(time_lazysp(first.graph, checker, QUERY, model=model, world=recipe.label))
    if ompl:
        for model in MODELS:
            live = LiveWorlds("arm", domains[model].spec(), tuple(worlds) * repeats)
            runs += time_ompl(first.graph, QUERY, live, model=model)
    return runs


def table(header: list[str], rows: list[list[str]]) -> None:
    print("| " + " | ".join(header) + " |")
    print("|" + "---|" * len(header))
    for row in rows:
        print("| " + " | ".join(row) + " |")


def print_edges(summary: dict[str, Any]) -> None:
    print("\n## Edge by edge: spheres vs meshes (same roadmap, same worlds)\n")
    rows = []
    for name, b in {**summary["families"], "all": summary["all"]}.items():
        rows.append(
            [
                name,
                str(b["worlds"]),
                str(b["edges"]),
                str(b["free_spheres"]),
                str(b["free_meshes"]),
                f"{100 * b['agree'] / max(b['edges'], 1):.2f} %",
                str(b["spheres_only_blocked"]),
                str(b["meshes_only_blocked"]),
                f"{b['ms_spheres_mean']:.3f} ({b['ms_spheres_median']:.3f})",
                f"{b['ms_meshes_mean']:.3f} ({b['ms_meshes_median']:.3f})",
                f"{b['time_ratio']:.2f}",
            ]
        )
    table(
        [
            "worlds",
            "n",
            "edges",
            "free (spheres)",
            "free (meshes)",
            "agree",
            "blocked only by spheres",
            "blocked only by meshes",
            "ms/edge spheres (median)",
            "ms/edge meshes (median)",
            "ratio",
        ],
        rows,
    )
    print("\n### Edges blocked only by the meshes, by mesh link\n")
    table(
        [
            "link",
            "edges",
            "at an end vertex (distinct vertices)",
            "depth median (mm)",
            "depth max (mm)",
            "sphere clearance median (mm)",
            "median contact point (link frame, m)",
        ],
        [
            [
                link,
                str(m["edges"]),
                f"{m['at_end_vertex']} ({m['distinct_vertices']})",
                f"{m['depth_mm_median']:.1f}",
                f"{m['depth_mm_max']:.1f}",
                f"{m['sphere_clearance_mm_median']:.1f}",
                str(m["point_median_m"]),
            ]
            for link, m in summary["misses_by_link"].items()
        ],
    )


def print_cover(domain: ArmDomain) -> dict[str, Any]:
    meshes = arm_link_meshes(domain.params, robot_texts(domain.params.urdf_path)[0])
    cover = sphere_cover(domain.robot, meshes)
    print("\n## How far the collision meshes stick out of the sphere model (per element)\n")
    table(
        ["link", "max outside (mm)", "share of surface outside the spheres", "worst point (link frame, m)"],
        [
            [
                e.link,
                f"{1e3 * e.max_excess:.1f}",
                f"{100 * e.outside_share:.0f} %",
                str(np.round(e.worst_point, 3).tolist()),
            ]
            for e in cover.elements
        ],
    )
    print(
        f"\nSphere growth that contains the meshes: max {1e3 * cover.growth.max():.1f} mm, "
        f"mean {1e3 * cover.growth.mean():.1f} mm (bound {1e3 * cover.bound:.1f} mm included)"
    )
    return {
        "elements": [
            {"link": e.link, "max_outside_mm": 1e3 * e.max_excess, "outside_share": e.outside_share}
            for e in cover.elements
        ],
        "growth_mm_max": 1e3 * float(cover.growth.max()),
        "growth_mm_mean": 1e3 * float(cover.growth.mean()),
    }


def print_plans(summary: dict[str, Any]) -> None:
    print("\n## Time to a verified plan (start 0 -> goal 1), same roadmap and worlds\n")
    rows = []
    for method, b in summary.items():
        s, m = b["spheres"], b["meshes"]
        rows.append(
            [
                method,
                str(b["worlds"]),
                f"{s['verified']} / {m['verified']} (both {b['both_verified']})",
                f"{s['ms_mean']:.2f} ({s['ms_median']:.2f})",
                f"{m['ms_mean']:.2f} ({m['ms_median']:.2f})",
                f"{b['ratio']:.2f}",
                f"{b['ratio_median']:.2f}",
                f"{s['checks_mean']:.1f} / {m['checks_mean']:.1f}",
                f"{s['check_ms_mean']:.2f} / {m['check_ms_mean']:.2f}",
            ]
        )
    table(
        [
            "method",
            "worlds",
            "verified (spheres / meshes)",
            "ms spheres (median)",
            "ms meshes (median)",
            "ratio of means",
            "median ratio",
            "checks spheres / meshes",
            "check ms spheres / meshes",
        ],
        rows,
    )


def main() -> None:
    args = parse()
    prior = load_prior(args.prior, expected_domain="arm")
    domains = {m: ArmDomain.from_spec({**prior.domain_spec, "collision_model": m}) for m in MODELS}
    if not np.array_equal(domains["spheres"].graph.edges, prior.graph.edges):
        raise SystemExit(f"the prior {args.prior} was built on another roadmap than its spec gives")
    worlds = recipes(args)
    print(f"{len(worlds)} worlds, {prior.graph.num_edges} edges each", file=sys.stderr)
    results = [] if args.skip_edges else compare(domains["spheres"], domains["meshes"], worlds, args.edges)
    edge_summary: dict[str, Any] = {}
    cover: dict[str, Any] = {}
    if results:
        edge_summary = summarize(results)
        print_edges(edge_summary)
        cover = print_cover(domains["meshes"])
    ompl = not args.no_ompl and ompl_available()[0]
    runs = plans(domains, Planner(prior), worlds[: args.plan_worlds], ompl, max(args.repeats, 1))
    plan_summary = summarize_plans(runs)
    print_plans(plan_summary)
    if args.json is not None:
        misses = [m.__dict__ for r in results for m in r.misses]
        args.json.write_text(
            json.dumps(
                {
                    "edges": edge_summary,
                    "misses": misses,
                    "cover": cover,
                    "plans": plan_summary,
                    "runs": [r.__dict__ for r in runs],
                },
                indent=1,
                default=float,
            )
        )


if __name__ == "__main__":
    main()
