"""Roadmap: segment counts, interior edge samples, extra states as vertices 2..M+1 and the refusals."""

from __future__ import annotations

import re

import numpy as np
import pytest
from conftest import SHARED_DATA
from scipy.sparse import coo_array
from scipy.sparse.csgraph import connected_components

from drd_planner.core.graph import ExplicitGraph
from drd_planner.domains.arm_params import DEFAULT_GOAL, DEFAULT_START, ArmParams
from drd_planner.domains.arm_roadmap import (
    EdgeSamples,
    build_roadmap,
    graph_states,
    segment_counts,
    statically_valid,
)
from drd_planner.domains.arm_robot import ROBOT_MODELS, robot_texts
from drd_planner.exceptions import ProblemError
from drd_planner.geometry.robot import RobotModel


def test_segment_counts_keep_every_joint_step_within_the_resolution() -> None:
    a = np.array([[0.0, 0.0], [0.0, 0.0], [0.0, 0.0]])
    b = np.array([[0.1, 0.0], [0.35, -0.1], [0.0, 0.0]])
    assert segment_counts(a, b, 0.1).tolist() == [1, 4, 1]


def test_edge_samples_are_interior_and_in_bisection_order() -> None:
    states = np.array([[0.0, 0.0], [0.4, 0.0], [0.4, 0.05]])
    graph = ExplicitGraph(np.array([[0, 1], [1, 2]]), np.array([0.4, 0.05]), 3, vertex_states=states)
    samples = EdgeSamples.of_graph(graph, 0.1)
    assert samples.offsets.tolist() == [0, 3, 3]
    assert samples.fractions[0] == pytest.approx(0.5)  # the middle first
    assert sorted(samples.fractions.tolist()) == pytest.approx([0.25, 0.5, 0.75])
    q = samples.configurations(graph, 0)
    assert q.shape == (3, 2)
    assert np.all((q[:, 0] > 0) & (q[:, 0] < 0.4))
    with pytest.raises(ProblemError, match="resolution"):
        EdgeSamples.of_graph(graph, 0.0)
    with pytest.raises(ProblemError, match="vertex states"):
        graph_states(ExplicitGraph(np.array([[0, 1]]), np.array([1.0]), 2))


# --------------------------------------------------------------------------------------------------
# build_roadmap with the shared Panda: extra states as vertices 2..M+1, refusals


PANDA = SHARED_DATA / "panda"
SMALL = {"num_samples": 150, "k": 6, "seed": 3}


@pytest.fixture(scope="module")
def robot() -> RobotModel:
    if not (PANDA / "panda_spherized.urdf").is_file():
        pytest.skip(f"shared Panda model {PANDA} not present (set DRD_SHARED_DATA)")
    return ROBOT_MODELS.model(*robot_texts(None, None, None))


@pytest.fixture(scope="module")
def plain(robot: RobotModel) -> ExplicitGraph:
    return build_roadmap(robot, ArmParams(**SMALL))


def extras_near(graph: ExplicitGraph, vertices: list[int], step: float = 0.01) -> list[list[float]]:
    """Statically valid states a little away from some roadmap vertices (not repeating any of them)."""
    states = graph_states(graph)
    return (states[vertices] + step).tolist()


def test_extra_states_are_vertices_two_on_joined_to_their_nearest(robot: RobotModel, plain: ExplicitGraph) -> None:
    extras = extras_near(plain, [10, 40, 90, 120])
    assert statically_valid(robot, extras).all()
    graph = build_roadmap(robot, ArmParams(**SMALL, extra_states=extras))
    states = graph_states(graph)
    np.testing.assert_array_equal(states[0], DEFAULT_START)
    np.testing.assert_array_equal(states[1], DEFAULT_GOAL)
    np.testing.assert_array_equal(states[2:6], np.asarray(extras))
    assert graph.num_vertices >= plain.num_vertices + len(extras) - 2  # the component may grow or shrink a bit
    # Connected to the start: every vertex is in one component, which includes vertices 2..5.
    adjacency = coo_array(
        (np.ones(graph.num_edges), (graph.edges[:, 0], graph.edges[:, 1])), shape=(graph.num_vertices,) * 2
    )
    count, _ = connected_components(adjacency, directed=False)
    assert count == 1
    # Joined like every sample: each edge of an extra vertex x goes to a w that is among the k nearest of x,
    # or has x among its k nearest (ranks among the kept vertices can only be better than among all candidates).
    dist = np.linalg.norm(states[:, None, :] - states[None, :, :], axis=2)
    rank = np.argsort(np.argsort(dist, axis=1), axis=1)  # rank[a, b]: b's place in a's order (0: a itself)
    k = SMALL["k"]
    for x in range(2, 6):
        ends = graph.edges[(graph.edges == x).any(axis=1)]
        assert ends.shape[0] >= 1
        for w in ends[ends != x].tolist():
            assert rank[x, w] <= k or rank[w, x] <= k, (x, w)
    # No extra vertex has an edge to a vertex that is neither among its k nearest nor has it among its own.
    degree = np.bincount(graph.edges.ravel(), minlength=graph.num_vertices)
    assert np.all(degree[2:6] <= k + np.sum(rank[:, 2:6] <= k, axis=0))


