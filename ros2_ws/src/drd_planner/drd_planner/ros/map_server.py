"""The ``drd_map_server`` node: a site prior's site as the planner's latched maps, like Nav2's map_server.

Given a world prior of a real site (``prior``: a ``"corridors"`` prior such as the shipped ``heli_lines``;
or ``site_file``: a GIS site file, :mod:`~drd_planner.data.site_file`), it publishes once, latched (reliable,
transient_local, depth 1, so a planner that starts later still gets them):

- ``terrain`` (sensor_msgs/PointCloud2): the site's DEM as an organized cloud on the prior's terrain grid,
  heights in metres above the site's datum (z = 0 of the planning frame);
- ``obstacles`` (visualization_msgs/MarkerArray, DELETEALL first): every known power line at its nominal
  height (conductors as LINE_STRIPs, towers as CYLINDERs) and every known no-fly zone as its column
  (CYLINDER or CUBE): :mod:`~drd_planner.planning.site_world`.

Both in ``frame_id`` (default ``map``, the planner node's default planning frame), the same encoding the
planner node parses (:mod:`~drd_planner.planning.world_messages`). Parameters (:data:`MAP_SERVER_PARAMETERS`)
are read once at start and are read-only; each bad one is named in the one error the node raises
(:class:`MapServerError`), as is a prior of no real site.
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Mapping
from typing import Any

import rclpy
from rclpy.exceptions import ParameterException
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.utilities import try_shutdown
from sensor_msgs.msg import PointCloud2
from visualization_msgs.msg import MarkerArray

from drd_msgs_py.factory import RclpyMessages
from drd_planner.domains.helicopter_site import OperatingSite
from drd_planner.exceptions import DrdError
from drd_planner.planning.served_site import site_of_prior_file, site_of_site_file
from drd_planner.planning.site_world import site_messages, site_world
from drd_planner.ros.outputs import LATCHED
from drd_planner.ros.parameters import ParameterSpec

__all__ = ["MAP_SERVER_PARAMETERS", "MapServer", "MapServerError", "map_server_problems", "run_map_server"]


class MapServerError(DrdError):
    """The map server cannot start: bad parameters, or a prior or site file it cannot serve."""


def _name(kind: str, limit: int, allowed: str) -> Callable[[Any], str | None]:
    def check(value: Any) -> str | None:
        text = str(value)
        if not text or len(text) > limit or not all(c.isalnum() or c in allowed for c in text):
            return f"must be a {kind} (letters, digits and {' '.join(allowed)}; at most {limit} characters)"
        return None

    return check


def _file(value: Any) -> str | None:
    text = str(value)
    if len(text) > 4096 or not text.isprintable():
        return "must be a file path or shipped name of at most 4096 printable characters"
    return None


#: Every parameter of the map server (read-only: read once at start).
MAP_SERVER_PARAMETERS: tuple[ParameterSpec, ...] = (
    ParameterSpec(
        "prior",
        "",
        "World prior of a real site ('corridors' model) whose site is published: a .npz path, or a shipped "
        "name such as heli_lines.",
        _file,
        read_only=True,
    ),
    ParameterSpec(
        "site_file",
        "",
        "GIS site file (drd-site/1 YAML) whose site is published instead of a prior's.",
        _file,
        read_only=True,
    ),
    ParameterSpec(
        "frame_id",
        "map",
        "Frame of both maps: the planner's planning frame (its frame_id parameter).",
        _name("frame name", 256, "_/."),
        read_only=True,
    ),
    ParameterSpec("terrain_topic", "terrain", "Topic of the terrain cloud.", _name("topic name", 256, "_/~"), True),
    ParameterSpec(
        "obstacles_topic", "obstacles", "Topic of the obstacle markers.", _name("topic name", 256, "_/~"), True
    ),
)


def map_server_problems(values: Mapping[str, Any]) -> list[str]:
    """Why each parameter value is refused (``"name reason"``, one line each), and whether a site is named."""
    specs = {spec.name: spec for spec in MAP_SERVER_PARAMETERS}
    problems = []
    for name, value in values.items():
        spec = specs.get(name)
        reason = None if spec is None or spec.check is None else spec.check(value)
        if reason is not None:
            problems.append(f"{name} {reason}")
    prior, site_file = str(values.get("prior", "")), str(values.get("site_file", ""))
    if not prior and not site_file:
        problems.append("prior or site_file must name the site to publish (e.g. prior:=heli_lines)")
    elif prior and site_file:
        problems.append("prior and site_file are both set: give one of them")
    return problems


class MapServer(Node):
    """See the module docstring.

    Raises:
        MapServerError: bad parameters (each named), or a prior or site file that gives no site.
    """

    def __init__(self, *, node_name: str = "drd_map_server", **kwargs: Any) -> None:
        super().__init__(node_name, **kwargs)
        for spec in MAP_SERVER_PARAMETERS:
            self.declare_parameter(spec.name, spec.default, spec.descriptor())
        values = {spec.name: self.get_parameter(spec.name).value for spec in MAP_SERVER_PARAMETERS}
        problems = map_server_problems(values)
        if problems:
            raise MapServerError("; ".join(problems))
        self.frame_id = str(values["frame_id"])
        log = self.get_logger().info
        try:
            if values["prior"]:
                self.site: OperatingSite = site_of_prior_file(str(values["prior"]), log=log)
            else:
                self.site = site_of_site_file(str(values["site_file"]), log=log)
            p = self.site.params
            log(
                f"site {self.site.name}: elevation grid {p.resolved_path()} ({p.grid_units}), lattice origin "
                f"{p.site_origin}, x axis {p.site_heading_deg:g} deg counter-clockwise from the grid's east, "
                f"datum {self.site.datum:.1f} m of the grid (z = 0)"
            )
            self.world = site_world(self.site)
        except DrdError as exc:
            raise MapServerError(str(exc)) from exc
        self._terrain = self.create_publisher(PointCloud2, str(values["terrain_topic"]), LATCHED)
        self._obstacles = self.create_publisher(MarkerArray, str(values["obstacles_topic"]), LATCHED)
        self.publish_maps()

    def publish_maps(self) -> None:
        """Publish the terrain and the obstacles, stamped now (latched: late subscribers get them too)."""
        now = self.get_clock().now().seconds_nanoseconds()
        markers, cloud = site_messages(
            self.site, frame_id=self.frame_id, stamp=(int(now[0]), int(now[1])), msgs=RclpyMessages(), world=self.world
        )
        self._terrain.publish(cloud)
        self._obstacles.publish(markers)
        terrain = self.world.terrain
        self.get_logger().info(
            f"published {self._terrain.topic_name} ({terrain.shape[0]} x {terrain.shape[1]} points, "
            f"{terrain.cell_size:g} m cells) and {self._obstacles.topic_name} ({len(markers.markers) - 1} markers: "
            f"{len(self.world.wires)} wire spans, {len(self.world.solids) - len(self.world.nofly)} towers, "
            f"{len(self.world.nofly)} no-fly zones) in frame {self.frame_id!r}, latched"
        )


def run_map_server(overrides: Mapping[str, str], args: list[str] | None = None) -> int:
    """Run a :class:`MapServer` until SIGINT / SIGTERM; the exit status (2: it could not start, the reason printed).

    Args:
        overrides: parameter values from the command line's flags (they win over ``--ros-args -p``).
        args: the process's arguments for rclpy (program name first, then ``--ros-args ...``).
    """
    rclpy.init(args=args)
    try:
        node = MapServer(parameter_overrides=[Parameter(name, value=value) for name, value in overrides.items()])
    except (MapServerError, ParameterException, ValueError, TypeError) as exc:
        print(f"drd_map_server: error: {exc}", file=sys.stderr)
        try_shutdown()
        return 2
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    try:
        while node.context.ok():
            executor.spin_once(timeout_sec=0.25)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        executor.shutdown()
        node.destroy_node()
        try_shutdown()
    return 0
