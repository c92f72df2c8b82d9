#!/usr/bin/env python3
# mypy: allow-untyped-calls
"""Request-to-plan latency of the planner node on a bundled scenario, split into checks and the rest.

The real node (as ``planner_node`` runs it: a ``SingleThreadedExecutor`` for maps and requests, its
own planning thread for plans) and a peer run in threads of this process (the harness of ``bench_node_burst.py``).
Maps: the first ``/obstacles`` and ``/terrain`` of
the bag (default ``bags/heli_wires.mcap``; ``--tree trees/arm_table_clutter.npz --bag
bags/arm_table_clutter.mcap --frame-id panda_link0`` for the arm), else the helicopter "wires" world of the tree's
domain drawn with ``--world-seed``. Each measured request is one ``goal_pose`` at the tree's goal (the arm's
tool-point position), sent when the node is idle; its latency is the wall time from publishing it
to the ``Path`` arriving at the peer (subscribed raw: timed when its bytes arrive; rclpy's decoding
of a Path into Python objects, 35 to 75 us a pose, is a Python subscriber's own cost and is printed
apart). Its time outside the planner is that latency less the plan's ``total_s``: the goal is 5 ms
at the median. The "new query" run sends each request to another goal (a
vertex of a seeded order the node has not been asked for: its library and DiRECt tree are built
online, ``library_s``) instead; a goal with no free path on the map is skipped and counted. The node's summary on
``/diagnostics`` splits it (seconds):

- ``check_s``: time in the collision checker (FCL) for the checks of this plan;
- ``policy_s``: the policy's work: choosing each edge (``selection_s``: DiRECt tree walk, BiSECt)
  and updating its beliefs after each outcome (bias, posterior over the training worlds);
- ``prepare_s``: the snapshot's FCL scene and checker, built in the request only when the map
  callback had not built them already (the node builds them when a map arrives);
- the session's other work (``total_s`` less the above: path states, check log);
- ``plan_messaging_s``: building and publishing the ``Path``;
- ``wait_s``: the request taken -> the plan started (the executor's hand-over to the planning
  thread);
- DDS and executors: the rest of the latency (the request and the Path crossing DDS, the executors
  of the node and of the peer).

"Selection and messaging" is everything but the collision checks: the policy, messaging (building
and publishing, DDS, executors, hand-over) and the session's bookkeeping. The goal is that this
stays under 10% of the latency. It holds only when checks dominate, so the script also prints the
per-check cost at which the measured overhead would be 10%: checks cheaper than that cannot reach
the goal on any planner that pays this overhead.

Cold run: before each request the obstacle map is published again, so the plan runs on a new map
snapshot with no cached check (the realistic case: maps change between requests); the node
prepares the scene when that map arrives, as in use. The node runs with ``replan_on_map_update``
off here, so a map update triggers no re-check that would warm the snapshot's check cache; the
request goes out once the node holds the new snapshot and its planning thread is idle again. Warm
run: the same snapshot for every request, so every check is a cache hit.

To see where the node's threads spend their time, run the script under a sampling profiler that
sees every thread, e.g. ``py-spy record -o profile.svg -- python scripts/experiments/bench_node_latency.py``.

Usage: python scripts/experiments/bench_node_latency.py [--requests 30] [--bag bags/heli_wires.mcap]
       [--tree trees/heli_wires.npz] [--world-seed 1] [--frame-id map] [--no-warm] [--no-new]
       [--json FILE]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import threading
import time
from collections.abc import Iterator
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np
from geometry_msgs.msg import PoseStamped
from nav_msgs.msg import Path as PathMsg
from rclpy.parameter import Parameter
from rclpy.serialization import deserialize_message

from drd_planner.bench.node_harness import Harness, default_maps, path_pose_count, wait_for

REPO_ROOT = Path(__file__).resolve().parents[2]
DEFAULT_TREE = REPO_ROOT / "trees" / "heli_wires.npz"
DEFAULT_BAG = REPO_ROOT / "bags" / "heli_wires.mcap"
#: Goal: selection and messaging under this share of the cold request-to-plan latency.
GOAL_SHARE = 0.10
#: Goal: a request's median time outside the planner (latency less ``total_s``), seconds.
OUTSIDE_GOAL_S = 0.005


@dataclass
class Sample:
    """One request's times (seconds, from the node's summary and the peer's clock) and counts."""

    latency: float
    check: float
    selection: float
    policy: float
    prepare: float
    total: float
    wait: float
    plan_messaging: float
    checks: int
    map_version: int
    library: float = 0.0
    query: str = ""

    @property
    def session_other(self) -> float:
        """The planning session's work outside checks, policy, library and preparation (path states, log)."""
        return max(self.total - self.check - self.policy - self.prepare - self.library, 0.0)

    @property
    def transport(self) -> float:
        """DDS and executors: the latency outside the node's own work on the request."""
        return self.latency - self.wait - self.total - self.plan_messaging

    @property
    def messaging(self) -> float:
        """Messaging: building and publishing the Path, the hand-over, DDS and the executors."""
        return self.plan_messaging + self.wait + self.transport

    @property
    def outside(self) -> float:
        """The request's time outside the planner: its latency less the plan (``total_s``)."""
        return self.latency - self.total

    @property
    def overhead(self) -> float:
        """Selection and messaging: everything in the latency but the collision checks."""
        return self.latency - self.check


