"""The benchmark runner: seeding, failures and the check cap, the JSON's Table-1 blocks."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from conftest import gccd_folder

from drd_planner.bench.runner import (
    DEFAULT_POLICIES,
    TABLE1_POLICIES,
    BenchmarkResult,
    PolicySettings,
    PolicyStats,
    available_policies,
    benchmark_json,
    json_safe,
    policy_context,
    run_benchmark,
    run_world,
    train_bias,
)
from drd_planner.bench.stats import table1_stats
from drd_planner.core.policies import DEFAULT_ALPHA, DEFAULT_ETA, POLICIES, PolicyContext
from drd_planner.core.problem import Problem
from drd_planner.core.tree import DecisionTree, build_tree
from drd_planner.data.gccd import load_gccd_folder
from drd_planner.data.planar_problem import make_planar_problem
from drd_planner.exceptions import DrdError, ProblemError


@pytest.fixture(scope="module")
def problem() -> Problem:
    return load_gccd_folder(gccd_folder("dataset_2d_1"))


@pytest.fixture(scope="module")
def tree(problem: Problem) -> DecisionTree:
    return build_tree(problem, progress=False)


def test_default_policies_are_the_registered_table1_set() -> None:
    assert DEFAULT_POLICIES == tuple(p for p in TABLE1_POLICIES if p in POLICIES)
    assert {"direct_bisect", "bisect", "direct_only", "bisect_all"} <= set(DEFAULT_POLICIES)
    assert available_policies(["bisect", "no_such_policy", "direct_bisect"]) == ("bisect", "direct_bisect")


def test_policy_context_passes_the_graph_when_supported(problem: Problem, tree: DecisionTree) -> None:
    ctx = policy_context(problem, theta=train_bias(problem), tree=tree, seed=5, settings=PolicySettings(eta=0.3))
    assert ctx.seed == 5
    assert ctx.eta == 0.3
    assert ctx.tree is tree
    assert isinstance(ctx, PolicyContext)
    assert ctx.graph is problem.graph
    assert ctx.graph is not None
    assert (ctx.start, ctx.goal) == (problem.start, problem.goal)


def test_policy_context_carries_the_training_worlds(problem: Problem) -> None:
    ctx = policy_context(problem, theta=train_bias(problem), tree=None, seed=0)
    worlds = problem.require_worlds()
    # uniform prior
    assert ctx.train_worlds is not None
    assert ctx.train_weights is None
    np.testing.assert_array_equal(ctx.train_worlds, worlds.X[worlds.train_ids])
    # Only a policy that needs them pays for the copy (a context is built for every episode).
    lean = policy_context(problem, theta=train_bias(problem), tree=None, seed=0, policy="bisect")
    assert lean.train_worlds is None
    full = policy_context(problem, theta=train_bias(problem), tree=None, seed=0, policy="lazysp_posterior")
    assert full.train_worlds is not None


def test_bench_runs_the_learned_lazysp_selectors(problem: Problem, tmp_path: Path) -> None:
    from drd_planner.cli.main import main

    names = ["lazysp", "lazysp_posterior", "lazysp_posterior_delta"]
    out = tmp_path / "lazy.json"
    argv = ["bench", "--gccd", str(gccd_folder("dataset_2d_1")), "--max-worlds", "3"]
    assert main([*argv, "--policies", ",".join(names), "--json", str(out)]) == 0
    doc = json.loads(out.read_text())
    assert list(doc["policies"]) == names
    for name in names:
        assert doc["policies"][name]["failures"] == 0
        assert all(c > 0 for c in doc["policies"][name]["checks"])
    assert not set(names[1:]) & set(DEFAULT_POLICIES)  # opt-in baselines


def test_run_world_reproduces_the_benchmark_episodes(problem: Problem, tree: DecisionTree) -> None:
    res = run_benchmark(problem, policies=["direct_only", "bisect"], tree=tree, seed=7, max_worlds=4, progress=False)
    theta = train_bias(problem)
    for name in ("direct_only", "bisect"):
        again = [
            run_world(problem, name, world, theta=theta, tree=tree, seed=7 + k).num_checks
            for k, world in enumerate(res.test_ids)
        ]
        assert again == res.policies[name].checks
    assert res.settings == {
        "seed": 7,
        "eta": 0.2,
        "pseudo_count": None,
        "alpha": 0.99,
        "max_worlds": 4,
        "max_checks": None,
    }


def test_failures_and_the_check_cap(problem: Problem, tree: DecisionTree) -> None:
    res = run_benchmark(problem, policies=["bisect", "direct_only"], tree=tree, max_worlds=5, progress=False)
    for stats in res.policies.values():
        assert stats.failures == len(stats.failed_worlds)
    capped = run_benchmark(problem, policies=["bisect"], tree=tree, max_worlds=5, max_checks=3, progress=False)
    stats = capped.policies["bisect"]
    full = res.policies["bisect"].checks
    # With the cap every episode stops at min(its uncapped checks, 3); those that needed more fail.
    assert stats.checks == [min(c, 3) for c in full]
    assert stats.failed_worlds == [k for k, c in enumerate(full) if c > 3]
    assert stats.failures == sum(c > 3 for c in full) > 0


def test_run_benchmark_rejects_bad_arguments(problem: Problem) -> None:
    with pytest.raises(DrdError, match="no_such"):
        run_benchmark(problem, policies=["no_such"], progress=False)
    with pytest.raises(DrdError, match="max_worlds"):
        run_benchmark(problem, policies=["bisect"], max_worlds=0, progress=False)
    with pytest.raises(DrdError, match="max_checks"):
        run_benchmark(problem, policies=["bisect"], max_checks=0, progress=False)
    with pytest.raises(DrdError, match="outside"):
        run_world(problem, "bisect", 5000, theta=train_bias(problem), tree=None, seed=0)


def _hand_result() -> BenchmarkResult:
    checks = {
        "direct_bisect": [10, 10, 10, 10, 10],
        "bisect": [10, 12, 15, 20, 10],
        "random": [20, 10, 10, 10, 5],
    }
    stats = {p: PolicyStats(c, 0, [0.5] * len(c), 0.0) for p, c in checks.items()}
    stats["random"] = PolicyStats(checks["random"], 1, [0.5] * 5, 0.0, [4])
    return BenchmarkResult("hand", [3, 1, 4, 1, 5], [5.0, 5.0, 10.0, 5.0, float("nan")], stats)


def test_benchmark_json_relative_blocks() -> None:
    res = _hand_result()
    doc = benchmark_json(res, resamples=300, seed=3)
    json.dumps(doc, allow_nan=False)
    table = table1_stats(res.checks(), lower_bound=res.lower_bound, resamples=300, seed=3)
    for name, block in doc["policies"].items():
        assert block["relative"] == table.policies[name].as_json()
        assert set(block["relative"]) == {"per_world", "unfiltered", "filtered"}
        assert set(block["relative"]["filtered"]) == {"n", "p40", "p60", "median", "mean", "mean_ci"}
    bis = doc["policies"]["bisect"]["relative"]
    assert bis["filtered"]["n"] == 3
    assert bis["filtered"]["p40"] == pytest.approx(0.41)
    assert bis["unfiltered"]["p60"] == pytest.approx(0.35)
    assert doc["policies"]["random"]["failed_worlds"] == [4]
    assert doc["oracle_lower_bound"]["relative"]["per_world"] == [-0.5, -0.5, 0.0, -0.5, None]
    assert doc["relative_protocol"]["tie_subset"] == ["direct_bisect", "bisect"]
    assert doc["relative_protocol"]["num_kept"] == 3


def test_benchmark_json_without_the_reference_has_null_relative_blocks() -> None:
    res = _hand_result()
    del res.policies["direct_bisect"]
    doc = benchmark_json(res)
    assert all(block["relative"] is None for block in doc["policies"].values())
    assert doc["relative_protocol"] is None
    assert doc["oracle_lower_bound"]["relative"] is None
    # Another reference works.
    doc = benchmark_json(res, reference="bisect", tie_subset=["bisect", "random"])
    assert doc["policies"]["random"]["relative"]["per_world"] == pytest.approx([1.0, -1 / 6, -1 / 3, -0.5, -0.5])


def test_benchmark_json_file_round_trip(problem: Problem, tree: DecisionTree, tmp_path: Path) -> None:
    res = run_benchmark(problem, policies=["direct_bisect", "bisect"], tree=tree, max_worlds=3, progress=False)
    path = tmp_path / "b.json"
    path.write_text(json.dumps(benchmark_json(res), allow_nan=False))
    doc = json.loads(path.read_text())
    per_world = doc["policies"]["bisect"]["relative"]["per_world"]
    ref = np.array(res.policies["direct_bisect"].checks, dtype=float)
    expect = (np.array(res.policies["bisect"].checks) - ref) / ref
    assert per_world == pytest.approx(expect.tolist())
    assert doc["tree"]["nodes"] == tree.num_nodes


def test_json_safe_replaces_non_finite_floats() -> None:
    doc = {
        "a": float("nan"),
        "b": [1.0, float("inf"), {"c": -float("inf"), "d": 2}],
        "e": (3.5, "x"),
        "f": None,
    }
    assert json_safe(doc) == {"a": None, "b": [1.0, None, {"c": None, "d": 2}], "e": [3.5, "x"], "f": None}
    json.dumps(json_safe(doc), allow_nan=False)


def test_direct_bisect_fixed_runs_on_a_paper_rule_tree() -> None:
    """With a tree built by another region rule, direct_bisect_fixed is still the paper's method exactly."""
    from drd_planner.bench.runner import PolicySettings, paper_rule_tree

    fixed = PolicySettings(
        DEFAULT_ETA, DEFAULT_ALPHA, None
    )  # direct_bisect with the paper's eta and leaf, on its own tree

    problem = make_planar_problem(model="forest", num_worlds=150, seed=2)
    per_check = build_tree(problem, progress=False, region_rule="per_check")
    paper = build_tree(problem, progress=False)
    assert paper_rule_tree(problem, paper) is paper
    assert per_check.num_nodes != paper.num_nodes  # the rules build different trees here
    rebuilt = paper_rule_tree(problem, per_check)
    assert rebuilt.region_rule == "probability"
    np.testing.assert_array_equal(rebuilt.edge, paper.edge)
    mixed = run_benchmark(problem, policies=("direct_bisect_fixed",), tree=per_check, max_worlds=8)
    plain = run_benchmark(problem, policies=("direct_bisect_fixed",), tree=paper, max_worlds=8)
    assert mixed.policies["direct_bisect_fixed"].checks == plain.policies["direct_bisect_fixed"].checks
    own = run_benchmark(problem, policies=("direct_bisect",), tree=per_check, max_worlds=8, settings=fixed)
    assert own.policies["direct_bisect"].checks != plain.policies["direct_bisect_fixed"].checks
    assert mixed.tree_info["region_rule"] == "per_check"


