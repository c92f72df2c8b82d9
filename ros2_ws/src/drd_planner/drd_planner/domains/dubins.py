"""Dubins curves: shortest paths of bounded curvature between planar poses, and their sampling.

A Dubins path joins two poses (x, y, heading) with at most three segments, each a left arc (L), a
right arc (R) of the turning radius, or a straight line (S). Of the six candidate words (LSL, RSR,
LSR, RSL, RLR, LRL) the shortest is optimal (Dubins 1957). The word lengths are the closed forms of
Shkel & Lumelsky (2001) in coordinates normalised by the turning radius (one function per word in
:data:`_WORD_SOLVERS`); every candidate is integrated and kept only if it really ends at the goal pose,
so a wrong closed form can never produce a wrong path.

Heading convention: headings are radians counter-clockwise from +x, and every path carries the range
its caller works in (:data:`HeadingRange`): ``"signed"`` wraps headings to [-pi, pi) (the helicopter
lattice, the query connector), ``"unsigned"`` to [0, 2 pi) (the SE(2) lattice). The range decides how
the chord direction is expressed when the relative angles are formed and how sampled headings are
wrapped; both users get exactly the numbers they got from their former, separate implementations.

Units: positions and lengths in the caller's length unit (metres for the helicopter), headings in radians.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal, NamedTuple

import numpy as np
import numpy.typing as npt

from drd_planner.arrays import FloatArray
from drd_planner.exceptions import ProblemError

__all__ = ["DubinsPath", "HeadingRange", "dubins_path", "wrap_angle"]

HeadingRange = Literal["signed", "unsigned"]
"""Where headings are wrapped: ``"signed"`` to [-pi, pi), ``"unsigned"`` to [0, 2 pi)."""

Pose = tuple[float, float, float]
_Params = tuple[float, float, float]

_TWO_PI = 2.0 * math.pi
_EPS = 1e-9  # tolerance of the normalised word equations (tangent cases)
_WORDS: tuple[str, ...] = ("LSL", "RSR", "LSR", "RSL", "RLR", "LRL")


def wrap_angle(angle: npt.ArrayLike, headings: HeadingRange = "signed") -> FloatArray:
    """Angles (any shape, radians) wrapped to [-pi, pi) (``"signed"``) or [0, 2 pi) (``"unsigned"``)."""
    a = np.asarray(angle, dtype=np.float64)
    if headings == "unsigned":
        return np.asarray(np.mod(a, _TWO_PI), dtype=np.float64)
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
        start: (x, y, heading rad) of the first pose.
        word: three letters from "LRS", e.g. "LSR"; letter i is the type of segment i.
        segments: lengths of the three segments (arc lengths for L and R; length unit, >= 0).
        radius: turning radius (length unit, > 0).
        headings: the range sampled headings are wrapped to.
    """

    start: Pose
    word: str
    segments: tuple[float, float, float]
    radius: float
    headings: HeadingRange = "signed"

    @property
    def length(self) -> float:
        """Total length (length unit)."""
        return float(sum(self.segments))

    @property
    def turning(self) -> float:
        """Total absolute heading change along the path, radians."""
        return float(sum(seg / self.radius for kind, seg in zip(self.word, self.segments, strict=True) if kind != "S"))

    def sample(self, s: npt.ArrayLike) -> FloatArray:
        """Poses at arc lengths ``s`` (n,) in [0, length]: (n, 3) as x, y, heading (wrapped, see ``headings``)."""
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
        out[:, 2] = wrap_angle(out[:, 2], self.headings)
        return out

    def sample_evenly(self, spacing: float) -> FloatArray:
        """(K, 3) poses at K = ceil(length / spacing) + 1 evenly spaced arc lengths, both ends included.

        Consecutive samples are at most ``spacing`` apart along the path (and so in the plane).

        Raises:
            ProblemError: non-positive spacing.
        """
        if not spacing > 0:
            raise ProblemError(f"sample spacing must be positive, got {spacing}")
        count = max(2, math.ceil(self.length / spacing - 1e-9) + 1)
        return self.sample(np.linspace(0.0, self.length, count))

    def end(self) -> Pose:
        """The final pose (x, y, heading wrapped to the path's range)."""
        x, y, h = self.sample(np.array([self.length]))[0]
        return float(x), float(y), float(h)


