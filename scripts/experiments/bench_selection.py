#!/usr/bin/env python3
"""How long the planner takes to choose each check, on the shipped priors: a script that reports.

    python scripts/experiments/bench_selection.py [--priors trees/heli_wires.npz,...] [--queries 20] [--worlds 10]
        [--seed 0] [--settings shipped,posterior] [--repeat 1] [--profile 12] [--save-checks F]
        [--compare-checks F] [--json F]

For each prior (``drd_planner.planner.load_prior``) it plans a fixed, seeded set of episodes with
``Planner.plan``: the prior's stored query and ``--queries`` random new queries between vertices, each
against ``--worlds`` of the prior's training worlds (``prior.worlds`` rows) in which some path of the
query's library is free, answered from the table (``TableOracle``). Each setting is one planner:

* ``shipped``: the prior's own eta, kappa and region rule (the stored query's own, the prior's for others);
* ``posterior``: eta 1, kappa 5 and the per-check rule for every query (``Planner.set_leaf``): BiSECt with
  the posterior leaf from the first check, the costliest selection;
* ``tree``: eta 0.2, kappa 5 and the per-check rule: the DiRECt tree (grown online for new queries), then
  the posterior leaf.

The planners run without the probe (``probe_probability=None``): a new query whose union path is likely free
would otherwise often be planned without a library stage, and it is the library stage's selection that is
measured. Every episode runs twice: a warm-up pass builds each query's library and grows its online tree along the
branches taken (building is another measurement), then the measured pass. Per check it reports, from the
second check of the library stage on (stages ``tree`` and ``bisect``):

* ``cpu ms/check``: CPU time (``time.process_time``) between the end of one check and the start of the
  next, i.e. the policy's update after the outcome, the runner's bookkeeping and the next selection;
* ``select ms``: the wall time of the selection alone, as the plan records it (``CheckRecord.select_ms``);

and the first selection (policy set-up included) apart. With ``--repeat R`` > 1 the measured pass plans
each episode R times in a row (the same checks each time) and each check counts with the smallest of its R
times: on a shared machine the least disturbed one. With ``--profile N`` a third pass runs under
cProfile and prints the N functions with the most own time, as a share of the profiled episode loops.
``--save-checks`` writes every episode's checks (edge, outcome, stage), status and path as JSON;
``--compare-checks`` compares them with such a file and reports how many episodes differ.
"""

from __future__ import annotations

import argparse
import cProfile
import json
import pstats
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from drd_planner import Planner, TableOracle
from drd_planner.planner import load_prior
from drd_planner.planner.result import PlanResult

ROOT = Path(__file__).resolve().parents[2]
DEFAULT_PRIORS = ("trees/heli_wires.npz", "trees/heli_lines.npz", "trees/arm_table_clutter.npz")
#: Setting name -> (eta, kappa, region rule) for ``Planner.set_leaf``; None: the prior's own.
SETTINGS: dict[str, tuple[float, float | None, str] | None] = {
    "shipped": None,
    "posterior": (1.0, 5.0, "per_check"),
    "tree": (0.2, 5.0, "per_check"),
}
LIBRARY_STAGES = ("tree", "bisect")


class StampedOracle:
    """A table oracle that notes the CPU time just before and just after each check."""

    def __init__(self, outcomes: np.ndarray[Any, Any]) -> None:
        self._table = TableOracle(outcomes)
        self.before: list[float] = []
        self.after: list[float] = []

    def check(self, edge: int) -> bool:
        """The table's answer, between two CPU time stamps."""
        self.before.append(time.process_time())
        free = self._table.check(edge)
        self.after.append(time.process_time())
        return free


@dataclass(frozen=True)
class Episode:
    """One planned episode: which query, against which training world."""

    kind: str  # "stored" or "new"
    start: int
    goal: int
    world: int

    def key(self, prior: str, setting: str) -> str:
        """A name unique within one run of this script."""
        return f"{prior}|{setting}|{self.kind}|{self.start}-{self.goal}|w{self.world}"


