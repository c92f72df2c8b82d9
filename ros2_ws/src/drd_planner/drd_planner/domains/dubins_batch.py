"""Many shortest Dubins paths at once, sketched: their lengths and a few points along each, vectorised.

:func:`~drd_planner.domains.dubins.dubins_path` builds and verifies one path at a time (about a millisecond
each in Python); ranking thousands of candidate motions by what the training worlds say about them needs only
a handful of points along each. :func:`dubins_sketches` evaluates the six words' closed forms for all pairs at
once, keeps for each pair the shortest word whose integrated end pose is the target (as :func:`dubins_path`
does), and integrates the chosen paths at a few arc-length fractions. The points are for estimates only (a
prior, a ranking); a motion that is checked is always built by :func:`dubins_path`.

Units: the length unit of the poses and radius; headings in radians.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from drd_planner.arrays import FloatArray
from drd_planner.domains.dubins import _WORDS, _chord_frame, _word_segments, wrap_angle

__all__ = ["dubins_sketches"]

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
    pick = np.arange(s.shape[0])
    length = ranked[word, pick]
    fallback = ~np.isfinite(length)  # never expected: take the shortest closed form as it is
    word[fallback] = np.argmin(lengths[:, fallback], axis=0)
    length = lengths[word, pick]
    arcs = length[:, None] * np.clip(np.asarray(fractions, dtype=np.float64), 0.0, 1.0)[None, :]
    poses = _integrate(s, _SIGNS[word], segments[word, pick], arcs, radius)
    poses[..., 2] = wrap_angle(poses[..., 2])
    return np.asarray(length, dtype=np.float64), poses