def _advance(
    x: float, y: float, h: float, kind: str, s: FloatArray, radius: float
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Poses after moving ``s`` (n,) along one segment of type ``kind`` from (x, y, h); headings unwrapped."""
    if kind == "S":
        return x + s * math.cos(h), y + s * math.sin(h), np.full(s.shape, h)
    sign = 1.0 if kind == "L" else -1.0
    h1 = h + sign * s / radius
    px = x + sign * radius * (np.sin(h1) - math.sin(h))
    py = y - sign * radius * (np.cos(h1) - math.cos(h))
    return px, py, h1


class _Relative(NamedTuple):
    """The normalised problem: start and end headings relative to the chord, and the chord length / radius."""

    a: float
    b: float
    d: float
    sa: float
    sb: float
    ca: float
    cb: float
    cab: float

    @classmethod
    def of(cls, a: float, b: float, d: float) -> _Relative:
        """The problem with its sines and cosines."""
        return cls(a, b, d, math.sin(a), math.sin(b), math.cos(a), math.cos(b), math.cos(a - b))


def _lsl(r: _Relative) -> _Params | None:
    p2 = 2.0 + r.d * r.d - 2.0 * r.cab + 2.0 * r.d * (r.sa - r.sb)
    if p2 < -_EPS:
        return None
    tmp = math.atan2(r.cb - r.ca, r.d + r.sa - r.sb)
    return _mod2pi(-r.a + tmp), math.sqrt(max(p2, 0.0)), _mod2pi(r.b - tmp)


def _rsr(r: _Relative) -> _Params | None:
    p2 = 2.0 + r.d * r.d - 2.0 * r.cab + 2.0 * r.d * (r.sb - r.sa)
    if p2 < -_EPS:
        return None
    tmp = math.atan2(r.ca - r.cb, r.d - r.sa + r.sb)
    return _mod2pi(r.a - tmp), math.sqrt(max(p2, 0.0)), _mod2pi(-r.b + tmp)


def _lsr(r: _Relative) -> _Params | None:
    p2 = -2.0 + r.d * r.d + 2.0 * r.cab + 2.0 * r.d * (r.sa + r.sb)
    if p2 < -_EPS:
        return None
    p = math.sqrt(max(p2, 0.0))
    tmp = math.atan2(-r.ca - r.cb, r.d + r.sa + r.sb) - math.atan2(-2.0, p)
    return _mod2pi(-r.a + tmp), p, _mod2pi(-r.b + tmp)


def _rsl(r: _Relative) -> _Params | None:
    p2 = -2.0 + r.d * r.d + 2.0 * r.cab - 2.0 * r.d * (r.sa + r.sb)
    if p2 < -_EPS:
        return None
    p = math.sqrt(max(p2, 0.0))
    tmp = math.atan2(r.ca + r.cb, r.d - r.sa - r.sb) - math.atan2(2.0, p)
    return _mod2pi(r.a - tmp), p, _mod2pi(r.b - tmp)


def _middle_arc(cosine: float) -> float | None:
    """The normalised middle arc of RLR/LRL from its cosine, or None when the word does not exist."""
    if abs(cosine) > 1.0 + _EPS:
        return None
    return _mod2pi(_TWO_PI - math.acos(min(max(cosine, -1.0), 1.0)))


def _rlr(r: _Relative) -> _Params | None:
    p = _middle_arc((6.0 - r.d * r.d + 2.0 * r.cab + 2.0 * r.d * (r.sa - r.sb)) / 8.0)
    if p is None:
        return None
    t = _mod2pi(r.a - math.atan2(r.ca - r.cb, r.d - r.sa + r.sb) + p / 2.0)
    return t, p, _mod2pi(r.a - r.b - t + p)


def _lrl(r: _Relative) -> _Params | None:
    p = _middle_arc((6.0 - r.d * r.d + 2.0 * r.cab + 2.0 * r.d * (r.sb - r.sa)) / 8.0)
    if p is None:
        return None
    t = _mod2pi(-r.a - math.atan2(r.ca - r.cb, r.d + r.sa - r.sb) + p / 2.0)
    return t, p, _mod2pi(r.b - r.a - t + p)


#: The closed form of each word: normalised (t, p, q) segment lengths, or None when the word has no solution.
_WORD_SOLVERS: dict[str, Callable[[_Relative], _Params | None]] = {
    "LSL": _lsl,
    "RSR": _rsr,
    "LSR": _lsr,
    "RSL": _rsl,
    "RLR": _rlr,
    "LRL": _lrl,
}


def _word_params(word: str, a: float, b: float, d: float) -> _Params | None:
    """Normalised (t, p, q) of one word for relative headings ``a``, ``b`` and chord ``d`` (radii), or None."""
    return _WORD_SOLVERS[word](_Relative.of(a, b, d))


def _check_input(start: Pose, end: Pose, radius: float) -> None:
    """Raise ProblemError for a non-positive or non-finite radius or non-finite poses."""
    if not (math.isfinite(radius) and radius > 0.0):
        raise ProblemError(f"turning radius must be positive and finite, got {radius}")
    if not all(math.isfinite(v) for v in (*start, *end)):
        raise ProblemError(f"Dubins poses must be finite, got {start} and {end}")


def dubins_path(start: Pose, end: Pose, *, radius: float, headings: HeadingRange = "signed") -> DubinsPath:
    """The shortest Dubins path from ``start`` to ``end``.

    Args:
        start: (x, y, heading rad).
        end: (x, y, heading rad).
        radius: turning radius (length unit, > 0).
        headings: the caller's heading range: the chord direction is taken in it and the path samples
            headings wrapped to it.

    Returns:
        The shortest of the six words whose sampled end pose matches ``end`` (1e-6 times max(1, radius)
        in position, 1e-6 rad in heading).

    Raises:
        ProblemError: non-positive or non-finite radius or poses.
    """
    _check_input(start, end, radius)
    dx, dy = end[0] - start[0], end[1] - start[1]
    d = math.hypot(dx, dy) / radius
    chord = math.atan2(dy, dx) if d > 0.0 else 0.0
    if headings == "unsigned":
        chord = _mod2pi(chord)
    a, b = _mod2pi(start[2] - chord), _mod2pi(end[2] - chord)
    first = (float(start[0]), float(start[1]), float(start[2]))
    candidates: list[tuple[float, int, DubinsPath]] = []
    for index, word in enumerate(_WORDS):
        params = _word_params(word, a, b, d)
        if params is None:
            continue
        segments = (params[0] * radius, params[1] * radius, params[2] * radius)
        path = DubinsPath(first, word, segments, float(radius), headings)
        candidates.append((path.length, index, path))
    # Shortest first (ties in word order): the first whose integrated end is the goal is the answer, so
    # usually one word is integrated instead of six.
    for _, _, path in sorted(candidates, key=lambda c: (c[0], c[1])):
        ex, ey, eh = path.end()
        if (
            math.hypot(ex - end[0], ey - end[1]) < 1e-6 * max(1.0, radius)
            and abs(float(wrap_angle(eh - end[2]))) < 1e-6
        ):
            return path
    raise ProblemError(f"no Dubins path from {start} to {end}")  # cannot happen: RSR/LSL always exist


def _mod2pi_array(angle: FloatArray) -> FloatArray:
    """Elementwise :func:`_mod2pi`."""
    out = np.mod(angle, _TWO_PI)
    return np.asarray(np.where(out > _TWO_PI - 1e-9, 0.0, out), dtype=np.float64)


def _word_segments(a: FloatArray, b: FloatArray, d: FloatArray) -> FloatArray:
    """(6, N, 3) normalised segment lengths t, p, q of each word (inf where the word does not exist)."""
    sa, sb, ca, cb, cab = np.sin(a), np.sin(b), np.cos(a), np.cos(b), np.cos(a - b)
    out = np.full((len(_WORDS), a.size, 3), np.inf)
    with np.errstate(invalid="ignore"):
        p2 = 2.0 + d * d - 2.0 * cab + 2.0 * d * (sa - sb)  # LSL
        tmp = np.arctan2(cb - ca, d + sa - sb)
        words = [(p2 >= -_EPS, _mod2pi_array(-a + tmp), np.sqrt(np.maximum(p2, 0.0)), _mod2pi_array(b - tmp))]
        p2 = 2.0 + d * d - 2.0 * cab + 2.0 * d * (sb - sa)  # RSR
        tmp = np.arctan2(ca - cb, d - sa + sb)
        words.append((p2 >= -_EPS, _mod2pi_array(a - tmp), np.sqrt(np.maximum(p2, 0.0)), _mod2pi_array(-b + tmp)))
        p2 = -2.0 + d * d + 2.0 * cab + 2.0 * d * (sa + sb)  # LSR
        p = np.sqrt(np.maximum(p2, 0.0))
        tmp = np.arctan2(-ca - cb, d + sa + sb) - np.arctan2(-2.0, p)
        words.append((p2 >= -_EPS, _mod2pi_array(-a + tmp), p, _mod2pi_array(-b + tmp)))
        p2 = -2.0 + d * d + 2.0 * cab - 2.0 * d * (sa + sb)  # RSL
        p = np.sqrt(np.maximum(p2, 0.0))
        tmp = np.arctan2(ca + cb, d - sa - sb) - np.arctan2(2.0, p)
        words.append((p2 >= -_EPS, _mod2pi_array(a - tmp), p, _mod2pi_array(b - tmp)))
        for row, (ok, t, p, q) in enumerate(words):
            out[row] = np.where(ok[:, None], np.column_stack([t, p, q]), np.inf)
        for row, sign in ((4, 1.0), (5, -1.0)):  # RLR, LRL
            cosine = (6.0 - d * d + 2.0 * cab + 2.0 * sign * d * (sa - sb)) / 8.0
            ok = np.abs(cosine) <= 1.0 + _EPS
            p = _mod2pi_array(_TWO_PI - np.arccos(np.clip(cosine, -1.0, 1.0)))
            if sign > 0:
                t = _mod2pi_array(a - np.arctan2(ca - cb, d - sa + sb) + p / 2.0)
                q = _mod2pi_array(a - b - t + p)
            else:
                t = _mod2pi_array(-a - np.arctan2(ca - cb, d + sa - sb) + p / 2.0)
                q = _mod2pi_array(b - a - t + p)
            out[row] = np.where(ok[:, None], np.column_stack([t, p, q]), np.inf)
    return out


def _word_lengths(a: FloatArray, b: FloatArray, d: FloatArray) -> FloatArray:
    """(6, N) normalised lengths t + p + q of each word (order of ``_WORDS``; inf where a word does not exist)."""
    return np.asarray(_word_segments(a, b, d).sum(axis=2), dtype=np.float64)


def _chord_frame(
    starts: npt.ArrayLike, ends: npt.ArrayLike, radius: float
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray]:
    """(N, 3) starts and ends broadcast, their headings a, b (N,) from the chord, and d (N,) in radii.

    Raises:
        ProblemError: a radius that is not positive and finite.
    """
    s = np.atleast_2d(np.asarray(starts, dtype=np.float64))
    e = np.atleast_2d(np.asarray(ends, dtype=np.float64))
    s, e = np.broadcast_arrays(s, e)
    if not (math.isfinite(radius) and radius > 0.0):
        raise ProblemError(f"turning radius must be positive and finite, got {radius}")
    dx, dy = e[:, 0] - s[:, 0], e[:, 1] - s[:, 1]
    d = np.hypot(dx, dy) / radius
    chord = np.where(d > 0.0, np.arctan2(dy, dx), 0.0)
    return s, e, _mod2pi_array(s[:, 2] - chord), _mod2pi_array(e[:, 2] - chord), d


def dubins_lengths(starts: npt.ArrayLike, ends: npt.ArrayLike, *, radius: float) -> FloatArray:
    """(N,) lengths of the shortest Dubins paths between (N, 3) (or broadcast (3,)) poses, vectorised.

    The same closed forms as :func:`dubins_path` without the integration that verifies each word, for ranking
    many candidates at once; :func:`dubins_path` of a chosen pair gives its verified path.

    Args:
        starts: (N, 3) or (3,) poses x, y, heading (rad).
        ends: (N, 3) or (3,) poses.
        radius: turning radius (length unit, > 0).
    """
    _, _, a, b, d = _chord_frame(starts, ends, radius)
    return np.asarray(_word_lengths(a, b, d).min(axis=0) * radius, dtype=np.float64)


def _turn_to_point(starts: FloatArray, point: FloatArray, radius: float, sign: float) -> tuple[FloatArray, FloatArray]:
    """Arc (rad) and straight length of the turn-then-straight path (left: sign 1) from each pose to a point.

    NaN where the point lies inside the turning circle (no such path).
    """
    h = starts[:, 2]
    cx = starts[:, 0] - sign * radius * np.sin(h)
    cy = starts[:, 1] + sign * radius * np.cos(h)
    wx, wy = point[0] - cx, point[1] - cy
    dist = np.hypot(wx, wy)
    with np.errstate(invalid="ignore", divide="ignore"):
        straight = np.sqrt(dist * dist - radius * radius)
        tangent = np.arctan2(wy, wx) - sign * np.arccos(np.clip(radius / dist, -1.0, 1.0))
    first = h - sign * math.pi / 2.0  # angle of the start point seen from the centre
    arc = _mod2pi_array(sign * (tangent - first))
    bad = ~(dist >= radius)
    return np.where(bad, np.nan, arc), np.where(bad, np.nan, straight)


def point_lengths(starts: npt.ArrayLike, point: npt.ArrayLike, *, radius: float) -> FloatArray:
    """(N,) lengths of the shortest turn-then-straight paths from (N, 3) poses to a point (any final heading).

    A path from a pose to a point whose final heading is free turns left or right on the turning circle and
    then flies straight (Dubins' CS words); where the point lies inside both turning circles there is no
    such path and the length is inf (a loop would be needed: the caller looks at other poses).
    """
    s = np.atleast_2d(np.asarray(starts, dtype=np.float64))
    p = np.asarray(point, dtype=np.float64).ravel()[:2]
    best = np.full(s.shape[0], np.inf)
    for sign in (1.0, -1.0):
        arc, straight = _turn_to_point(s, p, radius, sign)
        length = arc * radius + straight
        best = np.where(np.isfinite(length) & (length < best), length, best)
    return best


def path_to_point(start: Pose, point: tuple[float, float], *, radius: float) -> DubinsPath | None:
    """The shortest turn-then-straight path from ``start`` to ``point`` (final heading free), or None.

    None when the point lies inside both turning circles of ``start``. The path's word is ``LSL`` or ``RSR``
    with a zero last segment (its final heading is the straight's direction).
    """
    _check_input(start, (point[0], point[1], 0.0), radius)
    s = np.array([start], dtype=np.float64)
    best: DubinsPath | None = None
    for sign, word in ((1.0, "LSL"), (-1.0, "RSR")):
        arc, straight = _turn_to_point(s, np.asarray(point, dtype=np.float64), radius, sign)
        if not (np.isfinite(arc[0]) and np.isfinite(straight[0])):
            continue
        path = DubinsPath(
            (float(start[0]), float(start[1]), float(start[2])),
            word,
            (float(arc[0]) * radius, float(straight[0]), 0.0),
            float(radius),
        )
        if best is None or path.length < best.length - 1e-12:
            best = path
    return best
