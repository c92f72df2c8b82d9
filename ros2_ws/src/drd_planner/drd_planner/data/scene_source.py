"""World source ``--scenes DIR``: MoveIt PlanningScene files as worlds, their requests' states as graph vertices.

Worlds: the folder's ``scene*.yaml`` files sorted by name (the first ``--worlds N`` of them, or all), each read by
:func:`~drd_planner.geometry.moveit_scene.parse_planning_scene` into primitives and checked by the domain's
``scene_checker`` on a scene with the domain's margin (the checks the domain makes of a world of its own).

Vertices: the ``request*.yaml`` MotionPlanRequests that go with the scenes used (``requestK.yaml`` with
``sceneK.yaml``; a request without a scene of the same K is always used) give their start state and their
joint goals in the domain's joint order (``domain.joint_names``). The first request's start and goal become the
spec keys ``start`` and ``goal`` unless ``--domain-spec`` gives them; every other distinct state is appended to
the spec key ``extra_states`` (graph vertices joined like every sample). ``--no-requests`` leaves them out.

Spec defaults: a domain's ``SCENE_SPEC_DEFAULTS`` (:func:`spec_defaults`; the arm's turns its floor test off)
apply under the user's ``--domain-spec``.
"""

from __future__ import annotations

import importlib
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from drd_planner.data.world_sources import (
    FileRecord,
    ResolvedSource,
    SceneFolder,
    online_domain,
    records_from_json,
)
from drd_planner.domains.base import Domain, EdgeChecker
from drd_planner.domains.spec_docs import params_class
from drd_planner.exceptions import DatasetError, GeometryError, ProblemError
from drd_planner.geometry.moveit_request import joint_vector, parse_motion_plan_request
from drd_planner.geometry.moveit_scene import ScenePrimitive, parse_planning_scene
from drd_planner.geometry.moveit_yaml import MAX_YAML_BYTES
from drd_planner.geometry.scene import Scene

__all__ = [
    "REQUEST_PREFIX",
    "SCENE_PREFIX",
    "WORLD_MODEL",
    "SceneWorlds",
    "open_worlds",
    "request_files",
    "resolve",
    "scene_files",
    "scene_of",
    "spec_defaults",
]

SCENE_PREFIX, REQUEST_PREFIX = "scene", "request"
#: The dataset's ``world_model`` field for scene worlds.
WORLD_MODEL = SceneFolder.world_model

_SCENE_HINT = (
    "scene worlds hold box, sphere and cylinder primitives in the planning frame only: change that object, "
    "move the file out of the --scenes folder, or stop before it with --worlds N"
)

State = tuple[float, ...]


def scene_files(folder: Path) -> list[Path]:
    """The folder's ``scene*.yaml`` files, sorted by name.

    Raises:
        DatasetError: not a folder, or no scene file in it.
    """
    if not folder.is_dir():
        raise DatasetError(f"--scenes {folder}: not a folder")
    files = sorted((p for p in folder.glob(f"{SCENE_PREFIX}*.yaml") if p.is_file()), key=lambda p: p.name)
    if not files:
        raise DatasetError(
            f"--scenes {folder}: no {SCENE_PREFIX}*.yaml files (MoveIt PlanningScene YAML, one world each)"
        )
    return files


def _key(path: Path, prefix: str) -> str:
    """What follows ``prefix`` in the file's stem (``0001`` of ``scene0001.yaml``)."""
    return path.stem[len(prefix) :]


def request_files(folder: Path, used: Sequence[Path], scenes: Sequence[Path]) -> list[Path]:
    """The ``request*.yaml`` files that go with the ``used`` scenes (of all the folder's ``scenes``), by name."""
    used_keys = {_key(p, SCENE_PREFIX) for p in used}
    all_keys = {_key(p, SCENE_PREFIX) for p in scenes}
    found = sorted((p for p in folder.glob(f"{REQUEST_PREFIX}*.yaml") if p.is_file()), key=lambda p: p.name)
    return [p for p in found if _key(p, REQUEST_PREFIX) in used_keys or _key(p, REQUEST_PREFIX) not in all_keys]


def scene_primitives(path: str, data: bytes) -> tuple[ScenePrimitive, ...]:
    """The primitives of a scene file's bytes.

    Raises:
        DatasetError: not UTF-8, or a scene the importer refuses (the file and object named, and what to do).
    """
    try:
        return parse_planning_scene(data.decode("utf-8"), source=path)
    except UnicodeDecodeError as exc:
        raise DatasetError(f"{path}: not UTF-8 text ({exc})") from exc
    except GeometryError as exc:
        raise DatasetError(f"{exc}; {_SCENE_HINT}") from exc


def scene_of(primitives: Sequence[ScenePrimitive], margin: float) -> Scene:
    """A collision scene with every primitive (named by its object), queries inflated by ``margin`` metres."""
    scene = Scene(margin=margin)
    for primitive in primitives:
        scene.add(primitive.shape, primitive.pose, name=primitive.name)
    return scene


@dataclass
class _States:
    """Joint states found in requests, in file order (start first, then the goals, per request)."""

    states: list[State] = field(default_factory=list)
    first_start: tuple[State, str] | None = None
    first_goal: tuple[State, str] | None = None