class Probe:
    """Sends one request at a time and collects its Path arrival and its summary."""

    def __init__(self, harness: Harness) -> None:
        self.harness = harness
        self._lock = threading.Lock()
        self._plans: list[float] = []
        self.last_path: bytes = b""  # the newest non-empty Path as it arrived (serialized)
        self._summaries: dict[str, dict[str, str]] = {}
        self._checks: dict[int, int] = {}
        self._removers = [harness.listen_plans(self._on_plan), harness.listen(self._on_status)]
        self._count = 0

    def close(self) -> None:
        """Stop listening."""
        for remove in self._removers:
            remove()

    def _on_plan(self, item: tuple[float, bytes]) -> None:
        now, data = item
        if path_pose_count(data):  # an empty Path withdraws a plan; it answers no request
            with self._lock:
                self._plans.append(now)
                self.last_path = data

    def _on_status(self, item: tuple[float, Any]) -> None:
        _, status = item
        values = {str(kv.key): str(kv.value) for kv in status.values}
        if values.get("request") == "goal_pose" and "request_stamp" in values:
            with self._lock:
                self._summaries[values["request_stamp"]] = values

    def request(self, goal: Any | None = None, *, timeout: float = 30.0) -> Sample | None:
        """Publish one goal_pose (default: the stored goal) and wait for its Path and summary.

        None when the goal has no free path on the map (a summary without a Path).
        """
        self._count += 1
        stamp = (2_000_000 + self._count, 0)
        key = f"{stamp[0]}.{stamp[1]:09d}"
        if goal is None:
            goal = self.harness.goal(stamp)
        else:
            goal.header.stamp.sec, goal.header.stamp.nanosec = stamp
        with self._lock:
            plans = len(self._plans)
        start = time.perf_counter()
        self.harness.goals.publish(goal)

        def done() -> bool:
            with self._lock:
                summary = self._summaries.get(key)
                return summary is not None and (len(self._plans) > plans or summary.get("result") != "found")

        if not wait_for(done, timeout):
            raise RuntimeError(f"no plan for request {key}: {self.harness.node.errors[-3:]}")
        with self._lock:
            values = self._summaries[key]
            if values.get("result") != "found":
                return None
            arrived = self._plans[plans]
        return Sample(
            latency=arrived - start,
            check=float(values["check_s"]),
            selection=float(values["selection_s"]),
            policy=float(values["policy_s"]),
            prepare=float(values["prepare_s"]),
            total=float(values["total_s"]),
            wait=float(values["wait_s"]),
            plan_messaging=float(values["plan_messaging_s"]),
            checks=int(values["checks"]),
            map_version=int(values["map_version"]),
            library=float(values.get("library_s", 0.0)),
            query=values.get("query", ""),
        )


