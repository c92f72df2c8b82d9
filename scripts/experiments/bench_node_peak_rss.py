#!/usr/bin/env python3
# mypy: allow-untyped-calls
"""Peak RSS of a real PlannerNode taking a stream of the largest terrains it accepts (a script, not a test).

Loads the helicopter Wires tree, then feeds ``--updates`` terrain clouds of ``--size`` x ``--size`` cells (the
default 500 x 500 is ``max_terrain_cells``) through the node's terrain callback, each one a new map that is
converted, made current and prepared (FCL terrain tiles and each tree's checker), as on the ``terrain`` topic.
Prints seconds per update and the process's peak RSS (``ru_maxrss``) after each.

Usage: python scripts/experiments/bench_node_peak_rss.py [--size 500] [--updates 6]
"""

from __future__ import annotations

import argparse
import os
import resource
import time

import numpy as np


def _peak_mib() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=500, help="terrain rows = columns (cells)")
    parser.add_argument("--updates", type=int, default=6, help="terrain messages to send")
    args = parser.parse_args()
    os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    import rclpy
    from rclpy.parameter import Parameter
    from rclpy.utilities import try_shutdown

    from drd_msgs_py.factory import RclpyMessages
    from drd_msgs_py.terrain import cloud_from_heightfield
    from drd_planner.geometry.terrain import Heightfield
    from drd_planner.ros.node import PlannerNode

    rclpy.init()
    node = PlannerNode(parameter_overrides=[Parameter("prior_paths", value=["heli_wires"])])
    try:
        if node.trigger_configure().name != "SUCCESS":
            raise SystemExit(f"configure failed: {node.errors}")
        node.trigger_activate()
        print(f"node configured: peak RSS {_peak_mib():.0f} MiB")
        msgs = RclpyMessages()
        n = args.size
        yy, xx = np.mgrid[0:n, 0:n]
        for k in range(args.updates):
            heights = 20.0 * np.sin(xx / 37.0 + k) * np.cos(yy / 53.0) + 30.0
            terrain = Heightfield((-100.0, -100.0), 1.0 + 0.1 * k, heights)
            cloud = cloud_from_heightfield(terrain, frame_id="map", msgs=msgs)
            t0 = time.perf_counter()
            node._on_map("terrain", cloud)
            seconds = time.perf_counter() - t0
            print(
                f"terrain {n} x {n} #{k + 1}: {seconds:.2f} s, map version {node.snapshot.version}, "
                f"errors {len(node.errors)}, peak RSS {_peak_mib():.0f} MiB"
            )
    finally:
        node.destroy_node()
        try_shutdown()


if __name__ == "__main__":
    main()
