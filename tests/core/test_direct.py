"""DiRECt greedy step (docs/algorithms.md, "DiRECt") against an independent brute-force reference.

The reference below uses no algebraic shortcut: every ECD problem is written out as an explicit list
of classes (sets of training worlds), and the EC weight of a version space is the explicit sum, over
pairs of surviving worlds in different classes, of P(h) P(h') (prior masses, never renormalised).
Only the colour *assignment* of the colouring variant is taken from production
(``greedy_region_colouring``, tested on its own below); all weights, logs and the tie rule are
recomputed here in plain Python.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from drd_planner.core.direct import DirectSelector, greedy_region_colouring, pick_best_test

TIE_RTOL = 1e-9

Classes = list[frozenset[int]]


# --------------------------------------------------------------------------------------------------
# Brute-force reference
# --------------------------------------------------------------------------------------------------


def atoms_of(R: npt.NDArray[np.bool_]) -> list[frozenset[int]]:
    """Groups of worlds with identical membership rows of R (computed on the whole database)."""
    groups: dict[tuple[bool, ...], set[int]] = {}
    for h in range(R.shape[0]):
        groups.setdefault(tuple(bool(v) for v in R[h]), set()).add(h)
    return [frozenset(g) for g in groups.values()]


def ecd_problems(R: npt.NDArray[np.bool_], colouring: bool) -> list[Classes]:
    """The ECD problems of variant (b) (or (c) with colouring), each as an explicit list of classes."""
    n, m = R.shape
    atoms = atoms_of(R)
    region = [frozenset(h for h in range(n) if R[h, r]) for r in range(m)]
    problems: list[Classes] = []
    if not colouring:
        for r in range(m):
            outside = [a for a in atoms if not (a & region[r])]
            problems.append([region[r], *outside])
    else:
        colour = [int(c) for c in greedy_region_colouring(R)]
        for k in sorted(set(colour)):
            members = [r for r in range(m) if colour[r] == k]
            covered: set[int] = set()
            for r in members:
                assert not (covered & region[r]), "regions of one colour must be disjoint"
                covered |= region[r]
            outside = [a for a in atoms if not (a & covered)]
            problems.append([region[r] for r in members] + outside)
    if any(not R[h].any() for h in range(n)):
        problems.append(list(atoms))
    for classes in problems:  # every ECD must partition the whole database
        seen: set[int] = set()
        for c in classes:
            assert not (seen & c)
            seen |= c
        assert seen == set(range(n))
    return problems


def ec_weight(classes: Classes, version_space: Sequence[int], prior: Sequence[float]) -> float:
    """Sum over pairs {h, h'} of surviving worlds in different classes of P(h) P(h')."""
    label = {}
    for j, c in enumerate(classes):
        for h in c:
            label[h] = j
    hs = list(version_space)
    total = 0.0
    for i in range(len(hs)):
        for k in range(i + 1, len(hs)):
            if label[hs[i]] != label[hs[k]]:
                total += prior[hs[i]] * prior[hs[k]]
    return total


def safe_log(x: float) -> float:
    """log with log 0 = -inf."""
    return math.log(x) if x > 0 else -math.inf


def log_add_exp(a: float, b: float) -> float:
    """log(e^a + e^b) with -inf handled."""
    if a == -math.inf:
        return b
    if b == -math.inf:
        return a
    hi, lo = max(a, b), min(a, b)
    return hi + math.log1p(math.exp(lo - hi))


def reference_pick(log_expected: Sequence[float], costs: Sequence[float]) -> int:
    """Maximise (1 - E)/c; scores within TIE_RTOL relative tie, broken by smaller log E, then first index."""
    scores = [-math.expm1(le) / c for le, c in zip(log_expected, costs, strict=True)]
    best = max(scores)
    near = [i for i, s in enumerate(scores) if s >= best - TIE_RTOL * abs(best)]
    lowest = min(log_expected[i] for i in near)
    if lowest == -math.inf:
        return next(i for i in near if log_expected[i] == -math.inf)
    return next(i for i in near if log_expected[i] <= lowest + TIE_RTOL * max(1.0, abs(lowest)))


@dataclass(frozen=True)
class RefChoice:
    """The reference's selection: edge id and log of the expected remaining Noisy-OR fraction."""

    edge: int
    log_expected: float
    # number of informative tests whose log E lies within the tie tolerance of the best one
    num_tied: int
    # True when the chosen edge is not the lowest-id informative edge
    not_first: bool


