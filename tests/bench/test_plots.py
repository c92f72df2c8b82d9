"""Figures: files are written, and what is drawn matches the data it comes from."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest
from conftest import gccd_folder
from matplotlib.colors import to_rgba
from matplotlib.figure import Figure

from drd_planner.bench.learning_curve import TrainingCurve, training_size_curve
from drd_planner.bench.plots import (
    COLOURS,
    draw_checked_edges,
    draw_normalised_costs,
    draw_training_curve,
    edge_layers,
    edge_segments,
    has_vertex_xy,
    plot_checked_edges,
    plot_normalised_costs,
    plot_training_curve,
    vertex_xy,
)
from drd_planner.bench.runner import run_world, train_bias
from drd_planner.bench.stats import table1_stats
from drd_planner.core.episode import EpisodeResult
from drd_planner.core.library import PathLibrary
from drd_planner.core.problem import Problem
from drd_planner.core.tree import DecisionTree, build_tree
from drd_planner.data.gccd import load_gccd_folder
from drd_planner.exceptions import DrdError, ProblemError


@pytest.fixture(scope="module")
def problem() -> Problem:
    return load_gccd_folder(gccd_folder("dataset_2d_1"))


@pytest.fixture(scope="module")
def tree(problem: Problem) -> DecisionTree:
    return build_tree(problem, progress=False)


@pytest.fixture(scope="module")
def episodes(problem: Problem, tree: DecisionTree) -> dict[str, EpisodeResult]:
    world = int(problem.require_worlds().test_ids[0])
    theta = train_bias(problem)
    return {
        name: run_world(problem, name, world, theta=theta, tree=tree, seed=0)
        for name in ("bisect", "direct_bisect", "direct_only")
    }


def _segment_set(segments: np.ndarray) -> set[tuple[float, ...]]:
    return {tuple(np.round(np.asarray(s, dtype=float).ravel(), 9)) for s in segments}


def _assert_written(paths: list[Path]) -> None:
    assert [p.suffix for p in paths] == [".png", ".svg"]
    for p in paths:
        assert p.is_file(), p
        assert p.stat().st_size > 1000, p
    assert paths[0].read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert b"<svg" in paths[1].read_bytes()[:2000]


def test_edge_layers_follow_the_check_log(problem: Problem, episodes: dict[str, EpisodeResult]) -> None:
    for result in episodes.values():
        layers = edge_layers(problem, result)
        assert layers.free.tolist() == [c.edge for c in result.checks if c.free]
        assert layers.blocked.tolist() == [c.edge for c in result.checks if not c.free]
        checked = {c.edge for c in result.checks}
        assert set(layers.unchecked.tolist()) == set(problem.library.library_edges.tolist()) - checked
        if result.success:
            assert result.path_edges is not None
            assert layers.path.tolist() == result.path_edges.tolist()
            assert set(layers.path.tolist()) <= set(layers.free.tolist())
        else:
            assert layers.path.size == 0


def test_drawn_edges_match_the_check_log(problem: Problem, episodes: dict[str, EpisodeResult]) -> None:
    result = episodes["bisect"]
    ax = Figure().add_subplot()
    drawn = draw_checked_edges(ax, problem, result, title="t")
    assert list(drawn) == ["unchecked", "free", "blocked", "path"]
    xy = vertex_xy(problem)
    assert problem.graph is not None
    for key, free in (("free", True), ("blocked", False)):
        edges = [c.edge for c in result.checks if c.free is free]
        expect = [np.stack([xy[problem.graph.edges[e, 0]], xy[problem.graph.edges[e, 1]]]) for e in edges]
        assert _segment_set(np.array(drawn[key].get_segments())) == _segment_set(np.array(expect))
        assert len(drawn[key].get_segments()) == len(edges)
        assert tuple(drawn[key].get_colors()[0]) == to_rgba(COLOURS[key])
    assert result.path_edges is not None
    assert _segment_set(np.array(drawn["path"].get_segments())) == _segment_set(
        edge_segments(problem, result.path_edges)
    )
    assert drawn["path"].get_linewidths()[0] > drawn["free"].get_linewidths()[0]
    assert ax.get_title() == "t"


def test_plot_checked_edges_writes_png_and_svg(
    problem: Problem, episodes: dict[str, EpisodeResult], tmp_path: Path
) -> None:
    paths = plot_checked_edges(problem, episodes, tmp_path / "sub" / "fig3.png", world=7)
    _assert_written(paths)
    assert paths[0].name == "fig3.png"
    svg = paths[1].read_text()
    for key in ("unchecked", "free", "blocked", "path"):
        assert f'id="{key}_edges"' in svg
    for name, result in episodes.items():
        assert f"{name}: {result.num_checks} checks" in svg


def test_checked_edges_need_coordinates(problem: Problem, episodes: dict[str, EpisodeResult], tmp_path: Path) -> None:
    assert problem.graph is not None
    bare = dataclasses.replace(problem, graph=dataclasses.replace(problem.graph, vertex_states=None))
    assert has_vertex_xy(problem)
    assert not has_vertex_xy(bare)
    with pytest.raises(ProblemError, match="vertex coordinates"):
        plot_checked_edges(bare, episodes, tmp_path / "x")
    no_graph = Problem("synthetic", PathLibrary.from_sequences([[0, 1]], 2), np.ones(2))
    with pytest.raises(ProblemError, match="synthetic"):
        vertex_xy(no_graph)
    assert not list(tmp_path.iterdir())


def test_normalised_costs_draw_the_medians(tmp_path: Path) -> None:
    checks = {
        "direct_bisect": [10, 10, 10, 10, 10],
        "bisect": [10, 12, 15, 20, 10],
        "random": [20, 10, 10, 10, 5],
    }
    table = table1_stats(checks, resamples=100)
    ax = Figure().add_subplot()
    bars = draw_normalised_costs(ax, table, ["bisect", "random", "mvoi"])
    medians = bars.lines[0].get_ydata()
    assert medians[:2].tolist() == pytest.approx([0.5, 0.0])  # bisect filtered 0.2, 0.5, 1.0; random 0, 0, 0
    assert np.isnan(medians[2])  # not run
    assert [t.get_text() for t in ax.get_xticklabels()] == ["bisect", "random", "mvoi"]
    assert any(np.allclose(line.get_ydata(), 0.0) for line in ax.get_lines()[:1])
    ax = Figure().add_subplot()
    draw_normalised_costs(ax, table, ["bisect", "random"], failures={"random": 2, "bisect": 0})
    assert [t.get_text() for t in ax.get_xticklabels()] == ["bisect", "random (2 failed)"]
    paths = plot_normalised_costs({"a": table, "b": table, "c": table}, ["bisect", "random"], tmp_path / "costs")
    _assert_written(paths)
    with pytest.raises(ProblemError):
        plot_normalised_costs({}, ["bisect"], tmp_path / "none")


def test_training_curve_plot(tmp_path: Path) -> None:
    curve = TrainingCurve(
        "hand",
        np.array([50, 100, 200]),
        {"direct_bisect": np.array([12.0, 11.0, 10.0]), "bisect": np.array([13.0, 13.0, 13.0])},
        np.array([0.5, 0.3, 0.2]),
        np.array([9, 21, 40]),
        10,
        0,
    )
    ax = Figure().add_subplot()
    drawn = draw_training_curve(ax, curve)
    assert drawn["direct_bisect"].get_ydata().tolist() == [12.0, 11.0, 10.0]
    assert drawn["failure_rate"].get_ydata().tolist() == [0.5, 0.3, 0.2]
    assert drawn["failure_rate"].get_xdata().tolist() == [50, 100, 200]
    _assert_written(plot_training_curve(curve, tmp_path / "curve.svg"))


def test_training_size_curve_on_a_dataset(problem: Problem) -> None:
    curve = training_size_curve(problem, sizes=[200, 50], max_worlds=3, seed=1)
    assert curve.sizes.tolist() == [50, 200]
    assert curve.num_test == 3
    assert set(curve.mean_checks) == {"direct_bisect", "direct_only", "bisect"}
    for values in curve.mean_checks.values():
        assert values.shape == (2,)
        assert np.all(values >= 1)
    assert np.all((curve.failure_rate >= 0) & (curve.failure_rate <= 1))
    assert np.all(curve.tree_nodes >= 1)
    assert curve.as_json()["sizes"] == [50, 200]
    # The same seed gives the same curve.
    again = training_size_curve(problem, sizes=[50], max_worlds=3, seed=1)
    assert again.mean_checks["direct_bisect"][0] == curve.mean_checks["direct_bisect"][0]
    with pytest.raises(DrdError, match="training sizes"):
        training_size_curve(problem, sizes=[5000])
    with pytest.raises(DrdError, match="at least one"):
        training_size_curve(problem, sizes=[])