def test_run_benchmark_trains_the_imitation_selector_once(problem: Problem, monkeypatch: pytest.MonkeyPatch) -> None:
    from drd_planner.bench import runner
    from drd_planner.bench.lazysp_imitation import DaggerSettings, ImitationModel, train_for_problem

    calls: list[int] = []

    def quick(prob: Problem, *, seed: int) -> ImitationModel:
        calls.append(seed)
        return train_for_problem(prob, seed=seed, settings=DaggerSettings(work_budget=2e6, rollouts=False))

    monkeypatch.setattr(runner, "train_for_problem", quick)
    res = run_benchmark(problem, policies=["lazysp", "lazysp_imitation"], seed=3, max_worlds=4, progress=False)
    assert calls == [3]  # once per dataset, with the run's seed, not once per episode
    assert res.imitation_model is not None
    assert res.settings["imitation"]["episodes"] >= 1
    assert res.policies["lazysp_imitation"].failures == 0
    # The run's model reproduces its episodes through run_world without training again.
    settings = PolicySettings(imitation_model=res.imitation_model)
    theta = train_bias(problem)
    again = [
        run_world(problem, "lazysp_imitation", w, theta=theta, tree=None, seed=3 + k, settings=settings).num_checks
        for k, w in enumerate(res.test_ids)
    ]
    assert again == res.policies["lazysp_imitation"].checks
    assert calls == [3]
    # run_world never trains per episode: without the run's model it says what is missing.
    with pytest.raises(ProblemError, match="imitation_model"):
        run_world(problem, "lazysp_imitation", res.test_ids[0], theta=theta, tree=None, seed=3)
    assert calls == [3]
    # Without the policy, nothing is trained and the settings block is unchanged.
    plain = run_benchmark(problem, policies=["lazysp"], seed=3, max_worlds=2, progress=False)
    assert plain.imitation_model is None
    assert "imitation" not in plain.settings
    assert calls == [3]
