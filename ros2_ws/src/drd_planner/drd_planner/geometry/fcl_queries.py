"""The few python-fcl calls the scene makes, written once so that FCL's traps are avoided in one place.

- python-fcl ORs every answer into the ``CollisionResult`` it is given, so a reused result keeps saying
  "collision" after the first hit: :func:`pair_collides` makes a fresh request and result for every call and
  reads FCL's own return value (the number of contacts).
- python-fcl's default broadphase callback only stops once it holds *more* than ``num_max_contacts`` contacts:
  at least one narrowphase call too many, and every candidate pair when many contacts are requested.
  :class:`FirstHitCallback` stops the broadphase at the first hit.
- ``continuousCollide`` against meshes crashes or silently says "free": it is never called; swept motions are
  checked as sampled discrete positions instead.
"""

from __future__ import annotations

import fcl

__all__ = ["FirstHitCallback", "first_hit", "pair_collides", "pair_contacts", "pair_distance"]


def pair_collides(first: fcl.CollisionObject, second: fcl.CollisionObject) -> bool:
    """Whether two FCL objects intersect (touching counts), with a fresh request and result."""
    contacts: int = fcl.collide(first, second, fcl.CollisionRequest(), fcl.CollisionResult())
    return contacts > 0


def pair_contacts(first: fcl.CollisionObject, second: fcl.CollisionObject, max_contacts: int) -> list[fcl.Contact]:
    """Up to ``max_contacts`` FCL contacts (position, normal, penetration depth in metres) of two objects.

    A fresh request (contacts enabled) and result for every call; an empty list when they do not intersect.
    """
    result = fcl.CollisionResult()  # fresh per call, see the module docstring
    fcl.collide(first, second, fcl.CollisionRequest(num_max_contacts=max_contacts, enable_contact=True), result)
    return list(result.contacts)


def pair_distance(first: fcl.CollisionObject, second: fcl.CollisionObject) -> float:
    """FCL's distance in metres between two objects that do not intersect (0 or negative when they do)."""
    distance: float = fcl.distance(first, second, fcl.DistanceRequest(), fcl.DistanceResult())
    return distance


class FirstHitCallback:
    """A broadphase collision callback that stops at the first colliding pair.

    Pass :meth:`on_pair` to ``DynamicAABBTreeCollisionManager.collide``; afterwards :attr:`hit` says whether any
    pair collided and :attr:`calls` how many candidate pairs the broadphase offered before it stopped.
    """

    def __init__(self) -> None:
        self._calls = 0
        self._hit = False

    @property
    def calls(self) -> int:
        """Number of candidate pairs the broadphase handed to the callback."""
        return self._calls

    @property
    def hit(self) -> bool:
        """Whether a colliding pair was found."""
        return self._hit

    def on_pair(self, first: fcl.CollisionObject, second: fcl.CollisionObject, _data: object) -> bool:
        """FCL callback: narrowphase one candidate pair; returning True stops the broadphase."""
        self._calls += 1
        if not self._hit and pair_collides(first, second):
            self._hit = True
        return self._hit


def first_hit(manager: fcl.DynamicAABBTreeCollisionManager, query: fcl.CollisionObject) -> FirstHitCallback:
    """Collide ``query`` against every object of ``manager``, stopping at the first hit.

    Returns:
        The callback, whose ``hit`` and ``calls`` describe the query.
    """
    callback = FirstHitCallback()
    manager.collide(query, None, callback.on_pair)
    return callback