def _request_states(files: Sequence[FileRecord], joint_names: Sequence[str]) -> _States:
    """Every request's start and goal states in the domain's joint order.

    Raises:
        DatasetError: a request that cannot be read, or whose joints do not match ``joint_names``.
    """
    found = _States()
    for record in files:
        name = Path(record.path).name
        try:
            request = parse_motion_plan_request(record.read().decode("utf-8"), source=record.path)
            if request.start is not None:
                where = f"{record.path}: start_state.joint_state"
                start = tuple(joint_vector(request.start, joint_names, where=where, allow_extra=True).tolist())
                found.states.append(start)
                found.first_start = found.first_start or (start, name)
            for k, goal in enumerate(request.goals):
                where = f"{record.path}: goal_constraints[{k}].joint_constraints"
                state = tuple(joint_vector(goal, joint_names, where=where).tolist())
                found.states.append(state)
                found.first_goal = found.first_goal or (state, name)
        except (GeometryError, UnicodeDecodeError) as exc:
            raise DatasetError(f"{exc} (leave the requests out with --no-requests)") from exc
    return found


def _endpoint(user_spec: Mapping[str, Any], key: str, found: tuple[State, str] | None) -> tuple[State, str]:
    """The spec's ``key`` (start or goal): the user's when given, else the first request's."""
    if key in user_spec:
        return tuple(float(v) for v in user_spec[key]), "--domain-spec"
    if found is None:
        raise DatasetError(
            f"no request*.yaml gives a {key} state (start_state.joint_state / goal_constraints): give "
            f"'{key}' in --domain-spec, or leave the requests out with --no-requests"
        )
    return found


def _with_requests(user_spec: Mapping[str, Any], found: _States) -> tuple[dict[str, Any], dict[str, Any]]:
    """The spec with the requests' start, goal and extra states, and what was taken from where."""
    start, start_from = _endpoint(user_spec, "start", found.first_start)
    goal, goal_from = _endpoint(user_spec, "goal", found.first_goal)
    given = [tuple(float(v) for v in state) for state in user_spec.get("extra_states", [])]
    seen = {start, goal, *given}
    added = []
    for state in found.states:
        if state not in seen:
            seen.add(state)
            added.append(state)
    spec = {
        **user_spec,
        "start": list(start),
        "goal": list(goal),
        "extra_states": [list(s) for s in given + added],
    }
    info = {"start_from": start_from, "goal_from": goal_from, "request_states": len(found.states)}
    return spec, {**info, "extra_states_added": len(added)}


def spec_defaults(request: SceneFolder, domain_name: str) -> Mapping[str, Any]:
    """The spec values a registered domain asks for when its worlds are MoveIt scenes (under the user's spec).

    A domain's parameter class (or its module) may define ``SCENE_SPEC_DEFAULTS``: the arm turns its floor test
    off (``floor_z`` null), since MoveIt has no implicit floor and a scene models its own support surfaces.
    """
    try:
        params = params_class(domain_name)
    except ProblemError:
        return {}
    found = getattr(params, "SCENE_SPEC_DEFAULTS", None)
    if found is None:
        found = getattr(importlib.import_module(params.__module__), "SCENE_SPEC_DEFAULTS", None)
    return dict(found) if isinstance(found, Mapping) else {}


def resolve(
    request: SceneFolder, domain: Domain, user_spec: Mapping[str, Any], num_worlds: int | None
) -> ResolvedSource:
    """Check the scene folder against ``domain`` and list its worlds (see the module docstring).

    Every scene used is read here, so a scene the importer refuses stops the build before any check.

    Raises:
        DatasetError: no scene files, too few for ``num_worlds``, an unreadable or unsupported scene, or
            requests whose joints do not match the domain's (each names the file and what to change).
    """
    online = online_domain(domain, "--scenes")
    folder = Path(request.folder)
    scenes = scene_files(folder)
    if num_worlds is not None and num_worlds > len(scenes):
        raise DatasetError(f"--worlds {num_worlds}: {folder} has only {len(scenes)} scene file(s)")
    used = scenes[: num_worlds or len(scenes)]
    records = [FileRecord.of(p, what="scene file", max_bytes=MAX_YAML_BYTES) for p in used]
    for record in records:
        scene_primitives(record.path, record.read())
    spec: dict[str, Any] | None = None
    taken: dict[str, Any] = {}
    requests = [
        FileRecord.of(p, what="request file", max_bytes=MAX_YAML_BYTES) for p in request_files(folder, used, scenes)
    ]
    if request.requests and requests:
        if not online.joint_names:
            raise DatasetError(
                f"--scenes {folder} has request*.yaml files, but domain {domain.name!r} has no joint states "
                "to put their start and goal in: leave them out with --no-requests"
            )
        spec, taken = _with_requests(user_spec, _request_states(requests, online.joint_names))
    provenance = {
        "kind": request.kind,
        "folder": request.folder,
        "scenes": [r.to_json() for r in records],
        "requests": [r.to_json() for r in requests] if request.requests else [],
        **taken,
    }
    return ResolvedSource(
        kind=request.kind,
        world_model=WORLD_MODEL,
        num_worlds=len(records),
        seeded=False,
        spec=spec,
        worker_data={"kind": request.kind, "files": [r.to_json() for r in records]},
        provenance=provenance,
    )


class SceneWorlds:
    """The scene worlds of a build, in a worker: scene file ``i`` is world ``i``."""

    def __init__(self, records: Sequence[FileRecord]) -> None:
        self.records = tuple(records)

    def checkers(self, domain: Domain, ids: Sequence[int]) -> Iterator[EdgeChecker]:
        """The domain's scene checker of each world (the file's bytes checked against its SHA-256)."""
        online = online_domain(domain, "scene worlds")
        for i in ids:
            if not 0 <= int(i) < len(self.records):
                raise DatasetError(f"scene world {i} is not among the build's {len(self.records)} scenes")
            record = self.records[int(i)]
            scene = scene_of(scene_primitives(record.path, record.read()), online.margin)
            yield online.scene_checker(scene)


def open_worlds(data: Mapping[str, Any]) -> SceneWorlds:
    """The scene worlds of a resolved source's ``worker_data``."""
    return SceneWorlds(records_from_json(data))
