"""Finding shipped trees and bags by name."""

from __future__ import annotations

from pathlib import Path

import pytest

from drd_planner.exceptions import DrdError, TreeFileError
from drd_planner.planning.shipped import resolve_bag_path, resolve_tree_path, shipped_dirs

REPO = Path(__file__).resolve().parents[2]


def test_bare_names_find_the_repository_trees() -> None:
    assert resolve_tree_path("heli_wires") == REPO / "trees" / "heli_wires.npz"
    assert resolve_tree_path("arm_table_clutter.npz") == REPO / "trees" / "arm_table_clutter.npz"
    assert REPO / "trees" in shipped_dirs("trees")


def test_paths_are_used_as_given_and_the_environment_comes_first(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    mine = tmp_path / "heli_wires.npz"
    mine.write_bytes(b"x")
    assert resolve_tree_path(str(mine)) == mine
    monkeypatch.setenv("DRD_TREES", str(tmp_path))
    assert resolve_tree_path("heli_wires") == mine
    bag = tmp_path / "flight.mcap"
    bag.write_bytes(b"x")
    monkeypatch.setenv("DRD_BAGS", str(tmp_path))
    assert resolve_bag_path("flight") == bag


def test_unknown_names_say_where_they_were_looked_for(tmp_path: Path) -> None:
    with pytest.raises(TreeFileError, match=r"nope\.npz in: .*trees"):
        resolve_tree_path("nope")
    with pytest.raises(TreeFileError, match="does not exist"):
        resolve_tree_path(str(tmp_path / "sub" / "missing.npz"))
    with pytest.raises(DrdError, match=r"nothing\.mcap"):
        resolve_bag_path("nothing")


def test_a_directory_is_not_reported_missing(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Issue 19 item 14: a directory given as a tree is called a directory, not "does not exist"."""
    folder = tmp_path / "sub"
    folder.mkdir()
    with pytest.raises(TreeFileError, match="is a directory, not a tree file") as info:
        resolve_tree_path(str(folder))
    assert "does not exist" not in str(info.value)
    monkeypatch.chdir(tmp_path)
    with pytest.raises(TreeFileError, match="sub is a directory"):
        resolve_tree_path("sub")
