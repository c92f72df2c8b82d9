#!/usr/bin/env python3
"""Helicopter starts and goals off the lattice: how many join and plan, on both shipped helicopter priors.

For each prior (``heli_wires``, ``heli_lines``) and each offset (0, 2, 10, 30, 50 m), ``--states`` random states
as **starts** (to the prior's stored goal) and as **goals** (from its stored start): a random vertex's position
moved that far horizontally in a random direction, an altitude drawn in the lattice's band and a random heading;
each planned on its own world of the prior's world model (``wires``, ``corridors``) with the real FCL checker
(:class:`~drd_planner.domains.helicopter_checker.HelicopterChecker`), by the planner the node uses (states snap to
a vertex only within 1e-6). Every state ends in one row:

- **refused**, with its reason (outside the lattice's extent, ...);
- **in collision**: the state itself is blocked on its world (below the terrain, within a wire's or zone's
  clearance); no plan can start or end there;
- **no free path**: a *reference* planner finds none either: it joins the state to its ``--reference-joins``
  shortest flyable motions at once and, when they do not suffice, to every other vertex a flyable motion reaches
  (join growth without a budget), searching the whole lattice each time; so "free path" means a free path
  through the lattice from one flyable motion joining the state;
- **planned** or **missed** (the reference found a path, the planner did not), with checks and CPU time.

"planned / path exists" is the issue's measure: every state whose world has a free path (by the reference) must
plan. Times are CPU seconds of this process (``time.process_time``), the query's library and tree included
(built per query: every state is a new query).

Usage:
    python scripts/experiments/bench_heli_states.py [--priors heli_wires,heli_lines] [--states 20] [--seed 1]
        [--offsets 0,2,10,30,50] [--reference-joins 96] [--join-batch 64] [--free-states] [--json FILE]
        [--markdown FILE]

``--free-states`` redraws a state that is in collision on its world (counted as redrawn) until it is clear, so
every state counts towards "planned / path exists" (on ``heli_lines`` three states in four drawn in the altitude
band lie below the terrain).

Seeds: the defaults of the connector and of the join growth (``--join-batch``) were chosen on ``--seed 0``
states; the README's table is ``--seed 1``.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, cast

import numpy as np

from drd_planner.planner import load_prior
from drd_planner.planner.connect import MotionOracle
from drd_planner.planner.dubins_connector import DubinsConnector, dubins_connector
from drd_planner.planner.planner import Planner
from drd_planner.planner.result import PlanResult
from drd_planner.planner.roadmap_growth import GrowthSettings
from drd_planner.planning.prior_domain import rebuild_domain

ROOT = Path(__file__).resolve().parents[2]
#: The world model each shipped prior was built with (``trees/README.md``).
WORLD_MODELS = {"heli_wires": "wires", "heli_lines": "corridors"}
KINDS = ("start", "goal")
#: With ``--free-states``, draws of a state in collision per state at most.
MAX_REDRAWS = 200


@dataclass
class Cell:
    """The outcomes of one (prior, kind, offset)."""

    states: int = 0
    redrawn: int = 0
    outcomes: Counter[str] = field(default_factory=Counter)
    refusals: Counter[str] = field(default_factory=Counter)
    checks: list[int] = field(default_factory=list)
    cpu_s: list[float] = field(default_factory=list)

    def row(self) -> dict[str, Any]:
        """The JSON of this cell."""
        exists = self.outcomes["planned"] + self.outcomes["missed"]
        return {
            "states": self.states,
            "redrawn_in_collision": self.redrawn,
            **{k: int(v) for k, v in sorted(self.outcomes.items())},
            "refusals": dict(self.refusals),
            "path_exists": exists,
            "planned_of_existing": self.outcomes["planned"] / exists if exists else None,
            "checks_median": float(np.median(self.checks)) if self.checks else None,
            "checks_mean": float(np.mean(self.checks)) if self.checks else None,
            "cpu_ms_median": 1e3 * float(np.median(self.cpu_s)) if self.cpu_s else None,
            "cpu_ms_mean": 1e3 * float(np.mean(self.cpu_s)) if self.cpu_s else None,
        }


def _random_state(rng: np.random.Generator, vertices: np.ndarray, offset: float) -> np.ndarray:
    """(4,) a vertex's position moved ``offset`` m horizontally, an altitude in the band, a random heading."""
    v = vertices[int(rng.integers(vertices.shape[0]))]
    angle = rng.uniform(0.0, 2.0 * np.pi)
    z = rng.uniform(vertices[:, 2].min(), vertices[:, 2].max())
    return np.array([v[0] + offset * np.cos(angle), v[1] + offset * np.sin(angle), z, rng.uniform(-np.pi, np.pi)])


