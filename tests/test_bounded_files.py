"""A user's file read with its size bounded first: each way it can fail is one error of the caller's type."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from drd_planner.bounded_files import read_bounded, read_bounded_text
from drd_planner.exceptions import SiteFileError


def test_a_small_file_is_read_whole(tmp_path: Path) -> None:
    path = tmp_path / "a.txt"
    path.write_text("héllo", encoding="utf-8")
    assert read_bounded(path, 100, "note", SiteFileError) == "héllo".encode()
    assert read_bounded_text(path, 100, "note", SiteFileError) == "héllo"


def test_each_failure_is_one_error_of_the_callers_type(tmp_path: Path) -> None:
    big = tmp_path / "big.txt"
    big.write_bytes(b"x" * 11)
    with pytest.raises(SiteFileError, match=r"note has 11 bytes; at most 10 are read \(make it smaller\)"):
        read_bounded(big, 10, "note", SiteFileError, hint=" (make it smaller)")
    with pytest.raises(SiteFileError, match="cannot read folder: not a regular file"):
        read_bounded(tmp_path, 10, "folder", SiteFileError)
    with pytest.raises(SiteFileError, match="cannot read missing: "):
        read_bounded(tmp_path / "nothing", 10, "missing", SiteFileError)
    latin = tmp_path / "latin.txt"
    latin.write_bytes("é".encode("latin-1"))
    with pytest.raises(SiteFileError, match="cannot read latin: not UTF-8 text"):
        read_bounded_text(latin, 10, "latin", SiteFileError)
    if hasattr(os, "mkfifo"):  # a pipe is refused from its type, never read (it would block)
        pipe = tmp_path / "pipe"
        os.mkfifo(pipe)
        with pytest.raises(SiteFileError, match="not a regular file"):
            read_bounded(pipe, 10, "pipe", SiteFileError)
