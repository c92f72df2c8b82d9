"""python-fcl traps (docs/architecture.md, "Known traps"): sticky CollisionResult, the broadphase
callback that never stops, continuousCollide, and meshes as surfaces."""

from __future__ import annotations

import re
from pathlib import Path

import fcl
import numpy as np
import pytest
import trimesh

import drd_planner
from drd_planner.geometry.fcl_queries import (
    FirstHitCallback,
    first_hit,
    pair_collides,
    pair_contacts,
    pair_distance,
)

PACKAGE = Path(drd_planner.__file__).resolve().parent
GEOMETRY = PACKAGE / "geometry"


def sphere_at(x: float, radius: float = 0.5) -> fcl.CollisionObject:
    return fcl.CollisionObject(fcl.Sphere(radius), fcl.Transform(np.array([x, 0.0, 0.0])))


def test_reused_result_stays_collided_in_plain_fcl() -> None:
    """The trap itself: python-fcl ORs answers into a result object that is reused."""
    box = fcl.CollisionObject(fcl.Box(1.0, 1.0, 1.0), fcl.Transform())
    result = fcl.CollisionResult()
    request = fcl.CollisionRequest()
    fcl.collide(box, sphere_at(0.0), request, result)
    assert result.is_collision
    contacts = fcl.collide(box, sphere_at(10.0), request, result)
    assert contacts == 0
    assert result.is_collision  # still "collision" although the second pair is free


def test_pair_collides_answers_each_pair_afresh() -> None:
    box = fcl.CollisionObject(fcl.Box(1.0, 1.0, 1.0), fcl.Transform())
    answers = [pair_collides(box, sphere_at(x)) for x in (0.0, 10.0, 0.9, 1.1, 0.0)]
    assert answers == [True, False, True, False, True]


def test_pair_collides_source_builds_fresh_request_and_result() -> None:
    source = (GEOMETRY / "fcl_queries.py").read_text()
    assert "fcl.collide(first, second, fcl.CollisionRequest(), fcl.CollisionResult())" in source
    for path in GEOMETRY.glob("*.py"):
        if path.name == "fcl_queries.py":
            continue  # pair_contacts binds its fresh result to read the contacts (tested below)
        text = path.read_text()
        # No other module keeps a CollisionResult around: every construction is inline in a call.
        assert not re.search(r"=\s*fcl\.CollisionResult\(", text), path.name


def test_pair_contacts_answers_each_pair_afresh() -> None:
    box = fcl.CollisionObject(fcl.Box(1.0, 1.0, 1.0), fcl.Transform())
    counts = [len(pair_contacts(box, sphere_at(x), 4)) for x in (0.0, 10.0, 0.9, 1.1)]
    assert counts[0] >= 1
    assert counts[1] == 0
    assert counts[2] >= 1
    assert counts[3] == 0
    (deep,) = pair_contacts(box, sphere_at(0.9), 1)
    assert 0.0 < float(deep.penetration_depth) < 0.2


def test_pair_distance() -> None:
    box = fcl.CollisionObject(fcl.Box(1.0, 1.0, 1.0), fcl.Transform())
    assert abs(pair_distance(box, sphere_at(2.0)) - 1.0) < 1e-6


def overlapping_boxes(count: int) -> fcl.DynamicAABBTreeCollisionManager:
    manager = fcl.DynamicAABBTreeCollisionManager()
    manager.registerObjects(
        [fcl.CollisionObject(fcl.Box(1.0, 1.0, 1.0), fcl.Transform(np.array([0.01 * k, 0, 0]))) for k in range(count)]
    )
    manager.setup()
    return manager


def test_first_hit_callback_stops_at_the_first_pair() -> None:
    manager = overlapping_boxes(100)
    callback = first_hit(manager, sphere_at(0.0))
    assert callback.hit
    assert callback.calls == 1


@pytest.mark.parametrize(("max_contacts", "expected_calls"), [(1, 2), (100, 100)])
def test_default_callback_runs_past_the_first_hit(max_contacts: int, expected_calls: int) -> None:
    """The trap: python-fcl's default callback only stops once it holds *more* than num_max_contacts contacts."""
    manager = overlapping_boxes(100)
    calls = []

    def counting(o1: fcl.CollisionObject, o2: fcl.CollisionObject, data: fcl.CollisionData) -> bool:
        calls.append(1)
        done: bool = fcl.defaultCollisionCallback(o1, o2, data)
        return done

    data = fcl.CollisionData(request=fcl.CollisionRequest(num_max_contacts=max_contacts))
    manager.collide(sphere_at(0.0), data, counting)
    assert data.result.is_collision
    assert len(calls) == expected_calls


def test_first_hit_on_a_free_query_visits_only_broadphase_candidates() -> None:
    manager = overlapping_boxes(100)
    callback = first_hit(manager, sphere_at(50.0))
    assert not callback.hit
    assert callback.calls == 0
    fresh = FirstHitCallback()
    assert (fresh.calls, fresh.hit) == (0, False)


def test_plain_fcl_sees_a_sphere_inside_a_closed_mesh_as_free() -> None:
    """The trap behind the scene's inside test: FCL meshes are surfaces."""
    box = trimesh.creation.box(extents=(2.0, 2.0, 2.0))
    model = fcl.BVHModel()
    model.beginModel(len(box.vertices), len(box.faces))
    model.addSubModel(box.vertices, box.faces)
    model.endModel()
    mesh = fcl.CollisionObject(model, fcl.Transform())
    assert not pair_collides(mesh, sphere_at(0.0, radius=0.1))
    assert pair_collides(mesh, sphere_at(0.95, radius=0.1))


def test_no_continuous_collide_anywhere_in_the_package() -> None:
    offenders = [
        str(path.relative_to(PACKAGE))
        for path in PACKAGE.rglob("*.py")
        if re.search(r"continuousCollide\s*\(|ContinuousCollision(Request|Result)", path.read_text())
    ]
    assert offenders == []
