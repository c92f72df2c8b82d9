"""Tests of the benchmark run settings (``drd_planner.bench.suite``): region rules and k-fold validation."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from conftest import gccd_folder

from drd_planner.bench.suite import SuiteOptions, resolve_settings
from drd_planner.cli.main import main
from drd_planner.core.region_rule import REGION_RULES
from drd_planner.data.planar_problem import make_planar_problem


@pytest.fixture(scope="module")
def problem():  # type: ignore[no-untyped-def]
    return make_planar_problem(num_vertices=60, model="one_wall", num_worlds=120, max_paths=40, seed=3)


def test_each_rule_is_validated_and_the_paper_rule_needs_to_be_beaten(problem) -> None:  # type: ignore[no-untyped-def]
    options = SuiteOptions(policies=("direct_bisect",), region_rules=REGION_RULES, validation_folds=2)
    resolved, choice, scores = resolve_settings(problem, options, progress=False)
    assert set(scores) == set(REGION_RULES)
    chosen = resolved.tree_options["region_rule"]
    assert choice is not None
    assert resolved.eta == choice.eta
    assert resolved.pseudo_counts == (choice.pseudo_count,)
    # The paper's rule stays unless the other is better by more than its validation noise.
    if chosen == "per_check":
        assert scores["per_check"] < scores["probability"] - choice.standard_error((choice.eta, choice.pseudo_count))
    else:
        per_check_alone = SuiteOptions(policies=("direct_bisect",), region_rules=("per_check",), validation_folds=2)
        _, other, _ = resolve_settings(problem, per_check_alone, progress=False)
        assert other is not None
        assert (
            scores["per_check"] >= scores["probability"] - other.standard_error((other.eta, other.pseudo_count)) - 1e-12
        )
    # By default both rules are validated, as the command line's --region-rule auto does.
    assert SuiteOptions().region_rules == REGION_RULES
    # Without candidates the tree's own rule is used and nothing is compared.
    plain, _, none = resolve_settings(
        problem, SuiteOptions(policies=("direct_bisect",), region_rules=()), progress=False
    )
    assert none == {}
    assert "region_rule" not in plain.tree_options


def test_bench_reports_the_rule_and_fold_validation(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    folder = gccd_folder("dataset_2d_1")
    out = tmp_path / "b.json"
    argv = ["bench", "--gccd", str(folder), "--policies", "direct_bisect,bisect", "--max-worlds", "6"]
    argv += ["--validation-folds", "3", "--json", str(out)]  # --region-rule auto is the default
    assert main(argv) == 0
    capsys.readouterr()
    settings = json.loads(out.read_text())["settings"]
    selection = settings["region_rule_selection"]
    assert selection["chosen"] in REGION_RULES
    assert set(selection["validated_mean_checks"]) == set(REGION_RULES)
    assert settings["eta_selection"]["folds"] == 3
    assert json.loads(out.read_text())["tree"]["region_rule"] == selection["chosen"]


def test_a_given_rule_is_not_validated(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    folder = gccd_folder("dataset_2d_1")
    out = tmp_path / "b.json"
    argv = ["bench", "--gccd", str(folder), "--policies", "direct_bisect", "--max-worlds", "4"]
    argv += ["--region-rule", "per_check", "--json", str(out)]
    assert main(argv) == 0
    capsys.readouterr()
    doc = json.loads(out.read_text())
    assert doc["tree"]["region_rule"] == "per_check"
    assert doc["settings"]["eta_selection"]["region_rule"] == "per_check"
    assert "region_rule_selection" not in doc["settings"]
