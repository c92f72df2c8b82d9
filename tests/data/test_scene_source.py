"""Tests of ``drd build-dataset --scenes DIR``: MoveIt scenes as worlds, request states as roadmap vertices.

A few MotionBenchMaker scenes and requests are copied from the shared data folder (skipped when absent), and
broken ones are written by the tests. The arm is the small 60-sample roadmap of ``tests/conftest.py``.
"""

from __future__ import annotations

import json
import shlex
import shutil
from pathlib import Path

import numpy as np
import pytest
from conftest import SHARED_DATA

from drd_planner.cli.build_dataset import main
from drd_planner.data.dataset_builder import FILE_WORLD_RULE, build_dataset
from drd_planner.data.dataset_file import load_dataset
from drd_planner.data.dataset_options import ALL_WORLDS, BuildOptions, DatasetRecipe
from drd_planner.data.scene_source import SceneWorlds, request_files, scene_files, spec_defaults
from drd_planner.data.world_sources import FileRecord, SceneFolder
from drd_planner.domains.arm_worlds import world_from_planning_scene
from drd_planner.domains.base import domain_from_spec
from drd_planner.exceptions import DatasetError
from drd_planner.geometry.moveit_request import joint_vector, read_motion_plan_request

MBM = SHARED_DATA / "mbm" / "table_pick_panda"
SMALL_ARM = {"num_samples": 60, "k": 5, "seed": 3}
SPEC = json.dumps(SMALL_ARM)

MESH_SCENE = """world:
  collision_objects:
    - id: Bowl
      meshes: [{triangles: [{vertex_indices: [0, 1, 2]}], vertices: [[0, 0, 0], [1, 0, 0], [0, 1, 0]]}]
      mesh_poses: [{position: [0, 0, 0], orientation: [0, 0, 0, 1]}]
"""


def _copy_scenes(folder: Path, keys: tuple[str, ...] = ("0001", "0002", "0003")) -> Path:
    if not (MBM / "scene0001.yaml").is_file() or not (SHARED_DATA / "panda").is_dir():
        pytest.skip(f"shared MotionBenchMaker scenes {MBM} or the Panda model not present")
    folder.mkdir(parents=True, exist_ok=True)
    for key in keys:
        for kind in ("scene", "request"):
            target = folder / f"{kind}{key}.yaml"
            shutil.copyfile(MBM / f"{kind}{key}.yaml", target)
            target.chmod(0o644)
    return folder


def _build(folder: Path, out: Path, **kwargs: object) -> Path:
    options = {k: kwargs.pop(k) for k in ("workers", "scheduler") if k in kwargs}
    recipe = DatasetRecipe(
        "arm",
        "",
        int(kwargs.pop("num_worlds", ALL_WORLDS)),  # type: ignore[call-overload]
        0,
        domain_spec=dict(SMALL_ARM, **kwargs.pop("spec", {})),  # type: ignore[arg-type]
        source=SceneFolder(str(folder), **kwargs),  # type: ignore[arg-type]
    )
    report = build_dataset(out, recipe, BuildOptions(progress=False, command=recipe.command(), **options))  # type: ignore[arg-type]
    assert report.complete
    return out


