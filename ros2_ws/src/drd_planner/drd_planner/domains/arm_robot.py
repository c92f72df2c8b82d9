"""The arm's robot files: where the shared Panda lives, reading descriptions, and a cache of parsed models.

A :class:`RobotLoader` turns description texts (URDF, spherized URDF, SRDF) into a
:class:`~drd_planner.geometry.robot.RobotModel` and keeps the last few it built (parsing takes tens of
milliseconds, and the arm's checks compare models by identity: the same texts must give the same object).
:data:`ROBOT_MODELS` is the loader the arm domains share by default, so two domains of one robot, and a
``robot_description`` equal to the domain's own files, use one model object.
"""

from __future__ import annotations

from collections import OrderedDict
from pathlib import Path

from drd_planner.exceptions import ProblemError
from drd_planner.geometry.robot import RobotModel
from drd_planner.settings import shared_data_dir

__all__ = ["ROBOT_MODELS", "RobotLoader", "RobotTexts", "default_panda_dir", "load_robot", "robot_texts"]

#: (URDF, spherized URDF or None, SRDF or None) texts of one robot.
RobotTexts = tuple[str, str | None, str | None]

#: Parsed models a loader keeps (the least recently used is dropped first).
MODELS_KEPT = 8


def default_panda_dir() -> Path:
    """The shared Panda folder: ``<shared data>/panda`` (:func:`drd_planner.settings.shared_data_dir`).

    Raises:
        ProblemError: the folder does not exist.
    """
    folder = shared_data_dir() / "panda"
    if not folder.is_dir():
        raise ProblemError(
            f"Panda model folder {folder} not found; set DRD_SHARED_DATA or give urdf_path in the arm spec"
        )
    return folder


def _read(path: str | None) -> str | None:
    """The text of a robot file (None for no path)."""
    if path is None:
        return None
    try:
        return Path(path).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise ProblemError(f"cannot read robot description {path}: {exc}") from exc


def robot_texts(
    urdf_path: str | None = None, sphere_urdf_path: str | None = None, srdf_path: str | None = None
) -> RobotTexts:
    """(URDF, spherized URDF or None, SRDF or None) texts of robot files; None means the shared Panda.

    With every path None: ``panda.urdf`` (kinematics), ``panda_spherized.urdf`` (spheres) and
    ``panda.srdf``. With ``urdf_path`` given, the other two default to "none" (the URDF must then be
    spherized itself and adjacent links are excluded from self-collision).

    Raises:
        ProblemError: a file cannot be read, or the shared Panda folder is missing.
    """
    if urdf_path is None:
        folder = default_panda_dir()
        urdf_path = str(folder / "panda.urdf")
        sphere_urdf_path = sphere_urdf_path or str(folder / "panda_spherized.urdf")
        srdf_path = srdf_path or str(folder / "panda.srdf")
    urdf = _read(urdf_path)
    assert urdf is not None
    return urdf, _read(sphere_urdf_path), _read(srdf_path)


class RobotLoader:
    """Builds robot models from description texts and keeps the last :data:`MODELS_KEPT` of them.

    Args:
        capacity: models kept.
    """

    def __init__(self, capacity: int = MODELS_KEPT) -> None:
        self._capacity = int(capacity)
        self._models: OrderedDict[RobotTexts, RobotModel] = OrderedDict()

    def model(self, urdf: str, sphere_urdf: str | None = None, srdf: str | None = None) -> RobotModel:
        """The model of these texts (the kept one when the texts were seen before).

        Raises:
            GeometryError: an invalid description.
        """
        key = (urdf, sphere_urdf, srdf)
        known = self._models.get(key)
        if known is not None:
            self._models.move_to_end(key)
            return known
        robot = RobotModel.from_urdf(urdf, sphere_urdf=sphere_urdf, srdf=srdf)
        self._models[key] = robot
        while len(self._models) > self._capacity:
            self._models.popitem(last=False)
        return robot

    def __len__(self) -> int:
        return len(self._models)


#: The loader arm domains share unless given their own.
ROBOT_MODELS = RobotLoader()


def load_robot(
    urdf_path: str | None = None,
    sphere_urdf_path: str | None = None,
    srdf_path: str | None = None,
    *,
    loader: RobotLoader = ROBOT_MODELS,
) -> RobotModel:
    """The robot model from files (see :func:`robot_texts`; None means the shared Panda files).

    Raises:
        ProblemError: a file cannot be read.
        GeometryError: a description is invalid.
    """
    return loader.model(*robot_texts(urdf_path, sphere_urdf_path, srdf_path))
