"""The prior files parameter: ``prior_paths``, its deprecated alias ``tree_paths``, and how both are shown."""

from __future__ import annotations

import importlib.util
from pathlib import Path
from types import ModuleType

import pytest

pytest.importorskip("rcl_interfaces", reason="rcl_interfaces (ROS or the PyPI wheels) not installed")

from drd_planner.ros.parameters import PARAMETERS, parameter_problems, prior_paths_of
from drd_planner.ros.planner_node import usage

DOCS_EXT = Path(__file__).resolve().parents[2] / "docs" / "_ext" / "drd_parameters.py"


def _docs_extension() -> ModuleType:
    pytest.importorskip("sphinx", reason="sphinx (the docs' requirements) not installed")
    spec = importlib.util.spec_from_file_location("drd_parameters_ext", DOCS_EXT)
    assert spec is not None
    assert spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_prior_paths_is_read_and_nothing_is_deprecated() -> None:
    names, warning = prior_paths_of({"prior_paths": ["heli_wires", "", "/a/b.npz"], "tree_paths": [""]})
    assert names == ["heli_wires", "/a/b.npz"]
    assert warning is None


def test_tree_paths_is_read_while_prior_paths_is_at_its_default_with_a_warning_naming_prior_paths() -> None:
    names, warning = prior_paths_of({"prior_paths": [""], "tree_paths": ["heli_lines"]})
    assert names == ["heli_lines"]
    assert warning is not None
    assert "tree_paths is deprecated" in warning
    assert "use prior_paths" in warning


def test_both_set_is_one_error_naming_both() -> None:
    with pytest.raises(ValueError, match="prior_paths and tree_paths are both set"):
        prior_paths_of({"prior_paths": ["heli_wires"], "tree_paths": ["heli_lines"]})


def test_neither_set_names_no_file_and_warns_nothing() -> None:
    assert prior_paths_of({"prior_paths": [""], "tree_paths": [""]}) == ([], None)
    assert prior_paths_of({}) == ([], None)


def test_both_names_are_checked_alike() -> None:
    too_many = [f"p{k}" for k in range(65)]
    problems = parameter_problems({"prior_paths": too_many, "tree_paths": too_many})
    assert problems == [
        "prior_paths names at most 64 prior files of at most 4096 characters each",
        "tree_paths names at most 64 prior files of at most 4096 characters each",
    ]


def test_the_alias_is_declared_with_the_same_default_and_marked_deprecated() -> None:
    specs = {spec.name: spec for spec in PARAMETERS}
    assert specs["tree_paths"].deprecated_for == "prior_paths"
    assert specs["tree_paths"].default == specs["prior_paths"].default
    assert [spec.name for spec in PARAMETERS if spec.deprecated_for is not None] == ["tree_paths"]
    assert specs["tree_paths"].descriptor().description.startswith("Deprecated: use prior_paths. Alias")
    assert specs["prior_paths"].descriptor().description == specs["prior_paths"].description


def test_help_marks_the_alias_deprecated() -> None:
    lines = usage().splitlines()
    (alias,) = [k for k, line in enumerate(lines) if line.strip().startswith("tree_paths ")]
    (new,) = [k for k, line in enumerate(lines) if line.strip().startswith("prior_paths ")]
    assert lines[alias + 1].strip().startswith("Deprecated: use prior_paths.")
    assert "eprecated" not in lines[new] + lines[new + 1]


def test_the_docs_table_lists_the_alias_as_deprecated() -> None:
    rows = {row[0]: row for row in _docs_extension().rows()}
    assert "prior_paths" in rows
    assert "tree_paths" not in rows
    _, kind, default, description = rows["tree_paths (deprecated)"]
    assert (kind, default) == ("string array", "['']")
    assert description.startswith("Deprecated: use prior_paths. Alias of prior_paths")
    assert description.count("Deprecated") == 1
    assert not rows["prior_paths"][3].startswith("Deprecated")