@pytest.fixture(scope="module")
def scenes(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return _copy_scenes(tmp_path_factory.mktemp("mbm") / "table_pick")


@pytest.fixture(scope="module")
def built(scenes: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    return _build(scenes, tmp_path_factory.mktemp("built") / "scenes.npz")


@pytest.mark.slow
def test_each_scene_is_checked_as_the_domain_checks_its_own_worlds(scenes: Path, built: Path) -> None:
    ds = load_dataset(built)
    domain = domain_from_spec("arm", ds.domain_spec)
    edges = np.arange(domain.graph.num_edges)
    expected = [domain.checker(world_from_planning_scene(p)).check_many(edges) for p in scene_files(scenes)]
    assert np.array_equal(ds.X, np.array(expected))
    assert ds.world_model == "moveit_scenes"
    assert np.array_equal(ds.world_seeds, [0, 1, 2])
    source = ds.provenance["world_source"]
    assert ds.provenance["world_seed_rule"] == FILE_WORLD_RULE
    assert [r["sha256"] for r in source["scenes"]] == [
        FileRecord.of(scenes / f"scene000{i}.yaml").sha256 for i in (1, 2, 3)
    ]
    assert len(source["requests"]) == 3
    assert source["start_from"] == "request0001.yaml"
    assert ds.domain_spec["floor_z"] is None  # the arm's scene-set default, under the user's spec


@pytest.mark.slow
def test_request_states_become_the_first_vertices(scenes: Path, built: Path) -> None:
    ds = load_dataset(built)
    joints = domain_from_spec("arm", ds.domain_spec).joint_names
    requests = [read_motion_plan_request(scenes / f"request000{i}.yaml") for i in (1, 2, 3)]
    assert requests[0].start is not None
    start = joint_vector(requests[0].start, joints, where="start", allow_extra=True)
    goals = [joint_vector(r.goals[0], joints, where="goal") for r in requests]
    states = ds.graph.vertex_states
    assert states is not None
    assert ds.start == 0
    assert ds.goal == 1
    assert np.array_equal(states[0], start)
    assert np.array_equal(states[1], goals[0])
    # The other requests start where the first does, so only their goals are new: vertices 2 and 3.
    assert np.array_equal(states[2:4], goals[1:])
    assert ds.domain_spec["extra_states"] == [g.tolist() for g in goals[1:]]
    assert ds.provenance["world_source"]["extra_states_added"] == 2


@pytest.mark.slow
def test_the_recorded_command_and_two_workers_give_the_same_bytes(
    built: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = shlex.split(load_dataset(built).provenance["command"])
    assert argv[:6] == ["drd", "build-dataset", "--domain", "arm", "--scenes", argv[5]]
    out = tmp_path / "again.npz"
    assert main([*argv[1:], "--out", str(out), "--workers", "2", "--chunk-size", "2"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith(f"wrote {out}: 3 worlds x ")
    assert "on 2 local worker(s)" in lines[0]
    assert lines[1].startswith("worlds: 3 scene file(s) of ")
    assert "2 added as vertices" in lines[1]
    assert out.read_bytes() == built.read_bytes()


@pytest.mark.slow
def test_a_dask_local_cluster_gives_the_same_bytes(built: Path, scenes: Path, tmp_path: Path) -> None:
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        out = _build(scenes, tmp_path / "dask.npz", scheduler=cluster.scheduler_address)
    assert out.read_bytes() == built.read_bytes()


@pytest.mark.slow
def test_worlds_takes_the_first_scenes_and_their_requests(scenes: Path, tmp_path: Path) -> None:
    used = scene_files(scenes)[:2]
    assert [p.name for p in request_files(scenes, used, scene_files(scenes))] == [
        "request0001.yaml",
        "request0002.yaml",
    ]
    ds = load_dataset(_build(scenes, tmp_path / "two.npz", num_worlds=2))
    assert ds.num_worlds == 2
    assert len(ds.domain_spec["extra_states"]) == 1
    assert "--worlds 2" in ds.provenance["command"]


def _request_state(scenes: Path, key: str, which: str) -> list[float]:
    joints = domain_from_spec("arm", SMALL_ARM).joint_names
    request = read_motion_plan_request(scenes / f"request{key}.yaml")
    state = request.start if which == "start" else request.goals[0]
    assert state is not None
    return joint_vector(state, joints, where=which, allow_extra=True).tolist()


@pytest.mark.slow
def test_no_requests_and_a_start_of_ones_own(scenes: Path, tmp_path: Path) -> None:
    start, goal = _request_state(scenes, "0001", "start"), _request_state(scenes, "0001", "goal")
    spec = {"start": start, "goal": goal}
    plain = load_dataset(_build(scenes, tmp_path / "plain.npz", requests=False, spec=spec))
    assert plain.domain_spec["extra_states"] == []
    assert plain.provenance["world_source"]["requests"] == []
    assert "--no-requests" in plain.provenance["command"]
    own = _request_state(scenes, "0003", "goal")
    ds = load_dataset(_build(scenes, tmp_path / "own.npz", spec={"start": own}))
    assert ds.domain_spec["start"] == own
    assert ds.domain_spec["goal"] == goal
    source = ds.provenance["world_source"]
    assert source["start_from"] == "--domain-spec"
    assert source["goal_from"] == "request0001.yaml"
    # The requests' start is now an extra state; the goal of request0003 is the start, so not repeated.
    assert ds.domain_spec["extra_states"] == [start, _request_state(scenes, "0002", "goal")]


@pytest.mark.slow
def test_a_scene_that_changed_is_refused_in_the_worker(scenes: Path, tmp_path: Path) -> None:
    folder = _copy_scenes(tmp_path / "copy", ("0001",))
    record = FileRecord.of(folder / "scene0001.yaml")
    domain = domain_from_spec("arm", SMALL_ARM)
    assert len(list(SceneWorlds([record]).checkers(domain, [0]))) == 1
    (folder / "scene0001.yaml").write_text((folder / "scene0001.yaml").read_text() + "\n# edited\n")
    with pytest.raises(DatasetError, match=r"scene0001\.yaml changed since the build was planned"):
        list(SceneWorlds([record]).checkers(domain, [0]))


def _refusal(argv: list[str], capsys: pytest.CaptureFixture[str]) -> str:
    assert main(["build-dataset", "--domain", "arm", "--domain-spec", SPEC, "--seed", "0", *argv]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1, err
    assert err.startswith("drd: error: "), err
    return err


def test_a_folder_without_scenes_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    if not (SHARED_DATA / "panda").is_dir():
        pytest.skip("shared Panda model not present")
    err = _refusal(["--scenes", str(tmp_path), "--out", str(tmp_path / "x.npz")], capsys)
    assert f"--scenes {tmp_path}: no scene*.yaml files (MoveIt PlanningScene YAML, one world each)" in err
    err = _refusal(["--scenes", str(tmp_path / "nope"), "--out", str(tmp_path / "x.npz")], capsys)
    assert "nope: not a folder" in err


@pytest.mark.slow
def test_refusals_name_the_file_the_check_and_the_parameter(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    folder = _copy_scenes(tmp_path / "scenes", ("0001", "0002"))
    out = ["--out", str(tmp_path / "x.npz")]
    err = _refusal(["--scenes", str(folder), "--worlds", "3", *out], capsys)
    assert f"--worlds 3: {folder} has only 2 scene file(s)" in err
    (folder / "scene0003.yaml").write_text(MESH_SCENE)
    err = _refusal(["--scenes", str(folder), *out], capsys)
    assert "scene0003.yaml: collision object 'Bowl' has meshes" in err
    assert "--worlds N" in err
    (folder / "scene0003.yaml").unlink()
    request = folder / "request0002.yaml"
    request.write_text(request.read_text().replace("panda_joint7", "wrist_roll"))
    err = _refusal(["--scenes", str(folder), *out], capsys)
    assert "request0002.yaml: start_state.joint_state lacks joints ['panda_joint7']" in err
    assert "--no-requests" in err
    assert not (tmp_path / "x.npz").exists()


def test_argument_combinations_are_argparse_errors(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    base = ["build-dataset", "--domain", "arm", "--seed", "0", "--out", str(tmp_path / "x.npz")]
    cases = [
        (["--scenes", "d", "--world-model", "clutter"], "--world-model: not allowed with --scenes"),
        (["--scenes", "d", "--frame", "map"], "--frame goes with --bags"),
        (["--bags", "a.mcap", "--no-requests"], "--no-requests goes with --scenes"),
        (["--scenes", "d", "--crop", "as-is"], "--crop goes with --terrain"),
        (["--world-model", "clutter"], "the following arguments are required: --worlds"),
        ([], "required: --world-model, --worlds (or worlds from files: --scenes, --bags, --terrain or --site-file)"),
        (["--scenes", "d", "--bags", "b"], "not allowed with argument --scenes"),
    ]
    for extra, message in cases:
        with pytest.raises(SystemExit) as info:
            main([*base, *extra])
        assert info.value.code == 2
        assert message in capsys.readouterr().err, extra
    with pytest.raises(SystemExit):
        main(["build-dataset", "--domain", "arm", "--scenes", "d"])
    assert "the following arguments are required: --seed, --out" in capsys.readouterr().err


def test_scene_files_sort_by_name_and_pair_their_requests(tmp_path: Path) -> None:
    for name in ("scene10.yaml", "scene02.yaml", "request02.yaml", "request10.yaml", "request99.yaml"):
        (tmp_path / name).write_text("{}")
    (tmp_path / "notes.yaml").write_text("{}")
    scenes = scene_files(tmp_path)
    assert [p.name for p in scenes] == ["scene02.yaml", "scene10.yaml"]
    paired = request_files(tmp_path, scenes[:1], scenes)
    assert [p.name for p in paired] == ["request02.yaml", "request99.yaml"]  # request99 has no scene: kept


def test_scene_spec_defaults_come_from_the_domains_parameters() -> None:
    assert spec_defaults(SceneFolder("/s"), "arm") == {"floor_z": None}
    assert spec_defaults(SceneFolder("/s"), "helicopter") == {}
    assert spec_defaults(SceneFolder("/s"), "grid_test") == {}  # not registered: no defaults


@pytest.mark.parametrize(
    ("content", "fragment"),
    [
        ("bomb", "aliases"),
        ("deep", "nested deeper than"),
        ("sparse", "bytes; at most"),
    ],
)
def test_hostile_scene_files_end_the_build_at_once_with_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], content: str, fragment: str
) -> None:
    """Issue 33 items 1-3: an alias bomb hung the build, deep nesting and a huge file ended in tracebacks."""
    import time

    folder = tmp_path / "hostile"
    folder.mkdir()
    scene = folder / "scene0001.yaml"
    if content == "bomb":
        lines = ['a0: &a0 ["xxxxxxxxxxxxxxxxxxxxxxxxxxxxxxx"]']
        lines += [f"a{k}: &a{k} [{', '.join([f'*a{k - 1}'] * 9)}]" for k in range(1, 10)]
        scene.write_text("\n".join(lines) + "\nworld: {collision_objects: [{id: *a9, primitives: []}]}\n")
    elif content == "deep":
        scene.write_text("world: " + "[" * 100_000 + "]" * 100_000 + "\n")
    else:
        sparse = tmp_path / "sparse.bin"
        with sparse.open("wb") as handle:
            handle.truncate(3 << 30)
        scene.symlink_to(sparse)
    t0 = time.perf_counter()
    err = _refusal(["--scenes", str(folder), "--out", str(tmp_path / "d.npz")], capsys)
    assert time.perf_counter() - t0 < 30.0
    assert fragment in err, err
    assert len(err) < 600, err
