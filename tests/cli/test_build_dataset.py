"""Tests of ``drd build-dataset`` and the ``--gccd | --dataset`` problem source (in-process)."""

from __future__ import annotations

import argparse
import json
import shlex
import sys
from pathlib import Path

import numpy as np
import pytest

from drd_planner.cli.build_dataset import (
    add_build_dataset_parser,
    cmd_build_dataset,
    main,
    parse_domain_spec,
)
from drd_planner.cli.main import main as drd
from drd_planner.data.dataset_file import load_dataset
from drd_planner.data.problem_source import ProblemSource, problem_domain
from drd_planner.domains.base import domain_from_spec
from drd_planner.exceptions import DatasetError, DrdError

# The grid test domain is named by its module (--domain-factory test_dataset_builder:GridDomain), which lives in
# tests/data: put that folder on sys.path, as pytest does when it collects it.
DATA_TESTS = str(Path(__file__).resolve().parents[1] / "data")
if DATA_TESTS not in sys.path:
    sys.path.insert(0, DATA_TESTS)

from test_dataset_builder import GRID_FACTORY  # noqa: E402

GRID = ["--domain", "grid_test", "--domain-factory", GRID_FACTORY, "--world-model", "uniform"]
SMALL = ["--worlds", "20", "--seed", "3", "--chunk-size", "5", "--max-paths", "20", "--workers", "1"]


def _one_error_line(err: str) -> str:
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("drd: error:"), err
    return lines[0]


@pytest.fixture(scope="module")
def built(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("cli") / "grid.npz"
    assert main(["build-dataset", *GRID, *SMALL, "--out", str(out)]) == 0
    return out


def test_build_dataset_writes_a_loadable_file(built: Path, capsys: pytest.CaptureFixture[str]) -> None:
    ds = load_dataset(built)
    assert ds.num_worlds == 20
    assert ds.seed == 3
    assert ds.domain == "grid_test"
    assert ds.library.num_paths <= 20
    assert ds.test_ids.size == 2


def test_recorded_command_recreates_the_same_bytes(
    built: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    command = load_dataset(built).provenance["command"]
    argv = shlex.split(command)
    assert argv[:2] == ["drd", "build-dataset"]
    assert "--out" not in argv
    assert "--workers" not in argv
    out = tmp_path / "again.npz"
    assert main([*argv[1:], "--out", str(out), "--workers", "2", "--chunk-size", "3"]) == 0
    line = capsys.readouterr().out.strip()
    assert line.startswith(f"wrote {out}: 20 worlds x 42 edges (")
    assert "7 chunks (0 resumed)" in line
    assert "on 2 local worker(s)" in line
    assert out.read_bytes() == built.read_bytes()


def test_parser_glue_and_spec_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    parser = argparse.ArgumentParser(prog="drd")
    sub = parser.add_subparsers(dest="command", required=True)
    add_build_dataset_parser(sub)
    spec = tmp_path / "spec.json"
    spec.write_text(json.dumps({"size": 3, "block_probability": 0.1}))
    out = tmp_path / "g3.npz"
    args = parser.parse_args(
        ["build-dataset", *GRID, *SMALL, "--domain-spec", str(spec), "--out", str(out), "--no-trajectories"]
    )
    assert args.func is cmd_build_dataset
    assert cmd_build_dataset(args) == 0
    ds = load_dataset(out)
    assert ds.domain_spec == {"size": 3, "block_probability": 0.1, "delay_s": 0.0}
    assert ds.graph.num_vertices == 9
    assert ds.edge_trajectories is None
    # The recorded command recreates the same bytes, trajectories left out included.
    again = tmp_path / "again.npz"
    argv = shlex.split(ds.provenance["command"])[1:]
    assert cmd_build_dataset(parser.parse_args([*argv, "--out", str(again)])) == 0
    assert again.read_bytes() == out.read_bytes()


def test_max_chunks_stops_and_the_same_command_resumes(
    built: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "grid.npz"
    argv = ["build-dataset", *GRID, *SMALL, "--out", str(out)]
    assert main([*argv, "--max-chunks", "2"]) == 0
    assert "stopped after 2 new chunk(s): 2/4 done" in capsys.readouterr().out
    assert not out.exists()
    assert main(argv) == 0
    assert "4 chunks (2 resumed)" in capsys.readouterr().out
    assert out.read_bytes() == built.read_bytes()


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--domain", "atlantis"], "unknown domain 'atlantis'; known: arm, helicopter, planar, se2"),
        (
            ["--world-model", "moon"],
            "unknown world model 'moon' for domain 'grid_test'; choose one of: uniform, wall",
        ),
        (["--domain-spec", "{bad json"], "--domain-spec: the inline JSON is not valid JSON"),
        (["--domain-spec", "no/such/file.json"], "is neither a JSON object nor an existing file"),
        (["--domain-spec", '{"size": "big"}'], "domain 'grid_test' cannot be built from its spec"),
        (["--domain-factory", "nowhere:Domain"], "domain factory 'nowhere:Domain' cannot be imported"),
    ],
)
def test_user_errors_exit_2_with_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], extra: list[str], message: str
) -> None:
    argv = ["build-dataset", *GRID, *SMALL, "--out", str(tmp_path / "x.npz"), *extra]
    if extra[0] == "--domain":
        argv.remove("--domain-factory")
        argv.remove(GRID_FACTORY)
    assert main(argv) == 2
    assert message in _one_error_line(capsys.readouterr().err)
    assert not (tmp_path / "x.npz").exists()


