"""``colcon build`` of both ament_python packages, as a ROS user (or the Docker image) runs it.

colcon comes from PyPI (``colcon-common-extensions`` in requirements-dev.txt); no ROS install is needed
for pure-Python packages. The build, install and log folders live under a temporary folder, and the
source tree is left as it was.
"""

from __future__ import annotations

import ast
import importlib.util
import os
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest

pytestmark = pytest.mark.slow  # nodes in child processes; several seconds each

REPO = Path(__file__).resolve().parents[1]
SRC = REPO / "ros2_ws" / "src"
PACKAGES = ("drd_msgs_py", "drd_planner")


def _colcon() -> list[str]:
    """The colcon command, run by this interpreter when it has colcon (console scripts use it)."""
    if importlib.util.find_spec("colcon_core") is not None:
        return [sys.executable, "-m", "colcon"]
    found = shutil.which("colcon")
    if found is None:
        pytest.skip("colcon not installed (pip install -r requirements-dev.txt: colcon-common-extensions)")
    return [found]


def _source_files() -> dict[str, float]:
    """Every file under the package sources with its modification time (build leftovers would show)."""
    return {
        str(p.relative_to(SRC)): p.stat().st_mtime
        for p in SRC.rglob("*")
        if p.is_file() and "__pycache__" not in p.parts and ".mypy_cache" not in p.parts
    }


