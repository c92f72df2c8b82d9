#!/usr/bin/env python3
# mypy: allow-untyped-calls
"""Burst benchmark of the planner node: N requests as fast as possible, answered or coalesced, memory.

The real :class:`~drd_planner.ros.node.PlannerNode` runs as ``planner_node`` runs it (a
``SingleThreadedExecutor`` for maps and requests, the node's own planning thread for plans) in threads
of this process; a peer node in another thread publishes the maps of the helicopter "wires" world of the
tree's domain (or the first maps of ``--bag``), then

- ``topic``: N ``goal_pose`` requests back to back. The node plans the newest pending request and
  counts the ones it superseded in the summary's ``coalesced`` value, so every request must show up
  on ``/diagnostics`` as answered (a summary) or coalesced (counted in a later summary);
- ``service``: N ``get_plan`` calls back to back (``call_async``); every call must get its response.

Per 25 handled requests the process's RSS (``/proc/self/statm``, less tracemalloc's own tables), the
Python heap traced by ``tracemalloc`` and the number of gc-tracked objects are printed, with rows
before and after the burst (nothing in flight), then latency percentiles (publish or call -> the
answer reaching the peer) and the answered / coalesced / lost counts. Each mode runs ``--repeat``
bursts: the first burst under tracemalloc shows the node's steady-state structures (its bounded plan
history, caches) being replaced by traced copies, so flat memory shows from the second burst on.
``--json FILE`` writes the same figures.

Usage: python scripts/experiments/bench_node_burst.py [--requests 200] [--mode both|topic|service]
       [--tree trees/heli_wires.npz] [--world-seed 1] [--bag bags/heli_wires.mcap] [--every 25]
       [--repeat 2] [--trace topic|both|none] [--warm-up-calls N] [--json FILE]
"""

from __future__ import annotations

import argparse
import gc
import json
import os
import threading
import time
import tracemalloc
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from nav_msgs.srv import GetPlan

from drd_planner.bench.node_harness import Harness, default_maps
from drd_planner.planning.service import HISTORY_LENGTH

REPO_ROOT = Path(__file__).resolve().parents[2]
DEFAULT_TREE = REPO_ROOT / "trees" / "heli_wires.npz"
_PAGE = os.sysconf("SC_PAGE_SIZE") if hasattr(os, "sysconf") else 4096


def rss_bytes() -> int:
    """Resident set size of this process now (bytes; Linux ``/proc/self/statm``, else peak RSS)."""
    try:
        return int(Path("/proc/self/statm").read_text().split()[1]) * _PAGE
    except OSError:
        import resource

        return int(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss) * 1024


@dataclass
class MemoryRow:
    """Memory when ``handled`` requests had been answered or coalesced.

    Attributes:
        handled: requests answered or coalesced so far.
        rss: resident set size, bytes, less the memory tracemalloc uses for its own traces.
        traced: Python heap traced by tracemalloc, bytes (0 when not tracing).
        objects: objects tracked by the garbage collector (a leak of messages or results grows it).
    """

    handled: int
    rss: int
    traced: int
    objects: int


@dataclass
class BurstReport:
    """What one burst gave.

    Attributes:
        mode: ``topic`` or ``service``.
        requests: requests sent.
        answered: requests that got their own answer (a summary, or a service response).
        coalesced: requests superseded before being served (the summaries' ``coalesced`` values).
        seconds: first send -> last answer.
        latencies_s: per answered request, send -> answer at the peer (seconds).
        memory: one row per ``every`` handled requests, taken during the burst (requests still queued
            or in flight hold memory then, so these rows show the peak and fall towards the end).
        before: the row just before the burst, after a garbage collection (nothing in flight).
        after: the row once every request was handled, after a garbage collection.
        results: ``result`` value of each summary (``found``, ...), service: poses per response.
    """

    mode: str
    requests: int
    answered: int = 0
    coalesced: int = 0
    seconds: float = 0.0
    latencies_s: list[float] = field(default_factory=list)
    memory: list[MemoryRow] = field(default_factory=list)
    results: list[str] = field(default_factory=list)
    before: MemoryRow | None = None
    after: MemoryRow | None = None

    @property
    def lost(self) -> int:
        """Requests neither answered nor coalesced."""
        return self.requests - self.answered - self.coalesced


def wait_progress(progress: Callable[[], int], goal: int, *, stall: float, timeout: float) -> None:
    """Wait until ``progress() >= goal``, ``stall`` seconds pass without progress, or ``timeout``."""
    end = time.monotonic() + timeout
    last, since = progress(), time.monotonic()
    while time.monotonic() < end and last < goal and time.monotonic() - since < stall:
        time.sleep(0.005)
        now = progress()
        if now != last:
            last, since = now, time.monotonic()


def memory_row(handled: int, *, collect: bool = False) -> MemoryRow:
    """The process's memory now (``collect``: after a full garbage collection)."""
    if collect:
        gc.collect()
    tracing = tracemalloc.is_tracing()
    traced = tracemalloc.get_traced_memory()[0] if tracing else 0
    own = tracemalloc.get_tracemalloc_memory() if tracing else 0
    return MemoryRow(handled, rss_bytes() - own, traced, len(gc.get_objects()))


