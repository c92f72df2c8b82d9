"""Dubins curves: shortest paths of bounded curvature between planar poses, and their sampling.

A Dubins path joins two poses (x, y, heading) with at most three segments, each a left arc (L), a
right arc (R) of the turning radius, or a straight line (S). Of the six candidate words (LSL, RSR,
LSR, RSL, RLR, LRL) the shortest is optimal (Dubins 1957). The formulas follow Shkel & Lumelsky
(2001) in coordinates normalised by the turning radius.

Units: metres for positions and lengths, radians for headings (counter-clockwise from +x).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from drd_planner.arrays import FloatArray
from drd_planner.exceptions import ProblemError

__all__ = ["DubinsPath", "dubins_path", "wrap_angle"]

_TWO_PI = 2.0 * math.pi
_EPS = 1e-9  # tolerance of the normalised word equations (tangent cases)
_WORDS: tuple[str, ...] = ("LSL", "RSR", "LSR", "RSL", "RLR", "LRL")


def wrap_angle(angle: npt.ArrayLike) -> FloatArray:
    """Angles wrapped to [-pi, pi), any shape, radians."""
    a = np.asarray(angle, dtype=np.float64)
    return np.asarray(np.mod(a + math.pi, _TWO_PI) - math.pi, dtype=np.float64)


def _mod2pi(angle: float) -> float:
    """``angle`` in [0, 2 pi); values within 1e-9 of a full turn snap to 0 (no spurious loops)."""
    out = math.fmod(angle, _TWO_PI)
    if out < 0.0:
        out += _TWO_PI
    return 0.0 if out > _TWO_PI - 1e-9 else out


@dataclass(frozen=True)
class DubinsPath:
    """One Dubins path.

    Attributes:
        start: (x m, y m, heading rad) of the first pose.
        word: three letters from "LRS", e.g. "LSR".
        segments: lengths of the three segments in metres (arc lengths for L and R).
        radius: turning radius in metres.
    """

    start: tuple[float, float, float]
    word: str
    segments: tuple[float, float, float]
    radius: float

    @property
    def length(self) -> float:
        """Total length in metres."""
        return float(sum(self.segments))

    @property
    def turning(self) -> float:
        """Total absolute heading change along the path, radians."""
        return float(
            sum(seg / self.radius for kind, seg in zip(self.word, self.segments, strict=True) if kind != "S")
        )

    def sample(self, s: npt.ArrayLike) -> FloatArray:
        """Poses at arc lengths ``s`` (n,) in [0, length] m: (n, 3) as x m, y m, heading rad in [-pi, pi)."""
        arc = np.clip(np.asarray(s, dtype=np.float64).ravel(), 0.0, self.length)
        out = np.empty((arc.size, 3), dtype=np.float64)
        x, y, h = self.start
        done = 0.0
        remaining = np.ones(arc.size, dtype=bool)
        for index, (kind, seg) in enumerate(zip(self.word, self.segments, strict=True)):
            last = index == 2
            sel = remaining & ((arc <= done + seg) | last)
            local = arc[sel] - done
            px, py, ph = _advance(x, y, h, kind, local, self.radius)
            out[sel, 0], out[sel, 1], out[sel, 2] = px, py, ph
            remaining &= ~sel
            ex, ey, eh = _advance(x, y, h, kind, np.array([seg]), self.radius)
            x, y, h = float(ex[0]), float(ey[0]), float(eh[0])
            done += seg
        out[:, 2] = wrap_angle(out[:, 2])
        return out

    def end(self) -> tuple[float, float, float]:
        """The final pose (x m, y m, heading rad in [-pi, pi))."""
        x, y, h = self.sample(np.array([self.length]))[0]
        return float(x), float(y), float(h)


def _advance(
    x: float, y: float, h: float, kind: str, s: FloatArray, radius: float
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Poses after moving ``s`` (n,) metres along one segment of type ``kind`` from (x, y, h)."""
    if kind == "S":
        return x + s * math.cos(h), y + s * math.sin(h), np.full(s.shape, h)
    sign = 1.0 if kind == "L" else -1.0
    h1 = h + sign * s / radius
    px = x + sign * radius * (np.sin(h1) - math.sin(h))
    py = y - sign * radius * (np.cos(h1) - math.cos(h))
    return px, py, h1


