"""Tests of the helicopter domain seam: registry, spec round trip, protocol, metadata."""

from __future__ import annotations

import json

import numpy as np
import pytest

from drd_planner.domains.base import Domain, EdgeChecker, domain_from_spec
from drd_planner.domains.helicopter import HelicopterDomain
from drd_planner.exceptions import ProblemError
from drd_planner.geometry.terrain import Heightfield

SMALL = {
    "lattice": {"x_range": [0, 400], "goal": [400, 0], "z_levels": [50, 80], "sample_spacing": 4.0},
    "vehicle_radius": 4.0,
    "margin": 1.0,
    "wire_segments": None,
    "models": {"wires": {"lines": [1, 1], "nofly": [{"center": [200, 100], "radius": 30}]}},
}


@pytest.fixture(scope="module")
def domain() -> HelicopterDomain:
    built = domain_from_spec("helicopter")
    assert isinstance(built, HelicopterDomain)
    return built


def test_registry_builds_the_domain_and_it_implements_the_protocol(domain: HelicopterDomain) -> None:
    assert isinstance(domain, Domain)
    assert domain.name == "helicopter"
    assert domain.world_models == ("wires", "canyon", "terrain", "corridors")
    checker = domain.checker(domain.make_world("wires", 0))
    assert isinstance(checker, EdgeChecker)
    assert isinstance(checker.check(0), bool)
    assert checker.check_many([0, 1]).dtype == bool


def test_default_spec_round_trips_through_the_registry(domain: HelicopterDomain) -> None:
    spec = domain.spec()
    text = json.dumps(spec)  # JSON-able
    again = domain_from_spec("helicopter", json.loads(text))
    assert again.spec() == spec
    assert np.array_equal(again.graph.edges, domain.graph.edges)
    assert np.array_equal(again.graph.lengths, domain.graph.lengths)
    assert (again.start, again.goal) == (domain.start, domain.goal)


def test_custom_spec_round_trips_and_is_used() -> None:
    domain = domain_from_spec("helicopter", SMALL)
    assert isinstance(domain, HelicopterDomain)
    spec = domain.spec()
    assert domain_from_spec("helicopter", json.loads(json.dumps(spec))).spec() == spec
    assert spec["vehicle_radius"] == 4.0
    assert spec["wire_segments"] is None
    states = domain.graph.vertex_states
    assert states is not None
    assert states[domain.goal].tolist() == [400.0, 0.0, 80.0, 0.0]  # middle of two levels = the upper one
    world = domain.make_world("wires", 0)
    assert len(world.nofly) == 1
    assert world.nofly[0].center == (200.0, 100.0)
    # same spec, same worlds, same answers
    other = domain_from_spec("helicopter", spec)
    edges = np.arange(domain.graph.num_edges)
    assert np.array_equal(
        domain.checker(world).check_many(edges), other.checker(other.make_world("wires", 0)).check_many(edges)
    )


def test_edge_trajectories_and_check_metadata(domain: HelicopterDomain) -> None:
    trajectories = domain.edge_trajectories()
    assert len(trajectories) == domain.graph.num_edges
    assert all(t.ndim == 2 and t.shape[1] == 4 and t.shape[0] >= 2 for t in trajectories)
    meta = domain.check_metadata()
    json.dumps(meta)
    assert meta["vehicle_radius_m"] == 5.0
    assert meta["margin_m"] == 2.0
    assert meta["effective_radius_m"] == 7.0
    assert meta["max_sample_step_m"] <= meta["sample_spacing_m"] + 1e-9
    assert meta["sample_spacing_m"] <= meta["vehicle_radius_m"]
    assert 20 <= meta["samples_per_edge"]["mean"] <= 40


@pytest.mark.parametrize(
    ("spec", "message"),
    [
        ({"robot": 1}, "unknown helicopter spec keys"),
        ({"vehicle_radius": 0}, "vehicle_radius"),
        ({"margin": -1}, "margin"),
        ({"vehicle_radius": 2.0}, "exceeds the vehicle radius"),
        ({"wire_segments": 0}, "wire_segments"),
        ({"wire_segments": "many"}, "wire_segments"),
        ({"models": {"ocean": {}}}, "unknown helicopter world models"),
        ({"models": {"wires": {"sag": [-1, 2]}}}, "sag"),
        ({"lattice": {"xy_spacing": "far"}}, "xy_spacing"),
        ({"lattice": []}, "lattice"),
    ],
)
def test_bad_specs_are_refused(spec: dict[str, object], message: str) -> None:
    with pytest.raises(ProblemError, match=message):
        domain_from_spec("helicopter", spec)


def test_checker_refuses_other_worlds(domain: HelicopterDomain) -> None:
    with pytest.raises(ProblemError, match="HelicopterWorld or a Scene"):
        domain.checker(np.zeros((3, 4)))
    with pytest.raises(ProblemError, match="unknown helicopter world model"):
        domain.make_world("ocean", 0)


def test_a_terrain_elsewhere_or_in_another_datum_is_not_the_lattices(domain: HelicopterDomain) -> None:
    """Issue 33 item 17: the world's own terrain fits; moved off the lattice or raised above it, it does not."""
    terrain = domain.make_world("wires", 3).terrain
    assert domain.terrain_mismatch(terrain) is None
    far = Heightfield(terrain.origin + 20_000.0, terrain.cell_size, terrain.heights)
    reason = domain.terrain_mismatch(far)
    assert reason is not None
    assert "do not overlap" in reason
    assert "the prior's lattice x [0, 700] m" in reason
    above_sea = Heightfield(terrain.origin, terrain.cell_size, terrain.heights + 1600.0)  # heights above MSL
    reason = domain.terrain_mismatch(above_sea)
    assert reason is not None
    assert "below it" in reason
    assert "not above sea level" in reason
    # Partly over the lattice, partly beyond it: the part over it decides, and it fits.
    shifted = Heightfield(terrain.origin + np.array([600.0, 0.0]), terrain.cell_size, terrain.heights)
    assert domain.terrain_mismatch(shifted) is None
