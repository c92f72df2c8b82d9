#!/usr/bin/env python3
"""Geometry speed benchmark: edge checks per second on one core (a script that measures; not a unit test).

Helicopter-like edge: 30 spheres of radius 5 m along a 100 m segment, 20-150 m above the shared SRTM terrain
(read with 90 m cells; a synthetic ridge when the shared data is absent), in a scene with 10 sagging wires and 5
no-fly cylinders. Arm-like edge: 15 configurations x 60 spheres (radius 0.08 m at the base down to 0.03 m at the
hand) of a 4-joint arm with straight-line joint interpolation, against a table box and 20 clutter boxes and
cylinders. Each edge is timed with ``spheres_collide`` (all spheres in index order) and ``sphere_sweep_free``
(bisection order), and the blocked fraction is printed, since blocked edges stop early.

Usage: python scripts/experiments/bench_geometry.py [--edges 1000] [--seed 0] [--data ../shared/data]
"""

from __future__ import annotations

import argparse
import math
import os
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from drd_planner.geometry.scene import Scene
from drd_planner.geometry.shapes import Box, Cylinder, Pose
from drd_planner.geometry.terrain import Heightfield, read_esri_ascii
from drd_planner.geometry.wires import Wire

REPO_ROOT = Path(__file__).resolve().parents[2]
DEFAULT_DATA = Path(os.environ.get("DRD_SHARED_DATA", REPO_ROOT.parent / "shared" / "data"))


def load_terrain(data: Path) -> Heightfield:
    """The shared SRTM grid with 90 m cells, or a synthetic 144 x 144 ridge field when it is absent."""
    path = data / "terrain" / "srtm_front_range_144.asc"
    if path.is_file():
        return read_esri_ascii(path).with_cell_size(90.0)
    print(f"note: {path} absent; using a synthetic terrain")
    ii, jj = np.mgrid[0:144, 0:144]
    return Heightfield((0.0, 0.0), 90.0, 2500.0 + 300.0 * np.sin(ii / 9.0) * np.cos(jj / 13.0))


def helicopter_scene(rng: np.random.Generator, terrain: Heightfield) -> Scene:
    """Terrain + 10 wires (30 m above ground, 200-400 m spans, 8 m sag) + 5 vertical no-fly cylinders."""
    scene = Scene(margin=1.0)
    scene.add_terrain(terrain)
    x0, x1, y0, y1 = terrain.extent
    for _ in range(10):
        a = rng.uniform((x0 + 1000, y0 + 1000), (x1 - 1000, y1 - 1000))
        heading = rng.uniform(0, 2 * math.pi)
        b = a + rng.uniform(200, 400) * np.array([math.cos(heading), math.sin(heading)])
        ha, hb = terrain.height_at(np.array([a, b]))
        scene.add_wire(Wire((*a, ha + 30.0), (*b, hb + 30.0), sag=8.0, diameter=0.03))
    for _ in range(5):
        c = rng.uniform((x0, y0), (x1, y1))
        scene.add(Cylinder(rng.uniform(300, 800), 6000.0), Pose((*c, 3000.0)))
    return scene


def helicopter_edges(rng: np.random.Generator, terrain: Heightfield, count: int) -> list[np.ndarray]:
    """``count`` edges, each (30, 3): a 100 m segment in a random direction 20-150 m above the start's ground."""
    x0, x1, y0, y1 = terrain.extent
    edges = []
    t = np.linspace(0.0, 1.0, 30)[:, None]
    for _ in range(count):
        start_xy = rng.uniform((x0 + 200, y0 + 200), (x1 - 200, y1 - 200))
        ground = float(terrain.height_at(start_xy)[0])
        start = np.array([*start_xy, ground + rng.uniform(20, 150)])
        step = rng.normal(size=3) * np.array([1.0, 1.0, 0.2])
        edges.append(start + t * (100.0 * step / np.linalg.norm(step)))
    return edges


def arm_scene(rng: np.random.Generator) -> Scene:
    """A 1.6 x 1.0 x 0.05 m table (top at z = -0.1) and 20 clutter boxes/cylinders standing on it."""
    scene = Scene(margin=0.01)
    scene.add(Box((1.6, 1.0, 0.05)), Pose((0.5, 0.0, -0.125)), name="table")
    for k in range(20):
        xy = rng.uniform((0.2, -0.45), (1.25, 0.45))
        yaw = rng.uniform(0, math.pi)
        quat = (0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2))
        height = rng.uniform(0.05, 0.3)
        pose = Pose((*xy, -0.1 + height / 2), quat)
        if k % 2:
            scene.add(Box(rng.uniform(0.03, 0.12, size=3) * (1, 1, 0) + (0, 0, height)), pose)
        else:
            scene.add(Cylinder(rng.uniform(0.02, 0.06), height), pose)
    return scene


