"""A domain's statically valid states: the capability that lets the planner grow a roadmap (optional).

A connector (:mod:`drd_planner.planner.connect`) may carry a :class:`StateSampler` as its ``sampler``
attribute (:func:`sampler_of`). With one, :class:`~drd_planner.planner.Planner` grows the query's graph when
it has no free path (:mod:`drd_planner.planner.roadmap_growth`) and refuses a start or goal state the sampler
says is invalid (:meth:`StateSampler.refusal`) before any check. Without one (the helicopter, planar and
authors' graphs today) there is no growth and states are served as before.

The arm's sampler is :class:`drd_planner.domains.arm_sampler.ArmStateSampler` (joint limits, self-collision,
the floor), registered through ``CONNECTORS["arm"]``.
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy.typing as npt

from drd_planner.arrays import BoolArray, FloatArray

__all__ = ["StateSampler", "sampler_of"]


@runtime_checkable
class StateSampler(Protocol):
    """Statically valid states of a domain: a sampling box and a validity test (see the module docstring)."""

    @property
    def lower(self) -> FloatArray:
        """(D,) lower bounds of the sampling box (state units)."""
        ...

    @property
    def upper(self) -> FloatArray:
        """(D,) upper bounds of the sampling box (state units)."""
        ...

    def valid(self, states: npt.ArrayLike) -> BoolArray:
        """(N,) True where an (N, D) state passes the domain's static rules (no world needed)."""
        ...

    def refusal(self, state: npt.ArrayLike, label: str) -> str | None:
        """Why the (D,) query state ``label`` (``start`` / ``goal``) cannot be served, one sentence; None if it can."""
        ...


def sampler_of(connector: object) -> StateSampler | None:
    """The connector's ``sampler`` when it has one that implements :class:`StateSampler`, else None."""
    sampler = getattr(connector, "sampler", None)
    return sampler if isinstance(sampler, StateSampler) else None
