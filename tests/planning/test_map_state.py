"""Map snapshots: bounded memory (terrain colliders and scenes are freed), incremental scenes, terrain equality."""

from __future__ import annotations

import gc
import weakref

import numpy as np
import pytest

import drd_planner.geometry.scene as scene_module
from drd_planner.geometry.pose import Pose
from drd_planner.geometry.scene import Scene
from drd_planner.geometry.shapes import Box, Sphere
from drd_planner.geometry.terrain import Heightfield
from drd_planner.geometry.terrain_collider import TerrainCollider
from drd_planner.planning.map_state import (
    COLLIDER_CACHE_SIZE,
    SCENE_CACHE_SIZE,
    MapSnapshot,
    Parts,
    SceneCache,
    changed_parts,
)


def _terrain(k: int) -> Heightfield:
    return Heightfield((0.0, 0.0), 1.0, np.full((9, 9), float(k)))


def _live_colliders() -> int:
    gc.collect()
    return sum(isinstance(obj, TerrainCollider) for obj in gc.get_objects())


def test_terrain_colliders_of_dropped_snapshots_are_freed() -> None:
    # Issue 19 item 3: the old WeakKeyDictionary's values referred to their keys, so no collider ever died.
    alive: weakref.WeakSet[TerrainCollider] = weakref.WeakSet()
    for k in range(8):
        snapshot = MapSnapshot(0).with_terrain(_terrain(k))
        assert snapshot.scene.spheres_collide([[4.0, 4.0, k - 0.5]], 0.1)
        alive.add(snapshot.cache.terrain_collider(snapshot.terrain))  # type: ignore[arg-type]
        del snapshot
    gc.collect()
    assert len(alive) <= COLLIDER_CACHE_SIZE


def test_snapshots_kept_by_the_caller_do_not_keep_their_scenes() -> None:
    # A node's plan history keeps snapshots (of one map store: one lineage, one cache); their FCL scenes (and
    # terrain tiles) must not stay with them.
    before = _live_colliders()
    history = []
    snapshot = MapSnapshot(0)
    for k in range(8):
        snapshot = snapshot.with_terrain(_terrain(k))
        assert not snapshot.scene.spheres_collide([[4.0, 4.0, k + 0.5]], 0.1)
        history.append(snapshot)
    assert _live_colliders() - before <= COLLIDER_CACHE_SIZE + SCENE_CACHE_SIZE
    old = history[0]
    assert old.scene.spheres_collide([[4.0, 4.0, -0.5]], 0.1)  # asked again: built again, same answers


def test_scene_is_built_once_while_kept() -> None:
    snapshot = MapSnapshot(0).with_terrain(_terrain(1))
    assert snapshot.scene is snapshot.scene
    cache = snapshot.cache
    assert cache.terrain_collider(snapshot.terrain) is cache.terrain_collider(snapshot.terrain)  # type: ignore[arg-type]


def _boxes(count: int, *, moved: int | None = None) -> dict[str, Parts]:
    out: dict[str, Parts] = {}
    for k in range(count):
        x = 3.0 * k + (0.5 if k == moved else 0.0)
        out[f"box/{k}"] = ((Box((1.0, 1.0, 1.0)), Pose((x, 0.0, 0.0))),)
    return out