@dataclass
class Tally:
    """Per-check times of one group of episodes (ms)."""

    episodes: int = 0
    checks: list[int] = field(default_factory=list)
    cpu_ms: list[float] = field(default_factory=list)
    select_ms: list[float] = field(default_factory=list)
    first_ms: list[float] = field(default_factory=list)

    def add(self, runs: list[tuple[PlanResult, StampedOracle, float]]) -> None:
        """Add one measured episode planned once or more: per check, the smallest time of the runs.

        Each run is a plan's result, its oracle's stamps and the CPU time at the call (:func:`plan_once`);
        every run of an episode makes the same checks.
        """
        self.episodes += 1
        result = runs[0][0]
        self.checks.append(result.num_checks)
        records = result.checks
        if records:
            self.first_ms.append(min((oracle.before[0] - t_call) * 1e3 for _, oracle, t_call in runs))
        for k in range(1, len(records)):
            if records[k].stage in LIBRARY_STAGES:
                self.cpu_ms.append(min((oracle.before[k] - oracle.after[k - 1]) * 1e3 for _, oracle, _ in runs))
                self.select_ms.append(min(run.checks[k].select_ms for run, _, _ in runs))

    def row(self) -> dict[str, float]:
        """Summary numbers of the group."""

        def stat(values: list[float], how: str) -> float:
            if not values:
                return float("nan")
            arr = np.asarray(values)
            return (
                float(np.median(arr) if how == "median" else np.mean(arr))
                if how != "p90"
                else float(np.percentile(arr, 90))
            )

        return {
            "episodes": self.episodes,
            "mean_checks": float(np.mean(self.checks)) if self.checks else float("nan"),
            "timed_checks": len(self.cpu_ms),
            "cpu_ms_median": stat(self.cpu_ms, "median"),
            "cpu_ms_mean": stat(self.cpu_ms, "mean"),
            "cpu_ms_p90": stat(self.cpu_ms, "p90"),
            "select_ms_median": stat(self.select_ms, "median"),
            "select_ms_mean": stat(self.select_ms, "mean"),
            "first_ms_median": stat(self.first_ms, "median"),
        }


def episodes_of(planner: Planner, rng: np.random.Generator, queries: int, worlds: int) -> list[Episode]:
    """The stored query and ``queries`` random new ones, each with up to ``worlds`` solvable training worlds."""
    prior = planner.prior
    assert prior.worlds is not None
    pairs = [("stored", qt.start, qt.goal) for qt in prior.trees]
    stored = {(s, g) for _, s, g in pairs}
    tries = 0
    while len(pairs) < len(prior.trees) + queries and tries < 50 * queries:
        tries += 1
        s, g = (int(v) for v in rng.choice(prior.graph.num_vertices, size=2, replace=False))
        if (s, g) in stored:
            continue
        model = planner.query_model(s, g)
        if model.library is None:
            continue  # no training world connects them: no library stage to measure
        stored.add((s, g))
        pairs.append(("new", s, g))
    out: list[Episode] = []
    for kind, s, g in pairs:
        library = planner.query_model(s, g).library
        assert library is not None
        solvable = np.flatnonzero(library.valid_paths(prior.worlds).any(axis=1))
        chosen = rng.choice(solvable, size=min(worlds, solvable.size), replace=False)
        out.extend(Episode(kind, s, g, int(w)) for w in sorted(chosen.tolist()))
    return out


def plan_once(planner: Planner, episode: Episode, seed: int) -> tuple[PlanResult, StampedOracle, float]:
    """Plan one episode; the result, its oracle's stamps and the CPU time at the call."""
    assert planner.prior.worlds is not None
    oracle = StampedOracle(planner.prior.worlds[episode.world])
    t_call = time.process_time()
    result = planner.plan(episode.start, episode.goal, oracle, seed=seed)
    return result, oracle, t_call


def check_log(result: PlanResult) -> dict[str, Any]:
    """What must not change: the checks in order, the status and the path."""
    return {
        "checks": [[c.edge, c.free, c.stage] for c in result.checks],
        "status": result.status.value,
        "edges": [int(e) for e in result.edges],
    }


def profile_table(profiler: cProfile.Profile, lines: int) -> list[dict[str, Any]]:
    """The ``lines`` functions with the most own time, as shares of the profiled episode loops."""
    stats = pstats.Stats(profiler).stats  # type: ignore[attr-defined]
    loop = sum(v[3] for k, v in stats.items() if k[2] == "run_episode") or 1.0
    rows = sorted(stats.items(), key=lambda kv: -kv[1][2])[:lines]
    out = []
    for (path, line, name), (_, calls, own, cum, _) in rows:
        where = "/".join(Path(path).parts[-2:]) if path != "~" else "builtin"
        out.append(
            {
                "function": f"{where}:{line}({name})",
                "calls": calls,
                "own_pct": 100.0 * own / loop,
                "cum_pct": 100.0 * cum / loop,
            }
        )
    return out


