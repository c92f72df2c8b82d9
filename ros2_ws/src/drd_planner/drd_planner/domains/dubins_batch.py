"""Many shortest Dubins paths at once, sketched: their lengths and a few points along each, vectorised.

:func:`~drd_planner.domains.dubins.dubins_path` builds and verifies one path at a time (about a millisecond
each in Python); ranking thousands of candidate motions by what the training worlds say about them needs only
a handful of points along each. :func:`dubins_sketches` evaluates the six words' closed forms for all pairs at
once, keeps for each pair the shortest word whose integrated end pose is the target (as :func:`dubins_path`
does), and integrates the chosen paths at a few arc-length fractions (for a prior, a ranking).
:func:`dubins_samples` samples the same verified paths evenly along their whole length, as the motions that
are checked are sampled (a state joined to a lattice by 16 motions: about 1 ms instead of 10).

Units: the length unit of the poses and radius; headings in radians.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from drd_planner.arrays import FloatArray
from drd_planner.domains.dubins import _WORDS, _chord_frame, _word_segments, wrap_angle
from drd_planner.exceptions import ProblemError

__all__ = ["dubins_samples", "dubins_sketches"]

#: Turn direction of each word's three segments (+1 left, -1 right, 0 straight), in the order of ``_WORDS``.
_SIGNS = np.array([[1, 0, 1], [-1, 0, -1], [1, 0, -1], [-1, 0, 1], [-1, 1, -1], [1, -1, 1]], dtype=np.float64)
#: How far (times max(1, radius)) an integrated end may lie from the target for a word to count.
_END_TOLERANCE = 1e-6


def _integrate(
    starts: FloatArray, signs: FloatArray, segments: FloatArray, arcs: FloatArray, radius: float
) -> FloatArray:
    """(N, P, 3) poses at arc lengths ``arcs`` (N, P) along paths of (N, 3) segment lengths and turn signs."""
    x = np.repeat(starts[:, 0:1], arcs.shape[1], axis=1)
    y = np.repeat(starts[:, 1:2], arcs.shape[1], axis=1)
    h = np.repeat(starts[:, 2:3], arcs.shape[1], axis=1)
    done = np.zeros(arcs.shape[0])
    for k in range(3):
        local = np.clip(arcs - done[:, None], 0.0, segments[:, k : k + 1])
        sign = signs[:, k : k + 1]
        turn = sign != 0
        h1 = h + sign * local / radius
        x = np.where(turn, x + sign * radius * (np.sin(h1) - np.sin(h)), x + local * np.cos(h))
        y = np.where(turn, y - sign * radius * (np.cos(h1) - np.cos(h)), y + local * np.sin(h))
        h = h1
        done = done + segments[:, k]
    return np.stack([x, y, h], axis=-1)


def _shortest_words(
    starts: npt.ArrayLike, ends: npt.ArrayLike, radius: float
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """(N, 3) starts, (N, 3) turn signs and (N, 3) segment lengths of the shortest verified word of each pair.

    A word counts only when its integrated end pose is the target (as :func:`dubins_path` requires); where
    none does (never expected) the shortest closed form is taken as it is.
    """
    s, e, a, b, d = _chord_frame(starts, ends, radius)
    segments = _word_segments(a, b, d) * radius  # (6, N, 3)
    lengths = segments.sum(axis=2)  # (6, N), inf where a word does not exist
    valid = np.isfinite(lengths)
    for row in range(len(_WORDS)):  # a word counts only when its integrated end is the target
        ok = valid[row]
        if not ok.any():
            continue
        signs = np.broadcast_to(_SIGNS[row], (int(ok.sum()), 3))
        end = _integrate(s[ok], signs, segments[row, ok], lengths[row, ok][:, None], radius)[:, 0]
        near = np.hypot(end[:, 0] - e[ok, 0], end[:, 1] - e[ok, 1]) < _END_TOLERANCE * max(1.0, radius)
        heading = np.abs(wrap_angle(end[:, 2] - e[ok, 2])) < 1e-6
        valid[row, np.flatnonzero(ok)] = near & heading
    ranked = np.where(valid, lengths, np.inf)
    word = np.argmin(ranked, axis=0)
    fallback = ~np.isfinite(ranked[word, np.arange(s.shape[0])])  # never expected
    word[fallback] = np.argmin(lengths[:, fallback], axis=0)
    return s, _SIGNS[word], segments[word, np.arange(s.shape[0])]


def dubins_sketches(
    starts: npt.ArrayLike, ends: npt.ArrayLike, *, radius: float, fractions: npt.ArrayLike
) -> tuple[FloatArray, FloatArray]:
    """The shortest Dubins paths between (N, 3) pose pairs: lengths (N,) and poses (N, P, 3) at ``fractions``.

    Args:
        starts: (N, 3) or (3,) poses x, y, heading (rad).
        ends: (N, 3) or (3,) poses.
        radius: turning radius (length unit, > 0).
        fractions: (P,) arc-length fractions in [0, 1] at which each path is sampled.

    Returns:
        (N,) path lengths and (N, P, 3) poses (x, y, heading wrapped to [-pi, pi)).
    """
    s, signs, segments = _shortest_words(starts, ends, radius)
    length = segments.sum(axis=1)
    arcs = length[:, None] * np.clip(np.asarray(fractions, dtype=np.float64), 0.0, 1.0)[None, :]
    poses = _integrate(s, signs, segments, arcs, radius)
    poses[..., 2] = wrap_angle(poses[..., 2])
    return np.asarray(length, dtype=np.float64), poses


def dubins_samples(
    starts: npt.ArrayLike, ends: npt.ArrayLike, *, radius: float, spacing: float
) -> tuple[FloatArray, list[FloatArray]]:
    """The shortest Dubins paths between (N, 3) pose pairs, each sampled evenly: lengths and poses, vectorised.

    The paths of :func:`dubins_path` (the same verified words), each sampled at K = ceil(length / spacing) + 1
    (at least 2) evenly spaced arc lengths, both ends included, as
    :meth:`~drd_planner.domains.dubins.DubinsPath.sample_evenly` does; all pairs integrated at once.

    Args:
        starts: (N, 3) or (3,) poses x, y, heading (rad).
        ends: (N, 3) or (3,) poses.
        radius: turning radius (length unit, > 0).
        spacing: largest arc length between consecutive samples (length unit, > 0).

    Returns:
        (N,) path lengths and, per pair, its (K, 3) poses (x, y, heading wrapped to [-pi, pi)).

    Raises:
        ProblemError: a radius or spacing that is not positive and finite.
    """
    if not (np.isfinite(spacing) and spacing > 0):
        raise ProblemError(f"sample spacing must be positive, got {spacing}")
    s, signs, segments = _shortest_words(starts, ends, radius)
    length = segments.sum(axis=1)
    counts = np.maximum(2, np.ceil(length / spacing - 1e-9).astype(np.int64) + 1)
    steps = np.arange(int(counts.max()) if counts.size else 0, dtype=np.float64)
    # Row i holds its K_i arc lengths as np.linspace(0, length_i, K_i) makes them (the same numbers), padded
    # with its end (cut off again below).
    last = (counts - 1)[:, None]
    arcs = np.where(steps[None, :] >= last, length[:, None], steps[None, :] * (length[:, None] / last))
    poses = _integrate(s, signs, segments, arcs, radius)
    poses[..., 2] = wrap_angle(poses[..., 2])
    return np.asarray(length, dtype=np.float64), [poses[i, : counts[i]] for i in range(s.shape[0])]
