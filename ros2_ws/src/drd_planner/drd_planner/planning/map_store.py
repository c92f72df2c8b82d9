"""The one map store: map messages in, versioned :class:`~drd_planner.planning.map_state.MapSnapshot` out.

The planner node, the bag tools and ``drd plan --bag`` all apply map messages (rclpy or rosbags alike)
through a :class:`MapStore`, so they hold the same maps after the same messages:

- ``obstacles`` (MarkerArray): :func:`drd_msgs_py.obstacles.obstacle_update` validates the whole array, the new
  markers become collision parts (:mod:`~drd_planner.planning.map_intake`), and the update is applied to the
  obstacle map (ADD replaces ``ns/id``, DELETE removes it, DELETEALL clears); obstacles the update does not
  touch, and those it gives again unchanged (a latched topic sends the whole map each time), keep their
  Obstacle and parts objects, so only what changed is built and a snapshot's scene rebuilds only that.
  Serialized bytes (a raw subscription) are read by :mod:`drd_msgs_py.marker_cdr`, only the markers whose
  bytes changed since the last array (:class:`~drd_msgs_py.marker_cdr.MarkerArrayReader`), and a marker
  whose content equals that of the held obstacle is not validated again;
- ``terrain`` (PointCloud2): the cloud's grid becomes the terrain heightfield (``unknown_terrain`` of the limits),
  unless no loaded prior can take it as its ground (``terrain_fit``, see :func:`terrain_fit_of`: it lies elsewhere in
  the planning frame, or above every vertex: heights in another datum; for a prior of a real site, it is not
  that site: :mod:`~drd_planner.planning.site_match`);
- ``robot_description`` (String): the URDF becomes the arm of the snapshot when the store has a robot loader
  (an arm prior), else the text is only kept;
- ``monitored_planning_scene`` (moveit_msgs PlanningScene, full or diff): its collision objects become
  collision parts (:class:`~drd_planner.planning.moveit_world.MoveItWorld`, keys ``moveit:<id>``) beside the
  MarkerArray obstacles; an octomap or anything else the world refuses raises and changes nothing.

Each accepted message makes the next snapshot version; a refused one raises
(:class:`~drd_msgs_py.exceptions.MessageError` or :class:`~drd_planner.exceptions.DrdError`, the text says
why) and leaves the maps as they were. Every snapshot of one store shares the store's scene cache.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any

from drd_msgs_py.marker_cdr import MarkerArrayReader
from drd_msgs_py.obstacles import Obstacle, obstacle_update
from drd_msgs_py.topics import topic_base
from drd_planner.domains.helicopter_site import OperatingSite
from drd_planner.domains.online import OnlineDomain
from drd_planner.exceptions import DrdError
from drd_planner.geometry.map_limits import MapLimits
from drd_planner.geometry.robot import RobotModel
from drd_planner.geometry.terrain import Heightfield
from drd_planner.planning.map_intake import obstacle_parts, terrain_from_cloud
from drd_planner.planning.map_state import MapSnapshot, Parts
from drd_planner.planning.moveit_world import MoveItWorld
from drd_planner.planning.site_match import site_mismatch

__all__ = ["MAP_SOURCES", "MapStore", "RobotLoader", "TerrainFit", "robot_loader_of", "terrain_fit_of"]

#: Turns a ``robot_description`` URDF into an arm model (limits applied by whoever made it).
RobotLoader = Callable[[str], RobotModel]
#: Why a terrain cannot be the loaded priors' ground, or None when it can be.
TerrainFit = Callable[[Heightfield], str | None]


def terrain_fit_of(domains: Sequence[OnlineDomain[Any]], sites: Sequence[OperatingSite | None] = ()) -> TerrainFit:
    """The fit of a terrain to the loaded priors: refused only when every prior says why not.

    Args:
        domains: the loaded priors' domains (:meth:`OnlineDomain.terrain_mismatch`; an arm's takes any).
        sites: per prior (same order) the real site it was trained on, or None
            (:func:`~drd_planner.planning.prior_site.prior_sites`); a terrain that fits a site prior's domain
            must also be that site (:func:`~drd_planner.planning.site_match.site_mismatch`). Missing
            entries count as None.
    """

    def mismatch(i: int, terrain: Heightfield) -> str | None:
        reason = domains[i].terrain_mismatch(terrain)
        site = sites[i] if i < len(sites) else None
        return site_mismatch(site, terrain) if reason is None and site is not None else reason

    def fit(terrain: Heightfield) -> str | None:
        reasons = [mismatch(i, terrain) for i in range(len(domains))]
        if not reasons or any(reason is None for reason in reasons):
            return None
        return "; ".join(f"prior {i}: {reason}" for i, reason in enumerate(reasons)) if len(reasons) > 1 else reasons[0]

    return fit


#: The map topics (base names) a store applies.
MAP_SOURCES = ("obstacles", "terrain", "robot_description", "monitored_planning_scene")


class MapStore:
    """The maps a planner holds: the current snapshot, the obstacle map behind it, the latest robot description.

    Args:
        frame_id: the planning frame (maps in another frame are refused).
        margin: collision margin of the snapshots' scenes, metres.
        limits: size limits of map messages, and how unknown terrain counts.
        robot_loader: turns a ``robot_description`` into the snapshot's arm; None: the text is only kept.
        terrain_fit: why a terrain is not the priors' ground (:func:`terrain_fit_of`); None: any terrain is taken.
    """

    def __init__(
        self,
        *,
        frame_id: str,
        margin: float = 0.0,
        limits: MapLimits = MapLimits.DEFAULT,
        robot_loader: RobotLoader | None = None,
        terrain_fit: TerrainFit | None = None,
    ) -> None:
        self.frame_id = frame_id
        self.limits = limits
        self._robot_loader = robot_loader
        self._terrain_fit = terrain_fit
        self._snapshot = MapSnapshot(0, margin=margin)
        self._obstacles: dict[str, Obstacle] = {}
        self._parts: dict[str, Parts] = {}
        self._description: str | None = None
        self._reader = MarkerArrayReader()  # serialized arrays: re-reads only the markers whose bytes changed
        self._moveit = MoveItWorld(frame_id=frame_id, limits=limits)

    @property
    def snapshot(self) -> MapSnapshot:
        """The maps after the last accepted message."""
        return self._snapshot

    @property
    def obstacles(self) -> Mapping[str, Obstacle]:
        """The obstacle map as its markers gave it (key ``ns/id``)."""
        return dict(self._obstacles)

    @property
    def robot_description(self) -> str | None:
        """The latest accepted ``robot_description`` text (None: none yet)."""
        return self._description

    @property
    def has_robot_loader(self) -> bool:
        """Whether a ``robot_description`` changes the snapshot's arm (an arm prior is loaded)."""
        return self._robot_loader is not None

    def apply(self, topic: str, msg: Any) -> MapSnapshot | None:
        """Apply a message of map topic ``topic`` (any namespace); the new snapshot, or None if ignored.

        A message of another topic, or a ``robot_description`` without a robot loader (its text is kept),
        leaves the snapshot as it is and gives None.

        Raises:
            MessageError: a malformed message or one over a limit (maps unchanged).
            DrdError: a shape, terrain or robot description the planner's geometry refuses (maps unchanged).
        """
        base = topic_base(topic)
        if base == "obstacles":
            return self.apply_obstacles(msg)
        if base == "terrain":
            return self.apply_terrain(msg)
        if base == "robot_description":
            return self.apply_robot_description(str(msg.data))
        if base == "monitored_planning_scene":
            return self.apply_planning_scene(msg)
        return None

    def apply_obstacles(self, msg: Any) -> MapSnapshot:
        """Apply a MarkerArray, as message or serialized bytes (see the module docstring); the new snapshot.

        Only the obstacles that differ from the held one of their key get new parts: a marker equal to the
        held obstacle keeps its :class:`Obstacle` (:func:`~drd_msgs_py.obstacles.obstacle_update`) and its parts.
        """
        update = obstacle_update(
            msg, frame_id=self.frame_id, limits=self.limits, held=self._obstacles, reader=self._reader
        )
        obstacles = update.apply(self._obstacles)  # refuses a map that grows beyond a limit
        held = self._obstacles
        parts = {key: self._parts[key] if o is held.get(key) else obstacle_parts(o) for key, o in obstacles.items()}
        self._parts = parts
        self._obstacles = obstacles
        self._snapshot = self._snapshot.with_obstacles({**self._parts, **self._moveit_parts()})
        return self._snapshot

    def apply_planning_scene(self, msg: Any) -> MapSnapshot:
        """Apply a MoveIt ``PlanningScene`` (see the module docstring); the new snapshot.

        Parts of objects the scene did not touch are kept as they were (the scene cache rebuilds only
        what changed).
        """
        self._moveit.apply(msg)  # refuses without changing anything
        self._snapshot = self._snapshot.with_obstacles({**self._parts, **self._moveit_parts()})
        return self._snapshot

    def _moveit_parts(self) -> dict[str, Parts]:
        """The MoveIt objects' parts; an object's parts equal to the current snapshot's stay those objects."""
        before = self._snapshot.obstacles
        moveit = self._moveit.parts()
        for key, parts in moveit.items():
            if before.get(key) == parts:
                moveit[key] = before[key]
        return moveit

    def apply_terrain(self, msg: Any) -> MapSnapshot:
        """Apply a terrain cloud; the new snapshot (DrdError: no loaded prior can take it as its ground)."""
        terrain = terrain_from_cloud(msg, frame_id=self.frame_id, limits=self.limits)
        mismatch = None if self._terrain_fit is None else self._terrain_fit(terrain)
        if mismatch is not None:
            raise DrdError(f"not the prior's terrain: {mismatch}")
        self._snapshot = self._snapshot.with_terrain(terrain)
        return self._snapshot

    def apply_robot_description(self, text: str) -> MapSnapshot | None:
        """Apply a URDF: the new snapshot with its arm, or None without a robot loader (the text is kept)."""
        if self._robot_loader is None:
            self._description = text
            return None
        robot = self._robot_loader(text)
        self._description = text
        self._snapshot = self._snapshot.with_robot(robot)
        return self._snapshot


def robot_loader_of(sessions: Sequence[Any], limits: MapLimits) -> RobotLoader | None:
    """The ``robot_description`` reader with ``limits`` of the prior that needs one (None: no prior does).

    ``sessions``: the loaded priors (:class:`~drd_planner.planning.session.QuerySession`).
    """
    needs = next((s for s in sessions if s.domain.needs_robot_description), None)
    loader: Any = None if needs is None else needs.robot_loader
    if loader is None:
        return None
    return lambda text: loader(text, limits=limits)  # type: ignore[no-any-return]
