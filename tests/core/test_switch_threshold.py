import numpy as np
import pytest

from drd_planner.core.episode import TableOracle, run_episode
from drd_planner.core.policies import DirectBisectPolicy
from drd_planner.core.switch_threshold import ValidationGrid, select_switch_threshold
from drd_planner.core.tree import build_tree
from drd_planner.data.planar_problem import make_planar_problem
from drd_planner.exceptions import ProblemError


@pytest.fixture(scope="module")
def problem():  # type: ignore[no-untyped-def]
    return make_planar_problem(num_vertices=60, model="one_wall", num_worlds=120, max_paths=40, seed=3)


def test_choice_is_the_best_validated_candidate(problem) -> None:  # type: ignore[no-untyped-def]
    choice = select_switch_threshold(
        problem, ValidationGrid(candidates=(0.1, 0.3, 1.0), pseudo_counts=(None, 10.0)), seed=1
    )
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

    choice = select_switch_threshold(problem, ValidationGrid(candidates=(0.2,), pseudo_counts=(kappa,)), seed=5)
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
        problem, ValidationGrid(candidates=(0.05,), pseudo_counts=(None,), tree_options=options), seed=5
    )
    default = select_switch_threshold(problem, ValidationGrid(candidates=(0.05,), pseudo_counts=(None,)), seed=5)
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
            total += run_episode(problem.library, problem.edge_costs, policy, TableOracle(worlds.X[w])).num_checks
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
    assert "eta" in a.describe()
    assert a.as_json()["pseudo_count"] == a.pseudo_count


@pytest.mark.parametrize("cands", [(), (0.0,), (1.5,), (-0.1, 0.5)])
def test_bad_candidates_are_refused(problem, cands) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(ProblemError, match="eta candidates"):
        select_switch_threshold(problem, ValidationGrid(candidates=cands))


@pytest.mark.parametrize("kappas", [(), (0.0,), (-1.0,), (float("nan"),)])
def test_bad_pseudo_counts_are_refused(problem, kappas) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(ProblemError, match="pseudo-counts"):
        select_switch_threshold(problem, ValidationGrid(candidates=(0.2,), pseudo_counts=kappas))


def test_max_worlds_limits_the_validation_worlds(problem) -> None:  # type: ignore[no-untyped-def]
    full = select_switch_threshold(problem, ValidationGrid(candidates=(0.2, 1.0), pseudo_counts=(None,)), seed=1)
    quick = select_switch_threshold(
        problem, ValidationGrid(candidates=(0.2, 1.0), pseudo_counts=(None,)), seed=1, max_worlds=3
    )
    assert len(full.validation_ids) > 3
    assert len(quick.validation_ids) == 3
    assert set(quick.validation_ids) <= set(problem.worlds.train_ids.tolist())
    assert quick.seconds > 0
    assert quick.as_json()["num_validation_worlds"] == 3
    with pytest.raises(ProblemError, match="max_worlds"):
        select_switch_threshold(problem, ValidationGrid(candidates=(0.2,), pseudo_counts=(None,)), max_worlds=0)


def test_summary_is_a_few_short_lines() -> None:
    from drd_planner.core.switch_threshold import SwitchThresholdChoice

    means = {(e, k): 10.0 + e + (k or 0) for e in (0.05, 0.1, 0.2, 0.4, 0.6, 1.0) for k in (None, 5.0, 20.0, 50.0)}
    choice = SwitchThresholdChoice(0.2, 5.0, means, tuple(range(90)), seconds=9.54)
    lines = choice.summary_lines()
    assert lines[0] == "eta 0.2, kappa 5: validated in 9.5 s on 90 held-out training worlds"
    assert lines[1].split() == ["mean", "checks", "fixed", "kappa", "5", "kappa", "20", "kappa", "50"]
    assert len(lines) == 2 + 6
    assert max(len(line) for line in lines) <= 100
    assert lines[4].split() == ["eta", "0.2", "10.20", "15.20*", "30.20", "60.20"]
    # Columns line up: every number ends under the end of its header (a "*" may follow it).
    for head in ("fixed", "kappa 5", "kappa 20", "kappa 50"):
        end = lines[1].index(head) + len(head)
        assert lines[3][end - 1].isdigit(), head
        assert lines[3][end : end + 1] in (" ", "*", ""), head


def test_k_fold_validation_uses_disjoint_folds_and_the_one_standard_error_rule(problem) -> None:  # type: ignore[no-untyped-def]
    grid = ValidationGrid(candidates=(0.05, 0.3, 1.0), pseudo_counts=(None, 10.0))
    choice = select_switch_threshold(problem, grid, seed=2, folds=3)
    worlds = problem.worlds
    held = np.asarray(choice.validation_ids)
    per_fold = round(0.1 * worlds.train_ids.size)
    # three disjoint folds
    assert held.size == 3 * per_fold
    assert np.unique(held).size == held.size
    assert np.isin(held, worlds.train_ids).all()
    assert worlds.R[held].any(axis=1).all()
    for candidate, means in choice.fold_means.items():
        assert len(means) == 3
        assert choice.mean_checks[candidate] == pytest.approx(np.mean(means))
    best = min(choice.mean_checks.values())
    best_candidate = min(choice.mean_checks, key=lambda c: (choice.mean_checks[c], -c[0]))
    within = {c for c, v in choice.mean_checks.items() if v <= best + choice.standard_error(best_candidate) + 1e-12}
    chosen = (choice.eta, choice.pseudo_count)
    assert chosen in within
    # The simplest of those within one standard error: no candidate there has a larger eta, and at the
    # same eta the fixed leaf goes first.
    assert all(c[0] <= chosen[0] for c in within)
    if chosen[1] is not None:
        assert (chosen[0], None) not in within
    assert choice.standard_error(chosen) >= 0.0
    summary = choice.as_json()
    assert summary["folds"] == 3
    assert set(summary["standard_error"]) == {
        f"eta {e:g}" + ("" if k is None else f" kappa {k:g}") for e, k in choice.mean_checks
    }
    assert "3 folds x" in choice.describe()
    # Same seed, same folds, same choice; one fold is the single split of before.
    assert select_switch_threshold(problem, grid, seed=2, folds=3) == choice
    single = select_switch_threshold(problem, grid, seed=2)
    assert single.fold_means == {}
    assert single.standard_error((single.eta, single.pseudo_count)) == 0.0


def test_folds_shrink_to_what_the_worlds_hold_and_bad_folds_are_refused(problem) -> None:  # type: ignore[no-untyped-def]
    grid = ValidationGrid(candidates=(0.2,), pseudo_counts=(None,))
    many = select_switch_threshold(problem, grid, seed=0, folds=1000, max_worlds=5)
    feasible = int(problem.worlds.R[problem.worlds.train_ids].any(axis=1).sum())
    assert len(many.fold_means[(0.2, None)]) == (feasible - 1) // 5  # folds of 5 worlds, one world kept
    assert len(many.validation_ids) == 5 * ((feasible - 1) // 5)
    for bad in (0, -1, 2.5):
        with pytest.raises(ProblemError, match="folds must be an integer >= 1"):
            select_switch_threshold(problem, grid, folds=bad)  # type: ignore[arg-type]
