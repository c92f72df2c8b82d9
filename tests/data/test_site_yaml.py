"""Safe YAML reading of site files: size first, no anchors or aliases, bounded nesting, checked keys."""

from __future__ import annotations

from pathlib import Path

import pytest

from drd_planner.data import site_yaml
from drd_planner.data.site_yaml import (
    check_keys,
    get_number,
    get_probability,
    get_range,
    get_section,
    get_string,
    read_yaml_mapping,
)
from drd_planner.exceptions import SiteFileError

BOMB = """\
a: &a ["lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol"]
b: &b [*a, *a, *a, *a, *a, *a, *a, *a, *a]
c: &c [*b, *b, *b, *b, *b, *b, *b, *b, *b]
d: [*c, *c, *c, *c, *c, *c, *c, *c, *c]
"""


def _write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "site.yaml"
    path.write_text(text)
    return path


def test_a_plain_mapping_is_read(tmp_path: Path) -> None:
    data = read_yaml_mapping(_write(tmp_path, "format: drd-site/1\ndem: {path: dem.tif}\n"))
    assert data == {"format": "drd-site/1", "dem": {"path": "dem.tif"}}


def test_a_yaml_bomb_and_any_alias_or_anchor_is_refused(tmp_path: Path) -> None:
    with pytest.raises(SiteFileError, match="anchors and aliases"):
        read_yaml_mapping(_write(tmp_path, BOMB))
    with pytest.raises(SiteFileError, match="anchors and aliases"):
        read_yaml_mapping(_write(tmp_path, "a: &x 1\n"))


def test_python_tags_size_depth_and_non_mappings_are_refused(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    with pytest.raises(SiteFileError, match="is not valid YAML"):
        read_yaml_mapping(_write(tmp_path, "a: !!python/object/apply:os.system ['true']\n"))
    with pytest.raises(SiteFileError, match="must hold a YAML mapping"):
        read_yaml_mapping(_write(tmp_path, "- 1\n- 2\n"))
    with pytest.raises(SiteFileError, match="nested more than"):
        read_yaml_mapping(_write(tmp_path, "a: " + "[" * 50 + "]" * 50 + "\n"))
    with pytest.raises(SiteFileError, match="is not valid YAML"):
        read_yaml_mapping(_write(tmp_path, "a: [1\n"))
    monkeypatch.setattr(site_yaml, "MAX_SITE_BYTES", 10)
    with pytest.raises(SiteFileError, match="at most 10 are read"):
        read_yaml_mapping(_write(tmp_path, "format: drd-site/1\n"))


def test_getters_name_the_key_and_what_it_must_be() -> None:
    data = {"n": 2, "p": 1.5, "r": [3, 1], "s": "EGM96", "b": True, "sec": {"x": 1, "y": 2}}
    assert get_number(data, "n", "origin.") == 2.0
    assert get_number(data, "missing", "origin.", 4.0) == 4.0
    with pytest.raises(SiteFileError, match=r"origin\.missing is required"):
        get_number(data, "missing", "origin.")
    with pytest.raises(SiteFileError, match=r"origin\.b must be a finite number"):
        get_number(data, "b", "origin.")
    with pytest.raises(SiteFileError, match="must be >= 5"):
        get_number(data, "n", "", low=5.0)
    with pytest.raises(SiteFileError, match=r"uncertainty\.p must be a probability"):
        get_probability(data, "p", "uncertainty.", 0.5)
    assert get_range({"r": 3}, "r", "", (0.0, 1.0)) == (3.0, 3.0)
    with pytest.raises(SiteFileError, match=r"r must be \[lo, hi\]"):
        get_range(data, "r", "", (0.0, 1.0))
    with pytest.raises(SiteFileError, match="must be one of 'DEM', 'EGM96'"):
        get_string({"s": "NAVD88"}, "s", "", choices=("DEM", "EGM96"))
    assert get_string(data, "s", "", choices=("DEM", "EGM96")) == "EGM96"
    with pytest.raises(SiteFileError, match=r"sec: unknown key\(s\) \['y'\]; valid keys: x, z"):
        get_section(data, "sec", "", ("x", "z"))
    with pytest.raises(SiteFileError, match="must be a mapping with keys"):
        get_section(data, "n", "", ("x",))
    check_keys({"x": 1}, ("x",), "here")
