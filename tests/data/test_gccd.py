"""Tests of the authors'-format importer: reference statistics, direction merging and refusals."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import scipy.io
from conftest import gccd_folder, gccd_graph_datasets

from drd_planner.core.bounds import oracle_lower_bound
from drd_planner.core.problem import Problem
from drd_planner.data.gccd import REQUIRED_FILES, RawGraph, load_gccd_folder, merge_directions, read_graph_txt
from drd_planner.exceptions import DatasetError

# --------------------------------------------------------------------------------------------------
# The authors' datasets against docs/algorithms.md, "The authors' datasets"
# --------------------------------------------------------------------------------------------------

# folder: (tests, m, fraction of worlds with >= 1 valid path, oracle LB over the test worlds)
REFERENCE = {
    "dataset_2d_1": (923, 500, 0.809, 6.27),
    "dataset_2d_2": (2524, 500, 0.957, 8.27),
    "dataset_2d_3": (2524, 500, 0.943, 7.82),
    "dataset_2d_4": (1689, 500, 0.824, 7.36),
    "dataset_2d_5": (2524, 500, 0.529, 13.14),
    "dataset_2d_6": (1689, 500, 0.837, 10.60),
    "dataset_2d_7": (1689, 360, 1.000, 7.35),
    "dataset_xyh_1": (7981, 68, 0.954, 14.15),
    "dataset_xyh_3": (7981, 363, 0.757, 12.10),
    "dataset_xyh_4": (7981, 500, 0.889, 15.20),
    "dataset_xyh_5": (7981, 500, 0.788, 12.54),
    "dataset_heli_canyon_1": (1467, 453, 0.912, 7.04),
    "dataset_herb_1": (16643, 51, 0.72, 10.8),
}

# herb_1's stored R was computed per traversal direction; we recompute R from the OR-merged X.
STORED_R_DIFFERS = {"dataset_herb_1"}

_CACHE: dict[str, Problem] = {}


def _load(name: str) -> Problem:
    if name not in _CACHE:
        _CACHE[name] = load_gccd_folder(gccd_folder(name))
    return _CACHE[name]


def test_every_shared_graph_dataset_has_a_reference_row() -> None:
    present = gccd_graph_datasets()
    if not present:
        pytest.skip("shared datasets not present")
    assert set(present) <= set(REFERENCE), f"no reference row for {set(present) - set(REFERENCE)}"


@pytest.mark.parametrize("name", sorted(REFERENCE))
def test_dataset_matches_reference_table(name: str) -> None:
    tests, m, solvable, oracle_lb = REFERENCE[name]
    problem = _load(name)
    worlds = problem.require_worlds()
    assert problem.num_edges == tests
    assert problem.num_paths == m
    assert worlds.num_worlds == 1000
    assert worlds.train_ids.size == 900
    assert worlds.test_ids.size == 100
    assert worlds.X.shape == (1000, tests)
    assert worlds.R.shape == (1000, m)
    # R always means "every merged test of the path is free".
    np.testing.assert_array_equal(worlds.R, problem.library.valid_paths(worlds.X))
    assert float(worlds.R.any(axis=1).mean()) == pytest.approx(solvable, abs=5e-4)
    # Test worlds are drawn among the solvable ones, so the bound is finite everywhere.
    lb = oracle_lower_bound(worlds.R[worlds.test_ids], problem.library.path_costs(problem.edge_costs))
    assert np.all(np.isfinite(lb))
    if name in STORED_R_DIFFERS:
        assert problem.metadata["stored_R_mismatches"] > 0
    else:
        assert problem.metadata["stored_R_mismatches"] == 0
        assert round(float(lb.mean()), 2) == pytest.approx(oracle_lb, abs=1e-9)
    assert problem.metadata["source"] == "gccd"
    assert problem.metadata["folder"] == name
    assert len(problem.metadata["sha256"]) == 64


@pytest.mark.parametrize("name", ["dataset_2d_1", "dataset_xyh_1"])
def test_dataset_graph_is_consistent(name: str) -> None:
    problem = _load(name)
    graph = problem.graph
    assert graph is not None
    assert problem.start is not None
    assert problem.goal is not None
    assert problem.library.vertex_paths is not None
    for vertices, edges in zip(problem.library.vertex_paths, problem.library.path_edges, strict=True):
        assert vertices[0] == problem.start
        assert vertices[-1] == problem.goal
        np.testing.assert_array_equal(graph.vertex_path_to_edges(vertices), edges)
    if graph.directed:
        assert problem.metadata["one_way_rows"] == problem.metadata["stored_rows"]
    else:
        # Undirected: every stored row had its reverse, two rows per test.
        assert problem.metadata["stored_rows"] == 2 * problem.num_edges
        assert np.all(graph.edges[:, 0] > graph.edges[:, 1])


# --------------------------------------------------------------------------------------------------
# A small hand-made folder
# --------------------------------------------------------------------------------------------------

# 1-based rows "id parent child length" in MATLAB column-major order: both directions of {1,2} and
# {2,3}, and the one-way edge 1 -> 3. 0-based rows: r0=(1,0) r1=(0,1) r2=(2,1) r3=(0,2) r4=(1,2).
GRAPH_ROWS = ["1 2 1 1.0", "2 1 2 1.0", "3 3 2 2.0", "4 1 3 3.0", "5 2 3 2.0"]
GRAPH_TXT = "NumVertices: 4\nNumEdges: 5\n" + "\n".join(GRAPH_ROWS) + "\n"
# Kept rows r0 (partner r1), r2 (partner r4), r3 (one-way): merged edges (1,0), (2,1), (0,2).
MERGED_EDGES = [[1, 0], [2, 1], [0, 2]]
MERGED_LENGTHS = [1.0, 2.0, 3.0]
# Paths 1-2-3 (edges 0, 1) and 1-3 (edge 2).
PATH_LIBRARY = "1 2 3\n1 3\n"
# Worlds x stored rows r0..r4.
X_STORED = np.array(
    [
        [1, 1, 1, 1, 1],
        [1, 0, 0, 1, 0],
        [0, 1, 1, 0, 0],
        [0, 0, 0, 0, 1],
        [0, 0, 0, 0, 0],
        [1, 1, 0, 1, 1],
    ],
    dtype=np.uint8,
)
X_OR = np.array([[1, 1, 1], [1, 0, 1], [1, 1, 0], [0, 1, 0], [0, 0, 0], [1, 1, 1]], dtype=bool)
X_AND = np.array([[1, 1, 1], [0, 0, 1], [0, 0, 0], [0, 0, 0], [0, 0, 0], [1, 0, 1]], dtype=bool)
R_OR = np.array([[1, 1], [0, 1], [1, 0], [0, 0], [0, 0], [1, 1]], dtype=bool)
R_AND = np.array([[1, 1], [0, 1], [0, 0], [0, 0], [0, 0], [0, 1]], dtype=bool)
# The stored R differs from R_OR in two entries.
R_STORED = R_OR.astype(np.uint8).copy()
R_STORED[3, 0] = 1
R_STORED[5, 1] = 0
COORDS = "0.0,0.0\n1.0,0.0\n2.0,1.0\n3.0,3.0\n"


def write_folder(root: Path, *, skip: tuple[str, ...] = (), **files: object) -> Path:
    """Write the small dataset under ``root/ds``; ``files`` overrides file contents by name (dots as _)."""
    folder = root / "ds"
    folder.mkdir(parents=True, exist_ok=True)
    contents: dict[str, object] = {
        "graph.txt": GRAPH_TXT,
        "path_library.dat": PATH_LIBRARY,
        "start_idx.dat": "1\n",
        "goal_idx.dat": "3\n",
        "coll_check_results.mat": {"coll_check_results": X_STORED.astype(np.float64)},
        "world_library_assignment.mat": {"world_library_assignment": R_STORED.astype(np.float64)},
        "train_id.mat": {"train_id": np.array([[1.0], [2.0], [3.0], [4.0]])},
        "test_id.mat": {"test_id": np.array([[5.0], [6.0]])},
        "coord_set.dat": COORDS,
    }
    for key, value in files.items():
        contents[key.replace("_DOT_", ".")] = value
    for name, value in contents.items():
        if name in skip:
            continue
        path = folder / name
        if isinstance(value, bytes):
            path.write_bytes(value)
        elif isinstance(value, str):
            path.write_text(value)
        else:
            assert isinstance(value, dict)
            scipy.io.savemat(str(path), value)
    return folder


def test_small_folder_merges_directions_with_or(tmp_path: Path) -> None:
    problem = load_gccd_folder(write_folder(tmp_path))
    graph = problem.graph
    assert graph is not None
    assert not graph.directed
    assert graph.num_vertices == 4
    np.testing.assert_array_equal(graph.edges, MERGED_EDGES)
    np.testing.assert_array_equal(graph.lengths, MERGED_LENGTHS)
    assert graph.vertex_states is not None
    np.testing.assert_array_equal(graph.vertex_states, [[0, 0], [1, 0], [2, 1], [3, 3]])
    assert (problem.start, problem.goal) == (0, 2)
    assert [p.tolist() for p in problem.library.path_edges] == [[0, 1], [2]]
    assert problem.library.vertex_paths is not None
    assert [p.tolist() for p in problem.library.vertex_paths] == [[0, 1, 2], [0, 2]]
    np.testing.assert_array_equal(problem.edge_costs, np.ones(3))
    worlds = problem.require_worlds()
    np.testing.assert_array_equal(worlds.X, X_OR)
    np.testing.assert_array_equal(worlds.R, R_OR)
    np.testing.assert_array_equal(worlds.train_ids, [0, 1, 2, 3])
    np.testing.assert_array_equal(worlds.test_ids, [4, 5])
    meta = problem.metadata
    assert meta["merge"] == "or"
    assert meta["stored_rows"] == 5
    assert meta["one_way_rows"] == 1
    assert meta["stored_R_mismatches"] == 2
    assert meta["folder"] == "ds"
    assert problem.name == "ds"


def test_small_folder_merges_directions_with_and(tmp_path: Path) -> None:
    problem = load_gccd_folder(write_folder(tmp_path), merge="and")
    worlds = problem.require_worlds()
    np.testing.assert_array_equal(worlds.X, X_AND)
    np.testing.assert_array_equal(worlds.R, R_AND)
    assert problem.metadata["merge"] == "and"
    assert problem.metadata["stored_R_mismatches"] == int((R_STORED.astype(bool) != R_AND).sum())


def test_small_folder_without_optional_files(tmp_path: Path) -> None:
    problem = load_gccd_folder(write_folder(tmp_path, skip=("world_library_assignment.mat", "coord_set.dat")))
    assert problem.metadata["stored_R_mismatches"] is None
    assert problem.graph is not None
    assert problem.graph.vertex_states is None
    np.testing.assert_array_equal(problem.require_worlds().R, R_OR)


def test_vertex_coordinates_txt_is_read(tmp_path: Path) -> None:
    text = "1 0.0 0.0 5.0\n2 1.0 0.0 5.0\n3 2.0 1.0 6.0\n4 3.0 3.0 7.0\n"
    folder = write_folder(tmp_path, skip=("coord_set.dat",), vertex_coordinates_DOT_txt=text)
    graph = load_gccd_folder(folder).graph
    assert graph is not None
    assert graph.vertex_states is not None
    np.testing.assert_array_equal(graph.vertex_states[:, 2], [5, 5, 6, 7])


def test_folder_digest_changes_with_content(tmp_path: Path) -> None:
    a = load_gccd_folder(write_folder(tmp_path / "a")).metadata["sha256"]
    b = load_gccd_folder(write_folder(tmp_path / "b")).metadata["sha256"]
    c = load_gccd_folder(write_folder(tmp_path / "c", goal_idx_DOT_dat="2\n")).metadata["sha256"]
    assert a == b
    assert a != c


def test_read_graph_txt_converts_to_zero_based(tmp_path: Path) -> None:
    path = tmp_path / "graph.txt"
    path.write_text(GRAPH_TXT + "\n\n")  # trailing blank lines are ignored
    raw = read_graph_txt(path)
    assert raw.num_vertices == 4
    np.testing.assert_array_equal(raw.parents, [1, 0, 2, 0, 1])
    np.testing.assert_array_equal(raw.children, [0, 1, 1, 2, 2])
    np.testing.assert_array_equal(raw.lengths, [1.0, 1.0, 2.0, 3.0, 2.0])


def test_merge_directions_keeps_parent_greater_than_child() -> None:
    raw = RawGraph(
        num_vertices=4,
        parents=np.array([1, 0, 2, 0, 1]),
        children=np.array([0, 1, 1, 2, 2]),
        lengths=np.ones(5),
    )
    keep, partner = merge_directions(raw)
    np.testing.assert_array_equal(keep, [0, 2, 3])
    np.testing.assert_array_equal(partner, [1, 4, -1])
    assert np.all(raw.parents[keep][partner >= 0] > raw.children[keep][partner >= 0])


def test_merge_directions_whatever_the_row_order() -> None:
    # Reverse rows first: (0,1) before (1,0); one-way (3,2) with parent > child.
    raw = RawGraph(4, np.array([0, 3, 1]), np.array([1, 2, 0]), np.ones(3))
    keep, partner = merge_directions(raw)
    np.testing.assert_array_equal(keep, [1, 2])
    np.testing.assert_array_equal(partner, [-1, 0])


def test_merge_directions_directed_graph_keeps_every_row() -> None:
    raw = RawGraph(3, np.array([0, 1, 0]), np.array([1, 2, 2]), np.ones(3))
    keep, partner = merge_directions(raw)
    np.testing.assert_array_equal(keep, [0, 1, 2])
    np.testing.assert_array_equal(partner, [-1, -1, -1])


# --------------------------------------------------------------------------------------------------
# Refusals
# --------------------------------------------------------------------------------------------------

REQUIRED = REQUIRED_FILES


def _refused(folder: Path, filename: str) -> str:
    """Load ``folder``, expect a DatasetError, and check it names ``filename``; returns the message."""
    with pytest.raises(DatasetError) as info:
        load_gccd_folder(folder)
    message = str(info.value)
    assert filename in message.replace(str(folder.parent), ""), message
    assert "\n" not in message
    return message


def test_missing_folder_is_refused(tmp_path: Path) -> None:
    _refused(tmp_path / "no_such_dataset", "no_such_dataset")


def test_file_instead_of_folder_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "ds"
    path.write_text("not a folder")
    _refused(path, "ds")


@pytest.mark.parametrize("filename", REQUIRED)
def test_missing_required_file_is_refused(tmp_path: Path, filename: str) -> None:
    message = _refused(write_folder(tmp_path, skip=(filename,)), filename)
    for other in REQUIRED:
        if other != filename:
            assert other not in message


@pytest.mark.parametrize(
    "text",
    [
        pytest.param("NumVertices 4\nNumEdges: 5\n" + "\n".join(GRAPH_ROWS), id="no-colon"),
        pytest.param("NumVertices: four\nNumEdges: 5\n" + "\n".join(GRAPH_ROWS), id="not-integer"),
        pytest.param("NumNodes: 4\nNumEdges: 5\n" + "\n".join(GRAPH_ROWS), id="wrong-key"),
        pytest.param("NumVertices: 4\nNumVertices: 4\n" + "\n".join(GRAPH_ROWS), id="repeated-key"),
        pytest.param("", id="empty"),
        pytest.param("NumVertices: 4\nNumEdges: 4\n" + "\n".join(GRAPH_ROWS), id="num-edges-too-small"),
        pytest.param("NumVertices: 4\nNumEdges: 6\n" + "\n".join(GRAPH_ROWS), id="num-edges-too-large"),
        pytest.param(GRAPH_TXT.replace("3 3 2 2.0", "3 3 two 2.0"), id="non-numeric"),
        pytest.param(GRAPH_TXT.replace("3 3 2 2.0", "3 3 2"), id="short-row"),
        pytest.param(GRAPH_TXT.replace("3 3 2 2.0", "3 5 2 2.0"), id="vertex-too-large"),
        pytest.param(GRAPH_TXT.replace("3 3 2 2.0", "3 0 2 2.0"), id="vertex-zero"),
        pytest.param(GRAPH_TXT.replace("3 3 2 2.0", "3 3 2 -2.0"), id="negative-length"),
        pytest.param(GRAPH_TXT.replace("3 3 2 2.0", "3 3 2 nan"), id="nan-length"),
        pytest.param(GRAPH_TXT + "6 3 2 2.0\n", id="duplicate-row"),
    ],
)
def test_malformed_graph_txt_is_refused(tmp_path: Path, text: str) -> None:
    _refused(write_folder(tmp_path, graph_DOT_txt=text), "graph.txt")


def test_graph_rows_of_two_numbers_are_refused(tmp_path: Path) -> None:
    path = tmp_path / "graph.txt"
    path.write_text("NumVertices: 4\nNumEdges: 2\n1 2\n1 3\n")
    with pytest.raises(DatasetError, match=r"graph\.txt"):
        read_graph_txt(path)


def test_read_graph_txt_missing_file(tmp_path: Path) -> None:
    with pytest.raises(DatasetError, match=r"graph\.txt"):
        read_graph_txt(tmp_path / "graph.txt")


def test_x_with_wrong_number_of_columns_is_refused(tmp_path: Path) -> None:
    x = {"coll_check_results": X_STORED[:, :4].astype(np.float64)}
    message = _refused(write_folder(tmp_path, coll_check_results_DOT_mat=x), "coll_check_results.mat")
    assert "5" in message


def test_x_with_a_value_two_is_refused(tmp_path: Path) -> None:
    bad = X_STORED.astype(np.float64)
    bad[2, 3] = 2
    _refused(
        write_folder(tmp_path, coll_check_results_DOT_mat={"coll_check_results": bad}),
        "coll_check_results.mat",
    )


def test_x_with_a_wrong_variable_name_is_refused(tmp_path: Path) -> None:
    x = {"X": X_STORED.astype(np.float64)}
    _refused(write_folder(tmp_path, coll_check_results_DOT_mat=x), "coll_check_results.mat")


@pytest.mark.parametrize(
    "text",
    [
        pytest.param("1 2 3\n1 4\n", id="no-such-edge"),
        pytest.param("1 2 3\n1 9\n", id="vertex-out-of-range"),
        pytest.param("1 2 3\n1 x 3\n", id="non-numeric"),
        pytest.param("1 2 3\n1\n", id="single-vertex"),
        pytest.param("\n\n", id="empty"),
    ],
)
def test_bad_path_library_is_refused(tmp_path: Path, text: str) -> None:
    _refused(write_folder(tmp_path, path_library_DOT_dat=text), "path_library.dat")


@pytest.mark.parametrize(
    ("filename", "ids"),
    [
        ("train_id.mat", [1.0, 2.0, 7.0]),
        ("train_id.mat", [0.0, 1.0]),
        ("test_id.mat", [5.0, 7.0]),
        ("test_id.mat", [0.0]),
    ],
)
def test_world_ids_out_of_range_are_refused(tmp_path: Path, filename: str, ids: list[float]) -> None:
    variable = filename.removesuffix(".mat")
    override = {filename.replace(".", "_DOT_"): {variable: np.array(ids)[:, None]}}
    _refused(write_folder(tmp_path, **override), filename)


@pytest.mark.parametrize("filename", ["start_idx.dat", "goal_idx.dat"])
def test_non_integer_start_or_goal_is_refused(tmp_path: Path, filename: str) -> None:
    _refused(write_folder(tmp_path, **{filename.replace(".", "_DOT_"): "start\n"}), filename)


@pytest.mark.parametrize(
    "filename", ["coll_check_results.mat", "train_id.mat", "test_id.mat", "world_library_assignment.mat"]
)
def test_corrupt_mat_file_is_refused(tmp_path: Path, filename: str) -> None:
    junk = np.random.default_rng(7).integers(0, 256, size=512, dtype=np.uint8).tobytes()
    _refused(write_folder(tmp_path, **{filename.replace(".", "_DOT_"): junk}), filename)


def test_stored_r_of_wrong_shape_is_refused(tmp_path: Path) -> None:
    r = {"world_library_assignment": np.ones((6, 3))}
    _refused(write_folder(tmp_path, world_library_assignment_DOT_mat=r), "world_library_assignment.mat")


def test_vertex_coordinates_of_wrong_count_are_refused(tmp_path: Path) -> None:
    folder = write_folder(tmp_path, coord_set_DOT_dat="0.0,0.0\n1.0,0.0\n")
    with pytest.raises(DatasetError, match="vertex coordinates"):
        load_gccd_folder(folder)
