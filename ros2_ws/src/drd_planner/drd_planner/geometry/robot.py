"""A robot arm for collision checking: URDF chain + batched FK + sphere model + self-collision pairs.

Build it from strings (:meth:`RobotModel.from_urdf`): the kinematic URDF (for example ``panda.urdf``
from the ROS topic ``robot_description``), optionally a spherized URDF of the same robot whose
``<collision>`` elements are all spheres (``panda_spherized.urdf``; by default the kinematic URDF itself
must be spherized), and optionally an SRDF whose ``disable_collisions`` pairs are excluded from the
self-collision test. Without an SRDF, links joined by a joint (parent and child) are excluded. Links
rigidly attached to the same moving frame never move relative to each other and are always excluded.

Units: metres and radians.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from drd_planner.arrays import BoolArray, FloatArray, IntArray
from drd_planner.exceptions import GeometryError
from drd_planner.geometry.kinematics import ForwardKinematics
from drd_planner.geometry.urdf_model import (
    CollisionSpheres,
    KinematicChain,
    SrdfInfo,
    parse_collision_spheres,
    parse_srdf,
    parse_urdf_chain,
)

#: Configurations per block in the self-collision test (bounds the (block, P, 3) temporaries).
SELF_COLLISION_BLOCK = 4096

__all__ = ["RobotModel", "SphereGroups", "SphereModel", "build_sphere_groups"]


@dataclass(frozen=True)
class SphereModel:
    """Collision spheres attached to the moving frames of a chain.

    Attributes:
        link_index: (S,) index of each sphere's link into ``chain.link_names``.
        frame_index: (S,) moving frame (0..D) of each sphere.
        centres: (S, 3) centres in the moving frame (m).
        radii: (S,) radii (m).
    """

    link_index: IntArray
    frame_index: IntArray
    centres: FloatArray
    radii: FloatArray

    @property
    def count(self) -> int:
        """S, the number of spheres."""
        return int(self.radii.shape[0])


def _attach_spheres(chain: KinematicChain, spheres: CollisionSpheres) -> SphereModel:
    """Express link-frame spheres in the chain's moving frames."""
    link_index = np.array([chain.link_index(name) for name in spheres.link_names], dtype=np.int64)
    offsets = chain.link_offsets[link_index]
    centres = np.einsum("sij,sj->si", offsets[:, :3, :3], spheres.centres) + offsets[:, :3, 3]
    return SphereModel(link_index, chain.link_frames[link_index], centres, spheres.radii.copy())


def _excluded_pairs(chain: KinematicChain, srdf: SrdfInfo | None) -> set[tuple[str, str]]:
    """Link pairs (sorted) never checked for self-collision besides those of one moving frame.

    The pairs of one frame never move apart and are left out where pairs are made
    (:func:`_checked_link_pairs`), not listed here: L links in one frame are L^2 / 2 pairs.
    """
    if srdf is None:
        return {(min(a, b), max(a, b)) for a, b in chain.parent_child}
    unknown = sorted({n for pair in srdf.disabled_pairs for n in pair} - set(chain.link_names))
    if unknown:
        raise GeometryError(f"SRDF disables collisions of links the URDF does not have: {', '.join(unknown)}")
    return set(srdf.disabled_pairs)


def _checked_link_pairs(
    chain: KinematicChain, spheres: SphereModel, excluded: set[tuple[str, str]]
) -> tuple[tuple[str, str], ...]:
    """Pairs (sorted names, in sorted order) of links with spheres in different moving frames, not ``excluded``.

    Made frame pair by frame pair, so the work follows the pairs made, not the square of the links.
    """
    names = sorted({chain.link_names[i] for i in spheres.link_index.tolist()})
    by_frame: dict[int, list[int]] = {}
    for position, name in enumerate(names):
        by_frame.setdefault(int(chain.link_frames[chain.link_index(name)]), []).append(position)
    frames = list(by_frame.values())
    pairs = sorted(
        (min(i, j), max(i, j))
        for x, ours in enumerate(frames)
        for theirs in frames[x + 1 :]
        for i in ours
        for j in theirs
    )
    return tuple((names[i], names[j]) for i, j in pairs if (names[i], names[j]) not in excluded)


