"""Helicopter motions joining an off-lattice (x, y, z, heading) state to the lattice: flyable curves, ahead of it.

A helicopter's state is almost never a lattice vertex: odometry drifts metres off the lattice and its heading
is anything. :class:`DubinsConnector` joins such a state to several vertices by motions the vehicle can fly:

- **in the plane** the shortest Dubins path of the lattice's turning radius from the state to the vertex
  (a start; to the state from the vertex for a goal), so the state's heading and the vertex's are both
  honoured; a goal given without a heading (NaN heading, or a position alone) is reached by the shortest
  turn-then-straight path from the vertex, arriving with whatever heading that path has;
- **in altitude** a constant climb or descent along the curve, within the lattice's climb gradient;
- **which vertices**: the Dubins length to every vertex is computed at once (vectorised closed forms,
  :func:`~drd_planner.domains.dubins.dubins_lengths`), vertices whose altitude the climb limit cannot reach
  are dropped, and the ``neighbours`` shortest motions are kept (ties by vertex id). The shortest motions go
  to vertices *ahead* of a start (and
  behind a goal) with a heading it can turn to; vertices beside or behind need loops and come last. Looking at
  all vertices rather than the nearest ones matters: the nearest are the other headings and altitudes at
  the same lattice point, which only a loop longer than the lattice spacing reaches.

A state outside the lattice's extent (its vertices' horizontal bounding box and altitude band, grown by
one grid step and one level gap) is refused with the extent named. Each motion is sampled every
``spacing`` metres of arc; its samples are what the checker tests (the vehicle sphere at each).

Units: metres and radians.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from drd_planner.arrays import FloatArray, IntArray
from drd_planner.core.graph import ExplicitGraph
from drd_planner.core.status import PlanCause
from drd_planner.domains.dubins import dubins_lengths, path_to_point, point_lengths
from drd_planner.domains.dubins_batch import dubins_samples, dubins_sketches
from drd_planner.exceptions import ProblemError
from drd_planner.planner.connect import Motion, vertex_states_of
from drd_planner.planner.endpoints import QueryError
from drd_planner.planner.prior import WorldPrior

__all__ = ["DEFAULT_JOINS", "DubinsConnector", "LatticeExtent", "dubins_connector"]

#: Vertices a helicopter state is joined to, at most (the shortest flyable motions).
DEFAULT_JOINS = 16
#: How far (m) a motion's sampled end may lie from the vertex or state it joins (the path is verified).
END_TOLERANCE = 1e-6


@dataclass(frozen=True)
class LatticeExtent:
    """Where a helicopter state may be: the lattice's horizontal box and altitude band, grown by margins.

    Attributes:
        lower: (3,) x, y, z minima of the vertices (m).
        upper: (3,) x, y, z maxima (m).
        margin_xy: metres allowed beyond the box horizontally.
        margin_z: metres allowed beyond the altitude band.
    """

    lower: FloatArray
    upper: FloatArray
    margin_xy: float
    margin_z: float

    @classmethod
    def of_graph(cls, graph: ExplicitGraph) -> LatticeExtent:
        """The extent of a lattice graph's vertex states; margins one grid step and one level gap."""
        states = vertex_states_of(graph)[:, :3]
        return cls(states.min(axis=0), states.max(axis=0), _gap(states[:, 0:2]), _gap(states[:, 2:3]))

    def refusal(self, state: FloatArray, label: str) -> str | None:
        """Why ``state`` (x, y, z, ...) is outside the extent, or None when it is inside."""
        x, y, z = (float(v) for v in state[:3])
        lo, hi = self.lower - self.margin_xy, self.upper + self.margin_xy
        if not (lo[0] <= x <= hi[0] and lo[1] <= y <= hi[1]):
            return (
                f"{label} position ({x:.1f}, {y:.1f}) m is outside the lattice's horizontal extent x "
                f"[{self.lower[0]:.0f}, {self.upper[0]:.0f}] m, y [{self.lower[1]:.0f}, {self.upper[1]:.0f}] m "
                f"(+{self.margin_xy:.0f} m allowed)"
            )
        if not (self.lower[2] - self.margin_z <= z <= self.upper[2] + self.margin_z):
            return (
                f"{label} altitude {z:.1f} m is outside the lattice's altitude band [{self.lower[2]:.0f}, "
                f"{self.upper[2]:.0f}] m (+-{self.margin_z:.0f} m allowed)"
            )
        return None


def _gap(values: FloatArray) -> float:
    """The smallest positive spacing between the distinct values of any column (0 for a single value)."""
    gaps = [np.diff(np.unique(col)) for col in values.T]
    positive = np.concatenate([g[g > 1e-9] for g in gaps]) if gaps else np.zeros(0)
    return float(positive.min()) if positive.size else 0.0


