import numpy as np
import pytest

from drd_planner.core.episode import TableOracle, run_episode
from drd_planner.core.policies import DirectBisectPolicy
from drd_planner.core.switch_threshold import select_switch_threshold
from drd_planner.core.tree import build_tree
from drd_planner.domains.planar import make_planar_problem
from drd_planner.exceptions import ProblemError


@pytest.fixture(scope="module")
def problem():  # type: ignore[no-untyped-def]
    return make_planar_problem(num_vertices=60, model="one_wall", num_worlds=120, max_paths=40, seed=3)


def test_choice_is_the_best_validated_candidate(problem) -> None:  # type: ignore[no-untyped-def]
    choice = select_switch_threshold(problem, candidates=(0.1, 0.3, 1.0), pseudo_counts=(None, 10.0), seed=1)
    assert set(choice.mean_checks) == {(e, k) for e in (0.1, 0.3, 1.0) for k in (None, 10.0)}
    assert choice.mean_checks[(choice.eta, choice.pseudo_count)] == min(choice.mean_checks.values())
    worlds = problem.worlds
    held = np.asarray(choice.validation_ids)
    # Only feasible training worlds are held out; the test worlds are never touched.
    assert np.isin(held, worlds.train_ids).all()
    assert not np.isin(held, worlds.test_ids).any()
    assert worlds.R[held].any(axis=1).all()


@pytest.mark.parametrize("kappa", [None, 7.0])
def test_validation_means_are_recomputable(problem, kappa) -> None:  # type: ignore[no-untyped-def]
    import dataclasses

    choice = select_switch_threshold(problem, candidates=(0.2,), pseudo_counts=(kappa,), seed=5)
    assert (choice.eta, choice.pseudo_count) == (0.2, kappa)
    worlds = problem.worlds
    held = np.asarray(choice.validation_ids)
    fit = np.setdiff1d(worlds.train_ids, held)
    tree = build_tree(dataclasses.replace(problem, worlds=worlds.subset(fit, held)), progress=False)
    total = 0
    for w in held:
        policy = DirectBisectPolicy(tree, problem.library, problem.edge_costs, eta=0.2, pseudo_count=kappa)
        total += run_episode(problem.library, problem.edge_costs, policy, TableOracle(worlds.X[w])).num_checks
    assert choice.mean_checks[(0.2, kappa)] == pytest.approx(total / held.size)


@pytest.mark.parametrize("options", [{"max_prob_region": False}, {"top_regions": 3}])
def test_validation_tree_is_built_with_the_final_trees_options(problem, options) -> None:  # type: ignore[no-untyped-def]
    import dataclasses

    choice = select_switch_threshold(
        problem, candidates=(0.05,), pseudo_counts=(None,), seed=5, tree_options=options
    )
    default = select_switch_threshold(problem, candidates=(0.05,), pseudo_counts=(None,), seed=5)
    worlds = problem.worlds
    held = np.asarray(choice.validation_ids)
    fit = np.setdiff1d(worlds.train_ids, held)
    sub = dataclasses.replace(problem, worlds=worlds.subset(fit, held))
    trees = {"given": build_tree(sub, progress=False, **options), "default": build_tree(sub, progress=False)}
    means = {}
    for key, tree in trees.items():
        total = 0
        for w in held:
            policy = DirectBisectPolicy(tree, problem.library, problem.edge_costs, eta=0.05)
            total += run_episode(
                problem.library, problem.edge_costs, policy, TableOracle(worlds.X[w])
            ).num_checks
        means[key] = total / held.size
    assert choice.mean_checks[(0.05, None)] == pytest.approx(means["given"])
    assert default.mean_checks[(0.05, None)] == pytest.approx(means["default"])


def test_same_seed_same_choice_and_ties_go_to_larger_eta_then_fixed_leaf(problem) -> None:  # type: ignore[no-untyped-def]
    a = select_switch_threshold(problem, seed=7)
    b = select_switch_threshold(problem, seed=7)
    assert a == b
    best = min(a.mean_checks.values())
    tied = [k for k, v in a.mean_checks.items() if v == best]
    assert a.eta == max(e for e, _ in tied)
    if (a.eta, None) in tied:
        assert a.pseudo_count is None
    assert "eta" in a.describe() and a.as_json()["pseudo_count"] == a.pseudo_count


@pytest.mark.parametrize("cands", [(), (0.0,), (1.5,), (-0.1, 0.5)])
def test_bad_candidates_are_refused(problem, cands) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(ProblemError, match="eta candidates"):
        select_switch_threshold(problem, candidates=cands)


@pytest.mark.parametrize("kappas", [(), (0.0,), (-1.0,), (float("nan"),)])
def test_bad_pseudo_counts_are_refused(problem, kappas) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(ProblemError, match="pseudo-counts"):
        select_switch_threshold(problem, candidates=(0.2,), pseudo_counts=kappas)