def test_a_one_marker_update_builds_one_fcl_object(monkeypatch: pytest.MonkeyPatch) -> None:
    built: list[object] = []
    real = scene_module.make_fcl_geometry

    def counting(shape: object) -> object:
        built.append(shape)
        return real(shape)  # type: ignore[arg-type]

    monkeypatch.setattr(scene_module, "make_fcl_geometry", counting)
    obstacles = _boxes(50)
    first = MapSnapshot(0, margin=0.2).with_obstacles(obstacles)
    first.scene.spheres_collide_mask(np.zeros((1, 3)), 0.1)
    assert len(built) == 50
    built.clear()
    changed = dict(obstacles)
    changed["box/7"] = _boxes(50, moved=7)["box/7"]
    changed["ball/1"] = ((Sphere(0.5), Pose((0.0, 5.0, 0.0))),)
    del changed["box/3"]
    second = first.with_obstacles(changed)
    centres = np.random.default_rng(0).uniform((-2, -3, -2), (152, 8, 2), size=(2000, 3))
    got = second.scene.spheres_collide_mask(centres, 0.4)
    assert len(built) == 2  # the moved box and the new ball; 48 boxes shared with the first scene
    fresh = Scene(margin=0.2)
    for key, parts in changed.items():
        for k, (shape, pose) in enumerate(parts):
            fresh.add(shape, pose, name=f"{key}#{k}")
    assert got.tolist() == fresh.spheres_collide_mask(centres, 0.4).tolist()
    assert 0 < got.sum() < got.size
    # The first scene is unchanged: box 3 still there, box 7 where it was.
    assert first.scene.spheres_collide([[9.0, 0.0, 0.0]], 0.1)
    assert not first.scene.spheres_collide([[21.9, 0.0, 0.0]], 0.05)  # box 7 spans x 20.5-21.5 here
    assert second.scene.spheres_collide([[21.9, 0.0, 0.0]], 0.05)  # and 21-22 there
    assert not second.scene.spheres_collide([[9.0, 0.0, 0.0]], 0.1)


def test_a_scene_copy_shares_objects_but_moves_its_own() -> None:
    first = Scene(margin=0.1)
    first.add(Box((1.0, 1.0, 1.0)), Pose((0.0, 0.0, 0.0)), name="box")
    first.add_terrain(Heightfield((-50.0, -50.0), 10.0, np.full((11, 11), -20.0)))
    assert first.collides(Box((0.5, 0.5, 0.5)), Pose((0.0, 0.0, 0.0)))  # builds the broadphase
    second = first.copy()
    assert second.names == first.names
    assert second.terrain is first.terrain
    assert second.margin == 0.1
    second.set_pose("box", Pose((10.0, 0.0, 0.0)))
    second.add(Sphere(1.0), Pose((0.0, 10.0, 0.0)), name="ball")
    assert first.spheres_collide([[0.0, 0.0, 0.0]], 0.1)
    assert not first.spheres_collide([[10.0, 0.0, 0.0]], 0.1)
    assert not first.spheres_collide([[0.0, 10.0, 0.0]], 0.1)
    assert "ball" not in first
    assert second.spheres_collide([[10.0, 0.0, 0.0]], 0.1)
    assert not second.spheres_collide([[0.0, 0.0, 0.0]], 0.1)
    assert second.collides(Box((0.5, 0.5, 0.5)), Pose((10.0, 0.0, 0.0)))
    assert second.collides(Box((0.5, 0.5, 0.5)), Pose((0.0, 10.0, 0.0)))
    assert second.collides(Box((0.5, 0.5, 0.5)), Pose((30.0, 30.0, -25.0)))  # under the shared terrain
    first.set_pose("box", Pose((0.0, 20.0, 0.0)))  # the first scene's object is shared too: it gets its own
    assert first.collides(Box((0.5, 0.5, 0.5)), Pose((0.0, 20.0, 0.0)))
    assert not second.collides(Box((0.5, 0.5, 0.5)), Pose((0.0, 20.0, 0.0)))


def test_scenes_follow_terrain_and_obstacle_changes_across_snapshots() -> None:
    low, high = _terrain(-5), _terrain(-3)  # under the boxes (z -0.5 to 0.5)
    base = MapSnapshot(0).with_obstacles(_boxes(3)).with_terrain(low)
    probe = [[4.0, 4.0, -4.0]]
    assert not base.scene.spheres_collide(probe, 0.1)
    raised = base.with_terrain(high)
    assert raised.scene.spheres_collide(probe, 0.1)
    assert raised.scene.spheres_collide([[3.0, 0.0, 0.0]], 0.1)  # box 1 kept
    fewer = raised.with_obstacles({"box/0": _boxes(3)["box/0"]})
    assert not fewer.scene.spheres_collide([[3.0, 0.0, 0.0]], 0.1)
    assert fewer.scene.spheres_collide([[0.0, 0.0, 0.0]], 0.1)
    assert fewer.scene.spheres_collide(probe, 0.1)
    assert sorted(fewer.scene.names) == ["box/0#0", "terrain"]
    assert not base.scene.spheres_collide(probe, 0.1)  # the older snapshots' scenes did not change
    bare = MapSnapshot(0).with_obstacles({})  # another lineage without terrain: nothing of the others
    assert bare.scene.names == ()
    assert bare.scene.terrain is None


