"""A query session's motions: session-wide ids for the motions of its queries, and dense paths from pieces.

**Motion edge ids.** The :class:`~drd_planner.planner.Planner` numbers the new motions of each query from E
on, so the same id names different motions in different queries. A session that keeps published plans
(and re-checks them after a map update) needs ids that name one motion only: :class:`MotionRegistry` gives
every distinct motion (by its exact states) a session-wide id from E on, the same id while the motion is
remembered, and never reuses an id, so a forgotten motion is unknown rather than mistaken for another.
"""

from __future__ import annotations

from collections import OrderedDict

import numpy as np
import numpy.typing as npt

from drd_planner.arrays import FloatArray
from drd_planner.domains.pose_states import wrap_angle
from drd_planner.exceptions import PlanningError, UnverifiedPathError

__all__ = ["DEFAULT_MOTIONS_KEPT", "JOIN_TOLERANCE", "MotionRegistry", "join_pieces"]

#: Motions a session remembers (for ``edge_states`` and re-checks of published plans); oldest dropped first.
DEFAULT_MOTIONS_KEPT = 1024
#: How far (state units) consecutive pieces of a dense path may be apart where they meet.
JOIN_TOLERANCE = 1e-6


class MotionRegistry:
    """Session-wide ids of motions (see the module docstring).

    Args:
        first_id: the first id given (the graph's edge count E).
        capacity: motions remembered; the least recently used is forgotten first.
    """

    def __init__(self, first_id: int, *, capacity: int = DEFAULT_MOTIONS_KEPT) -> None:
        if capacity < 1:
            raise PlanningError(f"a session must remember at least one motion, got {capacity}")
        self._first = int(first_id)
        self._next = int(first_id)
        self._capacity = int(capacity)
        self._ids: OrderedDict[bytes, int] = OrderedDict()
        self._states: dict[int, FloatArray] = {}

    def __len__(self) -> int:
        return len(self._states)

    def id_for(self, states: npt.ArrayLike) -> int:
        """The id of the motion through the (K, D) ``states`` (registered now if new)."""
        array = np.array(states, dtype=np.float64)
        key = array.shape[1:].__repr__().encode() + array.tobytes()
        known = self._ids.get(key)
        if known is not None:
            self._ids.move_to_end(key)
            return known
        motion = self._next
        self._next += 1
        array.setflags(write=False)
        self._ids[key] = motion
        self._states[motion] = array
        while len(self._ids) > self._capacity:
            _, dropped = self._ids.popitem(last=False)
            del self._states[dropped]
        return motion

    def states(self, motion: int) -> FloatArray | None:
        """(K, D) states of a remembered motion id, tail first (None: not a motion id, or forgotten)."""
        return self._states.get(int(motion))

    def is_motion_id(self, edge: int) -> bool:
        """Whether ``edge`` is in the range of ids this registry has given (remembered or not)."""
        return self._first <= int(edge) < self._next


def join_pieces(pieces: list[FloatArray], *, dim: int, periodic: tuple[int, ...] = ()) -> FloatArray:
    """(K, dim) states of consecutive path pieces (each oriented in traversal order), shared states once.

    ``periodic`` names angle dimensions (rad), compared modulo 2 pi where pieces meet.

    Raises:
        UnverifiedPathError: two consecutive pieces do not meet (the path's bookkeeping is broken).
    """
    if not pieces:
        return np.zeros((0, dim))
    for k in range(1, len(pieces)):
        head, tail = pieces[k - 1][-1], pieces[k][0]
        diff = np.abs(tail - head)
        for d in periodic:
            diff[d] = abs(wrap_angle(float(tail[d] - head[d])))
        gap = float(np.max(diff))
        if not gap <= JOIN_TOLERANCE * max(1.0, float(np.max(np.abs(head)))):
            raise UnverifiedPathError(f"path pieces {k - 1} and {k} do not meet (gap {gap:.3g})")
    return np.concatenate([pieces[0]] + [p[1:] for p in pieces[1:]])