def reference_select(
    X: npt.NDArray[np.bool_],
    R: npt.NDArray[np.bool_],
    costs: Sequence[float],
    active: Sequence[int],
    *,
    prior: Sequence[float] | None = None,
    colouring: bool = False,
    candidate_edges: Sequence[int] | None = None,
) -> RefChoice | None:
    """Brute-force greedy DiRECt step; ties between tests go to the smallest edge id."""
    n, num_edges = X.shape
    p = [1.0] * n if prior is None else [float(v) for v in prior]
    hs = sorted({int(h) for h in active})
    problems = ecd_problems(R, colouring)
    w_now = [ec_weight(classes, hs, p) for classes in problems]
    if not hs or any(w == 0.0 for w in w_now):
        return None
    edges = list(range(num_edges)) if candidate_edges is None else sorted({int(e) for e in candidate_edges})
    mass_now = sum(p[h] for h in hs)
    tests: list[int] = []
    log_e: list[float] = []
    for e in edges:
        split = {x: [h for h in hs if bool(X[h, e]) == bool(x)] for x in (0, 1)}
        if not split[0] or not split[1]:
            continue
        acc = -math.inf
        for x in (0, 1):
            log_px = math.log(sum(p[h] for h in split[x]) / mass_now)
            big_l = 0.0
            for classes, w in zip(problems, w_now, strict=True):
                big_l += safe_log(ec_weight(classes, split[x], p)) - math.log(w)
            acc = log_add_exp(acc, log_px + big_l)
        tests.append(e)
        log_e.append(acc)
    if not tests:
        return None
    best = reference_pick(log_e, [float(costs[e]) for e in tests])
    le = log_e[best]
    tied = sum(
        1
        for v in log_e
        if (v == le) or (math.isfinite(le) and math.isfinite(v) and abs(v - le) <= 1e-6 * max(1.0, abs(le)))
    )
    return RefChoice(tests[best], le, tied, best != 0)


# --------------------------------------------------------------------------------------------------
# Random instances
# --------------------------------------------------------------------------------------------------


@dataclass
class Instance:
    """One random DiRECt problem and version space."""

    X: npt.NDArray[np.bool_]
    R: npt.NDArray[np.bool_]
    costs: npt.NDArray[np.float64]
    active: npt.NDArray[np.int64]
    prior: npt.NDArray[np.float64] | None
    colouring: bool
    candidates: npt.NDArray[np.int64] | None


