"""Every spec key of every registered domain with its default, unit and meaning, read from the docstrings.

The single source is the parameter dataclasses themselves: each documents its fields in the ``Attributes:``
section of its docstring (inherited entries are found along the class's MRO), one entry per field, for example
``resolution: max joint step between edge samples (rad), finite and > 0.``

The *unit* of an entry is the first parenthesised group whose whole text is a unit of :data:`UNITS`
(``(rad)`` above; a group such as ``(D,)`` or ``(100, 150 or 200)`` is not a unit and is skipped); the
*meaning* is the entry's text without that group. Defaults are the domain's default spec (its parameter
class built with no arguments, then ``to_spec()``), so they cannot drift either.

Keys are dotted paths: a field holding a parameter record is walked into (``lattice.xy_spacing``), a field
holding a mapping of records is walked into per name (``models.wires.bumps``), and so is a list of records
(``models.corridors.nofly[].center``). Which class holds a domain's parameters: the domain class itself when
it is a :class:`~drd_planner.domains.params.SpecParams` dataclass, else the return type of its ``params``
property.
"""

from __future__ import annotations

import dataclasses
import inspect
import json
import re
import typing
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from drd_planner.domains.base import DOMAIN_CLASSES
from drd_planner.domains.params import SpecParams
from drd_planner.exceptions import ProblemError

__all__ = [
    "UNITS",
    "SpecEntry",
    "attribute_docs",
    "params_class",
    "plain_text",
    "spec_entries",
    "spec_help",
]

#: The units an ``Attributes:`` entry may name in parentheses, with what each means.
UNITS: Mapping[str, str] = {
    "m": "metres",
    "unit square": "lengths in the side of the unit-square world (dimensionless)",
    "rad": "radians",
    "deg": "degrees",
    "s": "seconds",
    "cells": "lattice grid cells",
    "count": "a whole number of things",
    "seed": "an integer seed of a random generator",
    "index": "a position in a list (0 first)",
    "ratio": "a dimensionless number",
    "fraction": "a dimensionless number in [0, 1]",
    "flag": "true or false",
    "name": "one of the named choices",
    "file": "a file path (null: the default file)",
}

_PAREN = re.compile(r"\s*\(([^()]*)\)")
_ENTRY = re.compile(r"^(\w+)\s*:\s*(.*)$")


@dataclass(frozen=True)
class SpecEntry:
    """One spec key.

    Attributes:
        key: dotted path of the key in the spec (``"lattice.xy_spacing"``, ``"models.wires.bumps"``).
        default: its default value (JSON types: numbers, strings, lists, null).
        unit: a key of :data:`UNITS`, or ``""`` when its docstring entry names none.
        meaning: the docstring entry without the unit (``""`` when the field has no entry).
    """

    key: str
    default: Any
    unit: str
    meaning: str


def _attributes_section(doc: str) -> dict[str, str]:
    """``name -> text`` of the ``Attributes:`` section of a cleaned docstring (continuation lines joined)."""
    out: dict[str, str] = {}
    lines = doc.splitlines()
    try:
        start = next(i for i, line in enumerate(lines) if line.strip() == "Attributes:")
    except StopIteration:
        return out
    indent = len(lines[start]) - len(lines[start].lstrip())
    entry_indent: int | None = None
    current = ""
    for line in lines[start + 1 :]:
        depth = len(line) - len(line.lstrip())
        if line.strip() and depth <= indent:
            break  # the next section
        if not line.strip():
            continue
        entry_indent = depth if entry_indent is None else entry_indent
        match = _ENTRY.match(line.strip())
        if depth == entry_indent and match:
            current = match.group(1)
            out[current] = match.group(2)
        elif current:
            out[current] += " " + line.strip()
    return out


def attribute_docs(cls: type[Any]) -> dict[str, str]:
    """Field name -> its ``Attributes:`` entry, from ``cls`` and its bases (the nearest class wins)."""
    out: dict[str, str] = {}
    for klass in reversed(cls.__mro__):
        out.update(_attributes_section(inspect.cleandoc(klass.__dict__.get("__doc__") or "")))
    return out


_ROLE = re.compile(r":\w+:`(~?)([^`]*)`")


def _role_text(match: re.Match[str]) -> str:
    """A cross-reference's text: the last dotted part after ``~``, else the whole target."""
    return match.group(2).rsplit(".", 1)[-1] if match.group(1) else match.group(2)


def plain_text(text: str) -> str:
    """Docstring markup as plain text: ``:class:`~a.b.C``` -> ``C``, double backquotes dropped."""
    return _ROLE.sub(_role_text, text).replace("``", "")


