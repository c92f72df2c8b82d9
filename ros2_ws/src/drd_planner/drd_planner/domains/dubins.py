"""Shortest Dubins paths between planar poses and their sampling at a fixed arc-length spacing.

A Dubins path joins two poses (x, y, heading) by at most three segments: left arcs (L) and right arcs
(R) of the turning radius and straight lines (S). The shortest of the six words LSL, RSR, LSR, RSL,
RLR, LRL is optimal (Dubins 1957). Word lengths use the closed forms of Shkel & Lumelsky (2001) in
coordinates scaled by the turning radius; every candidate is integrated and kept only if it really ends
at the goal pose, so a wrong closed form can never produce a wrong path.

Units: positions and lengths in the caller's length unit, headings in radians counter-clockwise from +x.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from drd_planner.arrays import FloatArray
from drd_planner.exceptions import ProblemError

Pose = tuple[float, float, float]

__all__ = ["DubinsPath", "shortest_dubins_path"]

_TWO_PI = 2.0 * math.pi
_END_TOL = 1e-9  # relative end-pose tolerance (times the path scale) for accepting a word
_ROOT_TOL = 1e-10  # tangent cases: tiny negative squares / cosines beyond 1 from rounding still count
_CURVATURE = {"L": 1.0, "S": 0.0, "R": -1.0}


def _mod2pi(angle: float) -> float:
    """``angle`` in [0, 2 pi), with values within 1e-12 of a full turn mapped to 0."""
    out = math.fmod(angle, _TWO_PI)
    if out < 0.0:
        out += _TWO_PI
    return 0.0 if _TWO_PI - out < 1e-12 else out


@dataclass(frozen=True)
class DubinsPath:
    """A Dubins path: a start pose, a three-letter word and the three segment lengths.

    Attributes:
        start: (x, y, heading) start pose.
        word: e.g. ``"LSL"``; letter i is the type of segment i.
        segments: the three segment lengths (length unit, >= 0).
        radius: turning radius (length unit, > 0).
    """

    start: Pose
    word: str
    segments: tuple[float, float, float]
    radius: float

    @property
    def length(self) -> float:
        """Total length (length unit)."""
        return float(sum(self.segments))

    def poses_at(self, s: npt.ArrayLike) -> FloatArray:
        """Poses at arc lengths ``s`` (K,) in [0, length]: (K, 3) x, y, heading (heading in [0, 2 pi))."""
        arc = np.clip(np.asarray(s, dtype=np.float64).ravel(), 0.0, self.length)
        out = np.empty((arc.size, 3), dtype=np.float64)
        x, y, h = self.start
        offset = 0.0
        for letter, seg in zip(self.word, self.segments, strict=True):
            end = offset + seg
            mask = (arc >= offset) & (arc <= end)
            out[mask] = _advance(x, y, h, letter, arc[mask] - offset, self.radius)
            x, y, h = (float(v) for v in _advance(x, y, h, letter, np.array([seg]), self.radius)[0])
            offset = end
        out[:, 2] = np.mod(out[:, 2], _TWO_PI)
        return out

    def end_pose(self) -> FloatArray:
        """(3,) pose at the end of the path."""
        return np.asarray(self.poses_at(np.array([self.length]))[0], dtype=np.float64)

    def sample(self, spacing: float) -> FloatArray:
        """(K, 3) poses at K = ceil(length / spacing) + 1 evenly spaced arc lengths, both ends included.

        Consecutive samples are at most ``spacing`` apart along the path (and so in the plane).
        """
        if not spacing > 0:
            raise ProblemError(f"sample spacing must be positive, got {spacing}")
        count = max(2, math.ceil(self.length / spacing - 1e-9) + 1)
        return self.poses_at(np.linspace(0.0, self.length, count))


def _advance(x: float, y: float, h: float, letter: str, s: FloatArray, radius: float) -> FloatArray:
    """(K, 3) poses after moving ``s`` (K,) along one segment of type ``letter`` from (x, y, h)."""
    k = _CURVATURE[letter]
    if k == 0.0:
        return np.stack([x + s * math.cos(h), y + s * math.sin(h), np.full(s.shape, h)], axis=1)
    turn = k * s / radius
    hs = h + turn
    px = x + k * radius * (np.sin(hs) - math.sin(h))
    py = y - k * radius * (np.cos(hs) - math.cos(h))
    return np.stack([px, py, hs], axis=1)


def _word_parameters(word: str, a: float, b: float, d: float) -> tuple[float, float, float] | None:
    """Normalised segment lengths (t, p, q) of ``word`` or None when it does not exist (Shkel & Lumelsky)."""
    sa, sb, ca, cb = math.sin(a), math.sin(b), math.cos(a), math.cos(b)
    cab = math.cos(a - b)
    if word == "LSL":
        p2 = 2.0 + d * d - 2.0 * cab + 2.0 * d * (sa - sb)
        if p2 < -_ROOT_TOL:
            return None
        tmp = math.atan2(cb - ca, d + sa - sb)
        return _mod2pi(-a + tmp), math.sqrt(max(p2, 0.0)), _mod2pi(b - tmp)
    if word == "RSR":
        p2 = 2.0 + d * d - 2.0 * cab + 2.0 * d * (sb - sa)
        if p2 < -_ROOT_TOL:
            return None
        tmp = math.atan2(ca - cb, d - sa + sb)
        return _mod2pi(a - tmp), math.sqrt(max(p2, 0.0)), _mod2pi(-b + tmp)
    if word == "LSR":
        p2 = -2.0 + d * d + 2.0 * cab + 2.0 * d * (sa + sb)
        if p2 < -_ROOT_TOL:
            return None
        p = math.sqrt(max(p2, 0.0))
        tmp = math.atan2(-ca - cb, d + sa + sb) - math.atan2(-2.0, p)
        return _mod2pi(-a + tmp), p, _mod2pi(-b + tmp)
    if word == "RSL":
        p2 = -2.0 + d * d + 2.0 * cab - 2.0 * d * (sa + sb)
        if p2 < -_ROOT_TOL:
            return None
        p = math.sqrt(max(p2, 0.0))
        tmp = math.atan2(ca + cb, d - sa - sb) - math.atan2(2.0, p)
        return _mod2pi(a - tmp), p, _mod2pi(b - tmp)
    if word == "RLR":
        c = (6.0 - d * d + 2.0 * cab + 2.0 * d * (sa - sb)) / 8.0
        if abs(c) > 1.0 + _ROOT_TOL:
            return None
        p = _mod2pi(_TWO_PI - math.acos(max(-1.0, min(1.0, c))))
        t = _mod2pi(a - math.atan2(ca - cb, d - sa + sb) + p / 2.0)
        return t, p, _mod2pi(a - b - t + p)
    # LRL
    c = (6.0 - d * d + 2.0 * cab + 2.0 * d * (sb - sa)) / 8.0
    if abs(c) > 1.0 + _ROOT_TOL:
        return None
    p = _mod2pi(_TWO_PI - math.acos(max(-1.0, min(1.0, c))))
    t = _mod2pi(-a - math.atan2(ca - cb, d + sa - sb) + p / 2.0)
    return t, p, _mod2pi(b - a - t + p)


def shortest_dubins_path(start: Pose, goal: Pose, radius: float) -> DubinsPath:
    """The shortest Dubins path from ``start`` to ``goal`` (x, y, heading) with turning ``radius``.

    Raises:
        ProblemError: non-positive radius or non-finite poses.
    """
    if not radius > 0 or not math.isfinite(radius):
        raise ProblemError(f"turning radius must be positive and finite, got {radius}")
    if not all(math.isfinite(v) for v in (*start, *goal)):
        raise ProblemError(f"Dubins poses must be finite, got {start} -> {goal}")
    dx, dy = goal[0] - start[0], goal[1] - start[1]
    d = math.hypot(dx, dy) / radius
    theta = _mod2pi(math.atan2(dy, dx)) if d > 0 else 0.0
    a, b = _mod2pi(start[2] - theta), _mod2pi(goal[2] - theta)
    target = np.array([goal[0], goal[1]])
    scale = max(radius, math.hypot(dx, dy))
    best: DubinsPath | None = None
    for word in ("LSL", "RSR", "LSR", "RSL", "RLR", "LRL"):
        params = _word_parameters(word, a, b, d)
        if params is None:
            continue
        segs = (params[0] * radius, params[1] * radius, params[2] * radius)
        path = DubinsPath((float(start[0]), float(start[1]), float(start[2])), word, segs, float(radius))
        end = path.end_pose()
        heading_err = abs(math.remainder(float(end[2]) - goal[2], _TWO_PI))
        if np.abs(end[:2] - target).max() > _END_TOL * scale or heading_err > 1e-9:
            continue
        if best is None or path.length < best.length - 1e-12:
            best = path
    if best is None:  # pragma: no cover - some word always exists for finite poses
        raise ProblemError(f"no Dubins path from {start} to {goal}")
    return best
