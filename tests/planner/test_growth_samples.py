"""Where growth puts new vertices and edges: known-reachable parts, frontiers, samples, joins, the static filter."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from drd_planner.planner.growth_samples import (
    SampleMix,
    bridge_pairs,
    draw_states,
    frontier,
    known_reachable,
    nearest_pairs,
    parent_pairs,
    straight_motions,
)
from drd_planner.planner.state_sampler import StateSampler
from drd_planner.planner.straight_connector import StraightConnector


class DiskSampler:
    """The unit square with a forbidden disk (centre (0.5, 0.5), radius 0.2): a 2D domain's static rules."""

    lower = np.zeros(2)
    upper = np.ones(2)

    def valid(self, states: npt.ArrayLike) -> np.ndarray:
        q = np.asarray(states, dtype=np.float64).reshape(-1, 2)
        inside = np.all((q >= 0) & (q <= 1), axis=1)
        return inside & (np.linalg.norm(q - 0.5, axis=1) > 0.2)

    def refusal(self, state: npt.ArrayLike, label: str) -> str | None:
        return None if bool(self.valid(state)[0]) else f"{label} is in the disk"


def test_known_reachable_follows_free_edges_only() -> None:
    edges = np.array([[0, 1], [1, 2], [2, 3], [3, 4]])
    free = np.array([True, True, False, True])
    assert sorted(known_reachable(5, edges, free, 0).tolist()) == [0, 1, 2]
    assert sorted(known_reachable(5, edges, free, 4).tolist()) == [3, 4]
    blocked = ~free
    assert frontier(np.array([0, 1, 2]), edges, blocked, 5).tolist() == [2]  # 2 touches the blocked edge
    assert sorted(frontier(np.array([0, 1]), edges, blocked, 5).tolist()) == [0, 1]  # none does: all of it


def test_draw_states_keeps_valid_ones_with_their_parents() -> None:
    sampler = DiskSampler()
    assert isinstance(sampler, StateSampler)
    states = np.array([[0.1, 0.1], [0.9, 0.9], [0.1, 0.9]])
    mix = SampleMix(200, 0.3, 0.3, 0.2, (0.02, 0.1))
    drawn, parents = draw_states(np.random.default_rng(0), sampler, states, (np.array([0]), np.array([1, 2])), mix)
    assert 0 < drawn.shape[0] <= 200
    assert parents.shape == (drawn.shape[0], 2)
    assert sampler.valid(drawn).all()
    gaussian = (parents[:, 0] >= 0) & (parents[:, 1] < 0)
    bridges = parents[:, 1] >= 0
    uniform = parents[:, 0] < 0
    assert gaussian.any()
    assert bridges.any()
    assert uniform.any()
    near = np.linalg.norm(drawn[gaussian] - states[parents[gaussian, 0]], axis=1)
    assert np.median(near) < 0.2  # Gaussian samples stay near their centre
    again, _ = draw_states(np.random.default_rng(0), sampler, states, (np.array([0]), np.array([1, 2])), mix)
    np.testing.assert_array_equal(drawn, again)  # the same seed, the same samples


def test_joins_are_new_pairs_within_reach() -> None:
    states = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [0.1, 0.0], [0.9, 0.1]])
    new = np.array([3, 4])
    usable = np.array([True, True, False, True, True])  # vertex 2 is blocked: never joined
    pairs = nearest_pairs(states, new, usable, neighbours=2, reach=0.5)
    assert {tuple(p) for p in pairs.tolist()} == {(0, 3), (1, 4)}
    assert parent_pairs(new, np.array([[0, -1], [1, 2]]), states, reach=0.5).tolist() == [[0, 3], [1, 4]]
    bridges = bridge_pairs(states, np.array([0, 3]), np.array([1, 4]), count=1, reach=2.0)
    assert bridges.tolist() == [[3, 4]]  # the nearest pair across the two sides


def test_straight_motions_drop_statically_invalid_ones() -> None:
    states = np.array([[0.1, 0.5], [0.9, 0.5], [0.1, 0.1], [0.9, 0.1]])
    connector = StraightConnector(reach=2.0, resolution=0.05)
    kept, motions = straight_motions(states, np.array([[0, 1], [2, 3]]), connector=connector, sampler=DiskSampler())
    assert kept.tolist() == [[2, 3]]  # 0 -> 1 crosses the disk
    assert motions[0].shape[1] == 2
    assert np.allclose(motions[0][0], states[2])
    assert np.allclose(motions[0][-1], states[3])
    assert np.linalg.norm(np.diff(motions[0], axis=0), axis=1).max() <= 0.05 + 1e-12
