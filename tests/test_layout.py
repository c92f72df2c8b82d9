"""The package's structure rules (issue 17), checked so that they stay true.

- every module has a test file that mirrors it, or a row of the docs' table (docs/tests.md) names the test file that
  exercises it and says why it has none of its own;
- no module is over 500 lines;
- ``drd_msgs_py`` imports nothing from ``drd_planner`` (no package cycle), ``domains/`` nothing from ``data/``;
- no module imports from a higher floor (:data:`FLOORS`, docs/architecture.md "Floors"), at module level or
  inside a function;
- no code in ``planning/``, ``ros/``, ``planner/``, ``pictures/`` or ``cli/`` asks which concrete domain it holds, and
  ``planning/`` and ``ros/`` ask the domain's capabilities, never an ``is_arm`` flag;
- the product (``core/``, ``planner/``, ``planning/``, ``pictures/``, ``ros/``) imports nothing from ``bench/``;
- ``scripts/`` holds ``run.sh`` and two folders, ``experiments/`` and ``tools/``; no script imports another
  script or edits ``sys.path`` (shared code lives in the ``drd_planner.bench`` package).
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
SRC = REPO / "ros2_ws" / "src"
PACKAGES = {
    "drd_planner": SRC / "drd_planner" / "drd_planner",
    "drd_msgs_py": SRC / "drd_msgs_py" / "drd_msgs_py",
}
MAX_LINES = 500
CONCRETE_DOMAINS = ("ArmDomain", "HelicopterDomain", "Se2Domain", "PlanarDomain")


def _modules() -> list[tuple[str, Path]]:
    """(dotted name, path) of every module of both packages except ``__init__``."""
    found = []
    for package, root in PACKAGES.items():
        for path in sorted(root.rglob("*.py")):
            if path.name != "__init__.py":
                dotted = ".".join((package, *path.relative_to(root).with_suffix("").parts))
                found.append((dotted, path))
    return found


def _mirrored_test(dotted: str) -> list[Path]:
    """The test files that mirror module ``dotted``: ``tests/<sub>/test_<name>.py`` or ``test_<name>_*.py``.

    A ``test_<name>_<more>.py`` that is the exact mirror of another module ``<name>_<more>`` is that module's.
    """
    parts = dotted.split(".")
    folder = REPO / "tests" / ("msgs" if parts[0] == "drd_msgs_py" else "") / Path(*parts[1:-1])
    package_folder = PACKAGES[parts[0]] / Path(*parts[1:-1])
    siblings = {path.stem for path in package_folder.glob("*.py")}
    candidates = [folder / f"test_{parts[-1]}.py", *folder.glob(f"test_{parts[-1]}_*.py")]
    return sorted(
        path
        for path in candidates
        if path.is_file() and (path.stem == f"test_{parts[-1]}" or path.stem.removeprefix("test_") not in siblings)
    )


#: The docs page whose table names the test file of each module without a mirrored one.
TESTS_PAGE = REPO / "docs" / "tests.md"


def _docs_table() -> dict[str, str]:
    """Module -> test file from the docs' table of modules tested through other test files."""
    text = TESTS_PAGE.read_text(encoding="utf-8")
    section = text.split("## Which test exercises which module", 1)[1].split("\n#", 1)[0]
    rows = re.findall(r"^\| `([\w.]+)` \| `(tests/[\w/]+\.py)` \| \S", section, flags=re.MULTILINE)
    return dict(rows)


def _imports(path: Path) -> set[str]:
    """Every module name ``path`` imports (absolute imports, at any depth)."""
    names: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names.add(node.module)
    return names


@pytest.mark.parametrize(("dotted", "path"), _modules(), ids=[d for d, _ in _modules()])
def test_every_module_has_a_test_that_exercises_it(dotted: str, path: Path) -> None:
    if _mirrored_test(dotted):
        return
    table = _docs_table()
    assert dotted in table, f"{dotted} has no tests/.../test_{path.stem}.py and no row in docs/tests.md's table"
    assert (REPO / table[dotted]).is_file(), f"docs/tests.md names {table[dotted]} for {dotted}, which does not exist"


def test_the_docs_table_names_only_modules_without_a_mirrored_test() -> None:
    modules = {dotted for dotted, _ in _modules()}
    table = _docs_table()
    assert table, f'{TESTS_PAGE} has no table of modules under "## Which test exercises which module"'
    for dotted in table:
        assert dotted in modules, f"docs/tests.md's test table names {dotted}, which is not a module"
        assert not _mirrored_test(dotted), f"{dotted} has a mirrored test file; drop its row in docs/tests.md"


@pytest.mark.parametrize(("dotted", "path"), _modules(), ids=[d for d, _ in _modules()])
def test_no_module_is_over_500_lines(dotted: str, path: Path) -> None:
    lines = len(path.read_text(encoding="utf-8").splitlines())
    assert lines <= MAX_LINES, f"{dotted} has {lines} lines; split it by concept"


def test_drd_msgs_py_imports_nothing_from_drd_planner() -> None:
    for path in PACKAGES["drd_msgs_py"].rglob("*.py"):
        bad = sorted(n for n in _imports(path) if n.split(".")[0] == "drd_planner")
        assert not bad, f"{path.relative_to(REPO)} imports {bad}"


def test_domains_import_nothing_from_data() -> None:
    for path in (PACKAGES["drd_planner"] / "domains").rglob("*.py"):
        bad = sorted(n for n in _imports(path) if n.startswith("drd_planner.data"))
        assert not bad, f"{path.relative_to(REPO)} imports {bad}"