def _products(
    first: IntArray, first_count: IntArray, second: IntArray, second_count: IntArray
) -> tuple[IntArray, IntArray]:
    """Every pair of K products of ranges, product by product (first range outer): (x, y) positions.

    Product k pairs ``[first[k], first[k] + first_count[k])`` with ``[second[k], second[k] + second_count[k])``;
    the arrays are (K,) int64, the results (P,) with P = sum of first_count * second_count (numpy, no loop).
    """
    sizes = first_count * second_count
    k = np.repeat(np.arange(len(sizes)), sizes)
    local = np.arange(int(sizes.sum()), dtype=np.int64) - np.repeat(np.cumsum(sizes) - sizes, sizes)
    return first[k] + local // second_count[k], second[k] + local % second_count[k]


def _owner_pairs(owner: IntArray, owner_pairs: set[tuple[int, int]]) -> IntArray:
    """(P, 2) index pairs i < j, sorted by i then j, whose owners ``(owner[i], owner[j])`` are in ``owner_pairs``.

    ``owner_pairs`` is symmetric (both orders listed). The pairs of all owner pairs are made at once
    (:func:`_products`): the work follows the P pairs made, not the square of ``len(owner)``.
    """
    order = np.argsort(owner, kind="stable")
    size = int(owner.max()) + 1 if len(owner) else 0
    counts = np.bincount(owner, minlength=size).astype(np.int64)
    starts = np.cumsum(counts) - counts
    known = [(min(a, b), max(a, b)) for a, b in owner_pairs if 0 <= min(a, b) and max(a, b) < size]
    chunks = [np.zeros((0, 2), dtype=np.int64)]
    for a in sorted({a for a, b in known if a == b}):  # one owner with itself (not made by from_urdf)
        ours = order[starts[a] : starts[a] + counts[a]]
        i, j = np.triu_indices(len(ours), 1)
        chunks.append(np.stack([ours[i], ours[j]], axis=1))
    cross = np.array(sorted({(a, b) for a, b in known if a != b}), dtype=np.int64).reshape(-1, 2)
    x, y = _products(starts[cross[:, 0]], counts[cross[:, 0]], starts[cross[:, 1]], counts[cross[:, 1]])
    chunks.append(np.sort(np.stack([order[x], order[y]], axis=1), axis=1))
    pairs = np.concatenate(chunks).astype(np.int64)
    return pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))]


# --------------------------------------------------------------------------------------------------
# Two-level sphere hierarchy


@dataclass(frozen=True)
class SphereGroups:
    """Bounding spheres of small clusters of one link's spheres: a cheap first test before the spheres.

    A configuration's spheres of group g can only touch something the group's bounding sphere touches.

    Attributes:
        frame_index: (G,) moving frame of each group.
        link_index: (G,) link of each group.
        centres: (G, 3) bounding-sphere centres in the moving frame (m).
        radii: (G,) bounding radii (m).
        offsets: (G + 1,) int64; the spheres of group g are ``members[offsets[g]:offsets[g + 1]]``.
        members: (S,) sphere indices, grouped.
    """

    frame_index: IntArray
    link_index: IntArray
    centres: FloatArray
    radii: FloatArray
    offsets: IntArray
    members: IntArray

    @property
    def count(self) -> int:
        """G, the number of groups."""
        return int(self.radii.shape[0])

    def expand(self, groups: IntArray) -> tuple[IntArray, IntArray]:
        """(which, sphere) for (K,) group ids: every member sphere and its group's position in ``groups``."""
        starts = self.offsets[groups]
        counts = self.offsets[groups + 1] - starts
        which = np.repeat(np.arange(groups.shape[0], dtype=np.int64), counts)
        within = np.arange(which.shape[0], dtype=np.int64) - np.repeat(np.cumsum(counts) - counts, counts)
        return which, self.members[starts[which] + within]


