"""Reading a site file's YAML safely, and checking its values: the parser side of :mod:`.site_file`.

:func:`read_yaml_mapping` looks at the file's size before it reads it (:data:`MAX_SITE_BYTES`), refuses
anchors and aliases (no "billion laughs" expansion) and deep nesting while scanning the parser's events, and only
then builds plain Python data with ``yaml.safe_load`` (no Python objects). The getters check one value each and
name the key (``dem.path``) and what it must be; :func:`check_keys` names the valid keys of a section.
"""

from __future__ import annotations

import math
from collections.abc import Collection, Mapping
from pathlib import Path
from typing import Any

import yaml

from drd_planner.bounded_files import read_bounded_text
from drd_planner.exceptions import SiteFileError

__all__ = [
    "MAX_SITE_BYTES",
    "MAX_YAML_DEPTH",
    "check_keys",
    "get_number",
    "get_probability",
    "get_range",
    "get_section",
    "get_string",
    "read_yaml_mapping",
]

#: Largest site file read, bytes.
MAX_SITE_BYTES = 256 << 10

#: Deepest nesting of YAML collections in a site file.
MAX_YAML_DEPTH = 12


def read_yaml_mapping(path: Path, what: str = "site file") -> dict[str, Any]:
    """The YAML mapping in the file ``path`` (see the module docstring).

    Raises:
        SiteFileError: missing, too large, not UTF-8, not YAML, with anchors/aliases, nested too deeply, or
            not a mapping at the top.
    """
    text = read_bounded_text(path, MAX_SITE_BYTES, f"{what} {path}", SiteFileError)
    try:
        depth = 0
        for event in yaml.parse(text, Loader=yaml.SafeLoader):
            if isinstance(event, yaml.AliasEvent) or getattr(event, "anchor", None):
                raise SiteFileError(f"{what} {path}: YAML anchors and aliases (&, *) are not allowed")
            if isinstance(event, yaml.CollectionStartEvent):
                depth += 1
                if depth > MAX_YAML_DEPTH:
                    raise SiteFileError(f"{what} {path}: YAML nested more than {MAX_YAML_DEPTH} deep")
            elif isinstance(event, yaml.CollectionEndEvent):
                depth -= 1
        data = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        raise SiteFileError(f"{what} {path} is not valid YAML: {' '.join(str(exc).split())}") from None
    if not isinstance(data, dict):
        raise SiteFileError(f"{what} {path} must hold a YAML mapping (key: value lines), got {type(data).__name__}")
    return data


def check_keys(section: Mapping[str, Any], valid: Collection[str], where: str) -> None:
    """Refuse keys of ``section`` not in ``valid`` (the valid ones named)."""
    unknown = sorted(str(k) for k in section if k not in valid)
    if unknown:
        raise SiteFileError(f"{where}: unknown key(s) {unknown}; valid keys: {', '.join(valid)}")


def get_section(data: Mapping[str, Any], key: str, where: str, valid: Collection[str]) -> dict[str, Any]:
    """The mapping ``data[key]`` (``{}`` when absent), its keys checked against ``valid``."""
    value = data.get(key)
    if value is None:
        return {}
    if not isinstance(value, Mapping):
        raise SiteFileError(f"{where}{key} must be a mapping with keys {', '.join(valid)}, got {value!r:.80}")
    check_keys(value, valid, f"{where}{key}")
    return dict(value)


def get_number(
    data: Mapping[str, Any], key: str, where: str, default: float | None = None, *, low: float | None = None
) -> float:
    """The finite number ``data[key]`` (``default`` when absent; required when the default is None), >= ``low``."""
    value = data.get(key, default)
    if value is None:
        raise SiteFileError(f"{where}{key} is required (a number)")
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise SiteFileError(f"{where}{key} must be a finite number, got {value!r}")
    if low is not None and value < low:
        raise SiteFileError(f"{where}{key} must be >= {low:g}, got {value!r}")
    return float(value)


def get_probability(data: Mapping[str, Any], key: str, where: str, default: float) -> float:
    """The probability ``data[key]`` in [0, 1] (``default`` when absent)."""
    value = get_number(data, key, where, default)
    if not 0.0 <= value <= 1.0:
        raise SiteFileError(f"{where}{key} must be a probability in [0, 1], got {value!r}")
    return value


def get_range(
    data: Mapping[str, Any], key: str, where: str, default: tuple[float, float], *, low: float = 0.0
) -> tuple[float, float]:
    """The range ``data[key]`` = [lo, hi] (or one number for both) with ``low`` <= lo <= hi."""
    value = data.get(key, default)
    if isinstance(value, int | float) and not isinstance(value, bool):
        value = [value, value]
    ok = isinstance(value, list | tuple) and len(value) == 2
    ok = ok and all(isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v) for v in value)
    if not ok or not low <= value[0] <= value[1]:
        raise SiteFileError(f"{where}{key} must be [lo, hi] with {low:g} <= lo <= hi (or one number), got {value!r}")
    return float(value[0]), float(value[1])


def get_string(
    data: Mapping[str, Any], key: str, where: str, default: str | None = None, *, choices: Collection[str] = ()
) -> str:
    """The string ``data[key]`` (``default`` when absent; required when the default is None), one of ``choices``."""
    value = data.get(key, default)
    if value is None:
        raise SiteFileError(f"{where}{key} is required (a string)")
    if not isinstance(value, str) or not value:
        raise SiteFileError(f"{where}{key} must be a non-empty string, got {value!r}")
    if choices and value not in choices:
        raise SiteFileError(f"{where}{key} must be one of {', '.join(map(repr, choices))}, got {value!r}")
    return value
