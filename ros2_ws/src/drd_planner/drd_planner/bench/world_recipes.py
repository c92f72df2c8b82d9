"""How to make one benchmark world again anywhere: a world model and seed, or a scene file.

A :class:`WorldRecipe` is plain data (JSON-able), so a child process (the OMPL worker) rebuilds exactly the
world the parent checks: ``domain.make_world(model, seed)``, or ``domain.world_from_scene(path)`` for a
MoveIt PlanningScene file (the arm's MotionBenchMaker scenes).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from drd_planner.exceptions import ProblemError

__all__ = ["WorldRecipe", "scene_recipes", "seeded_recipes"]


@dataclass(frozen=True)
class WorldRecipe:
    """One world: ``model`` and ``seed``, or a ``scene`` file.

    Attributes:
        label: a short name for reports (``table_clutter:5``, ``box_panda/scene0001``).
        family: the group it is reported in (the world model, or the scene folder's name).
        model: the domain's world model (None for a scene).
        seed: the world seed (None for a scene).
        scene: the scene file (None for a seeded world).
    """

    label: str
    family: str
    model: str | None = None
    seed: int | None = None
    scene: str | None = None

    def make(self, domain: Any) -> Any:
        """The world of this recipe in ``domain`` (``make_world``; a scene: ``world_from_scene``).

        Raises:
            ProblemError: neither a model and seed nor a scene, or a domain that cannot read scenes.
        """
        if self.scene is not None:
            reader = getattr(domain, "world_from_scene", None)
            if reader is None:
                raise ProblemError(f"domain {domain.name!r} cannot read scene files ({self.scene})")
            return reader(self.scene)
        if self.model is None or self.seed is None:
            raise ProblemError(f"world recipe {self.label!r} needs a model and a seed, or a scene")
        return domain.make_world(self.model, int(self.seed))

    def to_json(self) -> dict[str, Any]:
        """The recipe as a JSON-able dict (:meth:`from_json` reads it back)."""
        return {
            "label": self.label,
            "family": self.family,
            "model": self.model,
            "seed": self.seed,
            "scene": self.scene,
        }

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> WorldRecipe:
        """The recipe of a :meth:`to_json` dict.

        Raises:
            ProblemError: a missing label or family.
        """
        try:
            seed = data.get("seed")
            return cls(
                label=str(data["label"]),
                family=str(data["family"]),
                model=None if data.get("model") is None else str(data["model"]),
                seed=None if seed is None else int(seed),
                scene=None if data.get("scene") is None else str(data["scene"]),
            )
        except (KeyError, TypeError, ValueError) as exc:
            raise ProblemError(f"bad world recipe {dict(data)!r}: {exc}") from exc


def seeded_recipes(model: str, seeds: range | list[int]) -> list[WorldRecipe]:
    """Recipes of ``model`` with each of ``seeds``."""
    return [WorldRecipe(f"{model}:{s}", model, model=model, seed=int(s)) for s in seeds]


def scene_recipes(folder: str | Path, limit: int | None = None) -> list[WorldRecipe]:
    """Recipes of the ``scene*.yaml`` files of ``folder`` (sorted; the first ``limit`` when given).

    Raises:
        ProblemError: the folder holds no scene file.
    """
    base = Path(folder)
    files = sorted(base.glob("scene*.yaml"))
    if not files:
        raise ProblemError(f"no scene*.yaml files in {base}")
    chosen = files if limit is None else files[:limit]
    return [WorldRecipe(f"{base.name}/{f.stem}", base.name, scene=str(f)) for f in chosen]