def _refusal_kind(reason: str) -> str:
    """A short name of a refusal's cause."""
    for key in ("horizontal extent", "altitude band", "heading", "NaN"):
        if key in reason:
            return key
    return reason[:60]


def _plan(planner: Planner, kind: str, state: np.ndarray, ends: tuple[int, int], checker: Any) -> PlanResult:
    start, goal = ends
    return planner.plan(state, goal, checker) if kind == "start" else planner.plan(start, state, checker)


def run_prior(name: str, args: argparse.Namespace) -> dict[str, Any]:
    """Every offset and kind of one prior."""
    prior = load_prior(ROOT / "trees" / f"{name}.npz")
    domain = rebuild_domain(prior, name)
    model = WORLD_MODELS[name]
    batch = None if args.join_batch == 0 else args.join_batch
    planner = Planner(prior, snap_tolerance=1e-6, growth=GrowthSettings(join_batch=batch))
    own = dubins_connector(prior)
    assert own is not None
    reference = Planner(
        prior,
        snap_tolerance=1e-6,
        growth=GrowthSettings(max_joins=10**6, max_rounds=10**6, seconds=None),
        connector=DubinsConnector(
            turning_radius=own.turning_radius,
            spacing=own.spacing,
            max_climb_gradient=own.max_climb_gradient,
            neighbours=args.reference_joins,
            extent=own.extent,
        ),
    )
    vertices = prior.graph.vertex_states
    assert vertices is not None
    ends = (int(domain.start), int(domain.goal))
    cells: dict[str, dict[str, Cell]] = {kind: {} for kind in KINDS}
    rng = np.random.default_rng(args.seed)
    for offset in args.offsets:
        for kind in KINDS:
            cell = cells[kind].setdefault(f"{offset:g}", Cell())
            for i in range(args.states):
                world_seed = args.seed * 1_000_000 + int(offset) * 1_000 + i * 2 + (kind == "goal")
                checker = cast("MotionOracle", domain.checker(domain.make_world(model, world_seed)))
                state = _random_state(rng, vertices, offset)
                for _ in range(args.free_states * MAX_REDRAWS):  # --free-states: only states clear of the world
                    if checker.check_motion(state[None, :]):
                        break
                    cell.redrawn += 1
                    state = _random_state(rng, vertices, offset)
                cell.states += 1
                t0 = time.process_time()
                result = _plan(planner, kind, state, ends, checker)
                cpu = time.process_time() - t0
                if result.status.value == "refused":
                    cell.outcomes["refused"] += 1
                    cell.refusals[_refusal_kind(result.reason)] += 1
                elif result.found:
                    cell.outcomes["planned"] += 1
                    cell.checks.append(result.num_checks)
                    cell.cpu_s.append(cpu)
                elif not checker.check_motion(state[None, :]):
                    cell.outcomes["in collision"] += 1
                elif _plan(reference, kind, state, ends, checker).found:
                    cell.outcomes["missed"] += 1
                    print(
                        f"  missed: {name} {kind} {np.round(state, 2).tolist()}: {result.reason}",
                        file=sys.stderr,
                    )
                else:
                    cell.outcomes["no free path"] += 1
            print(f"{name} {kind} {offset:g} m: {dict(cell.outcomes)}", file=sys.stderr, flush=True)
    return {
        "prior": name,
        "world_model": model,
        "joins": own.neighbours,
        "reference_joins": args.reference_joins,
        "cells": {kind: {off: c.row() for off, c in by.items()} for kind, by in cells.items()},
        "totals": _totals([c for by in cells.values() for c in by.values()]),
    }


