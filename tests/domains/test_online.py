"""The online domain interface: every registered domain implements it; the defaults; the typed registry."""

from __future__ import annotations

import numpy as np
import pytest

from drd_planner.domains.base import DOMAIN_CLASSES, LatticeMembers, domain_from_spec
from drd_planner.domains.online import OnlineDomain
from drd_planner.domains.planar import PlanarDomain
from drd_planner.exceptions import PlanningError, ProblemError

HELI = {"lattice": {"x_range": [0.0, 300.0], "y_range": [-100.0, 100.0], "goal": [300.0, 0.0]}}


def test_the_registry_maps_names_to_domain_classes() -> None:
    assert sorted(DOMAIN_CLASSES) == ["arm", "helicopter", "planar", "se2"]
    assert DOMAIN_CLASSES["planar"] is PlanarDomain
    assert "ocean" not in DOMAIN_CLASSES
    with pytest.raises(ProblemError, match="unknown domain 'ocean'; known: arm, helicopter, planar, se2"):
        domain_from_spec("ocean")


@pytest.mark.parametrize("name", ["planar", "se2"])
def test_point_domains_use_the_defaults(name: str) -> None:
    domain = domain_from_spec(name)
    assert isinstance(domain, OnlineDomain)
    assert domain.margin == 0.0
    assert domain.resolution == 0.0
    assert domain.robot is None
    assert domain.joint_names == ()
    assert domain.periodic_dims == ()
    assert domain.position_goals == "none"
    assert not domain.has_sweep_model
    assert domain.robot_loader() is None
    assert domain.sweep_robot(None) is None
    assert domain.world_model_params(domain.world_models[0]) == {}
    states = np.array([[0.1, 0.2, 0.3], [0.4, 0.5, 0.6]])
    np.testing.assert_array_equal(domain.positions(states), states[:, :3])
    with pytest.raises(PlanningError, match="no sweep model"):
        domain.sweep_spheres(None, [0], None)  # type: ignore[arg-type]
    with pytest.raises(PlanningError, match="no position goals"):
        domain.state_from_position([0.0, 0.0, 0.0], 0.0)


@pytest.mark.parametrize(("name", "spec"), [("se2", {}), ("helicopter", HELI)])
def test_lattice_domains_read_their_graph_from_the_lattice(name: str, spec: dict[str, object]) -> None:
    domain = domain_from_spec(name, spec)
    assert isinstance(domain, LatticeMembers)
    lattice = domain.lattice
    assert domain.graph is lattice.graph
    assert (domain.start, domain.goal) == (lattice.start, lattice.goal)
    assert domain.start != domain.goal


def test_the_helicopter_states_are_poses_with_a_periodic_heading() -> None:
    domain = domain_from_spec("helicopter", HELI)
    assert isinstance(domain, OnlineDomain)
    assert domain.periodic_dims == (3,)
    assert domain.position_goals == "pose"
    assert domain.has_sweep_model
    assert domain.margin == 2.0
    assert domain.joint_names == ()
    assert domain.robot_loader() is None
    np.testing.assert_allclose(domain.state_from_position([1.0, 2.0, 3.0], 4.0), [1.0, 2.0, 3.0, 4.0 - 2 * np.pi])
    assert domain.world_model_params("wires") == domain.spec()["models"]["wires"]

    class Source:
        def edge_states(self, edge: int) -> np.ndarray:
            return domain.lattice.trajectory(edge)

        def motion_states(self, edge: int) -> None:
            return None

    ((centres, reach),) = domain.sweep_spheres(Source(), [0], None)
    np.testing.assert_array_equal(centres, domain.lattice.trajectory(0)[:, :3])
    assert np.all(reach >= domain.vehicle_radius + 0.5 * domain.lattice.params.sample_spacing)


@pytest.mark.parametrize(
    ("name", "spec", "columns"),
    [
        ("planar", {}, "x, y (unit square)"),
        ("se2", {}, "x, y (unit square); heading rad"),
        ("helicopter", HELI, "x, y, z m; heading rad"),
    ],
)
def test_pose_domains_capabilities_say_the_node_plans_poses_from_odometry(
    name: str, spec: dict[str, object], columns: str
) -> None:
    domain = domain_from_spec(name, spec)
    assert isinstance(domain, OnlineDomain)
    assert not domain.plans_joint_goals
    assert domain.robot_state_topic == "odom"
    assert not domain.publishes_joint_trajectory
    assert not domain.needs_robot_description
    assert domain.state_columns == columns
