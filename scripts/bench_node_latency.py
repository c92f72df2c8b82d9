#!/usr/bin/env python3
# mypy: allow-untyped-calls
"""Request-to-plan latency of the planner node on the bundled scenario, split into checks and the rest.

The real node (the two-thread executor ``planner_node`` uses) and a peer run in threads of this
process (the harness of ``bench_node_burst.py``). Maps: the first ``/obstacles`` and ``/terrain`` of
``bags/heli_wires.mcap`` read with rosbags (when the bag exists), else the helicopter "wires" world of
the tree's domain drawn with ``--world-seed``. Each measured request is one ``goal_pose`` at the
tree's goal, sent when the node is idle; its latency is the wall time from publishing it to the
``Path`` arriving at the peer. The node's summary on ``/diagnostics`` for that request gives:

- ``check_s``: time in the collision checker (FCL) for the checks of this plan;
- ``selection_s``: time the policy took to choose the edges (DiRECt tree walk, BiSECt);
- the rest, ``latency - check_s - selection_s``: messaging, conversion and scheduling, which is
  split further into ``total_s - check_s - selection_s`` (the planning session's own work outside
  checks and selection: the snapshot's FCL scene build on the first plan of a snapshot, the checker,
  the path states) and ``latency - total_s`` (building and publishing the node's messages, DDS, the
  executor).

Cold run: before each request the obstacle map is published again, so the plan runs on a new map
snapshot: a new scene and no cached check (the realistic case: maps change between requests). The
node runs with ``replan_on_map_update`` off here, so a map update triggers no re-check that would warm
the snapshot before the request. Warm run: the same snapshot for every request, so every check is a
cache hit.

``--profile FILE`` runs the node on a single-threaded executor under cProfile (from its start: the map
messages and the two unmeasured warm-up requests are in the profile too), writes the stats (``pstats``
format) and prints where the node's time went.

Usage: python scripts/bench_node_latency.py [--requests 30] [--bag bags/heli_wires.mcap]
       [--tree trees/heli_wires.npz] [--world-seed 1] [--no-warm] [--profile FILE] [--json FILE]
"""

from __future__ import annotations

import argparse
import cProfile
import json
import os
import pstats
import sys
import threading
import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np
from rclpy.parameter import Parameter

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_node_burst import Harness, default_maps, wait_for

REPO_ROOT = Path(__file__).resolve().parents[1]
DEFAULT_TREE = REPO_ROOT / "trees" / "heli_wires.npz"
DEFAULT_BAG = REPO_ROOT / "bags" / "heli_wires.mcap"
#: Goal: selection and messaging under this share of the cold request-to-plan latency.
GOAL_SHARE = 0.10


@dataclass
class Sample:
    """One request's times (seconds) and counts."""

    latency: float
    check: float
    selection: float
    total: float
    checks: int
    map_version: int

    @property
    def rest(self) -> float:
        """Messaging, conversion and scheduling: the latency outside checks and selection."""
        return self.latency - self.check - self.selection

    @property
    def session_other(self) -> float:
        """The planning session's time outside checks and selection (scene build, checker, path)."""
        return self.total - self.check - self.selection

    @property
    def node_messaging(self) -> float:
        """Time outside the planning session: messages, DDS, the executor."""
        return self.latency - self.total


class Probe:
    """Sends one request at a time and collects its Path arrival and its summary."""

    def __init__(self, harness: Harness) -> None:
        self.harness = harness
        self._lock = threading.Lock()
        self._plans: list[float] = []
        self._summaries: dict[str, dict[str, str]] = {}
        self._checks: dict[int, int] = {}
        harness.listen_plans(self._on_plan)
        harness.listen(self._on_status)
        self._count = 0

    def _on_plan(self, item: tuple[float, Any]) -> None:
        now, path = item
        if len(path.poses):  # an empty Path withdraws a plan; it answers no request
            with self._lock:
                self._plans.append(now)

    def _on_status(self, item: tuple[float, Any]) -> None:
        _, status = item
        values = {str(kv.key): str(kv.value) for kv in status.values}
        if values.get("request") == "goal_pose" and "request_stamp" in values:
            with self._lock:
                self._summaries[values["request_stamp"]] = values

    def request(self, *, timeout: float = 30.0) -> Sample:
        """Publish one goal_pose and wait for its Path and summary."""
        self._count += 1
        stamp = (2_000_000 + self._count, 0)
        key = f"{stamp[0]}.{stamp[1]:09d}"
        goal = self.harness.goal(stamp)
        with self._lock:
            plans = len(self._plans)
        start = time.perf_counter()
        self.harness.goals.publish(goal)

        def done() -> bool:
            with self._lock:
                return len(self._plans) > plans and key in self._summaries

        if not wait_for(done, timeout):
            raise RuntimeError(f"no plan for request {key}: {self.harness.node.errors[-3:]}")
        with self._lock:
            arrived, values = self._plans[plans], self._summaries[key]
        if values.get("result") != "path_found":
            raise RuntimeError(f"request {key} gave {values.get('result')}: {values}")
        return Sample(
            latency=arrived - start,
            check=float(values["check_s"]),
            selection=float(values["selection_s"]),
            total=float(values["total_s"]),
            checks=int(values["checks"]),
            map_version=int(values["map_version"]),
        )


def run(harness: Harness, markers: Any, *, requests: int, cold: bool) -> list[Sample]:
    """``requests`` samples; ``cold``: the obstacle map is published again before each request."""
    probe = Probe(harness)
    samples = []
    for _ in range(requests):
        if cold:
            version = harness.node.snapshot.version

            def taken(version: int = version) -> bool:
                return bool(harness.node.snapshot.version > version)

            harness.obstacles.publish(markers)
            if not wait_for(taken, 10.0):
                raise RuntimeError(f"the node did not take the map: {harness.node.errors[-3:]}")
        samples.append(probe.request())
    return samples