def _totals(cells: list[Cell]) -> dict[str, Any]:
    total = Cell()
    for c in cells:
        total.states += c.states
        total.redrawn += c.redrawn
        total.outcomes.update(c.outcomes)
        total.refusals.update(c.refusals)
        total.checks += c.checks
        total.cpu_s += c.cpu_s
    return total.row()


def markdown(results: list[dict[str, Any]]) -> str:
    """The README's table."""
    lines = [
        "| prior | as | offset m | states | refused | in collision (redrawn) | no free path | path exists | planned "
        "(of those) | checks median | CPU ms median |",
        "|---|---|---:|---:|---:|---:|---:|---:|---|---:|---:|",
    ]
    for res in results:
        for kind, by in res["cells"].items():
            for off, row in by.items():
                share = row["planned_of_existing"]
                lines.append(
                    f"| {res['prior']} | {kind} | {off} | {row['states']} | {row.get('refused', 0)} | "
                    f"{row.get('in collision', 0)} ({row.get('redrawn_in_collision', 0)}) | "
                    f"{row.get('no free path', 0)} | "
                    f"{row['path_exists']} | "
                    f"{row.get('planned', 0)} ({'-' if share is None else f'{100 * share:.0f} %'}) | "
                    f"{_num(row['checks_median'], '.0f')} | {_num(row['cpu_ms_median'], '.0f')} |"
                )
        t = res["totals"]
        share = t["planned_of_existing"]
        lines.append(
            f"| **{res['prior']}** | all | 0-50 | {t['states']} | {t.get('refused', 0)} | "
            f"{t.get('in collision', 0)} ({t.get('redrawn_in_collision', 0)}) | "
            f"{t.get('no free path', 0)} | {t['path_exists']} | **{t.get('planned', 0)} "
            f"({'-' if share is None else f'{100 * share:.1f} %'})** | {_num(t['checks_median'], '.0f')} | "
            f"{_num(t['cpu_ms_median'], '.0f')} |"
        )
    return "\n".join(lines) + "\n"


def _num(value: float | None, fmt: str) -> str:
    return "-" if value is None else format(value, fmt)


def main(argv: list[str] | None = None) -> int:
    """Run the benchmark and print (and write) its table."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--priors", default="heli_wires,heli_lines")
    parser.add_argument("--states", type=int, default=20, help="states per prior, offset and kind")
    parser.add_argument("--offsets", default="0,2,10,30,50", help="metres off the nearest vertex, comma-separated")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--reference-joins", type=int, default=96, help="joins of the reference planner")
    parser.add_argument(
        "--join-batch",
        type=int,
        default=GrowthSettings().join_batch or 0,
        help="the planner's GrowthSettings.join_batch (0: every join at once)",
    )
    parser.add_argument(
        "--free-states",
        action="store_true",
        help="redraw a state that is in collision on its world (below the terrain, in a clearance)",
    )
    parser.add_argument("--json", type=Path)
    parser.add_argument("--markdown", type=Path)
    args = parser.parse_args(argv)
    args.offsets = [float(x) for x in args.offsets.split(",")]
    results = [run_prior(name, args) for name in args.priors.split(",")]
    table = markdown(results)
    print(table)
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps({"seed": args.seed, "results": results}, indent=1))
    if args.markdown:
        args.markdown.parent.mkdir(parents=True, exist_ok=True)
        args.markdown.write_text(table)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
