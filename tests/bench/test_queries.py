"""``drd bench --queries``: random queries through the Planner, with every policy on the same episodes."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from conftest import gccd_folder

from drd_planner.cli.main import main
from drd_planner.data.gccd import load_gccd_folder
from drd_planner.planner.query_sampling import draw_queries, reachable_fraction

POLICY_KEYS = {"checks", "failures", "false_no_path", "mean_overhead_ms", "path_cost_ratio", "mean_checks"}


def test_query_benchmark_json(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    folder = gccd_folder("dataset_2d_1")
    out = tmp_path / "q.json"
    argv = [
        "bench",
        "--gccd",
        str(folder),
        "--queries",
        "6",
        "--seed",
        "2",
        "--eta",
        "0.2",
        "--kappa",
        "none",
        "--policies",
        "direct_bisect,bisect,lazysp,check_all",
        "--json",
        str(out),
    ]
    assert main(argv) == 0
    report = capsys.readouterr().out
    assert "| direct_bisect |" in report
    assert "false no-path" in report
    doc = json.loads(out.read_text())
    problem = load_gccd_folder(folder)
    assert doc["queries"] == 6
    assert len(doc["episodes"]) == 6
    first = doc["episodes"][0]
    assert (first["start"], first["goal"]) == (problem.start, problem.goal)
    test_ids = problem.require_worlds().test_ids.tolist()
    assert [e["world"] for e in doc["episodes"]] == test_ids[:6]
    for name, stats in doc["policies"].items():
        assert POLICY_KEYS <= set(stats), name
        assert len(stats["checks"]) == 6
        assert stats["false_no_path"] == 0
        assert stats["failures"] == 0
    assert doc["policies"]["check_all"]["checks"] == [problem.num_edges] * 6
    assert all(r >= 1.0 - 1e-9 for r in [doc["policies"]["check_all"]["path_cost_ratio"]])


def test_drawn_queries_are_seeded_and_mostly_connected() -> None:
    problem = load_gccd_folder(gccd_folder("dataset_2d_2"))
    a = draw_queries(problem, 8, seed=4)
    assert a == draw_queries(problem, 8, seed=4)
    assert a[0] == (problem.start, problem.goal)
    worlds = problem.require_worlds()
    train = worlds.X[worlds.train_ids]
    for s, g in a[1:]:
        assert s != g
        assert reachable_fraction(problem.graph, train, s)[g] >= 0.45  # type: ignore[arg-type]


def test_unknown_query_policy_and_all_are_refused(capsys: pytest.CaptureFixture[str]) -> None:
    folder = gccd_folder("dataset_2d_1")
    assert main(["bench", "--gccd", str(folder), "--queries", "2", "--policies", "direct_only"]) == 2
    assert "known:" in capsys.readouterr().err
    assert main(["bench", "--all", str(folder.parent), "--queries", "2"]) == 2
    assert "--queries" in capsys.readouterr().err
    assert main(["bench", "--gccd", str(folder), "--queries", "0"]) == 2


def test_certificate_size_is_the_fewest_checks() -> None:
    from drd_planner.bench.queries import certificate_size
    from drd_planner.core.graph import ExplicitGraph

    # Square 0-1-2-3-0 plus the diagonal 0-2.
    graph = ExplicitGraph(np.array([[0, 1], [1, 2], [2, 3], [3, 0], [0, 2]]), np.ones(5), 4)
    free = np.ones(5, dtype=bool)
    assert certificate_size(graph, free, 0, 2) == 1  # the diagonal
    free[4] = False
    assert certificate_size(graph, free, 0, 2) == 2  # two edges around the square
    free[[0, 3]] = False
    assert certificate_size(graph, free, 0, 2) == 3  # no path: every edge at vertex 0 is a blocked cut