@pytest.fixture(scope="module")
def install(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The install folder of one ``colcon build`` of the workspace (about 3 s)."""
    command = _colcon()
    base = tmp_path_factory.mktemp("colcon")
    before = _source_files()
    started = time.perf_counter()
    done = subprocess.run(
        [
            *command,
            "--log-base",
            str(base / "log"),
            "build",
            "--base-paths",
            str(SRC),
            "--build-base",
            str(base / "build"),
            "--install-base",
            str(base / "install"),
            "--event-handlers",
            "console_direct-",
            "console_cohesion+",
        ],
        cwd=base,
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    seconds = time.perf_counter() - started
    assert done.returncode == 0, f"colcon build failed:\n{done.stdout}\n{done.stderr}"
    for package in PACKAGES:
        assert f"Finished <<< {package}" in done.stdout, done.stdout
    assert "2 packages finished" in done.stdout, done.stdout
    # Only files of other engineers' ongoing edits may change meanwhile; the build itself adds nothing.
    added = sorted(set(_source_files()) - set(before))
    assert not [a for a in added if ".egg-info" in a or a.startswith(("build", "install"))], added
    print(f"colcon build: {seconds:.1f} s")
    return base / "install"


def test_both_packages_are_installed_with_their_manifests_and_index_entries(install: Path) -> None:
    for package in PACKAGES:
        share = install / package / "share"
        assert (share / package / "package.xml").read_text() == (SRC / package / "package.xml").read_text()
        assert (share / "ament_index" / "resource_index" / "packages" / package).is_file()
        site = list((install / package / "lib").glob(f"python3*/site-packages/{package}/__init__.py"))
        assert len(site) == 1, f"{package} not installed as a Python package: {site}"


def test_console_scripts_are_installed_where_ros2_run_finds_them_and_run(install: Path) -> None:
    bin_dir = install / "drd_planner" / "lib" / "drd_planner"
    for script in ("drd", "planner_node"):
        path = bin_dir / script
        assert path.is_file(), f"{path} missing or not executable"
        assert os.access(path, os.X_OK), f"{path} missing or not executable"
        # Entry points run with the interpreter that ran colcon (the venv in the Docker image).
        assert path.read_text().splitlines()[0].startswith("#!")
    # The installed `drd` runs, and imports the installed copies of both packages.
    site = [str(p.parent.parent) for p in install.glob("*/lib/python3*/site-packages/*/__init__.py")]
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([*site, os.environ.get("PYTHONPATH", "")])}
    shebang = (bin_dir / "drd").read_text().splitlines()[0][2:].strip()
    done = subprocess.run(
        [shebang, str(bin_dir / "drd"), "--help"], capture_output=True, text=True, env=env, check=False
    )
    assert done.returncode == 0, done.stderr
    assert "usage" in done.stdout.lower(), done.stderr
    where = subprocess.run(
        [shebang, "-c", "import drd_planner, drd_msgs_py; print(drd_planner.__file__, drd_msgs_py.__file__)"],
        capture_output=True,
        text=True,
        env=env,
        check=True,
    ).stdout.split()
    assert all(Path(w).resolve().is_relative_to(install.resolve()) for w in where), where


def test_launch_file_and_config_files_are_installed(install: Path) -> None:
    share = install / "drd_planner" / "share" / "drd_planner"
    assert (share / "launch" / "planner.launch.py").read_text() == (
        SRC / "drd_planner" / "launch" / "planner.launch.py"
    ).read_text()
    configs = sorted(p.name for p in (SRC / "drd_planner" / "config").glob("*.yaml"))
    assert {"heli_wires.yaml", "arm_table_clutter.yaml"} <= set(configs)
    assert sorted(p.name for p in (share / "config").glob("*.yaml")) == configs


def test_shipped_trees_are_installed_for_bare_tree_names(install: Path) -> None:
    """``prior_paths: ["heli_wires"]`` resolves in share/drd_planner/trees of an installed package."""
    trees = sorted(p.name for p in (REPO / "trees").glob("*.npz"))
    assert trees, "no shipped trees"
    installed = install / "drd_planner" / "share" / "drd_planner" / "trees"
    assert sorted(p.name for p in installed.glob("*.npz")) == trees


def test_license_is_installed_with_the_manifest(install: Path) -> None:
    installed = install / "drd_planner" / "share" / "drd_planner" / "LICENSE"
    assert installed.read_text() == (REPO / "LICENSE").read_text()


# ------------------------------------------------------------------------------------------------------
# The manifests (no colcon needed)


def test_license_file_matches_the_manifests() -> None:
    text = (REPO / "LICENSE").read_text()
    assert text.startswith("BSD 3-Clause License\n\nCopyright (c) 2026, The drd_planner authors\n")
    assert "Neither the name of the copyright holder nor the names of its" in text
    for package in PACKAGES:
        assert "<license>BSD-3-Clause</license>" in (SRC / package / "package.xml").read_text()
        assert 'license="BSD-3-Clause"' in (SRC / package / "setup.py").read_text()


#: Import name -> rosdep key of the Python libraries the manifests declare.
ROSDEP_KEY = {
    "numpy": "python3-numpy",
    "scipy": "python3-scipy",
    "networkx": "python3-networkx",
    "tqdm": "python3-tqdm",
    "yaml": "python3-yaml",
    "typing_extensions": "python3-typing-extensions",
    "matplotlib": "python3-matplotlib",
    "trimesh": "python3-trimesh-pip",
}
#: Imports without a rosdep key: setup.py's install_requires / extras (pip; the Docker image's venv).
PIP_ONLY = {
    "fcl",
    "rosbags",
    "yourdfpy",
    "dask",
    "distributed",
    "ompl",
    "rasterio",
    "pyproj",
    "shapely",
    "osmium",
    "threadpoolctl",
}


def _imports(folder: Path) -> set[str]:
    """Top-level modules imported, and ROS interface packages named as ``pkg/msg/Type``, under folder."""
    names: set[str] = set()
    for path in folder.rglob("*.py"):
        if path.name == "setup.py":  # the build, not the package
            continue
        text = path.read_text()
        for node in ast.walk(ast.parse(text)):
            if isinstance(node, ast.Import):
                names |= {alias.name.split(".")[0] for alias in node.names}
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                names.add(node.module.split(".")[0])
        names |= set(re.findall(r"[\"']([a-z_]+_(?:msgs|interfaces))/(?:msg|srv)/[A-Z]\w*", text))
    return names - set(sys.stdlib_module_names) - {"__future__"}


def _exec_depends(package: str) -> set[str]:
    return set(re.findall(r"<exec_depend>([^<]+)</exec_depend>", (SRC / package / "package.xml").read_text()))


@pytest.mark.parametrize("package", PACKAGES)
def test_manifest_declares_every_import(package: str) -> None:
    declared = _exec_depends(package)
    other = next(p for p in PACKAGES if p != package)
    for name in sorted(_imports(SRC / package) - {package}):
        if name == other:
            continue  # see test_manifests_have_no_dependency_cycle
        if name in PIP_ONLY:
            continue
        key = ROSDEP_KEY.get(name, name)
        assert key in declared, f"{package}/package.xml: `{name}` is imported but {key} is no exec_depend"


def test_manifests_have_no_dependency_cycle() -> None:
    """colcon refuses a cycle; drd_planner (the node) depends on drd_msgs_py, not the reverse."""
    assert "drd_msgs_py" in _exec_depends("drd_planner")
    assert "drd_planner" not in _exec_depends("drd_msgs_py")
