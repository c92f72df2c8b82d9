"""The arm's sweep model: sphere speed bounds and the grown spheres of edges and motions."""

from __future__ import annotations

import numpy as np
import pytest

from drd_planner.domains.arm import ArmDomain
from drd_planner.domains.arm_sweep import sphere_rates
from drd_planner.domains.online import OnlineDomain


@pytest.fixture(scope="module")
def domain(small_arm: ArmDomain) -> ArmDomain:
    return small_arm


def test_rates_bound_how_fast_each_sphere_moves(domain: ArmDomain) -> None:
    rates = sphere_rates(domain.robot)
    assert rates.shape == (domain.robot.dof, domain.robot.spheres.count)
    assert np.all(rates >= 0)
    base = domain.robot.spheres.frame_index == 0
    assert np.all(rates[:, base] == 0)  # the fixed base spheres never move
    q = np.array(domain.graph.vertex_states[:2])  # type: ignore[index]
    step = np.zeros_like(q[0])
    step[0] = 1e-3
    moved = np.linalg.norm(domain.robot.sphere_centres(q + step) - domain.robot.sphere_centres(q), axis=2)
    assert np.all(moved <= 1e-3 * rates[0] + 1e-9)


def test_edge_spheres_hold_every_checked_configuration(domain: ArmDomain) -> None:
    assert isinstance(domain, OnlineDomain)
    assert domain.has_sweep_model
    assert domain.position_goals == "vertex"
    assert domain.joint_names == domain.robot.chain.joint_names
    assert domain.sweep_robot(domain.robot) is None

    class Source:
        def edge_states(self, edge: int) -> np.ndarray:
            raise AssertionError("the arm reads graph edges from its roadmap")

        def motion_states(self, edge: int) -> np.ndarray | None:
            return motion if edge == domain.graph.num_edges else None

    states = domain.graph.vertex_states
    assert states is not None
    motion = np.linspace(states[0], states[0] + 0.02, 3)
    spheres = domain.sweep_spheres(Source(), [0, domain.graph.num_edges], None)
    count = domain.robot.spheres.count
    interior = domain.samples.configurations(domain.graph, 0).shape[0]
    assert spheres[0][0].shape == ((interior + 2) * count, 3)
    assert spheres[0][1].shape == ((interior + 2) * count,)
    assert spheres[1][0].shape == (3 * count, 3)
    np.testing.assert_allclose(spheres[1][0][:count], domain.robot.sphere_centres(motion[:1])[0])
    assert np.all(spheres[1][1] >= np.tile(domain.robot.spheres.radii, 3))


def test_under_the_mesh_model_the_sweep_spheres_grow_to_hold_the_meshes(
    domain: ArmDomain, small_arm_meshes: ArmDomain
) -> None:
    meshes = small_arm_meshes

    class Source:
        def edge_states(self, edge: int) -> np.ndarray:
            raise AssertionError("the arm reads graph edges from its roadmap")

        def motion_states(self, edge: int) -> np.ndarray | None:
            return None

    ((centres, reach),) = domain.sweep_spheres(Source(), [0], None)
    ((mesh_centres, mesh_reach),) = meshes.sweep_spheres(Source(), [0], None)
    np.testing.assert_array_equal(mesh_centres, centres)
    assert np.all(mesh_reach >= reach)
    assert float(np.max(mesh_reach - reach)) > 0.01
