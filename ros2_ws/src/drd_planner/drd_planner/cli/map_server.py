"""``drd_map_server``: its flags, made into the map server node's parameters.

``drd_map_server --prior heli_lines [--frame-id map] [--ros-args ...]`` publishes the prior's site as the
planner's latched ``terrain`` and ``obstacles`` maps (:mod:`drd_planner.ros.map_server`). A flag wins over
the same parameter given with ``--ros-args -p``; everything from ``--ros-args`` on goes to rclpy.
``--site-file`` is offered where this install reads GIS site files (``drd_planner.data.site_file``).
"""

from __future__ import annotations

import argparse
import importlib.util
import sys
from collections.abc import Sequence

__all__ = ["build_parser", "main"]


def _site_files() -> bool:
    """Whether this install reads GIS site files (the module is looked up, not imported: --help stays light)."""
    return importlib.util.find_spec("drd_planner.data.site_file") is not None


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of ``drd_map_server`` (the part before ``--ros-args``)."""
    parser = argparse.ArgumentParser(
        prog="drd_map_server",
        description="Publish the site of a world prior of a real site (a 'corridors' prior such as heli_lines) "
        "as the drd_planner node's maps: the terrain as an organized PointCloud2 and the known power lines, "
        "towers and no-fly zones as a MarkerArray, both latched, in the planning frame.",
        epilog="ROS parameters: prior, site_file, frame_id, terrain_topic, obstacles_topic "
        "(--ros-args -p NAME:=VALUE). Example: drd_map_server --prior heli_lines",
    )
    parser.add_argument("--prior", help="the site prior: a .npz file, or a shipped prior's name (heli_lines)")
    if _site_files():
        parser.add_argument("--site-file", help="a GIS site file whose site is published instead of a prior's")
    parser.add_argument("--frame-id", help="frame of both maps: the planner's planning frame (default map)")
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """``drd_map_server``: a bad flag, parameter, prior or site file prints one error line and exits 2."""
    args = list(sys.argv[1:] if argv is None else argv)
    cut = args.index("--ros-args") if "--ros-args" in args else len(args)
    flags = build_parser().parse_args(args[:cut])
    overrides = {
        name: value
        for name, value in (
            ("prior", flags.prior),
            ("site_file", getattr(flags, "site_file", None)),
            ("frame_id", flags.frame_id),
        )
        if value is not None
    }
    from drd_planner.ros.map_server import run_map_server

    return run_map_server(overrides, ["drd_map_server", *args[cut:]])


if __name__ == "__main__":
    raise SystemExit(main())