def random_instance(seed: int) -> Instance:
    """A random small instance: n in 3..12 worlds, 2..8 edges, 1..5 paths, mixed options."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(3, 13))
    num_edges = int(rng.integers(2, 9))
    m = int(rng.integers(1, 6))
    X = rng.random((n, num_edges)) < rng.uniform(0.3, 0.9)
    if rng.random() < 0.6:  # paths as edge subsets: valid iff all their edges are free
        R = np.zeros((n, m), dtype=bool)
        for i in range(m):
            size = int(rng.integers(1, min(num_edges, 4) + 1))
            path = rng.choice(num_edges, size=size, replace=False)
            R[:, i] = X[:, path].all(axis=1)
    else:
        R = rng.random((n, m)) < rng.uniform(0.2, 0.7)
    k = int(rng.integers(1, n + 1)) if rng.random() < 0.3 else n - int(rng.integers(0, max(1, n // 3) + 1))
    active = rng.choice(n, size=max(1, k), replace=False).astype(np.int64)
    u = rng.random()
    if u < 0.4:
        prior = None
    elif u < 0.6:
        prior = rng.integers(1, 4, size=n).astype(np.float64)  # non-uniform path with exact ties
    elif u < 0.85:
        prior = rng.uniform(0.05, 3.0, size=n)
    else:
        prior = 10.0 ** rng.uniform(-2.0, 2.0, size=n)  # four orders of magnitude
    v = rng.random()
    if v < 0.5:
        costs = np.ones(num_edges)
    elif v < 0.75:
        costs = rng.integers(1, 4, size=num_edges).astype(np.float64)
    else:
        costs = rng.uniform(0.3, 3.0, size=num_edges)
    colouring = bool(rng.random() < 0.4)
    candidates = None
    if rng.random() < 0.3:
        size = int(rng.integers(1, num_edges + 1))
        candidates = rng.choice(num_edges, size=size, replace=True).astype(np.int64)  # shuffled, duplicates
    return Instance(X, R, costs, active, prior, colouring, candidates)


def compare(inst: Instance) -> RefChoice | None:
    """Run production and reference on one instance; assert they agree; return the reference choice."""
    sel = DirectSelector(
        inst.X,
        inst.R,
        inst.costs,
        prior=inst.prior,
        colouring=inst.colouring,
        candidate_edges=inst.candidates,
    )
    got = sel.select(inst.active)
    ref = reference_select(
        inst.X,
        inst.R,
        inst.costs.tolist(),
        inst.active.tolist(),
        prior=None if inst.prior is None else inst.prior.tolist(),
        colouring=inst.colouring,
        candidate_edges=None if inst.candidates is None else inst.candidates.tolist(),
    )
    if ref is None:
        assert got is None, f"production chose edge {got} where the reference returns None"
        return None
    assert got is not None, f"production returned None where the reference chooses {ref}"
    assert got.edge == ref.edge, f"production edge {got.edge} != reference edge {ref.edge} ({ref})"
    if math.isinf(ref.log_expected):
        assert got.log_expected_remaining == -math.inf
    else:
        assert got.log_expected_remaining == pytest.approx(ref.log_expected, rel=1e-9, abs=1e-9)
    expected_score = -math.expm1(ref.log_expected) / float(inst.costs[ref.edge])
    assert got.score == pytest.approx(expected_score, rel=1e-9, abs=1e-12)
    return ref


BLOCKS = 8
SEEDS_PER_BLOCK = 500


@pytest.mark.parametrize("block", range(BLOCKS))
def test_random_instances_match_reference(block: int) -> None:
    """Production and brute force pick the same edge (or both None) on random seeded instances."""
    chosen = not_first = decisive = 0
    for seed in range(block * SEEDS_PER_BLOCK, (block + 1) * SEEDS_PER_BLOCK):
        ref = compare(random_instance(10_000 + seed))
        if ref is not None:
            chosen += 1
            not_first += ref.not_first
            decisive += ref.num_tied == 1
    # The comparison is only meaningful if many instances make a real choice, and many of those are
    # neither "the first informative edge" nor a tie.
    assert chosen >= SEEDS_PER_BLOCK // 2, chosen
    assert not_first >= chosen // 4, (not_first, chosen)
    assert decisive >= chosen // 2, (decisive, chosen)


@st.composite
def instances(draw: st.DrawFn) -> Instance:
    """Hypothesis strategy for small DiRECt instances."""
    n = draw(st.integers(2, 9))
    num_edges = draw(st.integers(1, 6))
    m = draw(st.integers(1, 4))
    X = np.array(
        draw(st.lists(st.lists(st.booleans(), min_size=num_edges, max_size=num_edges), min_size=n, max_size=n)),
        dtype=bool,
    )
    if draw(st.booleans()):
        paths = draw(st.lists(st.sets(st.integers(0, num_edges - 1), min_size=1), min_size=m, max_size=m))
        R = np.stack([X[:, sorted(path)].all(axis=1) for path in paths], axis=1)
    else:
        R = np.array(
            draw(st.lists(st.lists(st.booleans(), min_size=m, max_size=m), min_size=n, max_size=n)),
            dtype=bool,
        )
    active = np.array(sorted(draw(st.sets(st.integers(0, n - 1), min_size=1))), dtype=np.int64)
    prior = draw(
        st.one_of(st.none(), st.lists(st.sampled_from([0.25, 0.5, 1.0, 2.0, 3.0, 0.7, 1.3]), min_size=n, max_size=n))
    )
    costs = draw(st.lists(st.sampled_from([1.0, 2.0, 0.5, 1.5, 3.0]), min_size=num_edges, max_size=num_edges))
    candidates = draw(st.one_of(st.none(), st.lists(st.integers(0, num_edges - 1), min_size=1, max_size=8)))
    return Instance(
        X,
        R,
        np.array(costs),
        active,
        None if prior is None else np.array(prior),
        draw(st.booleans()),
        None if candidates is None else np.array(candidates, dtype=np.int64),
    )


@settings(max_examples=300, deadline=None)
@given(instances())
def test_hypothesis_instances_match_reference(inst: Instance) -> None:
    """Property: the production selection equals the brute-force one on any small instance."""
    compare(inst)


# --------------------------------------------------------------------------------------------------
# Hand-computed cases
# --------------------------------------------------------------------------------------------------

# Worlds h0, h1 lie on path 0, h2 on path 1, h3 on none (so the null ECD exists). Atoms {h0,h1},
# {h2}, {h3}; the ECDs of path 0, path 1 and the null ECD all have exactly these three classes, so
# F = w^3 with w the EC weight of the partition {h0,h1} | {h2} | {h3}.
HAND_R = np.array([[1, 0], [1, 0], [0, 1], [0, 0]], dtype=bool)
# Tests (columns): e0 = [1,1,1,0] isolates h3, e1 = [1,0,1,0], e2 = [1,1,0,0] separates {h0,h1}.
HAND_X = np.array([[1, 1, 1], [1, 0, 1], [1, 1, 0], [0, 0, 0]], dtype=bool)


def test_hand_computed_uniform_prior() -> None:
    """Uniform prior: w(H) = 6 pairs - 1 same-class pair = 5.

    e0: x=1 keeps {h0,h1,h2}, w=2, p=3/4; x=0 keeps {h3}, w=0.   E = 3/4 (2/5)^3 = 0.048
    e1: x=1 keeps {h0,h2}, w=1; x=0 keeps {h1,h3}, w=1, p=1/2.    E = (1/5)^3    = 0.008
    e2: x=1 keeps {h0,h1}, w=0; x=0 keeps {h2,h3}, w=1, p=1/2.    E = 1/2 (1/5)^3 = 0.004
    Unit costs pick e2. With c(e2) = 3: scores 0.952, 0.992, 0.996/3 = 0.332, so e1 wins.
    """
    sel = DirectSelector(HAND_X, HAND_R, np.ones(3))
    assert sel.num_ecds == 3
    assert sel.has_null_ecd
    got = sel.select([0, 1, 2, 3])
    assert got is not None
    assert got.edge == 2
    assert got.log_expected_remaining == pytest.approx(math.log(0.004), rel=1e-12)
    assert got.score == pytest.approx(0.996, rel=1e-12)
    costly = DirectSelector(HAND_X, HAND_R, np.array([1.0, 1.0, 3.0])).select([0, 1, 2, 3])
    assert costly is not None
    assert costly.edge == 1
    assert costly.log_expected_remaining == pytest.approx(math.log(0.008), rel=1e-12)
    # restricting the candidates to e0 leaves e0, with E = 0.048
    only0 = DirectSelector(HAND_X, HAND_R, np.ones(3), candidate_edges=[0]).select([0, 1, 2, 3])
    assert only0 is not None
    assert only0.edge == 0
    assert only0.log_expected_remaining == pytest.approx(math.log(0.048), rel=1e-12)


def test_hand_computed_heavy_prior_flips_choice() -> None:
    """Prior (1, 1, 1, 10): class masses 2, 1, 10, so w(H) = 2*1 + 2*10 + 1*10 = 32, P(H') = 13.

    e0: x=0 keeps {h3}, w=0; x=1 keeps {h0,h1,h2}, w=2, p=3/13.   E = 3/13 (2/32)^3  ~ 5.6e-5
    e1: x=1 {h0,h2} w=1, p=2/13; x=0 {h1,h3} w=10, p=11/13.       E ~ 2.58e-2
    e2: x=1 {h0,h1} w=0; x=0 {h2,h3} w=10, p=11/13.               E = 11/13 (10/32)^3 ~ 2.58e-2
    The heavy world h3 makes isolating it (e0) best, unlike the uniform case.
    """
    got = DirectSelector(HAND_X, HAND_R, np.ones(3), prior=[1.0, 1.0, 1.0, 10.0]).select([0, 1, 2, 3])
    assert got is not None
    assert got.edge == 0
    assert got.log_expected_remaining == pytest.approx(math.log(3 / 13 * (2 / 32) ** 3), rel=1e-12)


def test_hand_case_matches_reference() -> None:
    """The brute-force reference reproduces the hand numbers (so it is not vacuous)."""
    ref = reference_select(HAND_X, HAND_R, [1.0, 1.0, 1.0], [0, 1, 2, 3])
    assert ref is not None
    assert ref.edge == 2
    assert ref.log_expected == pytest.approx(math.log(0.004))
    ref = reference_select(HAND_X, HAND_R, [1.0, 1.0, 1.0], [0, 1, 2, 3], prior=[1.0, 1.0, 1.0, 10.0])
    assert ref is not None
    assert ref.edge == 0


def test_ec_weight_by_hand() -> None:
    """Explicit pair sums of the reference on a tiny partition."""
    classes = [frozenset({0, 1}), frozenset({2}), frozenset({3})]
    assert ec_weight(classes, [0, 1, 2, 3], [1.0] * 4) == 5.0
    assert ec_weight(classes, [0, 1], [1.0] * 4) == 0.0
    assert ec_weight(classes, [0, 2, 3], [2.0, 1.0, 3.0, 5.0]) == 2 * 3 + 2 * 5 + 3 * 5


# --------------------------------------------------------------------------------------------------
# Tie rule
# --------------------------------------------------------------------------------------------------


def test_pick_best_test_rule() -> None:
    """Cost-weighted score, then smaller log E among near ties, then the first index."""
    assert pick_best_test([math.log(0.5), math.log(0.25)], [1.0, 1.0]) == 1
    assert pick_best_test([math.log(0.5), math.log(0.25)], [1.0, 2.0]) == 0  # 0.5 vs 0.375
    assert pick_best_test([math.log(0.5), math.log(0.5)], [1.0, 1.0]) == 0
    assert pick_best_test([-math.inf, -math.inf, math.log(0.1)], [2.0, 1.0, 1.0]) == 1
    # 1 - E rounds to 1 for both: the smaller log E wins
    assert pick_best_test([-800.0, -900.0], [1.0, 1.0]) == 1
    for le, c in (
        [[-1.0, -2.0, -2.0], [1.0, 1.0, 1.0]],
        [[-0.1, -3.0, -700.0, -math.inf], [1.0, 2.0, 3.0, 9.0]],
    ):
        assert pick_best_test(le, c) == reference_pick(le, c)


# --------------------------------------------------------------------------------------------------
# Colouring
# --------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("seed", range(40))
def test_colouring_never_shares_colour_across_overlap(seed: int) -> None:
    """Regions that share a world never share a colour; colours are 0..k-1."""
    rng = np.random.default_rng(seed)
    n, m = int(rng.integers(1, 30)), int(rng.integers(1, 25))
    R = rng.random((n, m)) < rng.uniform(0.02, 0.5)
    colour = greedy_region_colouring(R)
    assert colour.shape == (m,)
    assert set(colour.tolist()) == set(range(int(colour.max()) + 1))
    for a in range(m):
        for b in range(a + 1, m):
            if (R[:, a] & R[:, b]).any():
                assert colour[a] != colour[b], (a, b)


def test_colouring_star_and_extremes() -> None:
    """A star (hub overlaps every leaf, leaves disjoint) needs 2 colours; disjoint regions need 1."""
    leaves = 6
    R = np.zeros((leaves, leaves + 1), dtype=bool)
    R[:, 0] = True  # hub region holds every world
    for i in range(leaves):
        R[i, i + 1] = True  # leaf i holds world i only
    colour = greedy_region_colouring(R)
    assert colour[0] == 0
    assert set(colour[1:].tolist()) == {1}
    disjoint = np.eye(5, dtype=bool)
    assert greedy_region_colouring(disjoint).tolist() == [0] * 5
    clique = np.ones((3, 4), dtype=bool)
    assert sorted(greedy_region_colouring(clique).tolist()) == [0, 1, 2, 3]
    # the selector then has one ECD per colour (plus none for the null ECD: every world is covered)
    assert DirectSelector(np.ones((leaves, 2), dtype=bool), R, np.ones(2), colouring=True).num_ecds == 2
    assert DirectSelector(np.ones((leaves, 2), dtype=bool), R, np.ones(2)).num_ecds == leaves + 1


# --------------------------------------------------------------------------------------------------
# Stopping
# --------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("colouring", [False, True])
def test_select_none_when_active_in_one_region(colouring: bool) -> None:
    """All active worlds on one path: that region's ECD has weight 0, the DRD is solved."""
    R = np.array([[1, 0], [1, 1], [1, 0], [0, 1], [0, 0]], dtype=bool)  # worlds 0,1,2 on path 0
    X = np.array([[1, 0, 1], [0, 1, 1], [1, 1, 0], [0, 0, 1], [1, 0, 0]], dtype=bool)
    sel = DirectSelector(X, R, np.ones(3), colouring=colouring)
    assert sel.select([0, 1, 2]) is None  # three different atoms, but all in region 0
    assert reference_select(X, R, [1.0] * 3, [0, 1, 2], colouring=colouring) is None
    assert sel.select([0, 1, 2, 3]) is not None  # world 3 is off path 0 and splits atoms


@pytest.mark.parametrize("prior", [None, [1.0, 2.0, 0.5, 3.0, 1.5]])
def test_select_none_when_active_share_one_atom(prior: list[float] | None) -> None:
    """Active worlds with identical path rows (here: none valid) are one class of every ECD."""
    R = np.array([[0, 0], [0, 0], [0, 0], [1, 0], [0, 1]], dtype=bool)
    X = np.array([[1, 0], [0, 1], [1, 1], [0, 0], [1, 0]], dtype=bool)
    sel = DirectSelector(X, R, np.ones(2), prior=prior)
    assert sel.has_null_ecd
    assert sel.select([0, 1, 2]) is None
    assert sel.select([2]) is None
    assert sel.select([]) is None
    assert reference_select(X, R, [1.0, 1.0], [0, 1, 2], prior=prior) is None
    assert sel.select([0, 1, 2, 3]) is not None


def test_select_none_without_informative_test() -> None:
    """Active worlds in different atoms but identical on every candidate edge: nothing to ask."""
    R = np.array([[1, 0], [0, 1], [1, 1]], dtype=bool)
    X = np.array([[1, 0], [1, 1], [0, 1]], dtype=bool)
    sel = DirectSelector(X, R, np.ones(2), candidate_edges=[0])
    assert sel.select([0, 1]) is None
    assert reference_select(X, R, [1.0, 1.0], [0, 1], candidate_edges=[0]) is None
    got = DirectSelector(X, R, np.ones(2)).select([0, 1])
    assert got is not None
    assert got.edge == 1


# --------------------------------------------------------------------------------------------------
# Weighted priors: zero detection is relative to each branch's own squared mass
# --------------------------------------------------------------------------------------------------
# With a non-uniform prior, w = 1/2 (T^2 - a^2 - Q + S) cancels, so a weight is treated as zero when it
# is within a few ulps of its own version space's squared mass. These cases (found by the reference)
# pin that light-but-positive weights are not rounded away.


def test_tiny_weight_tie_break_exact_semantics() -> None:
    """Region {h0, h2}; h1 on no path. Prior (1e-7, 1e-7, 1). Both ECDs: classes {h0,h2} | {h1}.

    e0 = [1,1,0]: x=1 keeps {h0,h1}, w = 1e-14 > 0, so E = p1 (1e-14 / w(H'))^2 ~ 2e-21 > 0.
    e1 = [0,1,0]: x=1 keeps {h1}, x=0 keeps {h0,h2}: both weights 0, E = 0.
    (1 - E)/c is 1.0 for both in floating point, so the tie goes to the smaller log E: e1.
    An absolute threshold relative to P(H')^2 would round e0's 1e-14 weight to 0 and pick e0.
    """
    X = np.array([[1, 0], [1, 1], [0, 0]], dtype=bool)
    R = np.array([[1], [0], [1]], dtype=bool)
    prior = [1e-7, 1e-7, 1.0]
    ref = reference_select(X, R, [1.0, 1.0], [0, 1, 2], prior=prior)
    assert ref is not None
    assert ref.edge == 1
    got = DirectSelector(X, R, np.ones(2), prior=prior).select([0, 1, 2])
    assert got is not None
    assert got.edge == 1


def test_tiny_weight_not_reported_solved() -> None:
    """Prior ratio 1e13: w(H') = 1e-13 > 0, so the DRD is not solved and a test must be chosen."""
    X = np.array([[1], [0]], dtype=bool)
    R = np.array([[1], [0]], dtype=bool)
    prior = [1e-13, 1.0]
    assert reference_select(X, R, [1.0], [0, 1], prior=prior) is not None
    assert DirectSelector(X, R, np.ones(1), prior=prior).select([0, 1]) is not None