def _bounding_sphere(centres: FloatArray, radii: FloatArray) -> tuple[FloatArray, float]:
    """A sphere enclosing spheres: centred on their AABB's centre (not minimal, but tight enough)."""
    centre = ((centres - radii[:, None]).min(axis=0) + (centres + radii[:, None]).max(axis=0)) / 2.0
    return centre, float((np.linalg.norm(centres - centre, axis=1) + radii).max())


def _split(indices: list[int], centres: FloatArray, max_size: int) -> list[list[int]]:
    """Recursive median split of sphere indices along their centres' widest axis into groups <= max_size."""
    if len(indices) <= max_size:
        return [indices]
    points = centres[indices]
    axis = int(np.argmax(points.max(axis=0) - points.min(axis=0)))
    ordered = [indices[i] for i in np.argsort(points[:, axis], kind="stable")]
    half = len(ordered) // 2
    return _split(ordered[:half], centres, max_size) + _split(ordered[half:], centres, max_size)


def build_sphere_groups(spheres: SphereModel, *, max_size: int = 4) -> SphereGroups:
    """Group each link's spheres into clusters of at most ``max_size`` with bounding spheres."""
    groups: list[list[int]] = []
    for link in dict.fromkeys(spheres.link_index.tolist()):
        own = [int(i) for i in np.nonzero(spheres.link_index == link)[0]]
        groups.extend(_split(own, spheres.centres, max_size))
    bounds = [_bounding_sphere(spheres.centres[g], spheres.radii[g]) for g in groups]
    return SphereGroups(
        frame_index=np.array([spheres.frame_index[g[0]] for g in groups], dtype=np.int64),
        link_index=np.array([spheres.link_index[g[0]] for g in groups], dtype=np.int64),
        centres=np.array([c for c, _ in bounds]).reshape(-1, 3),
        radii=np.array([r for _, r in bounds]),
        offsets=np.concatenate([[0], np.cumsum([len(g) for g in groups])]).astype(np.int64),
        members=np.array([i for g in groups for i in g], dtype=np.int64),
    )


# --------------------------------------------------------------------------------------------------
# Robot