def test_no_extra_states_gives_the_same_bytes_as_an_empty_list(robot: RobotModel, plain: ExplicitGraph) -> None:
    again = build_roadmap(robot, ArmParams(**SMALL, extra_states=[]))
    assert again.edges.tobytes() == plain.edges.tobytes()
    assert again.lengths.tobytes() == plain.lengths.tobytes()
    assert graph_states(again).tobytes() == graph_states(plain).tobytes()


@pytest.mark.parametrize(
    ("extra", "says"),
    [
        ([list(DEFAULT_START)], r"^extra_states\[0\] repeats start \(every joint within"),
        ("twice", r"^extra_states\[1\] repeats extra_states\[0\]"),
        ([[0.0] * 6], r"^extra_states\[0\] has 6 joint values; the arm needs 7 joint values \(panda_joint1,"),
        (
            [[*DEFAULT_GOAL[:6], 0.7], [0.0, 0.3, 0.0, -3.0, 0.0, 0.3, 0.0], [9.0] * 7],
            r"^extra_states\[1\] configuration is not statically valid: self-colliding \(panda_link\d touches "
            r"panda_link\d\): change extra_states\[1\] in the arm spec.*\(also not statically valid: "
            r"extra_states\[2\]\)$",
        ),
    ],
)
def test_bad_extra_states_are_refused_naming_the_index(robot: RobotModel, extra: object, says: str) -> None:
    states = [[*DEFAULT_GOAL[:6], 0.7]] * 2 if extra == "twice" else extra
    with pytest.raises(ProblemError) as info:
        build_roadmap(robot, ArmParams(num_samples=20, k=4, extra_states=states))  # type: ignore[arg-type]
    assert re.search(says, str(info.value)), str(info.value)


def test_an_extra_state_apart_from_the_start_is_refused_with_what_to_raise(robot: RobotModel) -> None:
    near_start = (np.asarray(DEFAULT_START) + np.eye(7)[0] * 0.01).tolist()
    far = [-2.0, 0.0, 0.0, -1.0, 0.0, 1.5, 0.0]
    params = ArmParams(num_samples=30, k=1, goal=near_start, extra_states=[far])
    with pytest.raises(ProblemError) as info:
        build_roadmap(robot, params)
    text = str(info.value)
    assert text.startswith("extra_states[0] is not connected to the start in the roadmap (num_samples=30, k=1")
    assert "raise num_samples (e.g. to 60) or k (e.g. to 5)" in text
    # Raising k as the message says connects it, and it keeps vertex 2.
    graph = build_roadmap(robot, ArmParams(num_samples=30, k=5, goal=near_start, extra_states=[far]))
    np.testing.assert_array_equal(graph_states(graph)[2], far)


def test_start_and_goal_apart_says_which_parameters_to_raise(robot: RobotModel) -> None:
    far = [-2.0, 0.0, 0.0, -1.0, 0.0, 1.5, 0.0]
    with pytest.raises(ProblemError) as info:
        build_roadmap(robot, ArmParams(num_samples=30, k=1, goal=far))
    text = str(info.value)
    assert re.match(
        r"start and goal are not connected in the roadmap \(num_samples=30, k=1, seed=0; the start's component "
        r"has \d+ of \d+ vertices\): raise num_samples \(e\.g\. to 60\) or k \(e\.g\. to 5\) in the arm spec",
        text,
    ), text
