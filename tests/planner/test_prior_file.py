"""The world-prior file: round trip, safe refusals, and tree files loading as one-tree priors."""

from __future__ import annotations

import dataclasses
import json
import zipfile
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from drd_planner.core.tree import build_tree
from drd_planner.data.npz_format import payload_digest
from drd_planner.data.planar_problem import make_planar_problem
from drd_planner.data.tree_file import TreeBundle, save_tree
from drd_planner.exceptions import PriorFileError, ProblemError, TreeFileError
from drd_planner.planner import (
    LeafSetting,
    QueryTree,
    WorldPrior,
    load_prior,
    load_tree_bundle,
    prior_from_problem,
    save_prior,
)
from drd_planner.planner.build_settings import TreeSettings
from drd_planner.planner.prior_build import query_tree

REPO = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def prior() -> WorldPrior:
    problem = make_planar_problem(model="forest", num_worlds=150, seed=2)
    tree = build_tree(problem, progress=False)
    assert problem.start is not None
    assert problem.goal is not None
    own = QueryTree("own", problem.start, problem.goal, problem.library, tree)
    base = prior_from_problem(problem, domain="planar", trees=(own,), eta=0.4, pseudo_count=5.0)
    other, _ = query_tree(base, 3, 20, tree=TreeSettings())
    return WorldPrior(**{**base.__dict__, "trees": (own, other)})


def test_round_trip_keeps_everything(prior: WorldPrior, tmp_path: Path) -> None:
    path = save_prior(tmp_path / "p.npz", prior)
    back = load_prior(path, expected_domain="planar")
    assert back.worlds is not None
    assert prior.worlds is not None
    np.testing.assert_array_equal(back.worlds, prior.worlds)
    np.testing.assert_array_equal(back.graph.edges, prior.graph.edges)
    np.testing.assert_array_equal(back.graph.vertex_states, prior.graph.vertex_states)  # type: ignore[arg-type]
    assert (back.eta, back.alpha, back.pseudo_count, back.domain) == (0.4, prior.alpha, 5.0, "planar")
    assert [(t.start, t.goal, t.name) for t in back.trees] == [(t.start, t.goal, t.name) for t in prior.trees]
    for a, b in zip(back.trees, prior.trees, strict=True):
        np.testing.assert_array_equal(a.tree.edge, b.tree.edge)
        np.testing.assert_array_equal(a.tree.free_fraction, b.tree.free_fraction)
        assert all(np.array_equal(x, y) for x, y in zip(a.library.path_edges, b.library.path_edges, strict=True))
        assert a.tree.world_free is not None
    # Saving twice gives the same bytes (reproducible files).
    assert save_prior(tmp_path / "q.npz", back).read_bytes() == path.read_bytes()


def test_tree_bundle_of_a_prior(prior: WorldPrior, tmp_path: Path) -> None:
    path = save_prior(tmp_path / "p.npz", prior)
    bundle = load_tree_bundle(path, index=1)
    assert (bundle.problem.start, bundle.problem.goal) == (3, 20)
    with pytest.raises(PriorFileError, match="tree 5 does not exist"):
        load_tree_bundle(path, index=5)


def test_a_tree_file_loads_as_a_prior_with_one_tree(prior: WorldPrior, tmp_path: Path) -> None:
    own = prior.trees[0]
    problem = prior.query_problem(own)
    path = save_tree(tmp_path / "t.npz", TreeBundle(problem, own.tree, "planar", eta=0.3))
    loaded = load_prior(path)
    assert loaded.worlds is None
    assert not loaded.serves_any_query
    assert len(loaded.trees) == 1
    assert loaded.trees[0].start == own.start
    assert loaded.eta == 0.3
    with pytest.raises(PriorFileError, match="'planar', not 'arm'"):
        load_prior(path, expected_domain="arm")


def test_the_shipped_trees_load_as_priors() -> None:
    for name in ("heli_wires", "arm_table_clutter"):
        loaded = load_prior(REPO / "trees" / f"{name}.npz")
        assert len(loaded.trees) == 1