@pytest.mark.parametrize(
    ("option", "value", "message"),
    [
        ("--worlds", "0", "must be at least 1"),
        ("--worlds", "many", "'many' is not an integer"),
        ("--seed", "-1", "must be non-negative"),
        ("--chunk-size", "0", "must be at least 1"),
        ("--workers", "0", "must be at least 1"),
        ("--test-fraction", "1.5", r"must lie in [0, 1]"),
        ("--max-paths", "x", "'x' is not an integer"),
    ],
)
def test_bad_numbers_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], option: str, value: str, message: str
) -> None:
    argv = ["build-dataset", *GRID, *SMALL, "--out", str(tmp_path / "x.npz"), option, value]
    with pytest.raises(SystemExit) as info:
        main(argv)
    assert info.value.code == 2
    assert message in capsys.readouterr().err


def test_domain_spec_parsing(tmp_path: Path) -> None:
    assert parse_domain_spec(None) is None
    assert parse_domain_spec(' {"a": [1, 2]}') == {"a": [1, 2]}
    listed = tmp_path / "list.json"
    listed.write_text("[1, 2]")
    with pytest.raises(DatasetError, match="must hold a JSON object, not list"):
        parse_domain_spec(str(listed))


# --------------------------------------------------------------------------------------------------
# drd bench --dataset FILE


def test_dataset_source_gives_the_problem(built: Path) -> None:
    problem = ProblemSource(dataset=str(built)).load()
    ds = load_dataset(built)
    worlds = problem.require_worlds()
    assert problem.name == "grid"
    assert problem_domain(problem) == "grid_test"
    assert np.array_equal(worlds.X, ds.X)
    assert np.array_equal(worlds.test_ids, ds.test_ids)


def test_gccd_source_still_works() -> None:
    from conftest import gccd_folder

    folder = gccd_folder("dataset_2d_1")
    problem = ProblemSource(gccd=str(folder)).load()
    assert problem.name == "dataset_2d_1"
    assert problem_domain(problem) == "gccd"


def test_source_needs_exactly_one_of_gccd_and_dataset(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    for argv in ([], ["--gccd", "a", "--dataset", "b"]):
        with pytest.raises(SystemExit) as info:
            drd(["bench", *argv])
        assert info.value.code == 2
    with pytest.raises(DatasetError, match="dataset file not found"):
        ProblemSource(dataset=str(tmp_path / "none.npz")).load()
    with pytest.raises(DatasetError, match="give a dataset"):
        ProblemSource().load()


# --------------------------------------------------------------------------------------------------
# A registered domain, once it exists


def test_build_dataset_on_planar(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    try:
        planar = domain_from_spec("planar")
    except DrdError as exc:
        pytest.skip(f"planar domain not available yet: {exc}")
    model = planar.world_models[0]
    out = tmp_path / "planar.npz"
    argv = ["build-dataset", "--domain", "planar", "--world-model", model, "--worlds", "12", "--seed", "1"]
    assert main([*argv, "--workers", "1", "--chunk-size", "4", "--out", str(out)]) == 0
    ds = load_dataset(out)
    assert ds.X.shape == (12, planar.graph.num_edges)
    assert ds.domain == "planar"
    assert ds.world_model == model
    assert ds.check_metadata == json.loads(json.dumps(planar.check_metadata()))


# --------------------------------------------------------------------------------------------------
# --print-spec, and the arguments a build needs


def test_print_spec_needs_only_the_domain(capsys: pytest.CaptureFixture[str]) -> None:
    from drd_planner.domains.spec_docs import spec_help

    assert main(["build-dataset", "--domain", "planar", "--print-spec"]) == 0
    printed = capsys.readouterr().out
    assert printed == spec_help("planar") + "\n"
    assert "planar" in printed
    assert main(["build-dataset", "--domain", "atlantis", "--print-spec"]) == 2
    assert "unknown domain 'atlantis'" in _one_error_line(capsys.readouterr().err)


def test_a_build_still_needs_its_arguments(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as info:
        main(["build-dataset", "--domain", "planar", "--world-model", "forest", "--worlds", "3"])
    assert info.value.code == 2
    err = capsys.readouterr().err
    assert err.startswith("usage: drd build-dataset")
    assert "the following arguments are required: --seed, --out" in err
    with pytest.raises(SystemExit):
        main(["build-dataset", "--print-spec"])
    assert "the following arguments are required: --domain" in capsys.readouterr().err


def test_a_namespace_not_made_by_the_parser_gets_a_dataset_error(tmp_path: Path) -> None:
    args = argparse.Namespace(
        domain="planar", print_spec=False, world_model=None, worlds=None, seed=0, out=str(tmp_path / "x.npz")
    )
    with pytest.raises(DatasetError, match="required: --world-model, --worlds"):
        cmd_build_dataset(args)
