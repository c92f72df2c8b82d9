"""Where roadmap growth puts new vertices and edges (one round of :mod:`drd_planner.planner.roadmap_growth`).

A round starts from what the plan knows: the edges checked free and blocked so far. The start's and the
goal's **known-reachable components** are the vertices reached from each over edges checked free
(:func:`known_reachable`); their **frontier** is the part of each that touches an edge checked blocked (the
blocked region cuts them off there), or the whole component when none does (:func:`frontier`). New states
(:func:`draw_states`) are

- Gaussian samples around frontier vertices of the start's and of the goal's side (standard deviation drawn
  log-uniformly in a range, in state units), where the known free space ends; each is joined to its centre
  (its parent, as a tree grows) besides its nearest vertices;
- bridge samples on the segment between a frontier vertex of one side and the nearest of the other, with a
  smaller Gaussian jitter, where the two sides must meet; each is joined to both (:func:`parent_pairs`);
- uniform samples in the sampler's box, so that a region no frontier points at is reached too.

Only statically valid states (:meth:`StateSampler.valid <drd_planner.planner.state_sampler.StateSampler.valid>`)
become vertices. Each is joined to its k nearest vertices within reach, old and new (:func:`nearest_pairs`),
and the nearest vertices of the two known-reachable components are joined directly (:func:`bridge_pairs`,
as RRT-Connect's connect step tries the other tree), by straight motions sampled at the check resolution
(:func:`straight_motions`); a motion with a statically invalid sample among about :data:`STATIC_SAMPLES`
evenly spread ones is dropped (a cheap filter: the oracle's ``check_motion`` holds every sample of an edge
the search asks for to the static rules). Nothing here checks the world.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np
from scipy.sparse import coo_array
from scipy.sparse.csgraph import breadth_first_order
from scipy.spatial import cKDTree

from drd_planner.arrays import BoolArray, FloatArray, IntArray
from drd_planner.planner.state_sampler import StateSampler

__all__ = [
    "SampleMix",
    "SegmentMaker",
    "bridge_pairs",
    "draw_states",
    "frontier",
    "known_reachable",
    "nearest_pairs",
    "parent_pairs",
    "straight_motions",
]

#: Two states closer than this (state units) are one vertex: a sample this near a vertex is dropped.
SAME_STATE = 1e-6
#: Interior samples per new edge tested against the static rules when it is made (about; a cheap filter:
#: ``check_motion`` tests every sample of an edge the search asks for).
STATIC_SAMPLES = 8


@runtime_checkable
class SegmentMaker(Protocol):
    """Makes the motion of a new edge (:class:`~drd_planner.planner.straight_connector.StraightConnector`)."""

    def segment(self, tail: FloatArray, head: FloatArray) -> FloatArray:
        """(K, D) samples of the motion from ``tail`` to ``head``, both included, at the check resolution."""
        ...


@dataclass(frozen=True)
class SampleMix:
    """How a round's samples are drawn.

    Attributes:
        count: candidate states drawn per round (count), before the static test.
        start_share: fraction Gaussian around the start side's frontier.
        goal_share: fraction Gaussian around the goal side's frontier.
        bridge_share: fraction on segments between the two frontiers; the rest is uniform.
        sigma_range: (low, high) standard deviation of the Gaussian samples (state units, e.g. rad), drawn
            log-uniformly per sample.
    """

    count: int
    start_share: float
    goal_share: float
    bridge_share: float
    sigma_range: tuple[float, float]


def known_reachable(num_vertices: int, edges: IntArray, free: BoolArray, source: int) -> IntArray:
    """Vertex ids reached from ``source`` over the (E,) edges marked ``free`` (undirected), ``source`` first."""
    pairs = edges[free]
    graph = coo_array((np.ones(pairs.shape[0]), (pairs[:, 0], pairs[:, 1])), shape=(num_vertices, num_vertices)).tocsr()
    order = breadth_first_order(graph, source, directed=False, return_predecessors=False)
    return np.asarray(order, dtype=np.int64)


def frontier(component: IntArray, edges: IntArray, blocked: BoolArray, num_vertices: int) -> IntArray:
    """The vertices of ``component`` that touch an edge marked ``blocked`` (all of it when none does)."""
    touched = np.zeros(num_vertices, dtype=bool)
    touched[edges[blocked].reshape(-1)] = True
    inside = component[touched[component]]
    return inside if inside.size else component


def _gaussian(
    rng: np.random.Generator, states: FloatArray, anchors: IntArray, count: int, mix: SampleMix
) -> tuple[FloatArray, IntArray]:
    """(count, D) Gaussian samples around vertices ``anchors`` chosen uniformly, and (count, 2) their parents."""
    if count <= 0 or anchors.size == 0:
        return np.zeros((0, states.shape[1])), np.zeros((0, 2), dtype=np.int64)
    parent = anchors[rng.integers(anchors.size, size=count)]
    low, high = mix.sigma_range
    sigma = np.exp(rng.uniform(np.log(low), np.log(high), size=(count, 1)))
    drawn = states[parent] + sigma * rng.standard_normal((count, states.shape[1]))
    return np.asarray(drawn, dtype=np.float64), np.stack([parent, np.full(count, -1)], axis=1)


def _bridges(
    rng: np.random.Generator,
    states: FloatArray,
    side_a: IntArray,
    side_b: IntArray,
    count: int,
    mix: SampleMix,
) -> tuple[FloatArray, IntArray]:
    """(count, D) jittered points between vertices of two sides, and (count, 2) those two vertices.

    Each joins a random vertex of ``side_a`` to its nearest vertex of ``side_b``.
    """
    if count <= 0 or side_a.size == 0 or side_b.size == 0:
        return np.zeros((0, states.shape[1])), np.zeros((0, 2), dtype=np.int64)
    a = side_a[rng.integers(side_a.size, size=count)]
    _, nearest = cKDTree(states[side_b]).query(states[a])
    b = side_b[np.atleast_1d(nearest)]
    t = rng.uniform(0.2, 0.8, size=(count, 1))
    jitter = 0.5 * mix.sigma_range[0] * rng.standard_normal((count, states.shape[1]))
    drawn = states[a] + t * (states[b] - states[a]) + jitter
    return np.asarray(drawn, dtype=np.float64), np.stack([a, b], axis=1).astype(np.int64)


def draw_states(
    rng: np.random.Generator,
    sampler: StateSampler,
    states: FloatArray,
    sides: tuple[IntArray, IntArray],
    mix: SampleMix,
) -> tuple[FloatArray, IntArray]:
    """The round's statically valid candidate states, in draw order (see the module docstring).

    Args:
        rng: the plan's growth stream.
        sampler: the domain's box and static rules.
        states: (V, D) the graph's vertex states.
        sides: vertex ids of the start side's and the goal side's frontier.
        mix: how many of each kind.

    Returns:
        ``(states (N, D), parents (N, 2))``: each state's anchor vertices (-1: none), which it is joined to
        besides its nearest vertices (a Gaussian sample to its centre, a bridge sample to both ends).
    """
    n_start = round(mix.count * mix.start_share)
    n_goal = round(mix.count * mix.goal_share)
    n_bridge = round(mix.count * mix.bridge_share)
    n_uniform = max(mix.count - n_start - n_goal - n_bridge, 0)
    half = n_bridge // 2
    lower, upper = sampler.lower, sampler.upper
    start_side, goal_side = sides
    parts = [
        _gaussian(rng, states, start_side, n_start, mix),
        _gaussian(rng, states, goal_side, n_goal, mix),
        _bridges(rng, states, start_side, goal_side, half, mix),
        _bridges(rng, states, goal_side, start_side, n_bridge - half, mix),
        (lower + rng.random((n_uniform, lower.size)) * (upper - lower), np.full((n_uniform, 2), -1)),
    ]
    drawn = np.concatenate([part[0] for part in parts])
    parents = np.concatenate([part[1] for part in parts]).astype(np.int64)
    valid = sampler.valid(drawn)
    return np.asarray(drawn[valid], dtype=np.float64), parents[valid]


def parent_pairs(new: IntArray, parents: IntArray, states: FloatArray, *, reach: float) -> IntArray:
    """(M, 2) pairs u < v joining each vertex ``new[i]`` to its parents ``parents[i]`` (-1: none) within ``reach``."""
    pairs = np.stack([np.repeat(new, 2), parents.reshape(-1)], axis=1)
    pairs = pairs[pairs[:, 1] >= 0]
    near = np.linalg.norm(states[pairs[:, 0]] - states[pairs[:, 1]], axis=1)
    return np.sort(pairs[(near <= reach) & (near > SAME_STATE)], axis=1).astype(np.int64)


def nearest_pairs(states: FloatArray, new: IntArray, usable: BoolArray, *, neighbours: int, reach: float) -> IntArray:
    """(M, 2) pairs u < v joining each vertex of ``new`` to its nearest usable vertices, each pair once.

    Each is joined to its ``neighbours`` nearest other vertices marked ``usable`` ((V,) flags of the (V, D)
    ``states``) within ``reach`` (state units), old or new.
    """
    candidates = np.flatnonzero(usable)
    k = min(neighbours + 1, candidates.size)
    if new.size == 0 or k < 2:
        return np.zeros((0, 2), dtype=np.int64)
    dist, idx = cKDTree(states[candidates]).query(states[new], k=k, distance_upper_bound=reach)
    dist, idx = np.atleast_2d(dist), np.atleast_2d(idx)
    found = np.isfinite(dist.reshape(-1))
    pairs = np.stack([np.repeat(new, k)[found], candidates[idx.reshape(-1)[found]]], axis=1)
    keep = (pairs[:, 0] != pairs[:, 1]) & (dist.reshape(-1)[found] > SAME_STATE)
    return np.unique(np.sort(pairs[keep], axis=1), axis=0).astype(np.int64)


def bridge_pairs(states: FloatArray, side_a: IntArray, side_b: IntArray, *, count: int, reach: float) -> IntArray:
    """(M, 2) pairs u < v: the ``count`` shortest joins between two sets of vertices, shortest first.

    Each vertex of ``side_a`` (ids into the (V, D) ``states``) is matched to its three nearest vertices of
    ``side_b`` within ``reach`` (state units); the ``count`` shortest matches are kept.
    """
    if count < 1 or side_a.size == 0 or side_b.size == 0:
        return np.zeros((0, 2), dtype=np.int64)
    k = min(3, side_b.size)
    dist, idx = cKDTree(states[side_b]).query(states[side_a], k=k, distance_upper_bound=reach)
    dist, idx = dist.reshape(side_a.size, k), idx.reshape(side_a.size, k)
    rows, cols = np.nonzero(np.isfinite(dist) & (dist > SAME_STATE))
    order = np.argsort(dist[rows, cols], kind="stable")[:count]
    pairs = np.stack([side_a[rows[order]], side_b[idx[rows[order], cols[order]]]], axis=1)
    return np.sort(pairs, axis=1).astype(np.int64)


def straight_motions(
    states: FloatArray, pairs: IntArray, *, connector: SegmentMaker, sampler: StateSampler
) -> tuple[IntArray, list[FloatArray]]:
    """The (M', 2) pairs whose straight motions pass the cheap static filter, and those (K, D) motions (u to v).

    A motion is dropped when one of about :data:`STATIC_SAMPLES` evenly spread interior samples is statically
    invalid.
    """
    lines = [connector.segment(states[u], states[v]) for u, v in pairs.tolist()]
    if not lines:
        return pairs.reshape(-1, 2), []
    interiors = [line[1:-1][:: max(1, len(line) // STATIC_SAMPLES)] for line in lines]
    owner = np.repeat(np.arange(len(lines)), [len(q) for q in interiors])
    invalid = ~sampler.valid(np.concatenate(interiors))
    keep = np.bincount(owner[invalid], minlength=len(lines)) == 0
    return pairs[keep], [line for line, ok in zip(lines, keep.tolist(), strict=True) if ok]
