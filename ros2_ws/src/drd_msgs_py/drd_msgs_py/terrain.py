"""Terrain: organized ``sensor_msgs/PointCloud2`` <-> a :class:`~drd_msgs_py.shapes.HeightGrid`.

The cloud is a grid: ``height`` rows by ``width`` columns of float32 ``x, y, z`` (metres, other
fields allowed and ignored). Row i lies at y = y0 + i * cell, column j at x = x0 + j * cell, as in
the heightfield. A NaN ``z`` is an unknown height (counted as the limits' ``unknown_terrain`` says); x and y
must be finite and on the grid (within :data:`GRID_TOL` of a cell). A cloud that is not such a grid, or one
beyond a :class:`~drd_msgs_py.limits.MessageLimits` limit (checked before the payload is decoded), is
refused with a :class:`MessageError`, so the caller keeps its previous terrain. How unknown heights count in
collision checks is the consumer's choice (drd_planner's ``unknown_terrain``).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt

from drd_msgs_py.arrays import FloatArray
from drd_msgs_py.exceptions import MessageError
from drd_msgs_py.factory import MessageFactory, header
from drd_msgs_py.limits import DEFAULT_LIMITS, MessageLimits
from drd_msgs_py.shapes import GridLike, HeightGrid

__all__ = ["GRID_TOL", "cloud_from_heightfield", "heightfield_from_cloud"]


#: Allowed deviation of a point's x, y from its grid position, as a fraction of the cell size.
GRID_TOL = 1e-3
_FLOAT32 = 7  # sensor_msgs/PointField.FLOAT32


def _as_bytes(data: Any) -> npt.NDArray[np.uint8]:
    if isinstance(data, np.ndarray):
        return np.ascontiguousarray(data, dtype=np.uint8).reshape(-1)
    try:
        return np.frombuffer(memoryview(data), dtype=np.uint8)
    except TypeError:
        return np.asarray(list(data), dtype=np.uint8)


def _field_offsets(msg: Any) -> dict[str, int]:
    offsets: dict[str, int] = {}
    for field in msg.fields:
        offsets[str(field.name)] = int(field.offset)
        if str(field.name) in ("x", "y", "z") and (int(field.datatype) != _FLOAT32 or int(field.count) != 1):
            raise MessageError(f"PointCloud2 field {field.name!r} must be one float32 (datatype 7)")
    missing = [n for n in ("x", "y", "z") if n not in offsets]
    if missing:
        raise MessageError(f"PointCloud2 lacks field(s) {', '.join(missing)}")
    return offsets


def _data_size(data: Any) -> int:
    """Bytes in a cloud's ``data`` without copying it (numpy array, bytes, array.array or list)."""
    if isinstance(data, np.ndarray):
        return int(data.nbytes)
    try:
        return memoryview(data).nbytes
    except TypeError:
        return len(data)


def _check_header(msg: Any, frame_id: str, limits: MessageLimits) -> tuple[int, int]:
    """(rows, cols) of a cloud whose frame, organisation and sizes pass (nothing decoded yet)."""
    frame = str(msg.header.frame_id)
    if frame != frame_id:
        raise MessageError(f"terrain cloud is in frame {frame!r}; the planner works in {frame_id!r}")
    rows, cols = int(msg.height), int(msg.width)
    if rows < 2 or cols < 2:
        raise MessageError(f"terrain cloud must be organized with >= 2 rows and columns, got {rows} x {cols}")
    if rows * cols > limits.max_terrain_cells:
        raise MessageError(
            limits.refusal("max_terrain_cells", f"terrain cloud has {rows * cols} cells ({rows} x {cols})")
        )
    size = _data_size(msg.data)
    if size > limits.max_message_bytes:
        raise MessageError(limits.refusal("max_message_bytes", f"terrain cloud data has {size} bytes"))
    if bool(msg.is_bigendian):
        raise MessageError("big-endian terrain clouds are not supported")
    return rows, cols


def _columns(msg: Any, rows: int, cols: int) -> tuple[FloatArray, FloatArray, FloatArray]:
    """(rows, cols) x, y, z of a cloud (metres) once its layout is checked."""
    offsets = _field_offsets(msg)
    step, row_step = int(msg.point_step), int(msg.row_step)
    if step < 12 or any(o + 4 > step for o in (offsets["x"], offsets["y"], offsets["z"])):
        raise MessageError(f"PointCloud2 point_step {step} does not hold the x, y, z fields")
    if row_step < cols * step:
        raise MessageError(f"PointCloud2 row_step {row_step} < width x point_step {cols * step}")
    size = _data_size(msg.data)
    if size != rows * row_step:
        raise MessageError(
            f"PointCloud2 data has {size} bytes, expected height x row_step = {rows * row_step} (ragged cloud)"
        )
    grid = _as_bytes(msg.data).reshape(rows, row_step)[:, : cols * step].reshape(rows, cols, step)

    def column(name: str) -> FloatArray:
        o = offsets[name]
        return np.ascontiguousarray(grid[:, :, o : o + 4]).view("<f4")[..., 0].astype(np.float64)

    return column("x"), column("y"), column("z")