def _word_params(word: str, a: float, b: float, d: float) -> tuple[float, float, float] | None:
    """Normalised (t, p, q) of one word, or None when the word has no solution."""
    sa, sb, ca, cb = math.sin(a), math.sin(b), math.cos(a), math.cos(b)
    cab = math.cos(a - b)
    if word == "LSL":
        p2 = 2.0 + d * d - 2.0 * cab + 2.0 * d * (sa - sb)
        if p2 < -_EPS:
            return None
        p2 = max(p2, 0.0)
        tmp = math.atan2(cb - ca, d + sa - sb)
        return _mod2pi(-a + tmp), math.sqrt(p2), _mod2pi(b - tmp)
    if word == "RSR":
        p2 = 2.0 + d * d - 2.0 * cab + 2.0 * d * (sb - sa)
        if p2 < -_EPS:
            return None
        p2 = max(p2, 0.0)
        tmp = math.atan2(ca - cb, d - sa + sb)
        return _mod2pi(a - tmp), math.sqrt(p2), _mod2pi(-b + tmp)
    if word == "LSR":
        p2 = -2.0 + d * d + 2.0 * cab + 2.0 * d * (sa + sb)
        if p2 < -_EPS:
            return None
        p2 = max(p2, 0.0)
        p = math.sqrt(p2)
        tmp = math.atan2(-ca - cb, d + sa + sb) - math.atan2(-2.0, p)
        return _mod2pi(-a + tmp), p, _mod2pi(-b + tmp)
    if word == "RSL":
        p2 = -2.0 + d * d + 2.0 * cab - 2.0 * d * (sa + sb)
        if p2 < -_EPS:
            return None
        p2 = max(p2, 0.0)
        p = math.sqrt(p2)
        tmp = math.atan2(ca + cb, d - sa - sb) - math.atan2(2.0, p)
        return _mod2pi(a - tmp), p, _mod2pi(b - tmp)
    if word == "RLR":
        tmp = (6.0 - d * d + 2.0 * cab + 2.0 * d * (sa - sb)) / 8.0
        if abs(tmp) > 1.0 + _EPS:
            return None
        tmp = min(max(tmp, -1.0), 1.0)
        p = _mod2pi(_TWO_PI - math.acos(tmp))
        t = _mod2pi(a - math.atan2(ca - cb, d - sa + sb) + p / 2.0)
        return t, p, _mod2pi(a - b - t + p)
    # LRL
    tmp = (6.0 - d * d + 2.0 * cab + 2.0 * d * (sb - sa)) / 8.0
    if abs(tmp) > 1.0 + _EPS:
        return None
    tmp = min(max(tmp, -1.0), 1.0)
    p = _mod2pi(_TWO_PI - math.acos(tmp))
    t = _mod2pi(-a - math.atan2(ca - cb, d + sa - sb) + p / 2.0)
    return t, p, _mod2pi(b - a - t + p)


def dubins_path(
    start: tuple[float, float, float], end: tuple[float, float, float], *, radius: float
) -> DubinsPath:
    """The shortest Dubins path from ``start`` to ``end``.

    Args:
        start: (x m, y m, heading rad).
        end: (x m, y m, heading rad).
        radius: turning radius, metres (> 0).

    Returns:
        The shortest of the six words whose sampled end pose matches ``end`` (1e-6 m, 1e-6 rad).

    Raises:
        ProblemError: non-positive or non-finite radius or poses.
    """
    if not (math.isfinite(radius) and radius > 0.0):
        raise ProblemError(f"turning radius must be positive and finite, got {radius}")
    if not all(math.isfinite(v) for v in (*start, *end)):
        raise ProblemError(f"Dubins poses must be finite, got {start} and {end}")
    dx, dy = end[0] - start[0], end[1] - start[1]
    d = math.hypot(dx, dy) / radius
    phi = math.atan2(dy, dx) if d > 0.0 else 0.0
    a, b = _mod2pi(start[2] - phi), _mod2pi(end[2] - phi)
    best: DubinsPath | None = None
    for word in _WORDS:
        params = _word_params(word, a, b, d)
        if params is None:
            continue
        path = DubinsPath(
            start=(float(start[0]), float(start[1]), float(start[2])),
            word=word,
            segments=(params[0] * radius, params[1] * radius, params[2] * radius),
            radius=float(radius),
        )
        ex, ey, eh = path.end()
        ok = (
            math.hypot(ex - end[0], ey - end[1]) < 1e-6 * max(1.0, radius)
            and abs(float(wrap_angle(eh - end[2]))) < 1e-6
        )
        if ok and (best is None or path.length < best.length - 1e-12):
            best = path
    if best is None:  # cannot happen for finite input: RSR/LSL always exist
        raise ProblemError(f"no Dubins path from {start} to {end}")
    return best