def new_goals(harness: Harness, *, seed: int = 0) -> Iterator[Any]:
    """PoseStamped goals at the prior's vertices in a seeded order, never the stored start or goal.

    Helicopter: the vertex's position and heading; arm: its tool point (snapped back to that vertex).
    """
    session = harness.node.sessions[0]
    graph = session.prior.graph
    stored = {int(session.domain.start), int(session.domain.goal)}
    for vertex in np.random.default_rng(seed).permutation(graph.num_vertices):
        if int(vertex) in stored:
            continue
        state = session.vertex_state(int(vertex))
        x, y, z = (float(v) for v in session.positions(state[None])[-1])
        yaw = 0.0 if session.domain.plans_joint_goals or state.size < 4 else float(state[3])
        goal = PoseStamped()
        goal.header.frame_id = harness.frame_id
        goal.pose.position.x, goal.pose.position.y, goal.pose.position.z = x, y, z
        goal.pose.orientation.z, goal.pose.orientation.w = math.sin(yaw / 2.0), math.cos(yaw / 2.0)
        yield goal


def run(
    harness: Harness, markers: Any, *, requests: int, cold: bool, goals: Iterator[Any] | None = None
) -> tuple[list[Sample], int, bytes]:
    """``requests`` samples, the number of goals skipped (no free path) and the last Path (serialized).

    ``cold``: the obstacle map is published again before each request; ``goals``: a new goal for each
    request (None: the stored goal every time).
    """
    probe = Probe(harness)
    try:
        return _samples(harness, probe, markers, requests=requests, cold=cold, goals=goals)
    finally:
        probe.close()


def _samples(
    harness: Harness, probe: Probe, markers: Any, *, requests: int, cold: bool, goals: Iterator[Any] | None
) -> tuple[list[Sample], int, bytes]:
    """The samples of :func:`run`, taken with ``probe``."""
    samples: list[Sample] = []
    skipped = 0
    while len(samples) < requests:
        if cold:
            version = harness.node.snapshot.version

            def taken(version: int = version) -> bool:  # and re-checked against: the node is idle again
                return bool(harness.node.snapshot.version > version and harness.node.planning_idle)

            harness.obstacles.publish(markers)
            if not wait_for(taken, 10.0):
                raise RuntimeError(f"the node did not take the map: {harness.node.errors[-3:]}")
        sample = probe.request(None if goals is None else next(goals))
        if sample is None:
            skipped += 1
            if skipped > 5 * requests:
                raise RuntimeError(f"{skipped} goals without a free path: {harness.node.errors[-3:]}")
            continue
        samples.append(sample)
    return samples, skipped, probe.last_path


def decode_ms(data: bytes, repeat: int = 5) -> float:
    """Median ms rclpy takes to decode the serialized Path ``data`` into message objects (a Python subscriber's)."""
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        deserialize_message(data, PathMsg)
        times.append(time.perf_counter() - start)
    return 1e3 * float(np.median(times))


def print_outside(samples: list[Sample], path: bytes) -> None:
    """The request's time outside the planner against :data:`OUTSIDE_GOAL_S`, and a Python subscriber's decoding."""
    outside = 1e3 * np.array([s.outside for s in samples])
    p50, p95 = np.percentile(outside, 50), np.percentile(outside, 95)
    verdict = "met" if p50 <= 1e3 * OUTSIDE_GOAL_S else "NOT met"
    print(
        f"time outside the planner (request -> Path at the peer, less total_s): p50 {p50:.2f} ms, "
        f"p95 {p95:.2f} ms; goal p50 <= {1e3 * OUTSIDE_GOAL_S:.0f} ms: {verdict}"
    )
    print(
        f"  (the peer takes the Path serialized; rclpy would decode its {path_pose_count(path)} poses "
        f"into Python objects in {decode_ms(path):.2f} ms more, a Python subscriber's own cost)"
    )


