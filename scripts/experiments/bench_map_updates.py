#!/usr/bin/env python3
"""Map update cost benchmark: seconds and peak RSS per map message kind and size (a script, not a unit test).

Each case runs in a fresh child process (so its peak RSS, ``resource.getrusage`` ``ru_maxrss``, is its own)
under an address-space limit (``--max-gib``), and does what the node's map callback does with the message:
convert it through the node's map store (:class:`~drd_planner.planning.map_store.MapStore`), make the next
:class:`~drd_planner.planning.map_state.MapSnapshot` and build its FCL scene (and, for terrain, the helicopter
checker's terrain prefilter). Cases:

- ``markers N``: a full obstacle map of N cubes, then a one-marker update on top of it (the second row);
- ``terrain R``: an R x R terrain cloud (1 m cells, rolling hills), a second one replacing it while the first
  snapshot is still current (as in the node's map callback), then a one-marker update on top of it;
- ``tiny_cells``: a 2 x 2 heightfield with 1e-5 m cells (built directly: the converter refuses such cells) under
  a 5 m vehicle sphere, the helicopter checker's terrain window;
- ``mesh T``: one TRIANGLE_LIST marker of T triangles;
- ``urdf L``: the shared Panda ``robot_description`` with L extra links (skipped without the shared data).

Messages are converted with the :class:`~drd_planner.geometry.map_limits.MapLimits` defaults, or with the
values given as ``--limit name=value``; a refused message (over a limit) prints the refusal instead of timings.
Peak RSS is the child's maximum so far (its rows run in order).

Usage: python scripts/experiments/bench_map_updates.py [--max-gib 4] [--markers 1000 100000] [--terrain 300 1000 4000]
    [--limit max_terrain_cells=4000000 ...]
"""

from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
import time
from typing import Any

import numpy as np

HEADER = f"{'case':<34} {'size':>10} {'convert s':>10} {'scene s':>10} {'total s':>10} {'peak RSS MiB':>13}"


LIMITS: dict[str, Any] = {}
#: perf_counter() when the message under test was ready (a refusal's row reports the seconds since).
READY = [0.0]


def _rss_mib() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def _limits() -> Any:
    from drd_planner.geometry.map_limits import MapLimits

    return MapLimits.from_parameters(LIMITS)


def _msgs() -> Any:
    from rosbags.typesys import Stores, get_typestore

    from drd_msgs_py.factory import RosbagsMessages

    return RosbagsMessages(get_typestore(Stores.ROS2_JAZZY))


