"""Tests of the checksummed npz layout and its per-format reader and writer (more in test_dataset_file)."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from drd_planner.data.npz_format import NpzFormat, building_for_domain, read_checked_npz
from drd_planner.exceptions import DatasetError, ProblemError, TreeFileError

FORMAT = NpzFormat("drd_planner.test", 2, DatasetError, "test file", readable=(1, 2))


def test_write_read_round_trip_and_reproducible_bytes(tmp_path: Path) -> None:
    arrays = {"b": np.arange(5, dtype=np.int64), "a": np.eye(2)}
    one = FORMAT.write(tmp_path / "one.npz", {"note": "hi"}, arrays)
    two = FORMAT.write(tmp_path / "sub" / "two.npz", {"note": "hi"}, arrays)
    assert one.read_bytes() == two.read_bytes()
    header, back = FORMAT.read(one)
    assert header["note"] == "hi"
    assert header["format"] == "drd_planner.test"
    assert header["format_version"] == 2
    assert set(back) == {"a", "b"}
    assert np.array_equal(back["a"], np.eye(2))


def test_other_formats_and_versions_are_refused(tmp_path: Path) -> None:
    path = FORMAT.write(tmp_path / "f.npz", {}, {"a": np.zeros(1)})
    with pytest.raises(TreeFileError, match="is not a drd_planner tree file"):
        NpzFormat("drd_planner.tree", 2, TreeFileError, "tree file").read(path)
    with pytest.raises(DatasetError, match="this build reads version 3"):
        NpzFormat("drd_planner.test", 3, DatasetError, "test file").read(path)
    assert (
        read_checked_npz(
            path, format_name="drd_planner.test", format_version=(2,), error=DatasetError, what="test file"
        )[0]["format_version"]
        == 2
    )


def test_reserved_names_are_refused(tmp_path: Path) -> None:
    with pytest.raises(DatasetError, match="reserved"):
        FORMAT.write(tmp_path / "f.npz", {"format": "x"}, {})
    with pytest.raises(DatasetError, match="reserved"):
        FORMAT.write(tmp_path / "f.npz", {}, {"header": np.zeros(1)})


def _build(header: dict[str, str], expected_domain: str | None, build: Callable[[], int]) -> int:
    with building_for_domain(Path("some.npz"), header, error=TreeFileError, expected_domain=expected_domain):
        return build()


def test_building_for_domain_checks_the_domain_and_names_inconsistent_files() -> None:
    header = {"domain": "se2"}
    assert _build(header, None, lambda: 7) == 7
    assert _build(header, "se2", lambda: 7) == 7
    built: list[int] = []
    with pytest.raises(TreeFileError, match=r"some\.npz was built for domain 'se2', not 'arm'"):
        _build(header, "arm", lambda: built.append(1) or 7)
    assert built == []  # refused before building

    def inconsistent() -> int:
        raise ProblemError("edge 3 out of range")

    with pytest.raises(TreeFileError, match=r"some\.npz is inconsistent: edge 3 out of range"):
        _build(header, None, inconsistent)
    with pytest.raises(TreeFileError, match="inconsistent: 'x'"):
        _build(header, "se2", lambda: {"y": 1}["x"])

    def bug() -> int:
        raise MemoryError

    with pytest.raises(MemoryError):
        _build(header, None, bug)
