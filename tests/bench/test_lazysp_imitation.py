"""The imitation-learned LazySP selector: the clairvoyant oracle's Q against hand-worked values, the
features, deterministic DAgger training, safe episodes, the registry, bad input, and a real dataset."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import gccd_folder

from drd_planner.bench.lazysp_imitation import (
    DELTA_CAP,
    FEATURE_NAMES,
    IMITATION_POLICY,
    ClairvoyantOracle,
    DaggerSettings,
    ImitationLazySP,
    ImitationModel,
    candidate_features,
    fit_ridge,
    ranked_choice,
    train_for_problem,
    train_imitation_selector,
)
from drd_planner.bench.lazysp_learned import all_edge_outcomes
from drd_planner.bench.learned_policies import TRAIN_WORLD_POLICIES
from drd_planner.core.episode import EpisodeResult, GraphPathPolicy, TableOracle, run_episode
from drd_planner.core.graph import ExplicitGraph
from drd_planner.core.lazysp import LazySP
from drd_planner.core.library import PathLibrary
from drd_planner.core.policies import POLICIES, PolicyContext, graph_policies
from drd_planner.core.status import PlanStatus
from drd_planner.data.gccd import load_gccd_folder
from drd_planner.exceptions import ProblemError

# The chain 0 -e0- 1 -e1- 2 -e2- 3 (length 1 each), a detour around e0 (0 -e3- 4 -e4- 1, 1 + 1), one
# around e1 (1 -e5- 5 -e6- 2, 1.5 + 1.5) and a long edge 0 -e7- 3 (10).
GRAPH = ExplicitGraph(
    np.array([(0, 1), (1, 2), (2, 3), (0, 4), (4, 1), (1, 5), (5, 2), (0, 3)]),
    np.array([1.0, 1.0, 1.0, 1.0, 1.0, 1.5, 1.5, 10.0]),
    6,
)
# The world of the hand-worked oracle: e0, e1 and e6 blocked.
WORLD = np.array([0, 0, 1, 1, 1, 1, 0, 1], dtype=bool)


def toy_worlds(n: int, seed: int) -> np.ndarray:
    """(n, 8) random training worlds of GRAPH; the long edge e7 is always free."""
    x = np.random.default_rng(seed).random((n, 8)) > 0.4
    x[:, 7] = True
    return x


def run(policy: LazySP, world: np.ndarray) -> EpisodeResult:
    return run_episode(None, np.ones(world.size), policy, TableOracle(world))


def test_oracle_q_matches_the_hand_worked_values() -> None:
    # From the start, the lazy path is e0 e1 e2 (length 3); e0 and e1 are blocked on it. Deleting e0
    # costs 1 (detour e3 e4), deleting e1 costs 2 (e5 e6), so the rollout checks e1. Its next path is
    # e0 e5 e6 e2 (5): e0 costs 1, e6 costs 5 (only e7 is left), so it checks e6; then e7 (10) is free:
    # S = (e1, e6), final path (e7), R = 2 blocked + 1 free = 3.
    oracle = ClairvoyantOracle(GRAPH, 0, 3, WORLD)
    none = np.zeros(8, dtype=bool)
    picks, final = oracle.blocked_phase(frozenset())
    assert picks == (1, 6)
    assert final is not None
    np.testing.assert_array_equal(final, [7])
    assert oracle.rollout_cost(frozenset(), none) == 3
    # Q(e0) = 1 + R(e0 known blocked): path e3 e4 e1 e2, check e1, path e3 e4 e5 e6 e2, check e6,
    # then e7: 1 + 3 = 4 (the bound 1 + 3 - [e0 in S] = 4 too). Q(e1) = 1 + R({e1}) = 1 + 2 = 3 = R:
    # the oracle's own pick. Q(e2): free and not on the final path, so it is wasted: 1 + 3 = 4.
    for rollouts in (True, False):
        q = oracle.q_values(frozenset(), none, np.array([0, 1, 2]), np.inf if rollouts else -np.inf)
        np.testing.assert_array_equal(q, [4.0, 3.0, 4.0])
    # With e1 and e6 known blocked the path is e7 alone: checking it ends the episode (Q = R = 1).
    np.testing.assert_array_equal(oracle.q_values(frozenset({1, 6}), none, np.array([7])), [1.0])
    assert oracle.work > 0


def test_oracle_takes_the_better_continuation_for_a_blocked_edge() -> None:
    # e0 is not in S, but knowing it blocked first is no worse than the rollout's own order; and the
    # bound caps Q(e) at 1 + R whatever e's own greedy rollout does.
    oracle = ClairvoyantOracle(GRAPH, 0, 3, WORLD)
    checked = np.zeros(8, dtype=bool)
    checked[2] = True  # e2 checked free: it is not on the final path, so R does not count it
    assert oracle.rollout_cost(frozenset(), checked) == 3
    q = oracle.q_values(frozenset(), checked, np.array([0, 1]))
    assert q.max() <= 1 + oracle.rollout_cost(frozenset(), checked)
    # A world cut in two: the rollout ends with no path and counts only blocked checks.
    cut = WORLD.copy()
    cut[7] = False
    picks, final = ClairvoyantOracle(GRAPH, 0, 3, cut).blocked_phase(frozenset())
    assert final is None
    assert picks == (1, 6, 7)


def test_features_are_documented_and_capped() -> None:
    feats = candidate_features(
        np.array([0.2, 0.9]),
        np.array([0.3, 0.5]),
        np.array([np.inf, 2.0]),
        np.array([1.0, 3.0]),
        np.array([0, 2]),
        np.array([1.0, 1.0, 3.0]),
    )
    assert feats.shape == (2, len(FEATURE_NAMES))
    assert feats.dtype == np.float64
    row = dict(zip(FEATURE_NAMES, feats[0], strict=True))
    assert row == {
        "bias": 1.0,
        "posterior": 0.2,
        "marginal": 0.3,
        "delta": DELTA_CAP,
        "bridge": 1.0,
        "posterior_x_delta": 0.2 * DELTA_CAP,
        "position": 0.0,
        "length": 0.2,
        "first_open": 1.0,
    }
    np.testing.assert_allclose(feats[1], [1.0, 0.9, 0.5, 0.4, 0.0, 0.36, 1.0, 0.6, 0.0])
    assert ranked_choice(np.array([1.0, 0.5, 0.5]), np.array([0.9, 0.1, 0.3])) == 2  # tie: posterior
    assert ranked_choice(np.array([0.5, 0.5]), np.array([0.3, 0.3])) == 0  # then the earlier edge


def test_ridge_recovers_a_linear_target() -> None:
    rng = np.random.default_rng(0)
    feats = np.column_stack([np.ones(50), rng.random((50, 2))])
    w = np.array([0.5, -2.0, 1.0])
    np.testing.assert_allclose(fit_ridge(feats, feats @ w, np.ones(50), 0.0), w, atol=1e-9)


def test_training_is_deterministic_and_episodes_end_on_a_checked_free_path() -> None:
    x = toy_worlds(30, seed=1)
    settings = DaggerSettings(rounds=2, worlds_per_round=6)
    first = train_imitation_selector(GRAPH, 0, 3, x, seed=3, settings=settings)
    again = train_imitation_selector(GRAPH, 0, 3, x, seed=3, settings=settings)
    np.testing.assert_array_equal(first.weights, again.weights)
    assert first.feature_names == FEATURE_NAMES
    assert first.stats["episodes"] == 18
    assert first.stats["states"] > 0
    outcomes = all_edge_outcomes(x)
    for world in toy_worlds(20, seed=2):
        result = run(ImitationLazySP(GRAPH, 0, 3, outcomes, first), world)
        if result.status is PlanStatus.FOUND:
            assert result.path_edges is not None
            checked_free = {c.edge for c in result.checks if c.free}
            assert set(result.path_edges.tolist()) <= checked_free
            assert world[result.path_edges].all()
        else:
            assert result.status is PlanStatus.NO_PATH
        assert len({c.edge for c in result.checks}) == result.num_checks  # never checks twice


def test_registry_needs_a_model_trained_once() -> None:
    assert IMITATION_POLICY in POLICIES
    assert IMITATION_POLICY in graph_policies()
    assert IMITATION_POLICY in TRAIN_WORLD_POLICIES
    x = toy_worlds(10, seed=0)
    lib = PathLibrary.from_sequences([[0, 1, 2]], 8)
    args = (lib, np.ones(8), np.full(8, 0.5), None, 0)
    bare = PolicyContext(*args, graph=GRAPH, start=0, goal=3, train_worlds=x)
    with pytest.raises(ProblemError, match="imitation_model"):
        POLICIES[IMITATION_POLICY](bare)
    model = ImitationModel(np.zeros(len(FEATURE_NAMES)))
    ctx = PolicyContext(*args, graph=GRAPH, start=0, goal=3, train_worlds=x, imitation_model=model)
    with pytest.raises(ProblemError, match="training worlds"):
        POLICIES[IMITATION_POLICY](PolicyContext(*args, graph=GRAPH, start=0, goal=3, imitation_model=model))
    pol = POLICIES[IMITATION_POLICY](ctx)
    assert isinstance(pol, ImitationLazySP)
    assert isinstance(pol, GraphPathPolicy)
    assert pol.name == IMITATION_POLICY
    # All weights zero: every score ties, so the higher posterior (then the earlier edge) wins.
    path = pol.proposed_path()
    assert path is not None
    blocked = pol.blocked_probability()[path]
    assert pol.select() == int(path[int(np.argmax(blocked))])


def test_bad_input_names_the_problem() -> None:
    x = toy_worlds(5, seed=0)
    with pytest.raises(ProblemError, match=r"\(n_train, 8\)"):
        train_imitation_selector(GRAPH, 0, 3, x[:, :5], seed=0)
    with pytest.raises(ProblemError, match="at least one training world"):
        train_imitation_selector(GRAPH, 0, 3, x[:0], seed=0)
    with pytest.raises(ProblemError, match="goal vertex 9"):
        train_imitation_selector(GRAPH, 0, 9, x, seed=0)
    with pytest.raises(ProblemError, match="train_weights"):
        train_imitation_selector(GRAPH, 0, 3, x, seed=0, train_weights=np.ones(4))
    with pytest.raises(ProblemError, match="rounds"):
        train_imitation_selector(GRAPH, 0, 3, x, seed=0, settings=DaggerSettings(rounds=-1))
    with pytest.raises(ProblemError, match="beta"):
        train_imitation_selector(GRAPH, 0, 3, x, seed=0, settings=DaggerSettings(beta=2.0))
    with pytest.raises(ProblemError, match="weights must be"):
        ImitationModel(np.zeros(3))
    with pytest.raises(ProblemError, match="world_free"):
        ClairvoyantOracle(GRAPH, 0, 3, WORLD[:4])
    untrained = ImitationLazySP(GRAPH, 0, 3, all_edge_outcomes(x), None)
    with pytest.raises(ProblemError, match="trained model"):
        untrained.select()


def test_beats_forward_lazysp_on_one_wall() -> None:
    # Measured on dataset_2d_1 with this small budget (about 1.5 s of training): mean checks over the
    # first 40 test worlds 71.4-71.9 for seeds 0-4 against 85.1 for forward LazySP.
    problem = load_gccd_folder(gccd_folder("dataset_2d_1"))
    worlds = problem.require_worlds()
    assert problem.graph is not None
    assert problem.start is not None
    assert problem.goal is not None
    settings = DaggerSettings(work_budget=5e6, rollouts=False)
    model = train_for_problem(problem, seed=0, settings=settings)
    outcomes = all_edge_outcomes(worlds.X[worlds.train_ids])
    learned, forward = [], []
    for world in worlds.test_ids[:40]:
        x = worlds.X[world]
        result = run(ImitationLazySP(problem.graph, problem.start, problem.goal, outcomes, model), x)
        assert result.success
        learned.append(result.num_checks)
        forward.append(run(LazySP(problem.graph, problem.start, problem.goal), x).num_checks)
    assert np.mean(learned) <= np.mean(forward)