LINKS = np.array([0.35, 0.30, 0.25, 0.10])
SPHERES_PER_LINK = 15
ARM_RADII = np.linspace(0.08, 0.03, 4 * SPHERES_PER_LINK)


def arm_spheres(q: np.ndarray) -> np.ndarray:
    """(C, 60, 3) sphere centres of a yaw + 3-pitch arm at (C, 4) joint angles (base at the origin)."""
    out = np.zeros((q.shape[0], 4 * SPHERES_PER_LINK, 3))
    pitch = np.zeros(q.shape[0])
    start = np.zeros((q.shape[0], 3))
    s = (np.arange(SPHERES_PER_LINK) + 0.5) / SPHERES_PER_LINK
    for link in range(4):
        if link > 0:
            pitch = pitch + q[:, link]
        direction = np.stack([np.cos(q[:, 0]) * np.cos(pitch), np.sin(q[:, 0]) * np.cos(pitch), np.sin(pitch)], axis=1)
        if link == 0:
            direction = np.tile((0.0, 0.0, 1.0), (q.shape[0], 1))
        seg = slice(link * SPHERES_PER_LINK, (link + 1) * SPHERES_PER_LINK)
        out[:, seg] = start[:, None, :] + s[None, :, None] * (LINKS[link] * direction)[:, None, :]
        start = start + LINKS[link] * direction
    return out


def arm_edges(rng: np.random.Generator, count: int) -> list[np.ndarray]:
    """``count`` edges, each (15, 60, 3): straight joint-space motions between random reaching poses."""
    edges = []
    low = np.array([-1.2, 0.3, -1.6, -1.2])
    high = np.array([1.2, 1.2, 0.2, 0.6])
    for _ in range(count):
        qa = rng.uniform(low, high)
        qb = np.clip(qa + rng.normal(scale=0.25, size=4), low, high)
        t = np.linspace(0.0, 1.0, 15)[:, None]
        edges.append(arm_spheres(qa + t * (qb - qa)))
    return edges


def rate(label: str, check: Callable[[np.ndarray], bool], edges: list[np.ndarray]) -> float:
    """Run ``check`` on every edge (after a warm-up on 20); print and return edges per CPU second.

    CPU time of this process (``time.process_time``) is the one-core figure; wall time is printed too, but on a
    shared machine it also counts time spent waiting for a core.
    """
    for edge in edges[:20]:
        check(edge)
    wall0, cpu0 = time.perf_counter(), time.process_time()
    blocked = sum(1 for edge in edges if check(edge))
    cpu = time.process_time() - cpu0
    wall = time.perf_counter() - wall0
    per_second = len(edges) / cpu
    print(
        f"  {label:<36} {per_second:7.0f} edges/s CPU ({1e6 * cpu / len(edges):6.1f} us/edge; "
        f"wall {len(edges) / wall:7.0f} edges/s; {blocked / len(edges):5.1%} blocked)"
    )
    return per_second


def main() -> None:
    """Build both scenes, time both queries on the same edges, print edges per second."""
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--edges", type=int, default=1000)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--data", type=Path, default=DEFAULT_DATA)
    args = parser.parse_args()
    rng = np.random.default_rng(args.seed)

    terrain = load_terrain(args.data)
    t0 = time.perf_counter()
    heli = helicopter_scene(rng, terrain)
    print(f"helicopter scene: {len(heli)} obstacles, built in {time.perf_counter() - t0:.2f} s")
    heli_edges = helicopter_edges(rng, terrain, args.edges)
    rate("spheres_collide (30 x r=5 m)", lambda e: heli.spheres_collide(e, 5.0), heli_edges)
    rate("sphere_sweep_free (30 x r=5 m)", lambda e: not heli.sphere_sweep_free(e, 5.0), heli_edges)

    arm = arm_scene(rng)
    print(f"arm scene: {len(arm)} obstacles")
    edges = arm_edges(rng, args.edges)
    rate(
        "spheres_collide (15 x 60 spheres)",
        lambda e: arm.spheres_collide(e.reshape(-1, 3), np.tile(ARM_RADII, 15)),
        edges,
    )
    rate("sphere_sweep_free (15 x 60 spheres)", lambda e: not arm.sphere_sweep_free(e, ARM_RADII), edges)


if __name__ == "__main__":
    main()