class DubinsConnector:
    """Joins helicopter states to a lattice by flyable motions (see the module docstring).

    Args:
        turning_radius: the vehicle's (and the lattice's) turning radius, metres.
        spacing: largest arc-length step between the samples of a motion, metres.
        max_climb_gradient: largest |dz| / horizontal length of a motion.
        neighbours: vertices joined, at most.
        extent: where states may be (None: anywhere).
    """

    def __init__(
        self,
        *,
        turning_radius: float,
        spacing: float,
        max_climb_gradient: float = 0.5,
        neighbours: int = DEFAULT_JOINS,
        extent: LatticeExtent | None = None,
    ) -> None:
        if not (turning_radius > 0 and spacing > 0 and max_climb_gradient > 0 and neighbours >= 1):
            raise ProblemError(
                "a Dubins connector needs a positive radius, spacing and climb gradient, and neighbours >= 1"
            )
        if not math.isfinite(turning_radius + spacing + max_climb_gradient):
            raise ProblemError("a Dubins connector needs finite radius, spacing and climb gradient")
        self._radius = float(turning_radius)
        self._k = int(neighbours)
        self._spacing = float(spacing)
        self._climb = float(max_climb_gradient)
        self._extent = extent

    @property
    def reach(self) -> float:
        """No limit on distance: every lattice vertex is a candidate (inf)."""
        return math.inf

    @property
    def position_dims(self) -> int:
        """x, y, z."""
        return 3

    @property
    def turning_radius(self) -> float:
        """Metres."""
        return self._radius

    @property
    def spacing(self) -> float:
        """Largest arc-length step between a motion's samples, metres."""
        return self._spacing

    @property
    def max_climb_gradient(self) -> float:
        """Largest |dz| / horizontal length of a motion."""
        return self._climb

    @property
    def neighbours(self) -> int:
        """Vertices a state is joined to, at most."""
        return self._k

    @property
    def free_goal_dims(self) -> tuple[int, ...]:
        """(3,): a goal may leave its heading free (NaN, or a goal of x, y, z only)."""
        return (3,)

    @property
    def extent(self) -> LatticeExtent | None:
        """Where states may be (None: anywhere)."""
        return self._extent

    def connect(self, state: FloatArray, graph: ExplicitGraph, *, outgoing: bool) -> list[Motion]:
        """The ``neighbours`` shortest flyable motions from ``state`` to vertices (``outgoing``) or into it.

        A NaN heading (goals only) leaves the arrival heading free.

        Raises:
            QueryError: the state is outside the extent, or a start has no heading.
        """
        return self.motions_to(state, graph, self.ranked(state, graph, outgoing=outgoing)[: self._k], outgoing=outgoing)

    def motions_to(
        self, state: FloatArray, graph: ExplicitGraph, vertices: IntArray, *, outgoing: bool
    ) -> list[Motion]:
        """The motions joining ``state`` and each of ``vertices`` (in that order; from the state if ``outgoing``).

        A vertex no flyable motion joins (a climb steeper than the gradient, a goal inside both turning circles
        of a free-heading path) is left out. :meth:`connect` joins the first ``neighbours`` of :meth:`ranked`;
        the planner asks for more of the ranking when they do not suffice
        (:mod:`~drd_planner.planner.join_growth`) and for the motion straight to the query's other end.
        """
        states = vertex_states_of(graph)
        ids = np.asarray(vertices, dtype=np.int64)
        if not math.isfinite(float(state[3])):  # a goal's free heading: turn-then-straight paths, one by one
            if outgoing:
                raise QueryError("a start state needs a heading (the vehicle's yaw), got NaN")
            found = (self._motion_to_point(states[v], state, int(v)) for v in ids.tolist())
            return [motion for motion in found if motion is not None]
        targets = states[ids]
        own = np.broadcast_to(np.asarray(state, dtype=np.float64), targets.shape)
        tails, heads = (own, targets) if outgoing else (targets, own)
        horizontal, poses = dubins_samples(
            tails[:, [0, 1, 3]], heads[:, [0, 1, 3]], radius=self._radius, spacing=self._spacing
        )
        out: list[Motion] = []
        for i, v in enumerate(ids.tolist()):
            motion = self._sampled(tails[i], heads[i], int(v), float(horizontal[i]), poses[i], keep_heading=True)
            if motion is not None:
                out.append(motion)
        return out

    def ranked(self, state: FloatArray, graph: ExplicitGraph, *, outgoing: bool) -> IntArray:
        """(M,) every vertex a flyable motion joins to ``state``, by the motion's 3D length (ties by id).

        Raises:
            QueryError: the state is outside the extent, or a start has no heading.
        """
        states = vertex_states_of(graph)
        if states.shape[1] != 4 or state.shape != (4,):
            raise ProblemError("helicopter states are (x, y, z, heading)")
        label = "start" if outgoing else "goal"
        reason = None if self._extent is None else self._extent.refusal(state, label)
        if reason is not None:
            raise QueryError(reason, cause=PlanCause.outside(label))
        free_heading = not math.isfinite(float(state[3]))
        if free_heading and outgoing:
            raise QueryError("a start state needs a heading (the vehicle's yaw), got NaN")
        poses = states[:, [0, 1, 3]]
        own = state[[0, 1, 3]]
        if free_heading:
            horizontal = point_lengths(poses, own[:2], radius=self._radius)
        elif outgoing:
            horizontal = dubins_lengths(own, poses, radius=self._radius)
        else:
            horizontal = dubins_lengths(poses, own, radius=self._radius)
        dz = states[:, 2] - state[2] if outgoing else state[2] - states[:, 2]
        feasible = np.isfinite(horizontal) & (np.abs(dz) <= self._climb * horizontal + 1e-9)
        candidates = np.flatnonzero(feasible)
        length = np.hypot(horizontal[candidates], dz[candidates])
        return np.asarray(candidates[np.lexsort((candidates, length))], dtype=np.int64)

    def sketches(
        self,
        state: FloatArray,
        graph: ExplicitGraph,
        vertices: IntArray,
        *,
        outgoing: bool,
        fractions: FloatArray,
    ) -> tuple[FloatArray, FloatArray]:
        """The motions joining ``state`` and each of ``vertices``, sketched for a prior (never checked).

        Vectorised (:func:`~drd_planner.domains.dubins_batch.dubins_sketches`), a few milliseconds for a whole
        lattice where :meth:`motions_to` takes about one per motion. A goal without heading is sketched as the
        straight chord (its length is the turn-then-straight path's).

        Args:
            state: (4,) x, y, z, heading (NaN heading: a goal's free arrival heading).
            graph: the lattice graph.
            vertices: (M,) vertex ids.
            outgoing: the motions start at ``state`` (a start) rather than end there (a goal).
            fractions: (P,) arc-length fractions in [0, 1].

        Returns:
            (M,) 3D lengths (m) and (M, P, 3) x, y, z (m) at the fractions.
        """
        targets = vertex_states_of(graph)[np.asarray(vertices, dtype=np.int64)]
        own = np.broadcast_to(np.asarray(state, dtype=np.float64), targets.shape)
        tail, head = (own, targets) if outgoing else (targets, own)
        frac = np.asarray(fractions, dtype=np.float64)
        if not math.isfinite(float(state[3])):
            horizontal = point_lengths(tail[:, [0, 1, 3]], head[0, :2], radius=self._radius)
            xy = tail[:, None, :2] + frac[None, :, None] * (head - tail)[:, None, :2]
        else:
            horizontal, poses = dubins_sketches(
                tail[:, [0, 1, 3]], head[:, [0, 1, 3]], radius=self._radius, fractions=frac
            )
            xy = poses[..., :2]
        dz = head[:, 2] - tail[:, 2]
        z = tail[:, None, 2] + frac[None, :] * dz[:, None]
        return np.hypot(horizontal, dz), np.concatenate([xy, z[..., None]], axis=-1)

    def _motion_to_point(self, vertex_state: FloatArray, state: FloatArray, vertex: int) -> Motion | None:
        """The motion from a vertex to a goal ``state`` whose arrival heading is free (None: none exists)."""
        tail, head = vertex_state, state
        path = path_to_point((tail[0], tail[1], tail[3]), (head[0], head[1]), radius=self._radius)
        if path is None:
            return None
        n = max(2, math.ceil(path.length / self._spacing - 1e-9) + 1)
        pose = path.sample(np.linspace(0.0, path.length, n))
        return self._sampled(tail, head, vertex, path.length, pose, keep_heading=False)

    def _sampled(
        self,
        tail: FloatArray,
        head: FloatArray,
        vertex: int,
        horizontal: float,
        pose: FloatArray,
        *,
        keep_heading: bool,
    ) -> Motion | None:
        """The motion from its (K, 3) planar ``pose`` samples, climbing evenly from ``tail`` to ``head``.

        None when the climb is steeper than the climb gradient allows (as :meth:`ranked` decides), or when the
        sampled end misses the head (never expected: the paths are verified). The first and last samples are
        the two states themselves; the last keeps the head's heading unless it is free.
        """
        n = pose.shape[0]
        dz = float(head[2] - tail[2])
        if abs(dz) > self._climb * horizontal + 1e-9:
            return None
        s = np.linspace(0.0, horizontal, n)
        climb = dz * s / horizontal if horizontal > 0 else np.zeros(n)
        samples = np.column_stack([pose[:, 0], pose[:, 1], tail[2] + climb, pose[:, 2]])
        if math.hypot(samples[-1, 0] - head[0], samples[-1, 1] - head[1]) > END_TOLERANCE * max(1.0, self._radius):
            return None
        samples[0, :3] = tail[:3]
        samples[-1, :3] = head[:3]
        if keep_heading:
            samples[-1, 3] = head[3]
        samples[0, 3] = tail[3]
        return Motion(vertex, samples, math.hypot(horizontal, dz))


def dubins_connector(prior: WorldPrior) -> DubinsConnector | None:
    """The connector of a helicopter prior (None when its graph has no (x, y, z, heading) states)."""
    lattice = prior.domain_spec.get("lattice") or {}
    graph = prior.graph
    if graph.vertex_states is None or graph.vertex_states.shape[1] != 4 or graph.num_vertices == 0:
        return None
    return DubinsConnector(
        turning_radius=float(lattice.get("turning_radius", 100.0)),
        spacing=float(lattice.get("sample_spacing", 5.0)),
        max_climb_gradient=float(lattice.get("max_climb_gradient", 0.5)),
        extent=LatticeExtent.of_graph(graph),
    )
