"""Progress reports: plain lines on stderr when it is not a terminal, a bar when it is, nothing when off."""

from __future__ import annotations

import io

import pytest

from drd_planner import progress
from drd_planner.progress import Progress, progress_iter


class FakeTerminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_plain_lines_when_not_a_terminal(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(progress, "PLAIN_INTERVAL_S", 0.0)
    out = io.StringIO()
    with Progress(4, "validating eta x kappa", unit="episode", stream=out, announce=True) as bar:
        for _ in range(4):
            bar.update(1)
    lines = out.getvalue().splitlines()
    assert lines[0] == "validating eta x kappa: 4 episodes"
    assert lines[1].startswith("validating eta x kappa: 1/4 episodes (25%), 0 s elapsed, about ")
    assert lines[4].startswith("validating eta x kappa: 4/4 episodes (100%)")
    assert lines[-1].startswith("validating eta x kappa: 4/4 episodes done in ")
    assert "\r" not in out.getvalue()


def test_plain_lines_wait_for_the_interval() -> None:
    out = io.StringIO()
    with Progress(1000, "step", stream=out) as bar:  # the default interval: far longer than this loop
        for _ in range(1000):
            bar.update(1)
    assert out.getvalue() == ""


def test_disabled_is_silent_and_a_terminal_gets_a_bar(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(progress, "PLAIN_INTERVAL_S", 0.0)
    out = io.StringIO()
    with Progress(3, "quiet", stream=out, enabled=False, announce=True) as bar:
        bar.update(3)
    assert out.getvalue() == ""
    tty = FakeTerminal()
    with Progress(3, "bar", unit="world", stream=tty) as bar:
        bar.update(3)
    assert "bar: 100%" in tty.getvalue()
    assert "3/3" in tty.getvalue()


def test_progress_iter_yields_every_item_and_reports(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setattr(progress, "PLAIN_INTERVAL_S", 0.0)
    assert list(progress_iter(range(3), "bisect", unit="world")) == [0, 1, 2]
    err = capsys.readouterr().err.splitlines()
    assert err[0].startswith("bisect: 1/3 worlds (33%)")
    assert err[-1].startswith("bisect: 3/3 worlds done in ")


def test_a_resumed_step_counts_from_where_it_stopped(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(progress, "PLAIN_INTERVAL_S", 0.0)
    out = io.StringIO()
    with Progress(10, "edge checks", unit="chunk", stream=out, initial=6) as bar:
        bar.update(1)
    first = out.getvalue().splitlines()[0]
    assert first.startswith("edge checks: 7/10 chunks (70%), 0 s elapsed, about 0 s left")
