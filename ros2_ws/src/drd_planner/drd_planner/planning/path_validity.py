"""Is a path still valid on the maps now? Answered by re-checking only what the maps changed.

Nav2's ``is_path_valid`` (``nav2_msgs/srv/IsPathValid``) asks whether a path a client holds is still free.
:class:`ServedPaths` remembers the paths this node served (their poses, the session's edge ids behind them,
and the map snapshot each was last verified free on). A path asked about is matched to one of them by its
poses (same count, each position within :data:`MATCH_TOLERANCE_M`); then
:func:`~drd_planner.planning.replan.recheck_plan` checks on the current snapshot only the path's edges the
map changes since that snapshot can reach (none when nothing changed near it), stopping at the first
blocked one. A path found free is then remembered as verified on the current snapshot, so the next question
re-checks only what changed after it. A blocked path's ``invalid`` pose indices are the poses on the
blocked edge.

A path the node did not serve (or no longer remembers: :data:`PATHS_KEPT`) is checked pose by pose on the
current snapshot where the domain takes a state from a pose (the helicopter: position and yaw); the poses
are then all that is checked, not the motion between them. Elsewhere (the arm: a Path holds end-effector
positions, not joint states) such a path is answered invalid, with the reason.
"""

from __future__ import annotations

import threading
from collections import deque
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from drd_planner.arrays import FloatArray
from drd_planner.planning.map_state import MapSnapshot
from drd_planner.planning.replan import recheck_plan
from drd_planner.planning.session import QuerySession

__all__ = ["MATCH_TOLERANCE_M", "PATHS_KEPT", "PathValidity", "ServedPaths"]

#: How far (m) a pose asked about may lie from a served path's pose and still be that pose.
MATCH_TOLERANCE_M = 1e-3
#: Served paths remembered (the oldest is forgotten first).
PATHS_KEPT = 16


@dataclass
class _Served:
    """One served path: its session, edge ids, pose positions (K, 3) m, and the snapshot it is known free on."""

    session: QuerySession
    edges: tuple[int, ...]
    positions: FloatArray
    snapshot: MapSnapshot


@dataclass(frozen=True)
class PathValidity:
    """The answer to one question.

    Attributes:
        valid: every pose (served path: every edge) is free on the current maps.
        invalid: indices of the poses found blocked (served path: those on the first blocked edge).
        served: the path is one this node served (then only the edges a map change can reach were checked).
        rechecked: edges (served path) or poses (other path) checked now; 0 when nothing changed near it.
        text: one line for the log.
    """

    valid: bool
    invalid: tuple[int, ...]
    served: bool
    rechecked: int
    text: str


class ServedPaths:
    """The paths served so far, and the answer to "is this path still valid" (see the module docstring).

    Args:
        lock: held while checking (the node's planning lock: a session's caches serve one caller at a time).
    """

    def __init__(self, lock: threading.Lock | None = None) -> None:
        self._paths: deque[_Served] = deque(maxlen=PATHS_KEPT)
        self._lock = lock if lock is not None else threading.Lock()

    def remember(
        self, session: QuerySession, edges: tuple[int, ...], positions: npt.ArrayLike, snapshot: MapSnapshot
    ) -> None:
        """Remember a served path: its edge ids, its poses' (K, 3) positions in m, its verified snapshot."""
        xyz = np.asarray(positions, dtype=np.float64)[:, :3]
        with self._lock:
            self._paths.append(_Served(session, tuple(int(e) for e in edges), xyz, snapshot))

    def validity(
        self,
        positions: npt.ArrayLike,
        yaws: npt.ArrayLike,
        sessions: tuple[QuerySession, ...],
        snapshot: MapSnapshot,
    ) -> PathValidity:
        """Whether the path through ``positions`` (K, 3) m with headings ``yaws`` (K,) rad is free on ``snapshot``."""
        xyz = np.asarray(positions, dtype=np.float64).reshape(-1, 3)
        if xyz.shape[0] == 0:
            return PathValidity(False, (), False, 0, "an empty path is not valid (as Nav2)")
        with self._lock:
            served = self._match(xyz)
            if served is not None:
                return self._recheck(served, xyz, snapshot)
            return _check_poses(xyz, np.asarray(yaws, dtype=np.float64).ravel(), sessions, snapshot)

    def _match(self, xyz: FloatArray) -> _Served | None:
        for served in reversed(self._paths):
            if served.positions.shape == xyz.shape and np.max(np.abs(served.positions - xyz)) <= MATCH_TOLERANCE_M:
                return served
        return None

    def _recheck(self, served: _Served, xyz: FloatArray, snapshot: MapSnapshot) -> PathValidity:
        outcome = recheck_plan(served.session, served.edges, served.snapshot, snapshot)
        if outcome.kept:
            served.snapshot = snapshot  # known free here: the next question re-checks changes after it
            return PathValidity(True, (), True, len(outcome.rechecked), outcome.reason)
        on_edge = served.session.positions(served.session.edge_states(outcome.blocked[0]), snapshot)
        gaps = np.min(np.linalg.norm(xyz[:, None, :] - on_edge[None, :, :], axis=2), axis=1)
        invalid = tuple(int(i) for i in np.flatnonzero(gaps <= MATCH_TOLERANCE_M))
        return PathValidity(False, invalid, True, len(outcome.rechecked), outcome.reason)


def _check_poses(
    xyz: FloatArray, yaws: FloatArray, sessions: tuple[QuerySession, ...], snapshot: MapSnapshot
) -> PathValidity:
    """A path this node did not serve: each pose checked on ``snapshot`` (pose domains only)."""
    session = next((s for s in sessions if s.domain.position_goals == "pose"), None)
    if session is None:
        return PathValidity(False, (), False, 0, "a path this node did not plan cannot be checked here")
    check_motion: Any = getattr(session.checker(snapshot), "check_motion", None)
    if check_motion is None:
        return PathValidity(False, (), False, 0, f"{session.name}: the checker cannot check poses")
    invalid = tuple(
        i
        for i in range(xyz.shape[0])
        if not check_motion(session.domain.state_from_position(xyz[i], float(yaws[i]))[None, :])
    )
    text = f"{xyz.shape[0]} poses of a path this node did not plan checked: {len(invalid)} blocked"
    return PathValidity(not invalid, invalid, False, xyz.shape[0], text)