class RobotModel:
    """A serial arm with a sphere collision model.

    Args:
        chain: the kinematic chain.
        spheres: the sphere model attached to ``chain``.
        checked_link_pairs: link pairs (sorted names) tested for self-collision.
        named_states: name -> (D,) configuration (from SRDF group states covering every chain joint).
        group_size: most spheres per bounding group in the self-collision hierarchy.

    Attributes:
        groups: one bounding group per link, the first level of obstacle queries (measured fastest:
            fewer, larger groups cost fewer scene queries than small ones).
    """

    def __init__(
        self,
        *,
        chain: KinematicChain,
        spheres: SphereModel,
        checked_link_pairs: tuple[tuple[str, str], ...],
        named_states: dict[str, FloatArray] | None = None,
        group_size: int = 6,
    ) -> None:
        self.chain = chain
        self.fk = ForwardKinematics(chain)
        self.spheres = spheres
        self.groups = build_sphere_groups(spheres, max_size=spheres.count)
        self._self_groups = build_sphere_groups(spheres, max_size=group_size)
        self.checked_link_pairs = checked_link_pairs
        self.named_states = dict(named_states or {})
        self._sphere_map = self.fk.point_map(spheres.frame_index, spheres.centres)
        self._group_map = self.fk.point_map(self.groups.frame_index, self.groups.centres)
        self._self_group_map = self.fk.point_map(self._self_groups.frame_index, self._self_groups.centres)
        checked = {(chain.link_index(a), chain.link_index(b)) for a, b in checked_link_pairs}
        checked |= {(b, a) for a, b in checked}
        self.self_pairs: IntArray = _owner_pairs(spheres.link_index, checked)
        self._init_group_pairs(checked)

    def _init_group_pairs(self, checked: set[tuple[int, int]]) -> None:
        """Self-collision group pairs of checked link pairs, and their sphere pairs in CSR form."""
        g = self._self_groups
        self._group_pairs = _owner_pairs(g.link_index, checked)
        ga, gb = self._group_pairs[:, 0], self._group_pairs[:, 1]
        sizes = np.diff(g.offsets)
        x, y = _products(g.offsets[ga], sizes[ga], g.offsets[gb], sizes[gb])
        sphere_a, sphere_b = g.members[x], g.members[y]
        offsets = np.concatenate([[0], np.cumsum(sizes[ga] * sizes[gb])])
        self._group_pair_limit = (g.radii[self._group_pairs[:, 0]] + g.radii[self._group_pairs[:, 1]]) ** 2
        self._pair_offsets = np.array(offsets, dtype=np.int64)
        self._pair_a = np.array(sphere_a, dtype=np.int64)
        self._pair_b = np.array(sphere_b, dtype=np.int64)
        radii = self.spheres.radii
        self._pair_limit = (radii[self._pair_a] + radii[self._pair_b]) ** 2

    @classmethod
    def from_urdf(
        cls,
        urdf: str,
        *,
        sphere_urdf: str | None = None,
        srdf: str | None = None,
        tip_link: str | None = None,
        group: str | None = None,
    ) -> RobotModel:
        """Build the model from URDF (and optional spherized URDF and SRDF) strings.

        Args:
            urdf: kinematic URDF text.
            sphere_urdf: spherized URDF text with the same link names; ``urdf`` itself when None.
            srdf: SRDF text; its ``disable_collisions`` pairs are excluded and its group states become
                :attr:`named_states`.
            tip_link: chain tip; by default the tip of the SRDF ``group``'s chain, else see
                :func:`~drd_planner.geometry.urdf_model.parse_urdf_chain`.
            group: SRDF planning group whose chain and states to use (the first chain group when None).

        Raises:
            GeometryError: malformed or inconsistent descriptions.
        """
        info = parse_srdf(srdf) if srdf is not None else None
        if info is not None and tip_link is None and info.chains:
            name = group if group is not None else next(iter(info.chains))
            if name not in info.chains:
                raise GeometryError(f"SRDF has no chain group {name!r}; groups: {', '.join(info.chains)}")
            tip_link = info.chains[name][1]
        chain = parse_urdf_chain(urdf, tip_link=tip_link)
        spheres = _attach_spheres(chain, parse_collision_spheres(sphere_urdf if sphere_urdf else urdf))
        checked = _checked_link_pairs(chain, spheres, _excluded_pairs(chain, info))
        named: dict[str, FloatArray] = {}
        if info is not None:
            for (state_group, state), values in info.group_states.items():
                if (group is None or state_group == group) and all(j in values for j in chain.joint_names):
                    named.setdefault(state, np.array([values[j] for j in chain.joint_names]))
        return cls(chain=chain, spheres=spheres, checked_link_pairs=checked, named_states=named)

    # ----------------------------------------------------------------------------------------------
    # Kinematics

    @property
    def dof(self) -> int:
        """D, the number of chain joints."""
        return self.chain.dof

    @property
    def lower(self) -> FloatArray:
        """(D,) lower joint limits (rad or m)."""
        return self.chain.lower

    @property
    def upper(self) -> FloatArray:
        """(D,) upper joint limits (rad or m)."""
        return self.chain.upper

    def named_state(self, name: str) -> FloatArray:
        """(D,) configuration of an SRDF group state (for example ``"ready"``).

        Raises:
            GeometryError: no such state.
        """
        if name not in self.named_states:
            raise GeometryError(f"no named state {name!r}; known: {', '.join(sorted(self.named_states))}")
        state: FloatArray = self.named_states[name].copy()
        return state

    def within_limits(self, q: npt.ArrayLike) -> BoolArray:
        """(N,) True where every joint of the (N, D) configurations lies within its limits."""
        qa = self.fk.as_configurations(q)
        return np.asarray(np.all((qa >= self.lower) & (qa <= self.upper), axis=1), dtype=bool)

    def link_poses(self, q: npt.ArrayLike) -> FloatArray:
        """(N, L, 4, 4) pose of every URDF link for (N, D) configurations."""
        return self.fk.link_poses(q)

    def sphere_centres(self, q: npt.ArrayLike) -> FloatArray:
        """(N, S, 3) sphere centres (m) in the root frame for (N, D) configurations."""
        return self.sphere_centres_from_frames(self.fk.frames(q))

    def sphere_centres_from_frames(self, frames: FloatArray) -> FloatArray:
        """(N, S, 3) sphere centres (m) from (N, D + 1, 4, 4) frame poses."""
        return ForwardKinematics.apply_point_map(frames, self._sphere_map)

    def group_centres_from_frames(self, frames: FloatArray) -> FloatArray:
        """(N, G, 3) centres (m) of the per-link groups (:attr:`groups`) from (N, D + 1, 4, 4) frames."""
        return ForwardKinematics.apply_point_map(frames, self._group_map)

    # ----------------------------------------------------------------------------------------------
    # Self-collision

    def self_collision(self, q: npt.ArrayLike) -> BoolArray:
        """(N,) True where any checked sphere pair overlaps (distance < sum of radii) in a configuration.

        Group bounding spheres are tested first; sphere pairs only for the group pairs that overlap.
        """
        qa = self.fk.as_configurations(q)
        out = np.zeros(qa.shape[0], dtype=bool)
        if self._group_pairs.shape[0] == 0:
            return out
        for start in range(0, qa.shape[0], SELF_COLLISION_BLOCK):
            block = qa[start : start + SELF_COLLISION_BLOCK]
            out[start : start + block.shape[0]] = self._self_collision_block(block)
        return out

    def _self_collision_block(self, q: FloatArray) -> BoolArray:
        """:meth:`self_collision` of one block of configurations."""
        out = np.zeros(q.shape[0], dtype=bool)
        frames = self.fk.frames(q)
        centres = ForwardKinematics.apply_point_map(frames, self._self_group_map)
        d = centres[:, self._group_pairs[:, 0]] - centres[:, self._group_pairs[:, 1]]
        rows, pairs = np.nonzero(np.einsum("npi,npi->np", d, d) < self._group_pair_limit)
        if rows.size == 0:
            return out
        configs, row_pos = np.unique(rows, return_inverse=True)
        spheres = self.sphere_centres_from_frames(frames[configs])
        starts = self._pair_offsets[pairs]
        counts = self._pair_offsets[pairs + 1] - starts
        which = np.repeat(np.arange(pairs.shape[0], dtype=np.int64), counts)
        index = starts[which] + np.arange(which.shape[0]) - np.repeat(np.cumsum(counts) - counts, counts)
        at = row_pos[which]
        diff = spheres[at, self._pair_a[index]] - spheres[at, self._pair_b[index]]
        hit = np.einsum("ki,ki->k", diff, diff) < self._pair_limit[index]
        out[configs[at[hit]]] = True
        return out

    def self_collision_brute_force(self, q: npt.ArrayLike) -> BoolArray:
        """(N,) :meth:`self_collision` computed over every checked sphere pair directly (for testing)."""
        centres = self.sphere_centres(q)
        a, b = self.self_pairs[:, 0], self.self_pairs[:, 1]
        limit = (self.spheres.radii[a] + self.spheres.radii[b]) ** 2
        d = centres[:, a] - centres[:, b]
        return np.asarray(np.any(np.einsum("npi,npi->np", d, d) < limit, axis=1), dtype=bool)

    def describe(self) -> dict[str, Any]:
        """JSON-able summary: robot name, joints, limits, sphere, group and self-pair counts."""
        return {
            "robot": self.chain.robot_name,
            "joints": list(self.chain.joint_names),
            "lower": self.lower.tolist(),
            "upper": self.upper.tolist(),
            "spheres": self.spheres.count,
            "link_groups": self.groups.count,
            "self_collision_sphere_pairs": int(self.self_pairs.shape[0]),
        }
