"""Tests for drd_planner.cli.errors: one stderr line and the exit status of a failed or interrupted command."""

from __future__ import annotations

import argparse

import pytest

from drd_planner.cli.errors import ERROR_EXIT, INTERRUPT_EXIT, run_command
from drd_planner.exceptions import DatasetError, DrdError, InvariantError, UnverifiedPathError


def _args(func: object) -> argparse.Namespace:
    return argparse.Namespace(func=func)


def test_the_command_status_is_returned(capsys: pytest.CaptureFixture[str]) -> None:
    assert run_command(_args(lambda args: 0)) == 0
    assert run_command(_args(lambda args: 3)) == 3
    assert capsys.readouterr().err == ""


def test_a_drd_error_prints_one_line_and_exits_2(capsys: pytest.CaptureFixture[str]) -> None:
    def fail(args: argparse.Namespace) -> int:
        raise DatasetError("no such dataset")

    assert run_command(_args(fail)) == ERROR_EXIT == 2
    assert capsys.readouterr().err == "drd: error: no such dataset\n"


def test_an_interrupt_prints_the_callers_line_and_exits_130(capsys: pytest.CaptureFixture[str]) -> None:
    def interrupt(args: argparse.Namespace) -> int:
        raise KeyboardInterrupt

    assert run_command(_args(interrupt)) == INTERRUPT_EXIT == 130
    assert capsys.readouterr().err == "drd: interrupted\n"
    assert run_command(_args(interrupt), interrupted="drd: interrupted (resume later)") == 130
    assert capsys.readouterr().err == "drd: interrupted (resume later)\n"


def test_other_exceptions_are_bugs_and_propagate() -> None:
    def bug(args: argparse.Namespace) -> int:
        raise ValueError("a bug")

    with pytest.raises(ValueError, match="a bug"):
        run_command(_args(bug))


def test_a_broken_invariant_is_a_bug_not_a_refusal(capsys: pytest.CaptureFixture[str]) -> None:
    # An unverified path about to go out is a broken safety invariant: it keeps its traceback (no exit 2).
    def unverified(args: argparse.Namespace) -> int:
        raise UnverifiedPathError("edge 3 of the returned path was not checked free")

    assert not issubclass(UnverifiedPathError, DrdError)
    assert issubclass(UnverifiedPathError, InvariantError)
    assert issubclass(InvariantError, RuntimeError)
    with pytest.raises(UnverifiedPathError, match="edge 3"):
        run_command(_args(unverified))
    assert "drd: error" not in capsys.readouterr().err