COLUMNS = (
    ("latency", "request -> Path at the peer"),
    ("outside", "outside the planner (latency - total_s)"),
    ("check", "collision checks (check_s)"),
    ("policy", "policy: choosing edges, updating beliefs (policy_s)"),
    ("selection", "  of which choosing (selection_s)"),
    ("prepare", "scene + checker built in the request (prepare_s)"),
    ("library", "the query's library and tree, found or built (library_s)"),
    ("session_other", "session's other work (path states, check log)"),
    ("plan_messaging", "building + publishing the Path (plan_messaging_s)"),
    ("wait", "hand-over to the planning thread (wait_s)"),
    ("transport", "DDS and executors (the rest)"),
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


def shares(samples: list[Sample]) -> dict[str, float]:
    """Median over the requests of each one's shares: checks, policy, messaging, selection + messaging.

    Medians, because DDS now and then holds one message for tens to hundreds of milliseconds (the
    p95 column shows it), which would swamp a share of sums. ``node_overhead`` is the overhead share
    counted inside the node only (its own work on the request: the session and building and
    publishing the Path, without DDS, the executors and the hand-over): what the planner itself adds.
    """

    def median(values: list[float]) -> float:
        return float(np.median(values))

    return {
        "checks": median([s.check / s.latency for s in samples]),
        "policy": median([s.policy / s.latency for s in samples]),
        "messaging": median([s.messaging / s.latency for s in samples]),
        "overhead": median([s.overhead / s.latency for s in samples]),
        "node_overhead": median(
            [(s.total + s.plan_messaging - s.check) / (s.total + s.plan_messaging) for s in samples]
        ),
    }


def break_even_check_ms(samples: list[Sample], goal: float = GOAL_SHARE) -> float:
    """Per-check cost (ms) at which the median overhead would be ``goal`` of the latency.

    overhead / (overhead + n * c) = goal  =>  c = overhead * (1 - goal) / (goal * n), with the median
    overhead (latency less checks) and the mean number n of checks per plan.
    """
    overhead = float(np.median([s.overhead for s in samples]))
    n = float(np.mean([s.checks for s in samples]))
    return 1e3 * overhead * (1.0 - goal) / (goal * n) if n > 0 else float("inf")


def print_table(title: str, samples: list[Sample]) -> None:
    """The table of one run."""
    stats = summarize(samples)
    print(f"\n== {title}: {len(samples)} requests ==")
    print(f"{'':<56} {'mean ms':>9} {'p50 ms':>9} {'p95 ms':>9}")
    for name, label in COLUMNS:
        row = stats[name]
        print(f"{label:<56} {row['mean']:>9.2f} {row['p50']:>9.2f} {row['p95']:>9.2f}")
    checks = float(np.mean([s.checks for s in samples]))
    fresh = [s for s in samples if s.check > 0]
    per_check = 1e3 * sum(s.check for s in fresh) / max(sum(s.checks for s in fresh), 1)
    print(
        f"checks per plan: {checks:.1f} at {per_check:.3f} ms each; "
        f"map versions {samples[0].map_version}..{samples[-1].map_version}"
    )
    share = shares(samples)
    print(
        f"median shares of the latency: checks {100 * share['checks']:.1f}%, policy {100 * share['policy']:.1f}%, "
        f"messaging {100 * share['messaging']:.1f}%"
    )
    print(f"selection + messaging: {100 * share['overhead']:.1f}% of the latency")
    print(f"  inside the node only (without DDS and executors): {100 * share['node_overhead']:.1f}%")
    print(
        f"  it would be {100 * GOAL_SHARE:.0f}% with checks of {break_even_check_ms(samples):.2f} ms each "
        "(same overhead, same number of checks)"
    )


def _result(samples: list[Sample]) -> dict[str, Any]:
    return {
        "samples": [asdict(s) for s in samples],
        "stats": summarize(samples),
        "shares": shares(samples),
        "break_even_check_ms": break_even_check_ms(samples),
    }


def print_comparison(repeated: list[Sample], new: list[Sample], skipped: int) -> None:
    """Request-to-plan of a repeated and of a new query side by side (one run, the same machine)."""
    print("\n== request -> Path: repeated query against new query (cold maps both) ==")
    print(f"{'':<34} {'p50 ms':>9} {'p95 ms':>9} {'library p50 ms':>15} {'checks':>7}")
    for label, samples in (("repeated (stored goal)", repeated), ("new (another goal each time)", new)):
        latency = 1e3 * np.array([s.latency for s in samples])
        library = 1e3 * np.array([s.library for s in samples])
        print(
            f"{label:<34} {np.percentile(latency, 50):>9.2f} {np.percentile(latency, 95):>9.2f} "
            f"{np.percentile(library, 50):>15.2f} {np.mean([s.checks for s in samples]):>7.1f}"
        )
    queries = sorted({s.query for s in new})
    ratio = np.median([s.latency for s in new]) / np.median([s.latency for s in repeated])
    print(
        f"new / repeated (p50): {ratio:.2f}x; new queries served as {queries}; {skipped} goals skipped (no free path)"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--requests", type=int, default=30)
    parser.add_argument("--tree", type=Path, default=DEFAULT_TREE)
    parser.add_argument("--bag", type=Path, default=DEFAULT_BAG, help="maps from this bag when it exists")
    parser.add_argument("--world-seed", type=int, default=1, help="world of the maps when there is no bag")
    parser.add_argument(
        "--frame-id", default="map", help="planning frame of the node and the maps (the arm bag: panda_link0)"
    )
    parser.add_argument("--no-warm", action="store_true", help="skip the warm run (same snapshot)")
    parser.add_argument("--no-new", action="store_true", help="skip the new-query run (another goal each time)")
    parser.add_argument("--domain-id", type=int, default=None, help="ROS domain id (default: ROS_DOMAIN_ID)")
    parser.add_argument("--json", type=Path, default=None)
    args = parser.parse_args()
    os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    harness = Harness(
        tree=args.tree,
        frame_id=args.frame_id,
        domain_id=args.domain_id,
        parameters=[Parameter("replan_on_map_update", value=False)],
    )
    results: dict[str, Any] = {}
    try:
        bag = args.bag if args.bag is not None and args.bag.is_file() else None
        markers, cloud = default_maps(harness, world_seed=args.world_seed, bag=bag)
        source = f"the first maps of {bag}" if bag else f"the 'wires' world, seed {args.world_seed}"
        print(f"maps: {source}; tree {args.tree.name}")
        harness.publish_maps(markers, cloud)
        run(harness, markers, requests=2, cold=True)  # imports and first-use costs, not measured
        cold, _, path = run(harness, markers, requests=args.requests, cold=True)
        print_table("cold: a new map snapshot before each request", cold)
        print_outside(cold, path)
        results["cold"] = _result(cold)
        if not args.no_warm:
            warm, _, path = run(harness, markers, requests=args.requests, cold=False)
            print_table("warm: the same snapshot, every check a cache hit", warm)
            print_outside(warm, path)
            results["warm"] = _result(warm)
        if not args.no_new:
            new, skipped, path = run(harness, markers, requests=args.requests, cold=True, goals=new_goals(harness))
            print_table("new query: another goal and a new map snapshot before each request", new)
            print_outside(new, path)
            print_comparison(cold, new, skipped)
            results["new_query"] = {**_result(new), "skipped_goals": skipped}
        overhead = shares(cold)["overhead"]
        verdict = "met" if overhead < GOAL_SHARE else "NOT met"
        print(
            f"\ngoal (cold): selection + messaging < {100 * GOAL_SHARE:.0f}% of the latency: {verdict} "
            f"({100 * overhead:.1f}%)"
        )
    finally:
        harness.close()
    if args.json is not None:
        args.json.write_text(json.dumps(results, indent=2))


if __name__ == "__main__":
    main()