def test_refusals_name_the_problem(prior: WorldPrior, tmp_path: Path) -> None:
    path = save_prior(tmp_path / "p.npz", prior)
    with pytest.raises(PriorFileError, match="not found"):
        load_prior(tmp_path / "none.npz")
    with pytest.raises(PriorFileError, match="directory"):
        load_prior(tmp_path)
    with pytest.raises(PriorFileError, match="domain 'planar', not 'helicopter'"):
        load_prior(path, expected_domain="helicopter")
    text = tmp_path / "text.npz"
    text.write_text("not a prior")
    with pytest.raises(PriorFileError, match="not a readable prior or tree file") as info:
        load_prior(text)
    assert "holds text starting 'not a prior'" in str(info.value)  # what was found instead of an .npz
    assert "pickle" not in str(info.value)  # never numpy's advice to load pickles
    with pytest.raises(PriorFileError, match="is a directory"):
        load_tree_bundle(tmp_path)
    assert isinstance(PriorFileError("x"), TreeFileError)  # the node's existing catch still applies


def _rewrite(src: Path, dst: Path, edit: object, *, resign: bool = False) -> None:
    """Copy a prior with its header edited by ``edit(header) -> header``.

    The digests are left stale, or recomputed with ``resign`` (a file as a writer would make it).
    """
    with zipfile.ZipFile(src) as zin, zipfile.ZipFile(dst, "w") as zout:
        for item in zin.infolist():
            data = zin.read(item.filename)
            if item.filename == "header.npy":
                import io

                arr = np.load(io.BytesIO(data), allow_pickle=False)
                header = edit(json.loads(arr.tobytes().decode()))  # type: ignore[operator]
                if resign:
                    header["payload_sha256"] = payload_digest(header["array_sha256"], header)
                buf = io.BytesIO()
                np.save(buf, np.frombuffer(json.dumps(header).encode(), dtype=np.uint8), allow_pickle=False)
                data = buf.getvalue()
            zout.writestr(item, data)


def test_another_version_and_tampering_are_refused(prior: WorldPrior, tmp_path: Path) -> None:
    path = save_prior(tmp_path / "p.npz", prior)
    newer = tmp_path / "v3.npz"
    _rewrite(path, newer, lambda h: {**h, "format_version": 3})
    with pytest.raises(PriorFileError, match="version 3"):
        load_prior(newer)
    tampered = tmp_path / "t.npz"
    _rewrite(path, tampered, lambda h: {**h, "eta": 0.9})
    with pytest.raises(PriorFileError, match="checksum"):
        load_prior(tampered)


def test_a_prior_without_worlds_cannot_be_saved(prior: WorldPrior, tmp_path: Path) -> None:
    legacy = WorldPrior(**{**prior.__dict__, "worlds": None})
    with pytest.raises(PriorFileError, match="without training worlds"):
        save_prior(tmp_path / "x.npz", legacy)


def test_every_tree_of_a_prior_is_checked_as_a_walk(prior: WorldPrior, tmp_path: Path) -> None:
    """A prior whose second tree's paths do not reach that tree's goal is refused, naming the tree."""
    from drd_planner.data.npz_format import payload_digest

    def moved_goal(header: dict[str, Any]) -> dict[str, Any]:
        trees = [header["trees"][0], {**header["trees"][1], "goal": header["trees"][1]["goal"] + 1}]
        edited = {**header, "trees": trees}
        edited["payload_sha256"] = payload_digest(edited["array_sha256"], edited)  # as an attacker would
        return edited

    path = save_prior(tmp_path / "p.npz", prior)
    bad = tmp_path / "bad.npz"
    _rewrite(path, bad, moved_goal)
    with pytest.raises(PriorFileError, match=r"tree 1: library path 0 is not a walk from the start vertex 3"):
        load_prior(bad)


def test_the_shipped_files_fit_the_read_limits_with_room() -> None:
    """The size limits are generous: every shipped tree and dataset is far below each of them."""
    from drd_planner.data import safe_npz

    for path in sorted((REPO / "trees").glob("*.npz")) + sorted((REPO / "datasets").glob("*.npz")):
        with zipfile.ZipFile(path) as zf:
            infos = zf.infolist()
        assert path.stat().st_size * 10 < safe_npz.MAX_FILE_BYTES
        assert sum(i.file_size for i in infos) * 10 < safe_npz.MAX_TOTAL_BYTES
        assert max(i.file_size for i in infos) * 10 < safe_npz.MAX_MEMBER_BYTES
        # Deflate's own bound (about 1032:1) sets this limit, so it cannot leave more room: an array of equal
        # values (unit edge costs) reaches about half of it.
        assert max(i.file_size / i.compress_size for i in infos) * 2 < safe_npz.MAX_COMPRESSION_RATIO
        assert len(infos) * 10 < safe_npz.MAX_MEMBERS


