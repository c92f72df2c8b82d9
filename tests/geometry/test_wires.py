"""Wires: parabolic sag, capsule chains that contain the curve, and probes against a scene."""

from __future__ import annotations

import math

import numpy as np
import pytest

from drd_planner.exceptions import GeometryError
from drd_planner.geometry.scene import Scene
from drd_planner.geometry.wires import Wire

WIRE = Wire((0.0, 0.0, 50.0), (200.0, 0.0, 50.0), sag=10.0, diameter=0.04)


def test_lowest_point_at_mid_span_is_sag_below_the_chord() -> None:
    points = WIRE.points(201)
    lowest = int(np.argmin(points[:, 2]))
    assert lowest == 100
    np.testing.assert_allclose(points[lowest], [100.0, 0.0, 40.0])
    np.testing.assert_allclose(points[[0, -1]], [[0.0, 0.0, 50.0], [200.0, 0.0, 50.0]])
    np.testing.assert_allclose(WIRE.point_at([0.25])[0], [50.0, 0.0, 50.0 - 4 * 10.0 * 0.25 * 0.75])


def test_sag_is_measured_from_the_chord_between_uneven_towers() -> None:
    wire = Wire((0.0, 0.0, 40.0), (0.0, 100.0, 60.0), sag=5.0, diameter=0.02)
    np.testing.assert_allclose(wire.point_at([0.5])[0], [0.0, 50.0, 50.0 - 5.0])


def test_probe_at_wire_height_between_towers_hits() -> None:
    scene = Scene()
    scene.add_wire(WIRE)
    for t in (0.1, 0.25, 0.5, 0.8):
        assert scene.spheres_collide(WIRE.point_at([t]), 0.5)
    assert scene.spheres_collide([[50.0, 0.4, 42.5]], 0.5)


def test_one_metre_above_the_sagging_wire_at_mid_span_misses_for_radius_below_one() -> None:
    scene = Scene()
    scene.add_wire(WIRE)
    assert not scene.spheres_collide([[100.0, 0.0, 41.0]], 0.9)
    assert scene.spheres_collide([[100.0, 0.0, 41.0]], 1.0)
    assert not scene.spheres_collide([[100.0, 0.0, 50.0]], 5.0)  # on the chord, above the sagging wire


def segment_distance(points: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distance from each of (K, 3) points to the segment a-b (a reference for the chain test)."""
    ab = b - a
    t = np.clip((points - a) @ ab / (ab @ ab), 0.0, 1.0)
    return np.linalg.norm(points - (a + t[:, None] * ab), axis=1)


@pytest.mark.parametrize("segments", [None, 1, 4, 40])
def test_capsule_chain_covers_the_curve_within_the_diameter(segments: int | None) -> None:
    chain = WIRE.capsule_chain(segments)
    n = WIRE.default_segments() if segments is None else segments
    assert len(chain) == n
    radius = chain[0][0].radius
    assert radius == pytest.approx(WIRE.diameter / 2.0 + WIRE.sag / n**2)
    curve = WIRE.points(2001)
    distances = []
    for capsule, pose in chain:
        half = pose.rotation()[:, 2] * capsule.length / 2.0
        distances.append(segment_distance(curve, pose.position - half, pose.position + half))
    nearest = np.min(distances, axis=0)
    # Every curve point lies within the chain, deep enough that the whole wire tube is inside it.
    assert np.all(nearest + WIRE.diameter / 2.0 <= radius + 1e-9)
    if segments is None:
        assert WIRE.sag / n**2 <= WIRE.diameter / 2.0  # default chain: off by at most the wire radius


def test_default_chain_misses_probes_two_diameters_off_the_curve() -> None:
    scene = Scene()
    scene.add_wire(WIRE)
    t = np.linspace(0.02, 0.98, 97)
    on_curve = WIRE.point_at(t)
    assert scene.spheres_collide_mask(on_curve, 1e-3).all()
    below = on_curve - [0.0, 0.0, 2.0 * WIRE.diameter + 1e-3]
    assert not scene.spheres_collide_mask(below, 1e-3).any()


def test_straight_wire_needs_one_capsule() -> None:
    wire = Wire((0.0, 0.0, 0.0), (10.0, 0.0, 0.0), sag=0.0, diameter=0.1)
    assert wire.default_segments() == 1
    ((capsule, pose),) = wire.capsule_chain()
    assert capsule.length == pytest.approx(10.0)
    assert capsule.radius == pytest.approx(0.05)
    np.testing.assert_allclose(pose.rotation()[:, 2], [1.0, 0.0, 0.0], atol=1e-12)


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (((0, 0, 0), (0, 0, 0), 1.0, 0.1), "differ"),
        (((0, 0, 0), (1, 0, 0), -1.0, 0.1), "sag"),
        (((0, 0, 0), (1, 0, 0), 1.0, 0.0), "diameter"),
        (((0, 0, 0), (1, 0, math.nan), 1.0, 0.1), "finite"),
    ],
)
def test_invalid_wires(args: tuple[object, object, float, float], message: str) -> None:
    with pytest.raises(GeometryError, match=message):
        Wire(*args)  # type: ignore[arg-type]


def test_invalid_parameters() -> None:
    with pytest.raises(GeometryError, match=r"\[0, 1\]"):
        WIRE.point_at([1.5])
    with pytest.raises(GeometryError, match="n >= 2"):
        WIRE.points(1)
    with pytest.raises(GeometryError, match="segments"):
        WIRE.capsule_chain(0)
    assert WIRE == Wire((0, 0, 50), (200, 0, 50), 10.0, 0.04)
    assert hash(WIRE) == hash(Wire((0, 0, 50), (200, 0, 50), 10.0, 0.04))
