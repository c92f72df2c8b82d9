"""spec_docs: every spec key of every registered domain has a default, a unit and a meaning from its docstring."""

from __future__ import annotations

import dataclasses
import json
from dataclasses import dataclass
from typing import Any

import pytest

from drd_planner.domains.base import DOMAIN_CLASSES, domain_from_spec
from drd_planner.domains.helicopter_lattice_params import LatticeParams
from drd_planner.domains.helicopter_worlds import WORLD_MODELS
from drd_planner.domains.params import SpecParams, spec_keys
from drd_planner.domains.spec_docs import (
    UNITS,
    attribute_docs,
    params_class,
    plain_text,
    spec_entries,
    spec_help,
)
from drd_planner.exceptions import ProblemError


@pytest.mark.parametrize("name", list(DOMAIN_CLASSES))
def test_every_spec_key_has_a_unit_and_a_meaning(name: str) -> None:
    entries = spec_entries(name)
    missing = [e.key for e in entries if not e.meaning or e.unit not in UNITS]
    assert not missing, (
        f"{name} spec keys without an 'Attributes:' entry naming a unit in parentheses (one of "
        f"{', '.join(UNITS)}): {missing}; document them in the parameter dataclass's docstring"
    )


@pytest.mark.parametrize("name", list(DOMAIN_CLASSES))
def test_entries_cover_every_top_level_key_and_rebuild_the_default_spec(name: str) -> None:
    entries = spec_entries(name)
    cls = params_class(name)
    tops = {e.key.split(".")[0].split("[")[0] for e in entries}
    assert tops == set(spec_keys(cls))
    assert len({e.key for e in entries}) == len(entries)
    # The defaults, put back into a nested spec, are the domain's default spec.
    default = cls().to_spec()
    rebuilt: dict[str, Any] = {}
    for entry in entries:
        if "[]" in entry.key:
            continue
        *parents, last = entry.key.split(".")
        node = rebuilt
        for part in parents:
            node = node.setdefault(part, {})
        node[last] = entry.default
    listed = {e.key.split("[]")[0] for e in entries if "[]" in e.key}
    for path in listed:  # lists of records: documented by their first record; take their defaults whole
        *parents, last = path.split(".")
        source, node = default, rebuilt
        for part in parents:
            source, node = source[part], node.setdefault(part, {})
        node[last] = source[last]
    assert json.dumps(rebuilt, sort_keys=True) == json.dumps(default, sort_keys=True)
    assert cls.from_spec(rebuilt).to_spec() == default


def test_helicopter_nested_keys_are_walked() -> None:
    keys = {e.key for e in spec_entries("helicopter")}
    assert {f"lattice.{f.name}" for f in dataclasses.fields(LatticeParams)} <= keys
    for model in WORLD_MODELS:
        assert f"models.{model}.nofly" in keys
    assert "models.terrain.site" in keys
    assert "vehicle_radius" in keys
    entry = next(e for e in spec_entries("helicopter") if e.key == "lattice.xy_spacing")
    assert entry.unit == "m"
    assert entry.default == 50.0
    assert "grid spacing" in entry.meaning


def test_arm_entries_match_the_params_and_help_lists_every_key() -> None:
    entries = {e.key: e for e in spec_entries("arm")}
    assert entries["floor_z"].unit == "m"
    assert entries["floor_z"].default == 0.0
    assert entries["extra_states"].default == []
    assert entries["extra_states"].unit == "rad"
    assert entries["start"].unit == "rad"  # "(D,)" before it is a shape, not a unit
    assert entries["num_samples"].unit == "count"
    assert "(count)" not in entries["num_samples"].meaning
    text = spec_help("arm")
    for key, entry in entries.items():
        line = next(line for line in text.splitlines() if line.strip().startswith(f"{key} "))
        assert f"= {json.dumps(entry.default)}  [{entry.unit}]  {entry.meaning}" in line
    assert ":data:" not in text
    assert "``" not in text


def test_unknown_domain_names_the_registered_ones() -> None:
    with pytest.raises(ProblemError) as info:
        spec_help("boat")
    for name in DOMAIN_CLASSES:
        assert name in str(info.value)
    with pytest.raises(ProblemError, match="unknown domain 'boat'"):
        domain_from_spec("boat")  # the same names as the domain registry refuses


@dataclass(frozen=True)
class _Base(SpecParams):
    """A record.

    Attributes:
        width: how wide (m), a
            second line.
        label: a label (3 letters) without a unit.

    Raises:
        ProblemError: never.
    """

    width: float = 1.0
    label: str = "abc"


@dataclass(frozen=True)
class _Child(_Base):
    """A record with one more field.

    Attributes:
        angle: (D,) turn (deg).
    """

    angle: float = 0.0
    undocumented: int = 0


def test_attribute_docs_join_lines_follow_the_mro_and_leave_gaps_visible() -> None:
    docs = attribute_docs(_Child)
    assert docs["width"] == "how wide (m), a second line."
    assert docs["angle"] == "(D,) turn (deg)."
    assert docs["label"].startswith("a label")
    assert "undocumented" not in docs
    assert "ProblemError" not in docs
    assert plain_text("see :class:`~a.b.NoFlyZone` and ``x`` or :func:`f`") == "see NoFlyZone and x or f"
