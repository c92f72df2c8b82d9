"""Build domains by name (or by a "module:attribute" factory) for the dataset builder and its workers.

:func:`make_domain` turns ``(name, spec, factory)`` into a :class:`~drd_planner.domains.base.Domain`;
:class:`DomainFactory` does the same and keeps the last domain it built, so that a worker process that
evaluates many chunks of one build rebuilds the domain once. :func:`factory_for` tells which factory a
worker needs to rebuild a given domain instance, and :func:`world_model_params` reads a world model's
parameters for the dataset file's provenance.
"""

from __future__ import annotations

import dataclasses
import importlib
import json
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from drd_planner.domains.base import DOMAIN_CLASSES, Domain, domain_from_spec
from drd_planner.exceptions import DatasetError, DrdError

__all__ = ["DomainFactory", "factory_for", "make_domain", "world_model_params"]

#: (domain name, canonical spec JSON, factory or None): what identifies a domain a worker rebuilds.
DomainKey = tuple[str, str, str | None]


def make_domain(name: str, spec: Mapping[str, Any] | None = None, *, factory: str | None = None) -> Domain:
    """Build domain ``name`` from ``spec``: from the registry, or from ``factory`` ("module:attribute").

    ``factory`` names a class with a ``from_spec(spec) -> Domain`` classmethod or a callable
    ``(spec) -> Domain``; it lets a domain outside :data:`~drd_planner.domains.base.DOMAIN_CLASSES`
    (a plugin, a test domain) be rebuilt in worker processes.

    Raises:
        DatasetError: unknown name, a factory that cannot be imported, a spec the domain rejects, or a
            factory whose domain has another name.
    """
    spec_dict = dict(spec or {})
    if factory is None:
        if name not in DOMAIN_CLASSES:
            raise DatasetError(f"unknown domain {name!r}; known: {', '.join(sorted(DOMAIN_CLASSES))}")
        build: Callable[[dict[str, Any]], Domain] = lambda s: domain_from_spec(name, s)  # noqa: E731
    else:
        build = _import_factory(factory)
    try:
        domain = build(spec_dict)
    except DatasetError:
        raise
    except (DrdError, TypeError, ValueError, KeyError) as exc:
        raise DatasetError(f"domain {name!r} cannot be built from its spec: {exc}") from exc
    if domain.name != name:
        raise DatasetError(f"domain factory {factory!r} builds domain {domain.name!r}, not {name!r}")
    return domain


def _import_factory(factory: str) -> Callable[[dict[str, Any]], Domain]:
    """The ``from_spec`` (or the callable itself) that ``factory`` ("module:attribute") names."""
    module_name, sep, attr = factory.partition(":")
    if not sep or not module_name or not attr:
        raise DatasetError(f"domain factory must look like 'package.module:Name', got {factory!r}")
    try:
        target = getattr(importlib.import_module(module_name), attr)
    except (ImportError, AttributeError) as exc:
        raise DatasetError(f"domain factory {factory!r} cannot be imported: {exc}") from exc
    build: Callable[[dict[str, Any]], Domain] = getattr(target, "from_spec", target)
    return build


class DomainFactory:
    """Builds domains with :func:`make_domain` and keeps the last one (one build at a time per process).

    Keeping a single domain bounds the memory a long-lived worker (a Dask worker serving many builds)
    spends on domains.
    """

    def __init__(self) -> None:
        self._key: DomainKey | None = None
        self._domain: Domain | None = None

    def domain(self, name: str, spec_json: str, factory: str | None) -> Domain:
        """The domain ``(name, spec_json, factory)``: the kept one when it matches, else a new build."""
        key = (name, spec_json, factory)
        if self._domain is None or self._key != key:
            domain = make_domain(name, json.loads(spec_json), factory=factory)
            self.remember(domain, spec_json, factory)
            return domain
        return self._domain

    def remember(self, domain: Domain, spec_json: str, factory: str | None) -> None:
        """Keep ``domain`` (built from ``spec_json`` and ``factory``) in place of the one kept so far."""
        self._key = (domain.name, spec_json, factory)
        self._domain = domain


def factory_for(domain: Domain, factory: str | None, parallel: bool) -> str | None:
    """The factory workers use to rebuild ``domain`` (None: the registry).

    Raises:
        DatasetError: ``parallel`` and the domain can be rebuilt neither from the registry nor from an
            importable ``from_spec``.
    """
    if factory is not None:
        return factory
    cls = type(domain)
    path = f"{cls.__module__}:{cls.__qualname__}"
    registered = DOMAIN_CLASSES.get(domain.name) if domain.name in DOMAIN_CLASSES else None
    if registered is cls:
        return None
    if hasattr(cls, "from_spec") and "<locals>" not in cls.__qualname__:
        return path
    if parallel:
        raise DatasetError(
            f"domain {domain.name!r} ({path}) is not registered and has no importable from_spec: "
            "worker processes cannot rebuild it; pass domain_factory='module:attribute'"
        )
    return None


def _json_default(obj: Any) -> Any:
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        return dataclasses.asdict(obj)
    if isinstance(obj, np.ndarray | np.generic):
        return obj.tolist()
    if isinstance(obj, Mapping):
        return dict(obj)
    raise TypeError(f"{type(obj).__name__} is not JSON-safe")


def world_model_params(domain: Domain, model: str) -> dict[str, Any]:
    """The world model's parameters as JSON-safe data, when the domain reports them (else ``{}``).

    The protocol has no accessor for them, so this looks, in order, for ``domain.world_model_params(model)``,
    ``domain.model_params(model)`` (a mapping or a dataclass), and ``spec()["models"][model]``; values that
    cannot be written as JSON are recorded as their ``repr``.
    """
    for attr in ("world_model_params", "model_params"):
        method = getattr(domain, attr, None)
        if callable(method):
            params: Any = method(model)
            break
    else:
        models = domain.spec().get("models")
        params = models.get(model, {}) if isinstance(models, Mapping) else {}
    try:
        data = json.loads(json.dumps(params, default=_json_default, sort_keys=True, allow_nan=False))
    except (TypeError, ValueError):
        return {"repr": repr(params)}
    return data if isinstance(data, dict) else {"value": data}
