"""What a planning session needs of its domain on map snapshots: positions, edge states, the checker.

The base of :class:`~drd_planner.planning.session.QuerySession`: what it reads of the rebuilt domain
whatever the query (the checker per snapshot, positions, straight edge states, the snapshot's check cache),
kept apart from the query planning so that each module stays one concept.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np
import numpy.typing as npt

from drd_planner.arrays import FloatArray
from drd_planner.domains.base import EdgeChecker, domain_from_spec
from drd_planner.domains.online import OnlineDomain
from drd_planner.exceptions import DrdError, PlanningError
from drd_planner.geometry.robot import RobotModel
from drd_planner.planning.map_state import MapSnapshot
from drd_planner.planning.replan import SweepBoxCache

__all__ = [
    "DomainSession",
    "SnapshotCheckers",
    "domain_from_stored_spec",
    "state_positions",
    "straight_edge_states",
]


def domain_from_stored_spec(
    domain_name: str, spec: Mapping[str, Any], *, label: str, error: type[DrdError]
) -> OnlineDomain[Any]:
    """The domain a file's stored spec builds; any failure is one ``error`` naming ``label``.

    A spec the file checks let through may still fail deep in a domain's constructor with any
    exception: it must end in the loader's one clear error, not a traceback.
    """
    try:
        return domain_from_spec(domain_name, spec)
    except DrdError as exc:
        raise error(f"{label}: its domain spec cannot be rebuilt: {exc}") from exc
    except Exception as exc:
        raise error(f"{label}: its domain spec cannot be rebuilt ({type(exc).__name__}: {str(exc)[:200]})") from exc


def state_positions(
    domain: OnlineDomain[Any], states: npt.ArrayLike, dim: int, snapshot: MapSnapshot | None
) -> FloatArray:
    """(K, 3) positions (m, planning frame) of (K, ``dim``) states: x, y, z, or the arm's end effector.

    The arm uses ``snapshot.robot`` when the snapshot carries a ``robot_description``.
    """
    q = np.asarray(states, dtype=np.float64).reshape(-1, dim)
    return domain.positions(q, snapshot.robot if snapshot is not None else None)


def straight_edge_states(domain: OnlineDomain[Any], a: npt.ArrayLike, b: npt.ArrayLike) -> FloatArray:
    """(K, d) states of the straight edge from state ``a`` to state ``b``.

    No coordinate moves more than the domain's check resolution per step (one step without one).
    """
    start, end = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    resolution = float(domain.resolution)
    steps = max(1, int(np.ceil(np.max(np.abs(end - start)) / resolution))) if resolution > 0 else 1
    return np.asarray(start + np.linspace(0.0, 1.0, steps + 1)[:, None] * (end - start), dtype=np.float64)


class SnapshotCheckers:
    """The domain's edge checker on the latest snapshot asked for.

    One (snapshot, checker) pair is kept; replacing the tuple is atomic, so a map thread preparing the
    next snapshot never tears a planning thread's.
    """

    def __init__(self, domain: OnlineDomain[Any]) -> None:
        self._domain = domain
        self._prepared: tuple[MapSnapshot, EdgeChecker] | None = None

    def checker(self, snapshot: MapSnapshot) -> EdgeChecker:
        """The checker on ``snapshot``'s scene (and its ``robot_description`` arm), built once per snapshot."""
        prepared = self._prepared
        if prepared is not None and prepared[0] is snapshot:
            return prepared[1]
        checker = self._domain.scene_checker(snapshot.scene, snapshot.robot)
        self._prepared = (snapshot, checker)
        return checker

    def prepare(self, snapshot: MapSnapshot) -> float:
        """Build ``snapshot``'s scene and checker now; the seconds taken (0.0 for a snapshot without maps).

        The node calls this when a map arrives, so a request on that map starts checking at once.
        """
        if not snapshot.has_maps:
            return 0.0
        t0 = time.perf_counter()
        self.checker(snapshot)
        return time.perf_counter() - t0


class DomainSession:
    """What a planning session reads of its domain on snapshots; the base of the session class.

    Args:
        domain: the session's domain.
        name: a label for logs (the file stem).
    """

    def __init__(self, domain: OnlineDomain[Any], name: str) -> None:
        self._domain = domain
        self._name = name
        self._checkers = SnapshotCheckers(domain)
        self._sweep_boxes = SweepBoxCache()
        self._cache_snapshot: MapSnapshot | None = None
        self._cache: dict[int, bool] = {}

    @property
    def name(self) -> str:
        """The label given at construction."""
        return self._name

    @property
    def domain(self) -> OnlineDomain[Any]:
        """The rebuilt domain."""
        return self._domain

    @property
    def margin(self) -> float:
        """Collision margin of the domain (metres); snapshots for this session use it."""
        return float(self._domain.margin)

    @property
    def joint_names(self) -> tuple[str, ...]:
        """The arm's chain joint names, root to tip (empty for other domains)."""
        return self._domain.joint_names

    @property
    def robot_loader(self) -> Callable[[str], RobotModel] | None:
        """Turns a ``robot_description`` URDF into the snapshot's robot (the arm), or None."""
        return self._domain.robot_loader()

    @property
    def sweep_boxes(self) -> SweepBoxCache:
        """The sweep boxes of this session's edges (:mod:`~drd_planner.planning.replan`)."""
        return self._sweep_boxes

    def checker(self, snapshot: MapSnapshot) -> EdgeChecker:
        """The domain's edge checker on ``snapshot`` (kept for the latest snapshot, see :meth:`prepare`)."""
        return self._checkers.checker(snapshot)

    def prepare(self, snapshot: MapSnapshot) -> float:
        """Build ``snapshot``'s FCL scene and checker now; the seconds taken (0.0 for a snapshot without maps).

        The node calls this when a map arrives, so a request on that map starts checking at once.
        """
        return self._checkers.prepare(snapshot)

    def _outcomes(self, snapshot: MapSnapshot) -> dict[int, bool]:
        """The check outcomes cached for ``snapshot`` (a new cache for another snapshot object).

        Raises:
            PlanningError: the snapshot has no terrain and no obstacles yet (no maps).
        """
        if not snapshot.has_maps:
            raise PlanningError("no maps received yet: refusing to plan on an empty world")
        if snapshot is not self._cache_snapshot:  # the cache belongs to one snapshot object, not a number
            self._cache_snapshot, self._cache = snapshot, {}
        return self._cache
