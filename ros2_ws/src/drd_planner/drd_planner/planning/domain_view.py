"""What a planning session needs of its domain on map snapshots: positions, edge states, the checker.

Shared by :class:`~drd_planner.planning.session.PlanningSession` (one tree) and
:class:`~drd_planner.planning.query_session.QuerySession` (a whole prior).
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from typing import Any

import numpy as np
import numpy.typing as npt

from drd_planner.arrays import FloatArray
from drd_planner.domains.arm import ArmDomain
from drd_planner.domains.base import Domain, EdgeChecker, domain_from_spec
from drd_planner.exceptions import DrdError
from drd_planner.planning.map_state import MapSnapshot

__all__ = ["SnapshotCheckers", "domain_from_stored_spec", "state_positions", "straight_edge_states"]


def domain_from_stored_spec(
    domain_name: str, spec: Mapping[str, Any], *, label: str, error: type[DrdError]
) -> Domain:
    """The domain a file's stored spec builds; any failure is one ``error`` naming ``label``.

    A spec the file checks let through may still fail deep in a domain's constructor with any
    exception: it must end in the loader's one clear error, not a traceback.
    """
    try:
        return domain_from_spec(domain_name, spec)
    except DrdError as exc:
        raise error(f"{label}: its domain spec cannot be rebuilt: {exc}") from exc
    except Exception as exc:
        raise error(
            f"{label}: its domain spec cannot be rebuilt ({type(exc).__name__}: {str(exc)[:200]})"
        ) from exc


def state_positions(
    domain: Domain, states: npt.ArrayLike, dim: int, snapshot: MapSnapshot | None
) -> FloatArray:
    """(K, 3) positions (m, planning frame) of (K, ``dim``) states: x, y, z, or the arm's end effector.

    The arm uses ``snapshot.robot`` when the snapshot carries a ``robot_description``.
    """
    q = np.asarray(states, dtype=np.float64).reshape(-1, dim)
    if isinstance(domain, ArmDomain):
        robot = snapshot.robot if snapshot is not None else None
        return domain.end_effector_positions(q, robot)
    return np.array(q[:, :3], dtype=np.float64)


def straight_edge_states(domain: Domain, a: npt.ArrayLike, b: npt.ArrayLike) -> FloatArray:
    """(K, d) states of the straight edge from state ``a`` to state ``b``.

    No coordinate moves more than the domain's check resolution per step (one step without one).
    """
    start, end = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    resolution = float(getattr(domain, "resolution", 0.0))
    steps = max(1, int(np.ceil(np.max(np.abs(end - start)) / resolution))) if resolution > 0 else 1
    return np.asarray(start + np.linspace(0.0, 1.0, steps + 1)[:, None] * (end - start), dtype=np.float64)


class SnapshotCheckers:
    """The domain's edge checker on the latest snapshot asked for.

    One (snapshot, checker) pair is kept; replacing the tuple is atomic, so a map thread preparing the
    next snapshot never tears a planning thread's.
    """

    def __init__(self, domain: Domain) -> None:
        self._domain = domain
        self._prepared: tuple[MapSnapshot, EdgeChecker] | None = None

    def checker(self, snapshot: MapSnapshot) -> EdgeChecker:
        """The checker on ``snapshot``'s scene (and its ``robot_description`` arm), built once per snapshot."""
        prepared = self._prepared
        if prepared is not None and prepared[0] is snapshot:
            return prepared[1]
        checker: EdgeChecker
        if isinstance(self._domain, ArmDomain) and snapshot.robot is not None:
            checker = self._domain.checker(snapshot.scene, robot=snapshot.robot)
        else:
            checker = self._domain.checker(snapshot.scene)
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
