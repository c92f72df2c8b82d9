"""World source ``--bags FILE...``: each map snapshot of recorded bags is one world of a dataset.

Each bag's map messages (``obstacles``, ``terrain``, ``robot_description``) are applied in time order by a
:class:`~drd_planner.planning.map_store.MapStore` with the domain's margin and robot loader, exactly as the node
(and ``drd plan --bag``) applies them; the snapshot after each accepted message that holds maps (terrain or an
obstacle map) is one world, bags in the order given. A world is checked with the domain's ``scene_checker`` on
the snapshot's scene (and the snapshot's arm, after a ``robot_description``).

A map message the planner would refuse stops the build, naming the bag, topic, time and reason: a marker or
cloud in another frame than the planning frame (``--frame``; default: the frame of the first bag's first map
message), a shape the geometry refuses, a map over a size limit. A bag without any map snapshot is refused too.

This module is the bag kind of :mod:`drd_planner.data.world_sources` (``resolve`` and ``open_worlds``); it lives
in ``planning/`` because it applies map messages with the planner's one map store.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from drd_msgs_py.bags import bag_frame, read_bag, topic_base
from drd_msgs_py.exceptions import MessageError
from drd_planner.data.world_sources import (
    FileRecord,
    MapBags,
    ResolvedSource,
    online_domain,
    records_from_json,
)
from drd_planner.domains.base import Domain, EdgeChecker
from drd_planner.domains.online import OnlineDomain
from drd_planner.exceptions import DatasetError, DrdError
from drd_planner.planning.map_state import MapSnapshot
from drd_planner.planning.map_store import MAP_SOURCES, MapStore, terrain_fit_of

__all__ = [
    "DEFAULT_FRAME",
    "WORLD_MODEL",
    "BagSnapshot",
    "BagWorlds",
    "bag_snapshots",
    "open_worlds",
    "resolve",
]

#: The dataset's ``world_model`` field for bag worlds.
WORLD_MODEL = MapBags.world_model
#: The planning frame when neither ``--frame`` nor the bag names one (the node's ``frame_id`` default).
DEFAULT_FRAME = "map"


@dataclass(frozen=True)
class BagSnapshot:
    """One world of a bag: the maps after one accepted map message.

    Attributes:
        file: the bag it came from.
        topic: the map message's topic.
        time_ns: the message's bag time.
        snapshot: the maps (with their scene).
    """

    file: str
    topic: str
    time_ns: int
    snapshot: MapSnapshot

    def describe(self) -> dict[str, Any]:
        """JSON-able: which bag, message and snapshot version this world is."""
        return {
            "file": Path(self.file).name,
            "topic": self.topic,
            "time_ns": self.time_ns,
            "version": self.snapshot.version,
            "obstacles": len(self.snapshot.obstacles),
            "terrain": self.snapshot.terrain is not None,
        }


def bag_snapshots(record: FileRecord, *, frame: str, domain: OnlineDomain[Any]) -> list[BagSnapshot]:
    """The map snapshots of one bag (its bytes checked against the record's SHA-256).

    Raises:
        DatasetError: the bag changed, cannot be read, a map message is refused (the bag, topic, time and
            reason named), or it holds no map snapshot.
    """
    record.read()
    try:
        messages = read_bag(record.path)
    except MessageError as exc:
        raise DatasetError(str(exc)) from exc
    store = MapStore(
        frame_id=frame,
        margin=domain.margin,
        robot_loader=domain.robot_loader(),
        terrain_fit=terrain_fit_of([domain]),
    )
    out: list[BagSnapshot] = []
    for m in messages:
        base = topic_base(m.topic)
        if base not in MAP_SOURCES:
            continue
        try:
            snapshot = store.apply(base, m.message)
        except (MessageError, DrdError) as exc:
            raise DatasetError(
                f"bag {record.path}: {m.topic} at {m.time_ns} ns is refused: {exc} (maps must be in the "
                f"planning frame {frame!r}, chosen with --frame, and within the node's map limits)"
            ) from exc
        if snapshot is not None and snapshot.has_maps:
            out.append(BagSnapshot(record.path, m.topic, m.time_ns, snapshot))
    if not out:
        raise DatasetError(
            f"bag {record.path} has no map snapshot (no accepted {', '.join(MAP_SOURCES[:2])} message): "
            "record the map topics, or leave the bag out of --bags"
        )
    return out


def _frame(request: MapBags, first: FileRecord) -> str:
    """The planning frame: ``--frame``, else the first map message's frame in the first bag, else ``map``."""
    if request.frame is not None:
        return request.frame
    first.read()
    try:
        return bag_frame(read_bag(first.path)) or DEFAULT_FRAME
    except MessageError as exc:
        raise DatasetError(str(exc)) from exc


def resolve(request: MapBags, domain: Domain, user_spec: Mapping[str, Any], num_worlds: int | None) -> ResolvedSource:
    """Read every bag's snapshots with ``domain`` (margin, robot loader) and list them as worlds.

    Raises:
        DatasetError: see :func:`bag_snapshots`; or fewer snapshots than ``num_worlds``.
    """
    online = online_domain(domain, "--bags")
    records = [FileRecord.of(f, what="bag") for f in request.files]
    frame = _frame(request, records[0])
    snapshots = [s for record in records for s in bag_snapshots(record, frame=frame, domain=online)]
    if num_worlds is not None and num_worlds > len(snapshots):
        raise DatasetError(f"--worlds {num_worlds}: the bags hold only {len(snapshots)} map snapshot(s)")
    used = snapshots[: num_worlds or len(snapshots)]
    data = {"kind": request.kind, "frame": frame, "files": [r.to_json() for r in records]}
    provenance = {**data, "snapshots": [s.describe() for s in used]}
    return ResolvedSource(
        kind=request.kind,
        world_model=WORLD_MODEL,
        num_worlds=len(used),
        seeded=False,
        spec=None,
        worker_data=data,
        provenance=provenance,
    )


class BagWorlds:
    """The bag worlds of a build, in a worker: snapshot ``i`` of the bags, in order, is world ``i``.

    The bags are read (and checked against their SHA-256) on first use, with the domain's margin and robot loader.
    """

    def __init__(self, records: Sequence[FileRecord], frame: str) -> None:
        self.records = tuple(records)
        self.frame = frame
        self._snapshots: list[BagSnapshot] | None = None
        self._domain: Domain | None = None

    def snapshots(self, domain: OnlineDomain[Any]) -> list[BagSnapshot]:
        """Every snapshot of the bags, read once per domain."""
        if self._snapshots is None or self._domain is not domain:
            self._snapshots = [
                s for record in self.records for s in bag_snapshots(record, frame=self.frame, domain=domain)
            ]
            self._domain = domain
        return self._snapshots

    def checkers(self, domain: Domain, ids: Sequence[int]) -> Iterator[EdgeChecker]:
        """The domain's scene checker of each snapshot ``ids`` names (with the snapshot's arm, if any)."""
        online = online_domain(domain, "bag worlds")
        snapshots = self.snapshots(online)
        for i in ids:
            if not 0 <= int(i) < len(snapshots):
                raise DatasetError(f"bag world {i} is not among the bags' {len(snapshots)} map snapshots")
            snap = snapshots[int(i)].snapshot
            yield online.scene_checker(snap.scene, snap.robot)


def open_worlds(data: Mapping[str, Any]) -> BagWorlds:
    """The bag worlds of a resolved source's ``worker_data``."""
    frame = data.get("frame")
    if not isinstance(frame, str):
        raise DatasetError(f"bag world source data needs a 'frame' string, got {frame!r}")
    return BagWorlds(records_from_json(data), frame)
