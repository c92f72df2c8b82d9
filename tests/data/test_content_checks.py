"""The semantic checks of loaded files: walks, JSON limits, and domain-spec budgets that real specs meet."""

from __future__ import annotations

import numpy as np
import pytest

from drd_planner.core.graph import ExplicitGraph
from drd_planner.data.content_checks import check_walks
from drd_planner.data.safe_npz import json_depth, parse_json_header
from drd_planner.data.spec_limits import check_domain_spec
from drd_planner.domains.base import DOMAIN_CLASSES, domain_from_spec
from drd_planner.exceptions import ProblemError, TreeFileError


def _graph(directed: bool) -> ExplicitGraph:
    # 0 - 1 - 2 - 3 and a chord 0 - 2; edge ids 0: (1, 0) stored backwards, 1: (1, 2), 2: (2, 3), 3: (0, 2)
    return ExplicitGraph(np.array([[1, 0], [1, 2], [2, 3], [0, 2]]), np.ones(4), 4, directed)


def _paths(*paths: list[int]) -> tuple[np.ndarray, ...]:
    return tuple(np.array(p, dtype=np.int64) for p in paths)


def test_undirected_walks_use_edges_in_either_orientation() -> None:
    graph = _graph(directed=False)
    check_walks(graph, _paths([0, 1, 2], [3, 2]), 0, 3, _paths([0, 1, 2, 3], [0, 2, 3]))
    check_walks(graph, _paths([2, 1, 0]), 3, 0)  # the same walk backwards


@pytest.mark.parametrize(
    ("paths", "start", "goal", "bad"),
    [
        ([[2]], 0, 3, 0),  # one edge ending at the goal, far from the start
        ([[0, 2]], 0, 3, 0),  # a gap between the edges
        ([[3, 2], [0, 1]], 0, 3, 1),  # the second path stops short of the goal
        ([[0, 1, 2]], 1, 3, 0),  # starts at the wrong vertex
    ],
)
def test_non_walks_are_refused_naming_the_path(paths: list[list[int]], start: int, goal: int, bad: int) -> None:
    with pytest.raises(ProblemError, match=f"library path {bad} is not a walk"):
        check_walks(_graph(directed=False), _paths(*paths), start, goal)


def test_directed_walks_follow_edge_directions() -> None:
    graph = _graph(directed=True)
    check_walks(graph, _paths([1, 2]), 1, 3)
    with pytest.raises(ProblemError, match="not a walk"):
        check_walks(graph, _paths([0, 1, 2]), 0, 3)  # edge 0 runs 1 -> 0, not 0 -> 1


def test_vertex_paths_must_follow_the_edge_paths() -> None:
    with pytest.raises(ProblemError, match="vertex paths"):
        check_walks(_graph(directed=False), _paths([3, 2]), 0, 3, _paths([0, 1, 3]))


def test_start_and_goal_must_be_distinct_vertices_of_the_graph() -> None:
    with pytest.raises(ProblemError, match="goal vertex 9"):
        check_walks(_graph(directed=False), _paths([3, 2]), 0, 9)
    with pytest.raises(ProblemError, match="same vertex"):
        check_walks(_graph(directed=False), _paths([3, 2]), 3, 3)


def test_json_depth_ignores_brackets_in_strings() -> None:
    assert json_depth('{"a": [1, {"b": "[[[[{{"}], "c": "\\"]]"}') == 3
    assert json_depth("[]") == 1
    assert json_depth("1") == 0


def test_header_json_limits() -> None:
    from pathlib import Path

    def parse(text: str) -> object:
        raw = np.frombuffer(text.encode(), dtype=np.uint8)
        return parse_json_header(raw, error=TreeFileError, src=Path("t.npz"))

    assert parse('{"seed": 18446744073709551615, "x": -1.5e300}') == {"seed": 2**64 - 1, "x": -1.5e300}
    for text, reason in [
        ('{"seed": 18446744073709551616}', "out of range"),
        ('{"x": -Infinity}', "-Infinity"),
        ('{"x": 1e400}', "overflows"),
        ("[" * 65 + "]" * 65, "nested 65 deep"),
    ]:
        with pytest.raises(TreeFileError, match=reason):
            parse(text)


@pytest.mark.parametrize("name", sorted(DOMAIN_CLASSES))
def test_every_domain_default_spec_is_within_the_budgets(name: str) -> None:
    domain = domain_from_spec(name)
    graph = domain.graph
    check_domain_spec(name, domain.spec(), num_edges=graph.num_edges, mean_edge_length=float(graph.lengths.mean()))