COLUMNS = (
    ("latency", "request -> Path at the peer"),
    ("check", "collision checks (check_s)"),
    ("selection", "edge selection (selection_s)"),
    ("rest", "messaging, conversion, scheduling"),
    ("session_other", "  of which in the session (scene build, checker, path)"),
    ("node_messaging", "  of which in the node and DDS (messages, publish, executor)"),
)


def summarize(samples: list[Sample]) -> dict[str, dict[str, float]]:
    """mean, p50, p95 (ms) of each column."""
    out = {}
    for name, _ in COLUMNS:
        ms = 1e3 * np.array([getattr(s, name) for s in samples])
        out[name] = {
            "mean": float(ms.mean()),
            "p50": float(np.percentile(ms, 50)),
            "p95": float(np.percentile(ms, 95)),
        }
    return out


def share(samples: list[Sample]) -> float:
    """Share of selection + messaging (everything but collision checks) in the total latency."""
    latency = sum(s.latency for s in samples)
    return sum(s.selection + s.rest for s in samples) / latency


def share_with_scene(samples: list[Sample]) -> float:
    """The same share, counting the session's own work (mostly the FCL scene build) as collision checking."""
    latency = sum(s.latency for s in samples)
    return sum(s.selection + s.node_messaging for s in samples) / latency


def print_table(title: str, samples: list[Sample]) -> None:
    """The table of one run."""
    stats = summarize(samples)
    print(f"\n== {title}: {len(samples)} requests ==")
    print(f"{'':<62} {'mean ms':>9} {'p50 ms':>9} {'p95 ms':>9}")
    for name, label in COLUMNS:
        row = stats[name]
        print(f"{label:<62} {row['mean']:>9.2f} {row['p50']:>9.2f} {row['p95']:>9.2f}")
    checks = np.mean([s.checks for s in samples])
    print(f"checks per plan: {checks:.1f}; map versions {samples[0].map_version}..{samples[-1].map_version}")
    print(f"share of selection + messaging in the latency: {100 * share(samples):.1f}%")
    print(
        "  the same, counting the session's scene build with the collision checks: "
        f"{100 * share_with_scene(samples):.1f}%"
    )


def _result(samples: list[Sample]) -> dict[str, Any]:
    return {
        "samples": [asdict(s) for s in samples],
        "stats": summarize(samples),
        "share": share(samples),
        "share_with_scene": share_with_scene(samples),
    }


def print_profile(profiler: cProfile.Profile, path: Path) -> None:
    """Write the stats and print the node's biggest costs."""
    profiler.dump_stats(str(path))
    print(f"\n== cProfile of the node's executor thread (cold run), written to {path} ==")
    stats = pstats.Stats(profiler)
    stats.sort_stats("cumulative").print_stats(r"drd_planner|drd_msgs_py|rclpy/publisher", 30)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--requests", type=int, default=30)
    parser.add_argument("--tree", type=Path, default=DEFAULT_TREE)
    parser.add_argument("--bag", type=Path, default=DEFAULT_BAG, help="maps from this bag when it exists")
    parser.add_argument("--world-seed", type=int, default=1, help="world of the maps when there is no bag")
    parser.add_argument("--no-warm", action="store_true", help="skip the warm run (same snapshot)")
    parser.add_argument("--profile", type=Path, default=None, help="cProfile the node (cold run) into FILE")
    parser.add_argument("--domain-id", type=int, default=None, help="ROS domain id (default: ROS_DOMAIN_ID)")
    parser.add_argument("--json", type=Path, default=None)
    args = parser.parse_args()
    os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    profiler = cProfile.Profile() if args.profile is not None else None
    harness = Harness(
        tree=args.tree,
        domain_id=args.domain_id,
        parameters=[Parameter("replan_on_map_update", value=False)],
        profiler=profiler,
    )
    results: dict[str, Any] = {}
    try:
        bag = args.bag if args.bag is not None and args.bag.is_file() else None
        markers, cloud = default_maps(harness, world_seed=args.world_seed, bag=bag)
        source = f"the first maps of {bag}" if bag else f"the 'wires' world, seed {args.world_seed}"
        print(f"maps: {source}; tree {args.tree.name}; executor: {'single' if profiler else 'two'} thread(s)")
        harness.publish_maps(markers, cloud)
        run(harness, markers, requests=2, cold=True)  # imports and first-use costs, not measured
        cold = run(harness, markers, requests=args.requests, cold=True)
        print_table("cold: a new map snapshot before each request", cold)
        results["cold"] = {
            "samples": [asdict(s) for s in cold],
            "stats": summarize(cold),
            "share": share(cold),
        }
        if not args.no_warm:
            warm = run(harness, markers, requests=args.requests, cold=False)
            print_table("warm: the same snapshot, every check a cache hit", warm)
            results["warm"] = {
                "samples": [asdict(s) for s in warm],
                "stats": summarize(warm),
                "share": share(warm),
            }
        verdict = "met" if share(cold) < GOAL_SHARE else "NOT met"
        print(f"\ngoal (cold): selection + messaging < {100 * GOAL_SHARE:.0f}% of the latency: {verdict}")
    finally:
        harness.close()
    if profiler is not None and args.profile is not None:
        print_profile(profiler, args.profile)
    if args.json is not None:
        args.json.write_text(json.dumps(results, indent=2))


if __name__ == "__main__":
    main()
