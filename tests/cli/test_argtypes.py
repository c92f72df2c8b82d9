"""Bounded-number converters and the deprecated `--tree` spelling of `--prior` of the command-line tools."""

from __future__ import annotations

import argparse

import pytest

from drd_planner.cli.argtypes import add_prior_option, bounded_float, bounded_int


@pytest.mark.parametrize(
    ("parse", "text", "words"),
    [
        (bounded_int(at_least=1), "0", "must be at least 1"),
        (bounded_int(at_least=0), "-1", "must be non-negative"),
        (bounded_int(at_least=1), "1.5", "is not an integer"),
        (bounded_float(at_least=0.0, at_most=1.0), "1.5", "must lie in [0, 1]"),
        (bounded_float(above=0.0), "0", "must be > 0"),
        (bounded_float(at_least=0.0), "nan", "must be finite"),
        (bounded_float(at_least=0.0), "x", "is not a number"),
    ],
)
def test_out_of_range_values_are_refused_with_the_bound(parse: object, text: str, words: str) -> None:
    with pytest.raises(argparse.ArgumentTypeError) as info:
        parse(text)  # type: ignore[operator]
    assert words in str(info.value)


def test_values_within_the_bounds_are_converted() -> None:
    assert bounded_int(at_least=1)("3") == 3
    assert bounded_float(at_least=0.0, at_most=1.0)("1") == 1.0
    assert bounded_float(above=0.0)("0.25") == 0.25


def test_tree_is_a_deprecated_spelling_of_prior(capsys: pytest.CaptureFixture[str]) -> None:
    parser = argparse.ArgumentParser(prog="drd bench")
    add_prior_option(parser, help="the prior file")
    assert parser.parse_args(["--prior", "a.npz"]).prior == "a.npz"
    assert capsys.readouterr().err == ""
    assert parser.parse_args(["--tree", "b.npz"]).prior == "b.npz"
    assert capsys.readouterr().err == "drd bench: warning: --tree is deprecated; use --prior\n"
    assert parser.parse_args([]).prior is None
    help_text = parser.format_help()
    assert "--prior FILE" in help_text
    assert "--tree" not in help_text


def test_drd_bench_takes_tree_with_a_warning(capsys: pytest.CaptureFixture[str]) -> None:
    from drd_planner.cli.main import main

    assert main(["bench", "--all", "/nonexistent", "--tree", "t.npz"]) == 2
    err = capsys.readouterr().err.splitlines()
    assert err[0] == "drd bench: warning: --tree is deprecated; use --prior"
    assert err[1] == "drd: error: --prior fits one dataset and cannot be used with --all"