def _cubes(msgs: Any, keys: list[str], *, delete_all_first: bool, shift: float = 0.0) -> Any:
    from drd_planner.geometry.pose import Pose
    from drd_planner.geometry.shapes import Box

    obstacles = []
    for key in keys:
        k = int(key.rpartition("/")[2])
        obstacles.append((key, Box((1.0, 1.0, 1.0)), Pose((3.0 * (k % 300) + shift, 3.0 * (k // 300), 5.0))))
    return _markers(obstacles, msgs, delete_all_first=delete_all_first)


def _markers(obstacles: list[Any], msgs: Any, *, delete_all_first: bool = True) -> Any:
    from drd_planner.planning.world_messages import obstacle_markers

    return obstacle_markers(obstacles, frame_id="map", msgs=msgs, delete_all_first=delete_all_first)


def _store(margin: float = 0.0) -> Any:
    """The node's map store, in ``map``, with the benchmark's limits."""
    from drd_planner.planning.map_store import MapStore

    return MapStore(frame_id="map", margin=margin, limits=_limits())


def _touch(snapshot: Any) -> None:
    """Build the snapshot's scene and its packed arrays (what the first query would do)."""
    snapshot.scene.spheres_collide_mask(np.array([[0.0, 0.0, -1e4]]), 1.0)


def _obstacle_step(store: Any, msg: Any) -> tuple[Any, float, float]:
    t0 = READY[0] = time.perf_counter()
    snapshot = store.apply_obstacles(msg)
    t1 = time.perf_counter()
    _touch(snapshot)
    return snapshot, t1 - t0, time.perf_counter() - t1


def case_markers(n: int) -> list[dict[str, Any]]:
    msgs = _msgs()
    keys = [f"box/{k}" for k in range(n - 1)]  # with the DELETEALL first: n markers
    full = _cubes(msgs, keys, delete_all_first=True)
    one = _cubes(msgs, keys[:1], delete_all_first=False, shift=0.5)
    store = _store()
    snapshot, convert, scene = _obstacle_step(store, full)
    rows = [{"case": "markers: full map", "size": n, "convert": convert, "scene": scene, "rss": _rss_mib()}]
    _second, convert, scene = _obstacle_step(store, one)
    del snapshot  # as the node: the previous snapshot is alive while the next one is made
    rows.append({"case": "markers: one-marker update", "size": n, "convert": convert, "scene": scene})
    rows[-1]["rss"] = _rss_mib()
    return rows


def _cloud(msgs: Any, rows: int, cols: int, cell: float) -> Any:
    from drd_msgs_py.terrain import cloud_from_heightfield
    from drd_planner.geometry.terrain import Heightfield

    ii, jj = np.mgrid[0:rows, 0:cols].astype(np.float64)
    heights = 20.0 * np.sin(ii / 37.0) * np.cos(jj / 23.0)
    return cloud_from_heightfield(Heightfield((0.0, 0.0), cell, heights), frame_id="map", msgs=msgs)


def _terrain_step(store: Any, msg: Any, radius: float) -> tuple[Any, float, float]:
    from drd_planner.domains.helicopter_checker import HelicopterChecker

    t0 = READY[0] = time.perf_counter()
    snapshot = store.apply_terrain(msg)
    t1 = time.perf_counter()
    _touch(snapshot)
    points = np.array([[0.0, 0.0, 50.0], [0.0, 0.0, 60.0]])
    checker = HelicopterChecker(snapshot.scene, points, [0, 2], radius=radius)
    checker.check_many([0])
    return snapshot, t1 - t0, time.perf_counter() - t1


def case_terrain(size: int) -> list[dict[str, Any]]:
    msgs = _msgs()
    msg = _cloud(msgs, size, size, 1.0)
    store = _store(margin=1.0)
    snapshot, convert, scene = _terrain_step(store, msg, 5.0)
    rows = [{"case": "terrain: new cloud", "size": size * size, "convert": convert, "scene": scene}]
    rows[-1]["rss"] = _rss_mib()
    msg = _cloud(msgs, size, size, 0.9)
    del msgs
    _second, convert, scene = _terrain_step(store, msg, 5.0)
    del msg, snapshot
    rows.append({"case": "terrain: a second cloud replaces it", "size": size * size, "convert": convert})
    rows[-1] |= {"scene": scene, "rss": _rss_mib()}
    one = _cubes(_msgs(), ["box/0"], delete_all_first=False)
    _snap, convert, scene = _obstacle_step(store, one)
    rows.append({"case": "terrain: one-marker update", "size": size * size, "convert": convert, "scene": scene})
    rows[-1]["rss"] = _rss_mib()
    return rows


def case_tiny_cells() -> list[dict[str, Any]]:
    from drd_planner.domains.helicopter_checker import HelicopterChecker
    from drd_planner.geometry.scene import Scene
    from drd_planner.geometry.terrain import Heightfield

    t0 = time.perf_counter()
    scene = Scene(margin=1.0)
    scene.add_terrain(Heightfield((0.0, 0.0), 1e-5, [[0.0, 1.0], [2.0, 3.0]]))
    checker = HelicopterChecker(scene, np.array([[0.0, 0.0, 50.0], [0.0, 0.0, 60.0]]), [0, 2], radius=5.0)
    checker.check_many([0])
    seconds = time.perf_counter() - t0
    return [
        {
            "case": "heightfield 2x2, 1e-5 m cells",
            "size": 4,
            "convert": 0.0,
            "scene": seconds,
            "rss": _rss_mib(),
        }
    ]


def case_urdf(links: int) -> list[dict[str, Any]]:
    from drd_planner.domains.arm import ArmDomain, default_panda_dir
    from drd_planner.domains.base import domain_from_spec

    domain = domain_from_spec("arm", {"num_samples": 60, "k": 5, "seed": 3})
    assert isinstance(domain, ArmDomain)
    text = (default_panda_dir() / "panda_spherized.urdf").read_text()
    extra = "".join(
        f'<link name="extra_{k}"><collision><geometry><sphere radius="0.01"/></geometry></collision></link>'
        f'<joint name="extra_joint_{k}" type="fixed"><parent link="panda_hand"/><child link="extra_{k}"/>'
        f'<origin xyz="0 0 {0.001 * k}"/></joint>'
        for k in range(links)
    )
    text = text.replace("</robot>", extra + "</robot>")
    t0 = READY[0] = time.perf_counter()
    domain.robot_from_description(text, limits=_limits())
    seconds = time.perf_counter() - t0
    return [
        {
            "case": "robot_description extra links",
            "size": links,
            "convert": seconds,
            "scene": 0.0,
            "rss": _rss_mib(),
        }
    ]


def case_mesh(triangles: int) -> list[dict[str, Any]]:
    from drd_planner.geometry.pose import Pose
    from drd_planner.geometry.shapes import TriangleMesh

    rng = np.random.default_rng(0)
    vertices = rng.uniform(-50.0, 50.0, size=(3 * triangles, 3))
    mesh = TriangleMesh(vertices, np.arange(3 * triangles).reshape(-1, 3))
    msg = _markers([("mesh/0", mesh, Pose())], _msgs())
    _snapshot, convert, scene = _obstacle_step(_store(), msg)
    return [
        {
            "case": "one TRIANGLE_LIST marker",
            "size": triangles,
            "convert": convert,
            "scene": scene,
            "rss": _rss_mib(),
        }
    ]


def run_case(kind: str, size: int) -> list[dict[str, Any]]:
    """The rows of one case (in this process)."""
    if kind == "markers":
        return case_markers(size)
    if kind == "terrain":
        return case_terrain(size)
    if kind == "mesh":
        return case_mesh(size)
    if kind == "urdf":
        return case_urdf(size)
    return case_tiny_cells()


def child(kind: str, size: int, max_gib: float, limits: dict[str, Any]) -> None:
    """Run one case under an address-space limit and print its rows as JSON (errors as one row)."""
    LIMITS.update(limits)
    limit = int(max_gib * 2**30)
    resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
    try:
        rows = run_case(kind, size)
    except Exception as exc:  # a benchmark reports whatever happened, refusals and crashes alike
        text = f"{type(exc).__name__} after {time.perf_counter() - READY[0]:.3f} s: {exc}"
        rows = [{"case": f"{kind}", "size": size, "error": text[:220], "rss": _rss_mib()}]
    print(json.dumps(rows))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--max-gib", type=float, default=4.0, help="address-space limit of each case (GiB)")
    parser.add_argument("--markers", type=int, nargs="*", default=[1000, 100_000])
    parser.add_argument("--terrain", type=int, nargs="*", default=[100, 300, 700, 1000, 4000])
    parser.add_argument("--mesh", type=int, nargs="*", default=[10_000, 1_000_000])
    parser.add_argument("--urdf", type=int, nargs="*", default=[400, 8000])
    parser.add_argument("--limit", action="append", default=[], metavar="NAME=VALUE", help="a MapLimits value")
    parser.add_argument("--child", nargs=2, metavar=("KIND", "SIZE"), help=argparse.SUPPRESS)
    args = parser.parse_args()
    limits = {}
    for item in args.limit:
        name, _, value = item.partition("=")
        limits[name] = value if name == "unknown_terrain" else float(value)
    if args.child:
        child(args.child[0], int(args.child[1]), args.max_gib, limits)
        return
    cases = [("markers", n) for n in args.markers] + [("terrain", n) for n in args.terrain]
    cases += [("tiny_cells", 4)] + [("mesh", n) for n in args.mesh] + [("urdf", n) for n in args.urdf]
    print(HEADER)
    for kind, size in cases:
        proc = subprocess.run(
            [sys.executable, __file__, "--child", kind, str(size), "--max-gib", str(args.max_gib)]
            + [f"--limit={item}" for item in args.limit],
            capture_output=True,
            text=True,
            check=False,
        )
        lines = [line for line in proc.stdout.splitlines() if line.startswith("[")]
        if not lines:
            tail = (proc.stderr.strip().splitlines() or ["no output"])[-1]
            print(f"{kind:<34} {size:>10} crashed (exit {proc.returncode}): {tail[:120]}")
            continue
        for row in json.loads(lines[-1]):
            if "error" in row:
                print(f"{row['case']:<34} {row['size']:>10} {row['error']}  [{row['rss']:.0f} MiB]")
                continue
            total = row["convert"] + row["scene"]
            print(
                f"{row['case']:<34} {row['size']:>10} {row['convert']:>10.3f} {row['scene']:>10.3f} "
                f"{total:>10.3f} {row['rss']:>13.0f}"
            )


if __name__ == "__main__":
    main()