def _unit_and_meaning(text: str) -> tuple[str, str]:
    """The first parenthesised unit of an entry and the entry without it (as plain text)."""
    for match in _PAREN.finditer(text):
        if match.group(1).strip() in UNITS:
            meaning = (text[: match.start()] + text[match.end() :]).strip()
            return match.group(1).strip(), plain_text(meaning)
    return "", plain_text(text.strip())


def params_class(name: str) -> type[SpecParams]:
    """The parameter dataclass of registered domain ``name``.

    Raises:
        ProblemError: an unknown domain (the registered ones named), or one whose parameters cannot be found.
    """
    if name not in DOMAIN_CLASSES:
        raise ProblemError(f"unknown domain {name!r}; choose one of {DOMAIN_CLASSES.choices()}")
    domain: type[Any] = DOMAIN_CLASSES[name]
    cls: Any = domain
    if not issubclass(domain, SpecParams):
        prop = getattr(domain, "params", None)
        getter = prop.fget if isinstance(prop, property) else None
        cls = typing.get_type_hints(getter).get("return") if getter is not None else None
    if not (isinstance(cls, type) and issubclass(cls, SpecParams) and dataclasses.is_dataclass(cls)):
        raise ProblemError(
            f"domain {name!r} has no parameter dataclass: make the domain class a SpecParams dataclass or "
            "give it a ``params`` property returning one"
        )
    return cls


def _is_record(value: Any) -> bool:
    return dataclasses.is_dataclass(value) and not isinstance(value, type)


@dataclass(frozen=True)
class _Group:
    """A key holding records (a record, a mapping of records, a list of records) and its meaning."""

    key: str
    meaning: str


def _walk(record: Any, spec: Mapping[str, Any], prefix: str) -> Iterator[SpecEntry | _Group]:
    """The entries of one parameter record (instance) and its JSON spec, nested records walked into.

    A list of records is documented by its first record (keys ``key[].field``, defaults of that record).
    """
    docs = attribute_docs(type(record))
    for key, default in spec.items():
        value = getattr(record, key)
        path = f"{prefix}{key}"
        unit, meaning = _unit_and_meaning(docs.get(key, ""))
        if _is_record(value):
            yield _Group(path, meaning)
            yield from _walk(value, default, f"{path}.")
        elif isinstance(value, Mapping) and value and all(_is_record(v) for v in value.values()):
            yield _Group(path, meaning)
            for name, item in value.items():
                yield from _walk(item, default[name], f"{path}.{name}.")
        elif isinstance(value, Sequence) and value and all(_is_record(v) for v in value):
            yield _Group(f"{path}[]", f"{meaning} (default: {len(value)} items; the first one's values shown)")
            yield from _walk(value[0], default[0], f"{path}[].")
        else:
            yield SpecEntry(path, default, unit, meaning)


def _walk_domain(name: str) -> list[SpecEntry | _Group]:
    params = params_class(name)()
    return list(_walk(params, params.to_spec(), ""))


def spec_entries(name: str) -> list[SpecEntry]:
    """Every key of domain ``name``'s spec (leaves, dotted paths) in spec order, with default, unit, meaning.

    Raises:
        ProblemError: an unknown domain (the registered ones named).
    """
    return [item for item in _walk_domain(name) if isinstance(item, SpecEntry)]


def spec_help(name: str) -> str:
    """Every spec key of domain ``name`` as text: ``key = default [unit] meaning``, one key a line.

    Keys holding records get a heading line with their meaning. An undocumented key shows ``[?]``.

    Raises:
        ProblemError: an unknown domain (the registered ones named).
    """
    items = _walk_domain(name)
    entries = [item for item in items if isinstance(item, SpecEntry)]
    width = max(len(e.key) for e in entries)
    units = sorted({e.unit for e in entries if e.unit})
    lines = [f"{name} domain spec: a JSON object for --domain-spec; a missing key takes its default."]
    nested = next((e.key for e in entries if "." in e.key and "[]" not in e.key), None)
    if nested is not None:
        parts = nested.split(".")
        example = "".join(f'{{"{part}": ' for part in parts) + "..." + "}" * len(parts)
        lines.append(f"Nested keys are nested objects: {nested} is {example}.")
    lines.append("Units: " + "; ".join(f"{u} = {UNITS[u]}" for u in units))
    for item in items:
        if isinstance(item, _Group):
            lines.append(f"{item.key}: {item.meaning}")
            continue
        unit = f"[{item.unit}]" if item.unit else "[?]"
        lines.append(f"  {item.key:<{width}} = {json.dumps(item.default)}  {unit}  {item.meaning or '(undocumented)'}")
    return "\n".join(lines) + "\n"
