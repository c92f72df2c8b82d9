"""Tests of the ``ompl_lazyprm`` peer: embedding, path verification, worker protocol, and real OMPL runs."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Literal

import numpy as np
import pytest
from conftest import gccd_folder, require_ompl
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import dijkstra

from drd_planner.bench.ompl_peer import (
    SKIP_MESSAGE,
    LiveWorlds,
    OmplPeerError,
    coords_unusable,
    embed_vertices,
    ompl_available,
    read_worker_results,
    run_ompl_lazyprm,
    run_ompl_lazyprm_live,
    verify_path,
)
from drd_planner.bench.world_recipes import seeded_recipes
from drd_planner.core.graph import ExplicitGraph
from drd_planner.core.library import PathLibrary
from drd_planner.core.problem import Problem
from drd_planner.core.worlds import WorldDatabase
from drd_planner.data.gccd import load_gccd_folder
from drd_planner.domains.arm import ArmDomain
from drd_planner.exceptions import DrdError

# Two routes from 0 to 3: the short one over vertex 1, the long one over vertex 2.
COORDS = np.array([[0.0, 0.0], [0.5, 0.1], [0.5, -0.5], [1.0, 0.0]])
EDGES = np.array([[0, 1], [1, 3], [0, 2], [2, 3]])  # ids: 0 = 0-1, 1 = 1-3, 2 = 0-2, 3 = 2-3
# (world outcomes over edge ids 0..3, LazyPRM's checked edges in order, path edges or None).
# LazyPRM checks a candidate path's edges from the goal end and drops the first blocked one.
TINY_WORLDS = [
    ([1, 1, 1, 1], [1, 0], [0, 1]),  # short route free: 2 checks
    ([1, 0, 1, 1], [1, 3, 2], [2, 3]),  # short route blocked next to the goal: 3 checks
    ([0, 1, 1, 1], [1, 0, 3, 2], [2, 3]),  # short route blocked next to the start: 4 checks
    ([0, 1, 1, 0], [1, 0, 3], None),  # both blocked: 3 checks, then start and goal are cut apart
]


def tiny_problem(directed: bool = False, edges: np.ndarray = EDGES) -> Problem:
    lengths = np.linalg.norm(COORDS[edges[:, 0]] - COORDS[edges[:, 1]], axis=1)
    graph = ExplicitGraph(edges, lengths, 4, directed, COORDS)
    library = PathLibrary.from_sequences([[0, 1], [2, 3]], 4)
    x = np.array([w[0] for w in TINY_WORLDS], dtype=bool)
    worlds = WorldDatabase(x, library.valid_paths(x), np.array([], dtype=np.int64), np.arange(4))
    return Problem("tiny", library, np.ones(4), graph, 0, 3, worlds)


# --- no OMPL needed -------------------------------------------------------------------------------


def test_embedding_uses_coordinates_when_they_fit() -> None:
    graph = tiny_problem().graph
    assert graph is not None
    emb = embed_vertices(graph)
    assert emb.kind == "coords"
    np.testing.assert_array_equal(emb.states, COORDS)
    assert emb.connect_radius == pytest.approx(1e-3 * math.hypot(0.5, 0.1))  # 1e-3 x closest pair (0, 1)


def test_index_embedding_heuristic_never_exceeds_an_edge() -> None:
    graph = ExplicitGraph(EDGES, np.array([0.3, 0.2, 0.5, 0.4]), 4)  # no coordinates
    assert coords_unusable(graph) == "the graph has no vertex coordinates"
    emb = embed_vertices(graph)
    assert emb.kind == "index"
    assert emb.states.shape == (4, 1)
    spread = emb.states.max() - emb.states.min()
    assert spread < graph.lengths.min()  # so |h(u) - h(v)| <= w(u, v): a consistent heuristic
    assert emb.connect_radius < np.diff(emb.states[:, 0]).min()


def test_coords_refused_when_shorter_than_straight_line_or_duplicated() -> None:
    short = ExplicitGraph(EDGES, np.array([0.1, 0.51, 0.71, 0.71]), 4, False, COORDS)
    assert "shorter than the straight line" in str(coords_unusable(short))
    assert embed_vertices(short).kind == "index"
    with pytest.raises(OmplPeerError, match="coords embedding cannot be used"):
        embed_vertices(short, "coords")
    dup = ExplicitGraph(EDGES, np.ones(4), 4, False, np.array([[0, 0], [1, 1], [1, 1], [2, 2.0]]))
    assert coords_unusable(dup) == "two vertices share the same coordinates"
    with pytest.raises(OmplPeerError, match="unknown embedding"):
        embed_vertices(dup, "polar")  # type: ignore[arg-type]  # a wrong value on purpose


def test_verify_path_accepts_only_free_start_goal_graph_paths() -> None:
    graph = tiny_problem().graph
    assert graph is not None
    free = np.array([True, False, True, True])
    ok = verify_path(graph, free, 0, 3, [0, 2, 3])
    assert ok.ok
    assert ok.edges.tolist() == [2, 3]
    blocked = verify_path(graph, free, 0, 3, [0, 1, 3])
    assert not blocked.ok
    assert "[1]" in blocked.reason
    assert not verify_path(graph, free, 0, 3, [0, 2]).ok  # ends at 2, not the goal
    assert "not a graph path" in verify_path(graph, free, 0, 3, [0, 3]).reason
    assert not verify_path(graph, free, 0, 3, [0]).ok
    directed = tiny_problem(directed=True).graph
    assert directed is not None
    assert not verify_path(directed, np.ones(4, bool), 3, 0, [3, 2, 0]).ok  # against the edge direction


def _write_lines(path: Path, items: list[dict[str, object]], tail: str = "") -> None:
    path.write_text("".join(json.dumps(i) + "\n" for i in items) + tail)


def test_worker_results_complete_even_if_the_worker_crashed_afterwards(tmp_path: Path) -> None:
    result = tmp_path / "r.jsonl"
    _write_lines(result, [{"world": 4}, {"world": 7}, {"done": True}])
    assert [r["world"] for r in read_worker_results(result, 2, -11, "Segmentation fault")] == [4, 7]


def test_worker_crash_before_all_results_is_an_error(tmp_path: Path) -> None:
    result = tmp_path / "r.jsonl"
    _write_lines(result, [{"world": 4}], tail='{"world": 7, "che')
    with pytest.raises(OmplPeerError, match=r"crashed \(exit code -11\) after 1 of 2 worlds: boom"):
        read_worker_results(result, 2, -11, "boom\n")
    with pytest.raises(OmplPeerError, match="after 0 of 1 worlds"):
        read_worker_results(tmp_path / "missing.jsonl", 1, 1, "")
    _write_lines(result, [{"error": "RuntimeError: bad request"}])
    with pytest.raises(OmplPeerError, match="OMPL worker failed: RuntimeError: bad request"):
        read_worker_results(result, 1, 1, "")


def test_problem_without_graph_is_refused() -> None:
    p = tiny_problem()
    bare = Problem("bare", p.library, p.edge_costs, None, None, None, p.worlds)
    with pytest.raises(DrdError, match="needs a graph"):
        run_ompl_lazyprm(bare, [0], seed=0, time_limit_s=1.0)
    with pytest.raises(DrdError, match="world ids must lie"):
        run_ompl_lazyprm(p, [9], seed=0, time_limit_s=1.0)


def test_skip_message_names_the_extra() -> None:
    assert SKIP_MESSAGE == (
        "ompl_lazyprm skipped: OMPL not installed (the 'peer' extra): pip install -e 'ros2_ws/src/drd_planner[peer]'"
    )
    ok, message = ompl_available()
    assert message.startswith("OMPL ") if ok else message.startswith("ompl_lazyprm skipped")


# --- real OMPL runs ---------------------------------------------------------------------------------


@pytest.mark.parametrize("embedding", ["coords", "index"])
def test_lazyprm_on_two_route_graph(embedding: Literal["coords", "index"]) -> None:
    require_ompl()
    result = run_ompl_lazyprm(tiny_problem(), [0, 1, 2, 3], seed=3, time_limit_s=5.0, embedding=embedding)
    assert result["embedding"] == embedding
    assert result["checks"] == [len(w[1]) for w in TINY_WORLDS]
    assert result["failures"] == 1
    for block, (_, checked, path) in zip(result["worlds"], TINY_WORLDS, strict=True):
        assert block["checked_edges"] == checked
        assert block["success"] == (path is not None)
        assert block["path_edges"] == (path or [])
        assert block["roadmap"]["exact"], block["roadmap"]  # no edge beyond ours and the 2 connectors
        assert block["roadmap"]["edges_removed"] == sum(1 for e in checked if TINY_WORLDS[block["world"]][0][e] == 0)
        assert block["state_checks"] >= 2  # start and goal at least; counted apart from edge checks
        # The goal-side connector is asked once; the start-side one only when a whole path was free.
        assert block["connector_calls"] == (2 if path else 1)
        assert block["reverse_rejections"] == 0
        assert block["wall_s"] >= 0


def test_lazyprm_refuses_backwards_directed_edge_without_a_check() -> None:
    require_ompl()
    # Edge 1 now points 3 -> 1: the short route would use it backwards.
    problem = tiny_problem(directed=True, edges=np.array([[0, 1], [3, 1], [0, 2], [2, 3]]))
    result = run_ompl_lazyprm(problem, [0], seed=0, time_limit_s=5.0)
    block = result["worlds"][0]
    assert block["reverse_rejections"] == 1
    assert block["checked_edges"] == [3, 2]
    assert block["success"]
    assert block["path_edges"] == [2, 3]


def test_lazyprm_on_dataset_2d_1() -> None:
    require_ompl()
    problem = load_gccd_folder(gccd_folder("dataset_2d_1"))
    worlds = problem.require_worlds()
    graph = problem.graph
    assert graph is not None
    assert problem.start is not None
    assert problem.goal is not None
    ids = worlds.test_ids[:5]
    result = run_ompl_lazyprm(problem, ids, seed=0, time_limit_s=20.0)
    assert result["embedding"] == "coords"
    assert result["test_ids"] == ids.tolist()
    for block in result["worlds"]:
        x = worlds.X[block["world"]]
        free = csr_matrix((graph.lengths[x], (graph.edges[x, 0], graph.edges[x, 1])), shape=(100, 100))
        best = dijkstra(free, directed=False, indices=problem.start)[problem.goal]
        assert block["success"] == math.isfinite(best)  # LazyPRM is complete on the graph
        assert block["roadmap"]["exact"], block["roadmap"]
        if block["success"]:
            path = np.asarray(block["path_edges"])
            assert x[path].all()  # independently of verify_path
            assert set(path.tolist()) <= set(block["checked_edges"])
            assert graph.lengths[path].sum() == pytest.approx(best, abs=1e-6)  # the shortest free path
        assert block["checks"] == len(set(block["checked_edges"])) >= len(block["path_edges"])
    print(f"\nompl_lazyprm on dataset_2d_1, worlds {ids.tolist()}: checks {result['checks']}")
    _print_lazysp(problem, result["checks"])


def _print_lazysp(problem: Problem, ompl_checks: list[int]) -> None:
    from drd_planner.core.policies import POLICIES

    if "lazysp" not in POLICIES:
        print("lazysp is not in POLICIES yet: no comparison")
        return
    from drd_planner.bench.runner import run_benchmark

    try:
        res = run_benchmark(problem, policies=["lazysp"], max_worlds=len(ompl_checks), progress=False)
    except DrdError as exc:
        print(f"lazysp comparison unavailable: {exc}")
        return
    print(f"lazysp checks {res.policies['lazysp'].checks} vs ompl_lazyprm {ompl_checks}")


def test_benchmark_reports_the_peer_as_policy_ompl_lazyprm(capsys: pytest.CaptureFixture[str]) -> None:
    from drd_planner.bench.runner import run_benchmark

    ok, message = ompl_available()
    result = run_benchmark(tiny_problem(), policies=["bisect", "ompl_lazyprm"], progress=False)
    if not ok:
        assert "ompl_lazyprm" not in result.policies
        assert message in capsys.readouterr().err
        return
    stats = result.policies["ompl_lazyprm"]
    direct = run_ompl_lazyprm(tiny_problem(), result.test_ids, seed=0, time_limit_s=5.0)
    assert stats.checks == direct["checks"]
    assert stats.failures == direct["failures"]
    assert len(stats.select_ms) >= len(stats.checks)


# --- live checkers ----------------------------------------------------------------------------------


def test_live_mode_answers_with_the_domains_own_checker(small_arm: ArmDomain) -> None:
    require_ompl()
    graph = small_arm.graph
    recipes = (*seeded_recipes("clutter", [2, 3]), *seeded_recipes("table_clutter", [2]))
    result = run_ompl_lazyprm_live(graph, 0, 1, LiveWorlds("arm", small_arm.spec(), recipes), time_limit_s=20.0)
    assert [w["label"] for w in result["worlds"]] == [r.label for r in recipes]
    for block, recipe in zip(result["worlds"], recipes, strict=True):
        here = small_arm.checker(recipe.make(small_arm))
        asked = block["checked_edges"]
        assert block["checked_free"] == [here.check(e) for e in asked]  # the worker's checker is ours
        assert block["checks"] == len(set(asked))
        assert block["wall_s"] >= block["check_s"] > 0
        if block["success"]:
            assert set(block["path_edges"]) <= {e for e, f in zip(asked, block["checked_free"], strict=True) if f}
        else:
            assert not block["ompl_solved"] or block["failure_reason"]
    assert any(w["success"] for w in result["worlds"])


def test_live_mode_refuses_another_roadmap(small_arm: ArmDomain) -> None:
    require_ompl()
    spec = {**small_arm.spec(), "seed": small_arm.spec()["seed"] + 1}
    live = LiveWorlds("arm", spec, tuple(seeded_recipes("clutter", [2])))
    with pytest.raises(OmplPeerError, match="live domain's graph"):
        run_ompl_lazyprm_live(small_arm.graph, 0, 1, live, time_limit_s=5.0)
    with pytest.raises(OmplPeerError, match="goal vertex 999 outside"):
        run_ompl_lazyprm_live(small_arm.graph, 0, 999, live, time_limit_s=5.0)