def test_the_online_side_never_asks_for_a_concrete_domain() -> None:
    root = PACKAGES["drd_planner"]
    files = [
        *(root / "planning").rglob("*.py"),
        *(root / "ros").rglob("*.py"),
        *(root / "planner").rglob("*.py"),
        *(root / "pictures").rglob("*.py"),
    ]
    for path in [*files, *(root / "cli").rglob("*.py")]:
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            if isinstance(node, ast.Name) and node.id in CONCRETE_DOMAINS:
                pytest.fail(f"{path.relative_to(REPO)}:{node.lineno} names {node.id}; ask the OnlineDomain instead")


@pytest.mark.parametrize("subpackage", ["core", "planner", "planning", "pictures", "ros"])
def test_the_product_imports_nothing_from_the_benchmark_package(subpackage: str) -> None:
    for path in (PACKAGES["drd_planner"] / subpackage).rglob("*.py"):
        bad = sorted(n for n in _imports(path) if n == "drd_planner.bench" or n.startswith("drd_planner.bench."))
        assert not bad, f"{path.relative_to(REPO)} imports {bad}"


SCRIPTS = REPO / "scripts"


def test_scripts_are_experiments_or_tools() -> None:
    assert sorted(p.name for p in SCRIPTS.iterdir()) == ["experiments", "run.sh", "tools"]
    assert (SCRIPTS / "tools" / "make_bags.py").is_file()
    assert sorted((SCRIPTS / "experiments").glob("bench_*.py"))


def test_no_script_imports_another_or_edits_sys_path() -> None:
    scripts = sorted(SCRIPTS.rglob("*.py"))
    names = {path.stem for path in scripts}
    for path in scripts:
        text = path.read_text(encoding="utf-8")
        others = sorted(n.split(".")[0] for n in _imports(path) if n.split(".")[0] in names)
        assert not others, f"{path.relative_to(REPO)} imports the scripts {others}; move the code to drd_planner"
        assert "sys.path" not in text, f"{path.relative_to(REPO)} edits sys.path"


def test_planning_and_ros_ask_capabilities_not_is_arm() -> None:
    root = PACKAGES["drd_planner"]
    for path in [*(root / "planning").rglob("*.py"), *(root / "ros").rglob("*.py")]:
        for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), start=1):
            assert not re.search(r"\bis_arm\b", line), (
                f"{path.relative_to(REPO)}:{number} uses is_arm; ask a capability of the domain "
                "(plans_joint_goals, robot_state_topic, publishes_joint_trajectory, needs_robot_description)"
            )


#: The package's floors, lowest first: a module may import from its own floor and the ones below, never above.
#: A name is a top-level module or sub-package of ``drd_planner``; ``drd_planner/__init__.py`` (the public
#: facade) stands above them all.
FLOORS: tuple[frozenset[str], ...] = (
    frozenset({"arrays", "bounded_files", "exceptions", "settings", "progress"}),
    frozenset({"core"}),
    frozenset({"geometry"}),
    frozenset({"domains"}),
    frozenset({"data"}),
    frozenset({"planner"}),
    frozenset({"planning"}),
    frozenset({"pictures"}),
    frozenset({"ros"}),
    frozenset({"bench"}),
    frozenset({"cli"}),
)

#: Upward imports known and not fixed yet: (importer, imported module) -> why. An entry whose importer no
#: longer exists is ignored (the module moved); one whose import is gone must be dropped.
KNOWN_UPWARD: dict[tuple[str, str], str] = {}


def _floor(dotted: str) -> int:
    """The floor of module ``dotted`` of drd_planner (its sub-package or top-level module)."""
    part = dotted.split(".")[1]
    for index, names in enumerate(FLOORS):
        if part in names:
            return index
    raise AssertionError(f"{dotted}: {part} is on no floor; add it to FLOORS and docs/architecture.md")


def _upward_imports() -> list[tuple[str, str, int]]:
    """(importer, imported, line) of every import of a higher floor in drd_planner."""
    found = []
    root = PACKAGES["drd_planner"]
    inits = [
        (".".join(("drd_planner", *p.parent.relative_to(root).parts)), p) for p in sorted(root.glob("*/__init__.py"))
    ]
    for dotted, path in [*_modules(), *inits]:
        if not dotted.startswith("drd_planner."):
            continue
        own = _floor(dotted)
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Import):
                names = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
                names = [node.module]
            else:
                continue
            for name in names:
                if name.startswith("drd_planner.") and _floor(name) > own:
                    found.append((dotted, name, node.lineno))
    return found


def test_every_subpackage_and_module_of_the_package_is_on_a_floor() -> None:
    root = PACKAGES["drd_planner"]
    parts = {p.stem for p in root.glob("*.py") if p.stem != "__init__"} | {
        p.name for p in root.iterdir() if (p / "__init__.py").is_file()
    }
    placed = set().union(*FLOORS)
    assert parts <= placed, f"not on a floor: {sorted(parts - placed)}; add them to FLOORS and the docs"
    assert not placed - parts, f"FLOORS names what does not exist: {sorted(placed - parts)}"


def test_no_module_imports_from_a_higher_floor() -> None:
    upward = _upward_imports()
    new = [
        f"{importer} (line {line}) imports {name}: floor {_floor(importer)} -> {_floor(name)}"
        for importer, name, line in upward
        if (importer, name) not in KNOWN_UPWARD
    ]
    assert not new, "upward imports (move the helper down, or take it as a parameter):\n" + "\n".join(new)
    modules = {dotted for dotted, _ in _modules()}
    seen = {(importer, name) for importer, name, _ in upward}
    stale = [key for key in KNOWN_UPWARD if key[0] in modules and key not in seen]
    assert not stale, f"KNOWN_UPWARD entries no longer imported; drop them: {stale}"
