"""Tests for drd_planner.settings: one place that says where shared files are."""

from __future__ import annotations

from pathlib import Path

import pytest

from drd_planner.settings import checkout_root, shared_data_dir, shipped_dirs

REPO = Path(__file__).resolve().parents[1]


def test_checkout_root_is_this_repository() -> None:
    assert checkout_root() == REPO


def test_shared_data_dir_follows_the_environment(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    monkeypatch.delenv("DRD_SHARED_DATA", raising=False)
    assert shared_data_dir() == REPO.parent / "shared" / "data"
    monkeypatch.setenv("DRD_SHARED_DATA", str(tmp_path))
    assert shared_data_dir() == tmp_path


def test_shipped_dirs_put_the_environment_first(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    monkeypatch.setenv("DRD_TREES", str(tmp_path))
    assert shipped_dirs("trees")[:2] == [tmp_path, REPO / "trees"]
    missing = tmp_path / "missing"
    monkeypatch.setenv("DRD_BAGS", str(missing))
    assert missing not in shipped_dirs("bags")
    assert REPO / "bags" in shipped_dirs("bags")


def test_shipped_dirs_refuse_an_unknown_kind() -> None:
    with pytest.raises(ValueError, match="trees"):
        shipped_dirs("maps")  # type: ignore[arg-type]