def test_changed_parts_sees_a_new_unknown_terrain_option() -> None:
    heights = np.zeros((3, 3))
    heights[1, 1] = np.nan
    snapshot = MapSnapshot(0).with_terrain(Heightfield((0.0, 0.0), 1.0, heights))
    same = snapshot.with_terrain(Heightfield((0.0, 0.0), 1.0, heights.copy()))
    other = snapshot.with_terrain(Heightfield((0.0, 0.0), 1.0, heights, unknown="highest_neighbour"))
    assert changed_parts(snapshot, same) == []
    assert changed_parts(snapshot, other) is None


def test_a_new_terrain_is_built_after_the_oldest_is_let_go(monkeypatch: pytest.MonkeyPatch) -> None:
    """Peak memory of a stream of terrain updates: never more than COLLIDER_CACHE_SIZE colliders at once."""
    from drd_planner.planning import map_state

    alive: weakref.WeakSet[TerrainCollider] = weakref.WeakSet()
    at_build: list[int] = []

    def counting(terrain: Heightfield) -> TerrainCollider:
        gc.collect()
        at_build.append(len(alive))  # colliders still alive while the next one is being built
        collider = TerrainCollider(terrain)
        alive.add(collider)
        return collider

    monkeypatch.setattr(map_state, "TerrainCollider", counting)
    snapshot = MapSnapshot(0)
    for k in range(6):
        snapshot = snapshot.with_terrain(_terrain(k))  # the node keeps the current snapshot while it builds
        assert snapshot.scene.spheres_collide([[4.0, 4.0, k - 0.5]], 0.1)
    assert max(at_build) <= COLLIDER_CACHE_SIZE - 1


def test_each_lineage_of_snapshots_owns_its_cache() -> None:
    """Snapshots made from one another share one scene cache; an unrelated snapshot has its own."""
    first = MapSnapshot(0).with_terrain(_terrain(1))
    second = first.with_obstacles({"box/0": ((Box((1.0, 1.0, 1.0)), Pose((4.0, 4.0, 5.0))),)})
    other = MapSnapshot(0).with_terrain(_terrain(1))
    assert isinstance(first.cache, SceneCache)
    assert second.cache is first.cache
    assert other.cache is not first.cache
    assert second.scene is second.scene
    assert other.scene is not second.scene


def test_changed_parts_of_a_wires_world() -> None:
    """Removing an obstacle changes its parts; equal terrain heights change nothing, other heights everything."""
    from drd_planner.domains.helicopter import HelicopterDomain
    from drd_planner.domains.helicopter_worlds import world_parts

    domain = HelicopterDomain()
    world = domain.make_world("wires", 101)
    parts = {name: ((shape, pose),) for name, shape, pose in world_parts(world, wire_segments=8)}
    snapshot = MapSnapshot(1, parts, world.terrain, 0.5)
    same = snapshot.with_obstacles(dict(snapshot.obstacles))
    assert changed_parts(snapshot, same) == []
    key = sorted(snapshot.obstacles)[0]
    fewer = dict(snapshot.obstacles)
    removed = fewer.pop(key)
    assert changed_parts(snapshot, snapshot.with_obstacles(fewer)) == list(removed)
    terrain = snapshot.terrain
    assert terrain is not None
    copy = Heightfield(terrain.origin, terrain.cell_size, terrain.heights.copy())
    assert changed_parts(snapshot, snapshot.with_terrain(copy)) == []  # equal heights: nothing changed
    raised = Heightfield(terrain.origin, terrain.cell_size, terrain.heights + 1.0)
    assert changed_parts(snapshot, snapshot.with_terrain(raised)) is None  # terrain changed: check all
