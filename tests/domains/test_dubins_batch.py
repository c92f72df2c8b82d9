"""Many shortest Dubins paths sketched at once agree with the one-at-a-time verified paths."""

from __future__ import annotations

import numpy as np
import pytest

from drd_planner.domains.dubins import dubins_path
from drd_planner.domains.dubins_batch import dubins_samples, dubins_sketches
from drd_planner.exceptions import ProblemError


def test_sketches_match_the_verified_paths_word_for_word() -> None:
    rng = np.random.default_rng(0)
    n = 400
    starts = np.column_stack([rng.uniform(-900, 900, (n, 2)), rng.uniform(-np.pi, np.pi, n)])
    ends = np.column_stack([rng.uniform(-900, 900, (n, 2)), rng.uniform(-np.pi, np.pi, n)])
    ends[:20, :2] = starts[:20, :2]  # turning on the spot: loops only (CCC words)
    ends[20:30, :2] = starts[20:30, :2] + 50.0  # inside the turning circle
    fractions = np.linspace(0.0, 1.0, 8)
    lengths, poses = dubins_sketches(starts, ends, radius=300.0, fractions=fractions)
    assert lengths.shape == (n,)
    assert poses.shape == (n, 8, 3)
    for i in range(n):
        path = dubins_path(tuple(starts[i]), tuple(ends[i]), radius=300.0)
        assert lengths[i] == pytest.approx(path.length, abs=1e-6)
        expected = path.sample(fractions * path.length)
        assert np.allclose(poses[i, :, :2], expected[:, :2], atol=1e-6)
        assert np.allclose(np.cos(poses[i, :, 2] - expected[:, 2]), 1.0)
    assert np.allclose(poses[:, 0, :2], starts[:, :2])
    assert np.allclose(poses[:, -1, :2], ends[:, :2])


def test_one_start_broadcasts_and_a_bad_radius_is_refused() -> None:
    ends = np.array([[500.0, 0.0, 0.0], [0.0, 500.0, np.pi / 2]])
    lengths, poses = dubins_sketches(np.zeros(3), ends, radius=100.0, fractions=[0.0, 1.0])
    assert lengths[0] == pytest.approx(500.0)
    assert poses.shape == (2, 2, 3)
    with pytest.raises(ProblemError, match="turning radius"):
        dubins_sketches(np.zeros(3), ends, radius=0.0, fractions=[0.5])


def test_even_samples_are_the_verified_paths_sampled_evenly() -> None:
    rng = np.random.default_rng(1)
    n = 300
    starts = np.column_stack([rng.uniform(-900, 900, (n, 2)), rng.uniform(-np.pi, np.pi, n)])
    ends = np.column_stack([rng.uniform(-900, 900, (n, 2)), rng.uniform(-np.pi, np.pi, n)])
    ends[:15, :2] = starts[:15, :2]  # loops only
    ends[15:20] = starts[15:20]  # the same pose: a path of length 0, still two samples
    lengths, poses = dubins_samples(starts, ends, radius=300.0, spacing=7.0)
    assert len(poses) == n
    for i in range(n):
        path = dubins_path(tuple(starts[i]), tuple(ends[i]), radius=300.0)
        expected = path.sample_evenly(7.0)
        assert lengths[i] == pytest.approx(path.length, abs=1e-9)
        assert poses[i].shape == expected.shape
        assert np.allclose(poses[i][:, :2], expected[:, :2], rtol=0.0, atol=1e-9)
        assert np.allclose(np.cos(poses[i][:, 2] - expected[:, 2]), 1.0, rtol=0.0, atol=1e-12)
        assert np.all(np.abs(poses[i][:, 2]) <= np.pi)
        steps = np.hypot(*np.diff(poses[i][:, :2], axis=0).T)
        assert steps.max() <= 7.0 + 1e-9
    with pytest.raises(ProblemError, match="spacing"):
        dubins_samples(starts, ends, radius=300.0, spacing=0.0)
    empty_lengths, empty = dubins_samples(np.zeros((0, 3)), np.zeros((0, 3)), radius=300.0, spacing=5.0)
    assert empty_lengths.shape == (0,)
    assert empty == []