def test_a_trees_own_leaf_setting_round_trips_and_version_1_files_still_load(prior: WorldPrior, tmp_path: Path) -> None:
    own = dataclasses.replace(prior.trees[0], leaf=LeafSetting(0.1, None))
    other = dataclasses.replace(prior.trees[1], leaf=LeafSetting(0.6, 20.0))
    path = save_prior(tmp_path / "p.npz", dataclasses.replace(prior, trees=(own, other)))
    back = load_prior(path)
    assert [t.leaf for t in back.trees] == [LeafSetting(0.1, None), LeafSetting(0.6, 20.0)]
    assert (load_tree_bundle(path, index=1).eta, load_tree_bundle(path, index=1).pseudo_count) == (0.6, 20.0)
    # A version-1 file (before per-tree settings): every tree uses the prior's.
    old = tmp_path / "v1.npz"
    _rewrite(
        path,
        old,
        lambda h: {
            **h,
            "format_version": 1,
            "trees": [{k: v for k, v in t.items() if k != "leaf"} for t in h["trees"]],
        },
        resign=True,
    )
    assert [t.leaf for t in load_prior(old).trees] == [None, None]
    assert load_tree_bundle(old).eta == prior.eta
    bad = tmp_path / "bad.npz"
    _rewrite(
        path,
        bad,
        lambda h: {**h, "trees": [{**h["trees"][0], "leaf": {"eta": 2.0}}, h["trees"][1]]},
        resign=True,
    )
    with pytest.raises(PriorFileError, match=r"tree 0: header field 'eta'"):
        load_prior(bad)


def test_the_region_rule_round_trips_and_a_bad_one_is_refused(prior: WorldPrior, tmp_path: Path) -> None:
    assert prior.region_rule == "probability"  # the paper's unless chosen
    with pytest.raises(ProblemError, match="known: probability, per_check"):
        dataclasses.replace(prior, region_rule="cheapest")
    path = save_prior(tmp_path / "p.npz", dataclasses.replace(prior, region_rule="per_check"))
    assert load_prior(path).region_rule == "per_check"
    # A file written before the rule was stored plans new queries with the paper's rule.
    old = tmp_path / "old.npz"
    _rewrite(path, old, lambda h: {k: v for k, v in h.items() if k != "region_rule"}, resign=True)
    assert load_prior(old).region_rule == "probability"
    bad = tmp_path / "bad.npz"
    _rewrite(path, bad, lambda h: {**h, "region_rule": "cheapest"}, resign=True)
    with pytest.raises(PriorFileError, match="region rule must be one of probability, per_check"):
        load_prior(bad)
    # A tree's own rule (in its build info) is checked too, naming the tree.
    bad_tree = tmp_path / "bad_tree.npz"

    def tree_rule(header: dict[str, Any]) -> dict[str, Any]:
        first = {**header["trees"][0], "info": {**header["trees"][0]["info"], "region_rule": ["x"]}}
        return {**header, "trees": [first, header["trees"][1]]}

    _rewrite(path, bad_tree, tree_rule, resign=True)
    with pytest.raises(PriorFileError, match="tree 0: the tree's region rule must be a string"):
        load_prior(bad_tree)


def test_a_dataset_file_given_as_a_prior_says_how_to_make_the_prior(tmp_path: Path) -> None:
    from drd_planner.cli.main import main

    dataset = tmp_path / "data.npz"
    argv = [
        "build-dataset",
        "--domain",
        "planar",
        "--world-model",
        "one_wall",
        "--worlds",
        "12",
        "--seed",
        "1",
    ]
    assert main([*argv, "--out", str(dataset), "--workers", "1"]) == 0
    with pytest.raises(PriorFileError, match="is a dataset file") as info:
        load_prior(dataset)
    assert f"drd build-tree --dataset {dataset} --out PRIOR.npz" in str(info.value)