def _sample(report: BurstReport, handled: int, every: int) -> None:
    """Add a memory row for each multiple of ``every`` that ``handled`` reached."""
    last = report.memory[-1].handled if report.memory else 0
    if handled // every > last // every or (handled == report.requests and last != handled):
        report.memory.append(memory_row(handled))


def topic_burst(
    harness: Harness, *, requests: int, every: int = 25, stall: float = 5.0, timeout: float = 300.0
) -> BurstReport:
    """Publish ``requests`` goal_pose requests back to back; wait until all are answered or coalesced.

    Waiting ends early when nothing was handled for ``stall`` seconds (requests lost on the way).
    """
    report = BurstReport("topic", requests)
    sent: dict[str, float] = {}
    lock = threading.Lock()

    def on_status(item: tuple[float, Any]) -> None:
        now, status = item
        values = {str(kv.key): str(kv.value) for kv in status.values}
        if values.get("request") != "goal_pose":
            return
        with lock:
            report.answered += 1
            report.coalesced += int(values.get("coalesced", "0"))
            report.results.append(values.get("result", "?"))
            start = sent.get(values.get("request_stamp", ""))
            if start is not None:
                report.latencies_s.append(now - start)
            report.seconds = now - min(sent.values())
            _sample(report, report.answered + report.coalesced, every)

    def handled() -> int:
        with lock:
            return report.answered + report.coalesced

    report.before = memory_row(0, collect=True)
    remove = harness.listen(on_status)
    try:
        base = time.time_ns()
        for i in range(requests):  # messages are not kept: the burst itself must not look like a leak
            stamp_ns = base + i  # a distinct header stamp per request: the summary names the one it served
            goal = harness.goal((stamp_ns // 10**9, stamp_ns % 10**9))
            key = f"{goal.header.stamp.sec}.{goal.header.stamp.nanosec:09d}"
            with lock:
                sent[key] = time.perf_counter()
            harness.goals.publish(goal)
        del goal
        wait_progress(handled, requests, stall=stall, timeout=timeout)
        time.sleep(0.2)  # a late summary (more handled than sent would be a bug) shows up in the counts
    finally:
        remove()
    with lock:
        sent.clear()
    harness.settle()
    report.after = memory_row(handled(), collect=True)
    return report


def service_burst(
    harness: Harness, *, requests: int, every: int = 25, stall: float = 5.0, timeout: float = 300.0
) -> BurstReport:
    """Call get_plan ``requests`` times back to back (call_async); wait for every response (or a stall)."""
    report = BurstReport("service", requests)
    if not harness.client.wait_for_service(timeout_sec=10.0):
        raise RuntimeError("get_plan is not offered")
    lock = threading.Lock()
    report.before = memory_row(0, collect=True)
    first = time.perf_counter()

    def on_done(future: Any, start: float) -> None:
        now = time.perf_counter()
        with lock:
            report.answered += 1
            report.latencies_s.append(now - start)
            report.seconds = now - first
            result = future.result()
            report.results.append(str(len(result.plan.poses)) if result is not None else "none")
            _sample(report, report.answered, every)

    def handled() -> int:
        with lock:
            return report.answered

    for _ in range(requests):  # the futures are not kept: a kept response would look like a leak
        request = GetPlan.Request()
        request.goal = harness.goal()
        start = time.perf_counter()
        future = harness.client.call_async(request)
        future.add_done_callback(lambda f, start=start: on_done(f, start))
    del request, future  # the last future would keep its response alive through the "after" row
    wait_progress(handled, requests, stall=stall, timeout=timeout)
    harness.settle()
    report.after = memory_row(handled(), collect=True)
    return report


def percentiles(values: list[float]) -> dict[str, float]:
    """mean, p50, p95, max of ``values`` in milliseconds (NaN when empty)."""
    if not values:
        return {k: float("nan") for k in ("mean", "p50", "p95", "max")}
    ms = 1e3 * np.asarray(values)
    return {
        "mean": float(ms.mean()),
        "p50": float(np.percentile(ms, 50)),
        "p95": float(np.percentile(ms, 95)),
        "max": float(ms.max()),
    }


def print_report(report: BurstReport, *, note: str = "") -> None:
    """The memory table, the latencies and the counts of one burst."""
    traced = "tracemalloc on" if report.after is not None and report.after.traced else "tracemalloc off"
    print(f"\n== {report.mode} burst: {report.requests} requests ({', '.join(filter(None, (note, traced)))}) ==")
    print(f"{'':>7} {'handled':>8} {'RSS MiB':>9} {'traced MiB':>11} {'gc objects':>11}")
    labelled = [("before", report.before), *(("", r) for r in report.memory), ("after", report.after)]
    for label, row in labelled:
        if row is not None:
            print(f"{label:>7} {row.handled:>8} {row.rss / 2**20:>9.1f} {row.traced / 2**20:>11.3f} {row.objects:>11}")
    for what, growth in (
        ("during the burst", memory_growth(report, start=50)),
        ("before -> after", quiescent_growth(report)),
    ):
        if growth is not None:
            print(
                f"growth {what} ({growth['from']} -> {growth['to']} handled): RSS {growth['rss'] / 2**20:+.2f} MiB, "
                f"traced {growth['traced'] / 2**10:+.1f} KiB, gc objects {growth['objects']:+d}"
            )
    lat = percentiles(report.latencies_s)
    print(
        f"latency of answered requests (ms): mean {lat['mean']:.1f}  p50 {lat['p50']:.1f}  "
        f"p95 {lat['p95']:.1f}  max {lat['max']:.1f}"
    )
    print(f"answered {report.answered}  coalesced {report.coalesced}  lost {report.lost}  in {report.seconds:.2f} s")


def memory_growth(report: BurstReport, *, start: int) -> dict[str, int] | None:
    """RSS and traced-heap growth (bytes) from the row nearest ``start`` handled to the last row.

    The row nearest is the last one at or before ``start``, else the first after it: the rows are
    taken when summaries arrive, and a well-coalesced burst has only a few (each summary can cover
    dozens of superseded requests).
    """
    rows = report.memory
    before = [r for r in rows if r.handled <= start]
    first = before[-1] if before else next((r for r in rows if r.handled > start), None)
    if first is None or first is rows[-1]:
        return None
    return _difference(first, rows[-1])


def _difference(a: MemoryRow, b: MemoryRow) -> dict[str, int]:
    return {
        "from": a.handled,
        "to": b.handled,
        "rss": b.rss - a.rss,
        "traced": b.traced - a.traced,
        "objects": b.objects - a.objects,
    }


def quiescent_growth(report: BurstReport) -> dict[str, int] | None:
    """Growth from :attr:`BurstReport.before` to :attr:`BurstReport.after` (both with nothing in flight)."""
    if report.before is None or report.after is None:
        return None
    return _difference(report.before, report.after)


def warm_up(harness: Harness, *, burst: int = 50, calls: int | None = None) -> None:
    """Requests before measuring, so that one-time allocations are not counted as growth.

    One topic request (imports, caches, the first scene), as many single service calls as the node
    keeps served requests in its bounded ``history`` (:data:`drd_planner.planning.service.HISTORY_LENGTH`)
    plus one (or ``calls``), then a topic burst of ``burst`` requests (first-burst queues and wait
    sets). A request that is lost here (a node queue shorter than ``burst``) does not stop the warm-up.
    """
    if calls is None:
        calls = HISTORY_LENGTH + 1
    for run, count in ((topic_burst, 1), *((service_burst, 1) for _ in range(calls))):
        warm = run(harness, requests=count, stall=30.0)
        if warm.answered != count or warm.results[0] in ("none", "0"):
            raise RuntimeError(f"the warm-up {warm.mode} request was not answered: {harness.node.errors[-3:]}")
    topic_burst(harness, requests=burst, stall=2.0)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--requests", type=int, default=200)
    parser.add_argument("--mode", choices=("both", "topic", "service"), default="both")
    parser.add_argument("--tree", type=Path, default=DEFAULT_TREE)
    parser.add_argument("--world-seed", type=int, default=1)
    parser.add_argument("--bag", type=Path, default=None, help="take the maps from this MCAP bag instead")
    parser.add_argument("--every", type=int, default=25, help="memory row every N handled requests")
    parser.add_argument("--domain-id", type=int, default=None, help="ROS domain id (default: ROS_DOMAIN_ID)")
    parser.add_argument("--json", type=Path, default=None)
    parser.add_argument("--repeat", type=int, default=2, help="bursts per mode (the first traced one warms up)")
    parser.add_argument(
        "--warm-up-calls",
        type=int,
        default=None,
        help="service calls before measuring (default: history + 1)",
    )
    parser.add_argument(
        "--trace",
        choices=("topic", "both", "none"),
        default="topic",
        help="bursts run under tracemalloc (it slows each plan's message building about fourfold)",
    )
    args = parser.parse_args()
    os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    harness = Harness(tree=args.tree, domain_id=args.domain_id)
    reports = []
    try:
        markers, cloud = default_maps(harness, world_seed=args.world_seed, bag=args.bag)
        harness.publish_maps(markers, cloud)
        warm_up(harness, calls=args.warm_up_calls)
        for mode in ("topic", "service") if args.mode == "both" else (args.mode,):
            burst = topic_burst if mode == "topic" else service_burst
            if args.trace in (mode, "both"):
                tracemalloc.start()
            for k in range(args.repeat):
                plans = harness.plans
                report = burst(harness, requests=args.requests, every=args.every)
                print_report(report, note=f"burst {k + 1} of {args.repeat}")
                print(f"Path messages received on plan: {harness.plans - plans}")
                reports.append(report)
            tracemalloc.stop()
    finally:
        tracemalloc.stop()
        harness.close()
    if args.json is not None:
        out = [asdict(r) | {"lost": r.lost, "latency_ms": percentiles(r.latencies_s)} for r in reports]
        args.json.write_text(json.dumps(out, indent=2))


if __name__ == "__main__":
    main()