def _check_values(x: FloatArray, y: FloatArray, z: FloatArray, limits: MessageLimits) -> None:
    """Finite x, y; z finite or NaN (not all); every coordinate within ``limits.max_coordinate``."""
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(y))):
        raise MessageError("terrain cloud x and y must be finite (only z may be NaN = unknown)")
    if np.any(np.isinf(z)):
        raise MessageError("terrain cloud z must be finite or NaN, not infinite")
    for name, values in (("x", x), ("y", y), ("z", z)):
        problem = limits.coordinate_problem(values, f"terrain cloud {name} values")
        if problem is not None:
            raise MessageError(problem)
    if np.all(np.isnan(z)):
        raise MessageError("terrain cloud has no known height (every z is NaN)")


def _grid_spacing(x: FloatArray, y: FloatArray, limits: MessageLimits) -> float:
    """The cell size (metres) of a regular square grid along +x (columns) and +y (rows)."""
    rows, cols = x.shape
    x0, y0 = float(x[0, 0]), float(y[0, 0])
    cell = float(x[0, 1] - x0)
    if not cell > 0:
        raise MessageError("terrain cloud columns must go along +x with a positive spacing")
    if cell < limits.min_terrain_cell_size * (1.0 - GRID_TOL):
        raise MessageError(
            limits.refusal("min_terrain_cell_size", f"terrain cloud cells are {cell:.6g} m", side="under")
        )
    tol = GRID_TOL * cell + 1e-4 * max(1.0, abs(x0), abs(y0))  # float32 coordinates
    if (
        np.max(np.abs(x - (x0 + np.arange(cols) * cell)[None, :])) > tol
        or np.max(np.abs(y - (y0 + np.arange(rows) * cell)[:, None])) > tol
    ):
        raise MessageError("terrain cloud is not a regular square grid (rows along +y, columns along +x)")
    return cell


def heightfield_from_cloud(msg: Any, *, frame_id: str, limits: MessageLimits = DEFAULT_LIMITS) -> HeightGrid:
    """The height grid of an organized terrain cloud (rclpy or rosbags message).

    Size limits (``limits``: cells, payload bytes) are checked from the header and the payload's length before
    anything is decoded or copied.

    Raises:
        MessageError: wrong frame, not organized (height < 2 or width < 2), over a size limit (the text names
            the limit's parameter), empty, ragged (data size not rows x row_step), big-endian, fields missing or
            not float32, x/y not finite or not on a regular square grid of at least
            ``limits.min_terrain_cell_size``, a coordinate beyond ``limits.max_coordinate``, or no cell with
            four known heights.
    """
    rows, cols = _check_header(msg, frame_id, limits)
    x, y, z = _columns(msg, rows, cols)
    _check_values(x, y, z, limits)
    cell = _grid_spacing(x, y, limits)
    known = ~np.isnan(z)
    if not (known[:-1, :-1] & known[:-1, 1:] & known[1:, :-1] & known[1:, 1:]).any():
        raise MessageError(
            "terrain cloud has no cell with four known heights (a 2 x 2 block of points without NaN z); "
            "collision checks need at least one"
        )
    return HeightGrid((float(x[0, 0]), float(y[0, 0])), cell, z)


def cloud_from_heightfield(
    terrain: GridLike, *, frame_id: str, stamp: tuple[int, int] = (0, 0), msgs: MessageFactory
) -> Any:
    """An organized float32 x, y, z cloud of ``terrain`` (the inverse of :func:`heightfield_from_cloud`).

    ``terrain``: a :class:`HeightGrid` or any heightfield with ``origin``, ``cell_size``, ``heights``, ``shape``.
    """
    rows, cols = terrain.shape
    jj, ii = np.meshgrid(np.arange(cols), np.arange(rows))
    xyz = np.stack(
        [
            terrain.origin[0] + jj * terrain.cell_size,
            terrain.origin[1] + ii * terrain.cell_size,
            terrain.heights,
        ],
        axis=-1,
    ).astype("<f4")
    fields = [
        msgs("sensor_msgs/msg/PointField", name=name, offset=4 * k, datatype=_FLOAT32, count=1)
        for k, name in enumerate("xyz")
    ]
    return msgs(
        "sensor_msgs/msg/PointCloud2",
        header=header(msgs, frame_id, stamp),
        height=rows,
        width=cols,
        fields=fields,
        is_bigendian=False,
        point_step=12,
        row_step=12 * cols,
        data=np.frombuffer(xyz.tobytes(), dtype=np.uint8),
        is_dense=not bool(np.isnan(terrain.heights).any()),
    )
