"""The dataset file: a database of sampled worlds for one domain, and how it was made (docs/architecture.md).

Format: a checksummed ``.npz`` (:mod:`drd_planner.data.npz_format`; read by :mod:`drd_planner.data.safe_npz`)
with a JSON header (format name and version, software version, domain name and spec, world model and
its parameters, base seed, how edges were checked, provenance, sizes, checksums) and these arrays:

============== ============= ==================================================================
name           dtype         shape and meaning
============== ============= ==================================================================
edges          int64         (E, 2) vertex ids of each edge (graph order = X column order)
lengths        float64       (E,) edge lengths in the domain's length unit
costs          float64       (E,) cost of checking each edge
X_packed       uint8         (n, ceil(E / 8)) ``np.packbits(X, axis=1)``; X[h, e] True = edge free
R_packed       uint8         (n, ceil(m / 8)) ``np.packbits(R, axis=1)``; R[h, i] True = path free
path_edges     int64         library paths' edge ids, concatenated; ``path_offsets`` (m + 1,)
train_ids      int64         (n_train,) sorted training world rows
test_ids       int64         (n_test,) sorted test world rows
world_seeds    int64         (n,) the seed each world was generated from
vertex_states  float64       optional (V, d) vertex states
vertex_paths   int64         optional library paths as vertex ids, concatenated; ``vertex_offsets``
traj_states    float64       optional (K, D) sampled states along every edge, concatenated;
                             ``traj_offsets`` (E + 1,): edge e owns rows offsets[e]:offsets[e + 1]
============== ============= ==================================================================

A file that is missing, corrupt (checksum), truncated, of another format or version, or internally
inconsistent (shapes, R not equal to "all path edges free" in X, ids out of range) is refused with a
:class:`~drd_planner.exceptions.DatasetError` that says which.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from drd_planner import __version__
from drd_planner.arrays import BoolArray, FloatArray, IntArray
from drd_planner.core.graph import ExplicitGraph
from drd_planner.core.library import PathLibrary
from drd_planner.core.problem import Problem
from drd_planner.core.worlds import WorldDatabase
from drd_planner.data.npz_format import NpzFormat
from drd_planner.data.ragged import pack_ragged, unpack_ragged
from drd_planner.data.safe_npz import refusing
from drd_planner.exceptions import DatasetError, DrdError

__all__ = [
    "FORMAT_NAME",
    "FORMAT_VERSION",
    "Dataset",
    "load_dataset",
    "load_dataset_problem",
    "save_dataset",
]

FORMAT_NAME = "drd_planner.dataset"
FORMAT_VERSION = 1
_FORMAT = NpzFormat(FORMAT_NAME, FORMAT_VERSION, DatasetError, "dataset file")


_REQUIRED = {
    "edges": np.int64,
    "lengths": np.float64,
    "costs": np.float64,
    "X_packed": np.uint8,
    "R_packed": np.uint8,
    "path_edges": np.int64,
    "path_offsets": np.int64,
    "train_ids": np.int64,
    "test_ids": np.int64,
    "world_seeds": np.int64,
}
_OPTIONAL = {
    "vertex_states": np.float64,
    "vertex_paths": np.int64,
    "vertex_offsets": np.int64,
    "traj_states": np.float64,
    "traj_offsets": np.int64,
}
_PAIRS = (("vertex_paths", "vertex_offsets"), ("traj_states", "traj_offsets"))


@dataclass(frozen=True)
class Dataset:
    """A world database for one domain, with its graph, path library, split and provenance.

    Attributes:
        graph: the explicit graph (E edges; lengths in the domain's length unit; vertex states if known).
        start: start vertex id.
        goal: goal vertex id.
        library: the m library paths (edge ids; vertex sequences, start first, when known).
        X: (n, E) bool, X[h, e] True when edge e is collision-free in world h.
        R: (n, m) bool, R[h, i] True when every edge of library path i is free in world h.
        train_ids: (n_train,) int64 sorted training world rows.
        test_ids: (n_test,) int64 sorted test world rows (disjoint from train_ids).
        edge_costs: (E,) float64 positive cost of checking each edge (1 in every benchmark).
        world_seeds: (n,) int64 non-negative seed world h was generated from (``make_world(model, seed)``).
        domain: domain registry name.
        domain_spec: JSON-safe spec that rebuilds the domain (``domain_from_spec(domain, domain_spec)``).
        world_model: the world model's name.
        seed: the base seed every other seed was derived from.
        world_model_params: JSON-safe parameters of the world model, when the domain reports them.
        check_metadata: how edges were checked (resolution, margin, ... with units), from the domain.
        edge_trajectories: per edge a (K_e, D) float64 array of states along it, or None (straight lines).
        provenance: JSON-safe build information (command, builder settings, derived seeds).
        software_version: drd_planner version that built the dataset.
    """

    graph: ExplicitGraph
    start: int
    goal: int
    library: PathLibrary
    X: BoolArray
    R: BoolArray
    train_ids: IntArray
    test_ids: IntArray
    edge_costs: FloatArray
    world_seeds: IntArray
    domain: str
    domain_spec: dict[str, Any]
    world_model: str
    seed: int
    world_model_params: dict[str, Any] = field(default_factory=dict)
    check_metadata: dict[str, Any] = field(default_factory=dict)
    edge_trajectories: tuple[FloatArray, ...] | None = None
    provenance: dict[str, Any] = field(default_factory=dict)
    software_version: str = __version__

    def __post_init__(self) -> None:
        self._check_endpoints()
        x, r = self._checked_outcomes()
        n = x.shape[0]
        train, test = _checked_ids("train", self.train_ids, n), _checked_ids("test", self.test_ids, n)
        if np.intersect1d(train, test).size:
            raise DatasetError("train and test worlds overlap")
        costs = _checked_costs(self.edge_costs, self.graph.num_edges)
        seeds = _checked_seeds(self.world_seeds, n)
        self._check_vertex_paths()
        traj = self._checked_trajectories()
        object.__setattr__(self, "X", x)
        object.__setattr__(self, "R", r)
        object.__setattr__(self, "train_ids", train)
        object.__setattr__(self, "test_ids", test)
        object.__setattr__(self, "edge_costs", costs)
        object.__setattr__(self, "world_seeds", seeds)
        object.__setattr__(self, "edge_trajectories", traj)
        object.__setattr__(self, "start", int(self.start))
        object.__setattr__(self, "goal", int(self.goal))
        object.__setattr__(self, "seed", int(self.seed))

    def _check_endpoints(self) -> None:
        """The library indexes the graph's edges; start and goal are distinct vertices of the graph."""
        graph, num_edges = self.graph, self.graph.num_edges
        if self.library.num_edges != num_edges:
            raise DatasetError(f"library indexes {self.library.num_edges} edges, graph has {num_edges}")
        for name, v in (("start", self.start), ("goal", self.goal)):
            if not 0 <= int(v) < graph.num_vertices:
                raise DatasetError(f"{name} vertex {v} outside [0, {graph.num_vertices})")
        if int(self.start) == int(self.goal):
            raise DatasetError(f"start and goal are the same vertex ({self.start})")

    def _checked_outcomes(self) -> tuple[BoolArray, BoolArray]:
        """X (n, E) and R (n, m) as bool arrays, R consistent with X and the library."""
        num_edges = self.graph.num_edges
        x, r = np.asarray(self.X), np.asarray(self.R)
        if x.dtype != np.bool_ or x.ndim != 2 or x.shape[1] != num_edges:
            raise DatasetError(f"X must be bool (worlds, {num_edges}), got {x.dtype} {x.shape}")
        n = x.shape[0]
        if r.dtype != np.bool_ or r.shape != (n, self.library.num_paths):
            raise DatasetError(f"R must be bool ({n}, {self.library.num_paths}), got {r.dtype} {r.shape}")
        if not np.array_equal(self.library.valid_paths(x), r):
            raise DatasetError("R does not match X and the library (R[h, i] = all edges of path i free)")
        return x, r

    def _check_vertex_paths(self) -> None:
        vpaths = self.library.vertex_paths
        if vpaths is None:
            return
        for i, (vp, ep) in enumerate(zip(vpaths, self.library.path_edges, strict=True)):
            if vp.size < 2 or vp[0] != self.start or vp[-1] != self.goal:
                raise DatasetError(f"library path {i} does not run from the start to the goal vertex")
            try:
                same = np.array_equal(self.graph.vertex_path_to_edges(vp), ep)
            except DrdError:
                same = False
            if not same:
                raise DatasetError(f"library path {i}: its vertex sequence does not match its edge ids")

    def _checked_trajectories(self) -> tuple[FloatArray, ...] | None:
        if self.edge_trajectories is None:
            return None
        trajs = tuple(np.asarray(t, dtype=np.float64) for t in self.edge_trajectories)
        if len(trajs) != self.graph.num_edges:
            raise DatasetError(f"need one trajectory per edge ({self.graph.num_edges}), got {len(trajs)}")
        dims = {t.shape[1] if t.ndim == 2 else -1 for t in trajs}
        if len(dims) > 1 or -1 in dims:
            raise DatasetError("edge trajectories must all be (K_e, D) arrays with the same D")
        return trajs

    @property
    def num_worlds(self) -> int:
        """The number of worlds n."""
        return int(self.X.shape[0])

    def to_problem(self, *, name: str, metadata: dict[str, Any] | None = None) -> Problem:
        """The dataset as a :class:`Problem` with its world database (for benchmarks and tree building)."""
        meta = {
            "source": "dataset",
            "domain": self.domain,
            "domain_spec": self.domain_spec,
            "check_metadata": self.check_metadata,
            "world_model": self.world_model,
            "seed": self.seed,
            "num_worlds": self.num_worlds,
            **(metadata or {}),
        }
        return Problem(
            name=name,
            library=self.library,
            edge_costs=self.edge_costs,
            graph=self.graph,
            start=self.start,
            goal=self.goal,
            worlds=WorldDatabase(self.X, self.R, self.train_ids, self.test_ids),
            metadata=meta,
        )


def _checked_ids(name: str, raw: npt.ArrayLike, n: int) -> IntArray:
    """``raw`` world ids as sorted, distinct int64 ids in [0, n) (``name`` is "train" or "test")."""
    arr = np.asarray(raw)
    if arr.ndim != 1 or (arr.size and not np.issubdtype(arr.dtype, np.integer)):
        raise DatasetError(f"{name} ids must be a 1-D integer array")
    arr = arr.astype(np.int64)
    if arr.size and (arr[0] < 0 or arr[-1] >= n or np.any(np.diff(arr) <= 0)):
        raise DatasetError(f"{name} ids must be sorted, distinct and in [0, {n})")
    return arr


def _checked_costs(raw: npt.ArrayLike, num_edges: int) -> FloatArray:
    """(E,) finite positive float64 edge check costs."""
    costs = np.asarray(raw, dtype=np.float64)
    if costs.shape != (num_edges,) or not np.all(np.isfinite(costs)) or np.any(costs <= 0):
        raise DatasetError(f"edge costs must be ({num_edges},) finite and positive")
    return costs


def _checked_seeds(raw: npt.ArrayLike, n: int) -> IntArray:
    """(n,) non-negative int64 world seeds."""
    seeds = np.asarray(raw)
    if seeds.shape != (n,) or (seeds.size and not np.issubdtype(seeds.dtype, np.integer)):
        raise DatasetError(f"world seeds must be ({n},) integers, got {seeds.dtype} {seeds.shape}")
    if seeds.size and seeds.min() < 0:
        raise DatasetError("world seeds must be non-negative")
    return seeds.astype(np.int64)


def save_dataset(path: str | Path, dataset: Dataset) -> Path:
    """Write ``dataset`` to ``path`` (compressed ``.npz``; byte-identical for equal datasets).

    Returns:
        The path written.

    Raises:
        DatasetError: a metadata field is not JSON-safe.
    """
    ds = dataset
    arrays: dict[str, npt.NDArray[Any]] = {
        "edges": ds.graph.edges,
        "lengths": ds.graph.lengths,
        "costs": ds.edge_costs,
        "X_packed": np.packbits(ds.X, axis=1),
        "R_packed": np.packbits(ds.R, axis=1),
        "train_ids": ds.train_ids,
        "test_ids": ds.test_ids,
        "world_seeds": ds.world_seeds,
    }
    arrays["path_edges"], arrays["path_offsets"] = pack_ragged(ds.library.path_edges, np.int64)
    if ds.graph.vertex_states is not None:
        arrays["vertex_states"] = ds.graph.vertex_states
    if ds.library.vertex_paths is not None:
        arrays["vertex_paths"], arrays["vertex_offsets"] = pack_ragged(ds.library.vertex_paths, np.int64)
    if ds.edge_trajectories is not None:
        arrays["traj_states"], arrays["traj_offsets"] = pack_ragged(ds.edge_trajectories, np.float64)
    dtypes = {**_REQUIRED, **_OPTIONAL}
    arrays = {k: np.ascontiguousarray(v, dtype=dtypes[k]) for k, v in arrays.items()}
    header = {
        "software_version": ds.software_version,
        "domain": ds.domain,
        "domain_spec": ds.domain_spec,
        "world_model": ds.world_model,
        "world_model_params": ds.world_model_params,
        "seed": ds.seed,
        "check_metadata": ds.check_metadata,
        "provenance": ds.provenance,
        "num_worlds": ds.num_worlds,
        "num_edges": ds.graph.num_edges,
        "num_paths": ds.library.num_paths,
        "num_vertices": ds.graph.num_vertices,
        "directed": ds.graph.directed,
        "start": ds.start,
        "goal": ds.goal,
    }
    return _FORMAT.write(path, header, arrays)


def load_dataset(path: str | Path) -> Dataset:
    """Read and verify a dataset file.

    Raises:
        DatasetError: missing, unreadable, truncated, corrupt (checksum), another format or version,
            unexpected arrays or dtypes, or inconsistent contents; the message says which.
    """
    src = Path(path)
    header, arrays = _FORMAT.read(src)
    missing = [k for k in _REQUIRED if k not in arrays]
    if missing:
        raise DatasetError(f"{src} lacks required arrays: {', '.join(missing)}")
    for name, arr in arrays.items():
        want = {**_REQUIRED, **_OPTIONAL}.get(name)
        if want is None:
            raise DatasetError(f"{src}: unexpected array {name!r}")
        if arr.dtype != np.dtype(want):
            raise DatasetError(f"{src}: array {name!r} has dtype {arr.dtype}, expected {np.dtype(want)}")
    for a, b in _PAIRS:
        if (a in arrays) != (b in arrays):
            raise DatasetError(f"{src}: arrays {a!r} and {b!r} must be stored together")
    with refusing(DatasetError, src, "dataset file"):  # the last line of defence: nothing else escapes
        try:
            return _dataset_from(arrays, header)
        except DatasetError as exc:
            raise DatasetError(f"{src} is inconsistent: {exc}") from exc
        except (DrdError, KeyError, TypeError, ValueError, IndexError, OverflowError) as exc:
            raise DatasetError(f"{src} is inconsistent: {type(exc).__name__}: {exc}") from exc


def _unpack(packed: npt.NDArray[np.uint8], rows: int, cols: int, what: str) -> BoolArray:
    want = (rows, (cols + 7) // 8)
    if packed.shape != want:
        raise DatasetError(f"{what} has shape {packed.shape}, expected {want} for {rows} x {cols} bits")
    bits = np.unpackbits(packed, axis=1)
    if bits[:, cols:].any():
        raise DatasetError(f"{what} has non-zero padding bits")
    return bits[:, :cols].astype(bool)


def _int(header: dict[str, Any], key: str) -> int:
    value = header.get(key)
    if not isinstance(value, int) or isinstance(value, bool):
        raise DatasetError(f"header field {key!r} must be an integer, got {value!r}")
    return value


def _dict(header: dict[str, Any], key: str) -> dict[str, Any]:
    value = header.get(key, {})
    if not isinstance(value, dict):
        raise DatasetError(f"header field {key!r} must be an object")
    return value


def _dataset_from(c: dict[str, npt.NDArray[Any]], header: dict[str, Any]) -> Dataset:
    n, num_edges, m = _int(header, "num_worlds"), _int(header, "num_edges"), _int(header, "num_paths")
    if c["edges"].shape != (num_edges, 2):
        raise DatasetError(f"edges have shape {c['edges'].shape}, header says {num_edges} edges")
    graph = ExplicitGraph(
        c["edges"],
        c["lengths"],
        _int(header, "num_vertices"),
        bool(header["directed"]),
        c.get("vertex_states"),
    )
    path_edges = unpack_ragged(c["path_edges"], c["path_offsets"], m, "library path", DatasetError)
    vertex_paths = None
    if "vertex_paths" in c:
        vertex_paths = unpack_ragged(c["vertex_paths"], c["vertex_offsets"], m, "library vertex path", DatasetError)
    trajectories = None
    if "traj_states" in c:
        if c["traj_states"].ndim != 2:
            raise DatasetError(f"traj_states must be (K, D), got shape {c['traj_states'].shape}")
        trajectories = unpack_ragged(c["traj_states"], c["traj_offsets"], num_edges, "edge trajectory", DatasetError)
    return Dataset(
        graph=graph,
        start=_int(header, "start"),
        goal=_int(header, "goal"),
        library=PathLibrary(path_edges, num_edges, vertex_paths),
        X=_unpack(c["X_packed"], n, num_edges, "X_packed"),
        R=_unpack(c["R_packed"], n, m, "R_packed"),
        train_ids=c["train_ids"],
        test_ids=c["test_ids"],
        edge_costs=c["costs"],
        world_seeds=c["world_seeds"],
        domain=str(header["domain"]),
        domain_spec=_dict(header, "domain_spec"),
        world_model=str(header["world_model"]),
        seed=_int(header, "seed"),
        world_model_params=_dict(header, "world_model_params"),
        check_metadata=_dict(header, "check_metadata"),
        edge_trajectories=trajectories,
        provenance=_dict(header, "provenance"),
        software_version=str(header.get("software_version")),
    )


def load_dataset_problem(path: str | Path) -> Problem:
    """Load a dataset file as a :class:`Problem` named after the file (its stem), worlds included.

    This is what ``drd bench --dataset FILE`` runs; the metadata records the domain, world model, seed,
    file name and the file's SHA-256.

    Raises:
        DatasetError: as :func:`load_dataset`.
    """
    src = Path(path)
    dataset = load_dataset(src)
    digest = hashlib.sha256(src.read_bytes()).hexdigest()
    return dataset.to_problem(name=src.stem, metadata={"file": src.name, "sha256": digest})