def run_prior(path: Path, args: argparse.Namespace, logs: dict[str, Any]) -> dict[str, Any]:
    """Every setting of one prior: per-check times by query kind, profile rows, and the check logs."""
    name = path.stem
    report: dict[str, Any] = {}
    for setting in args.settings:
        planner = Planner(load_prior(path), cache_size=args.queries + 4, probe_probability=None)
        leaf = SETTINGS[setting]
        if leaf is not None:
            planner.set_leaf(leaf[0], leaf[1], region_rule=leaf[2])
        episodes = episodes_of(planner, np.random.default_rng(args.seed), args.queries, args.worlds)
        for episode in episodes:  # warm-up: libraries built, online trees grown along the branches taken
            plan_once(planner, episode, args.seed)
        tallies = {"stored": Tally(), "new": Tally()}
        for episode in episodes:
            runs = [plan_once(planner, episode, args.seed) for _ in range(args.repeat)]
            tallies[episode.kind].add(runs)
            logs[episode.key(name, setting)] = check_log(runs[0][0])
        entry: dict[str, Any] = {kind: t.row() for kind, t in tallies.items()}
        if args.profile > 0:
            profiler = cProfile.Profile()
            profiler.enable()
            for episode in episodes:
                plan_once(planner, episode, args.seed)
            profiler.disable()
            entry["profile"] = profile_table(profiler, args.profile)
        report[setting] = entry
        print_setting(name, setting, entry)
    return report


def print_setting(prior: str, setting: str, entry: dict[str, Any]) -> None:
    """One block of the report."""
    print(f"\n== {prior} [{setting}]")
    print(
        f"  {'queries':8s} {'episodes':>8s} {'checks':>7s} {'timed':>6s} {'cpu ms/check':>22s} "
        f"{'select ms (wall)':>18s} {'first ms':>9s}"
    )
    print(
        f"  {'':8s} {'':>8s} {'mean':>7s} {'':>6s} {'median / mean / p90':>22s} {'median / mean':>18s} {'median':>9s}"
    )
    for kind in ("stored", "new"):
        r = entry[kind]
        print(
            f"  {kind:8s} {r['episodes']:8d} {r['mean_checks']:7.2f} {r['timed_checks']:6d} "
            f"{r['cpu_ms_median']:6.3f} / {r['cpu_ms_mean']:6.3f} / {r['cpu_ms_p90']:6.3f} "
            f"{r['select_ms_median']:8.3f} / {r['select_ms_mean']:7.3f} {r['first_ms_median']:9.3f}"
        )
    for row in entry.get("profile", []):
        print(f"    {row['own_pct']:5.1f}% own {row['cum_pct']:5.1f}% cum {row['calls']:7d}  {row['function']}")


def compare(logs: dict[str, Any], reference: dict[str, Any]) -> None:
    """Print how many episodes have the same checks, status and path as ``reference``."""
    common = sorted(set(logs) & set(reference))
    differ = [k for k in common if logs[k] != reference[k]]
    print(f"\nchecks compared on {len(common)} episodes: {len(common) - len(differ)} identical, {len(differ)} differ")
    for key in differ[:10]:
        print(f"  differs: {key}")
    missing = len(set(reference) - set(logs))
    if missing:
        print(f"  {missing} episodes of the reference were not run here")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--priors", default=",".join(DEFAULT_PRIORS))
    parser.add_argument("--queries", type=int, default=20)
    parser.add_argument("--worlds", type=int, default=10)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--settings", default="shipped,posterior")
    parser.add_argument("--repeat", type=int, default=1, help="plans per measured episode (the least disturbed counts)")
    parser.add_argument("--profile", type=int, default=12, help="profile rows per setting (0: no profile)")
    parser.add_argument("--save-checks", type=Path, default=None)
    parser.add_argument("--compare-checks", type=Path, default=None)
    parser.add_argument("--json", type=Path, default=None)
    args = parser.parse_args()
    if args.repeat < 1:
        parser.error(f"--repeat must be at least 1; got {args.repeat}")
    args.settings = [s for s in args.settings.split(",") if s]
    unknown = set(args.settings) - set(SETTINGS)
    if unknown:
        parser.error(f"unknown settings {sorted(unknown)}; known: {', '.join(SETTINGS)}")
    logs: dict[str, Any] = {}
    report = {}
    for text in args.priors.split(","):
        path = Path(text) if Path(text).is_absolute() else ROOT / text
        report[path.stem] = run_prior(path, args, logs)
    if args.save_checks is not None:
        args.save_checks.write_text(json.dumps(logs))
        print(f"\nwrote the checks of {len(logs)} episodes to {args.save_checks}")
    if args.compare_checks is not None:
        compare(logs, json.loads(args.compare_checks.read_text()))
    if args.json is not None:
        args.json.write_text(json.dumps(report, indent=2))


if __name__ == "__main__":
    main()
