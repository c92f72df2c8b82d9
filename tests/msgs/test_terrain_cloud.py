"""PointCloud2 <-> height grid: round trip, NaN as unknown, and every refusal."""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest

from drd_msgs_py.exceptions import MessageError
from drd_msgs_py.limits import MessageLimits
from drd_msgs_py.shapes import HeightGrid
from drd_msgs_py.terrain import cloud_from_heightfield, heightfield_from_cloud

FRAME = "map"


def _grid(origin: tuple[float, float], cell: float, heights: Any) -> HeightGrid:
    """A height grid of ``heights`` (metres) at ``origin`` with ``cell`` spacing."""
    return HeightGrid(origin, cell, np.asarray(heights, dtype=np.float64))


def _terrain() -> HeightGrid:
    rng = np.random.default_rng(0)
    heights = rng.uniform(0, 40, (7, 9))
    heights[2, 3] = np.nan
    return _grid((-100.0, 250.0), 25.0, heights)


def test_round_trip_keeps_the_grid_and_float32_heights(msgs: Any) -> None:
    terrain = _terrain()
    cloud = cloud_from_heightfield(terrain, frame_id=FRAME, stamp=(3, 0), msgs=msgs)
    assert (cloud.height, cloud.width, cloud.point_step) == (7, 9, 12)
    back = heightfield_from_cloud(cloud, frame_id=FRAME)
    assert back.shape == terrain.shape
    assert back.cell_size == pytest.approx(25.0)
    np.testing.assert_allclose(back.origin, terrain.origin)
    np.testing.assert_array_equal(np.isnan(back.heights), np.isnan(terrain.heights))
    known = ~np.isnan(terrain.heights)
    np.testing.assert_allclose(back.heights[known], terrain.heights[known].astype(np.float32))


def _with(msgs: Any, **fields: Any) -> Any:
    cloud = cloud_from_heightfield(_terrain(), frame_id=FRAME, msgs=msgs)
    values = {name: getattr(cloud, name) for name in ("header", "height", "width", "fields", "is_bigendian")}
    values |= {name: getattr(cloud, name) for name in ("point_step", "row_step", "data", "is_dense")}
    values["data"] = np.asarray(
        bytearray(bytes(memoryview(values["data"]))) if not isinstance(values["data"], np.ndarray) else values["data"],
        dtype=np.uint8,
    )
    values.update(fields)
    return msgs("sensor_msgs/msg/PointCloud2", **values)


def _xyz(msgs: Any, fn: Any) -> np.ndarray:
    cloud = cloud_from_heightfield(_terrain(), frame_id=FRAME, msgs=msgs)
    data = (
        np.frombuffer(
            bytes(memoryview(cloud.data)) if not isinstance(cloud.data, np.ndarray) else cloud.data.tobytes(),
            dtype="<f4",
        )
        .copy()
        .reshape(7, 9, 3)
    )
    fn(data)
    return np.frombuffer(data.tobytes(), dtype=np.uint8)


@pytest.mark.parametrize(
    ("fields", "words"),
    [
        ({"header": ("std_msgs/msg/Header", {"frame_id": "odom"})}, "frame 'odom'"),
        ({"height": 1, "width": 63, "row_step": 756}, "organized"),
        ({"height": 0, "width": 0, "row_step": 0, "data": np.zeros(0, np.uint8)}, "organized"),
        ({"data": np.zeros(100, np.uint8)}, "ragged"),
        ({"is_bigendian": True}, "big-endian"),
        ({"fields": []}, "lacks field"),
        ({"point_step": 8}, "point_step"),
        ({"row_step": 10}, "row_step"),
    ],
)
def test_malformed_clouds_are_refused(msgs: Any, fields: dict[str, Any], words: str) -> None:
    built = {k: (msgs(v[0], **v[1]) if isinstance(v, tuple) else v) for k, v in fields.items()}
    with pytest.raises(MessageError, match=words):
        heightfield_from_cloud(_with(msgs, **built), frame_id=FRAME)


@pytest.mark.parametrize(
    ("edit", "words"),
    [
        (lambda d: d.__setitem__((0, 0, 0), np.nan), "x and y must be finite"),
        (lambda d: d.__setitem__((1, 1, 1), d[1, 1, 1] + 7.0), "regular square grid"),
        (lambda d: d.__setitem__((slice(None), slice(None), 2), np.nan), "no known height"),
        (lambda d: d.__setitem__((0, 0, 2), np.inf), "not infinite"),
    ],
)
def test_bad_coordinates_are_refused(msgs: Any, edit: Any, words: str) -> None:
    with pytest.raises(MessageError, match=words):
        heightfield_from_cloud(_with(msgs, data=_xyz(msgs, edit)), frame_id=FRAME)


# --------------------------------------------------------------------------------------------------
# Map limits and what planning needs (issue 19)


class _Untouchable:
    """A cloud payload that fails the test if anything decodes or copies it; only its length may be read."""

    def __init__(self, size: int) -> None:
        self.size = size

    def __len__(self) -> int:
        return self.size

    def __iter__(self) -> Any:
        raise AssertionError("the payload was decoded before the limits were checked")


def _header_only(msgs: Any, **fields: Any) -> SimpleNamespace:
    cloud = cloud_from_heightfield(_terrain(), frame_id=FRAME, msgs=msgs)
    values = {name: getattr(cloud, name) for name in ("header", "fields", "is_bigendian", "point_step")}
    values |= {"height": 7, "width": 9, "row_step": 108, "data": cloud.data} | fields
    return SimpleNamespace(**values)


def test_a_cloud_over_the_cell_limit_is_refused_from_its_header(msgs: Any) -> None:
    lying = _header_only(msgs, height=4000, width=4000, row_step=48_000, data=_Untouchable(4000 * 48_000))
    with pytest.raises(MessageError) as info:
        heightfield_from_cloud(lying, frame_id=FRAME)
    assert str(info.value) == (
        "terrain cloud has 16000000 cells (4000 x 4000), over the limit max_terrain_cells = 250000 "
        "(parameter max_terrain_cells)"
    )
    cloud = cloud_from_heightfield(_terrain(), frame_id=FRAME, msgs=msgs)  # 7 x 9 = 63 cells
    with pytest.raises(MessageError, match=r"63 cells .* max_terrain_cells = 62 "):
        heightfield_from_cloud(cloud, frame_id=FRAME, limits=MessageLimits(max_terrain_cells=62))
    assert heightfield_from_cloud(cloud, frame_id=FRAME, limits=MessageLimits(max_terrain_cells=63)).shape == (
        7,
        9,
    )


def test_a_cloud_over_the_byte_limit_is_refused_from_its_length(msgs: Any) -> None:
    padded = _header_only(msgs, row_step=10**7, data=_Untouchable(7 * 10**7))
    with pytest.raises(MessageError, match=r"70000000 bytes, over the limit max_message_bytes = 33554432 \("):
        heightfield_from_cloud(padded, frame_id=FRAME)
    cloud = cloud_from_heightfield(_terrain(), frame_id=FRAME, msgs=msgs)  # 756 bytes
    with pytest.raises(MessageError, match="parameter max_message_bytes"):
        heightfield_from_cloud(cloud, frame_id=FRAME, limits=MessageLimits(max_message_bytes=755))


def test_tiny_cells_huge_coordinates_and_too_few_known_heights_are_refused(msgs: Any) -> None:
    tiny = _grid((0.0, 0.0), 1e-5, [[0.0, 1.0], [2.0, 3.0]])
    with pytest.raises(MessageError, match=r"cells are 1e-05 m, under the limit min_terrain_cell_size = 0.05 \("):
        heightfield_from_cloud(cloud_from_heightfield(tiny, frame_id=FRAME, msgs=msgs), frame_id=FRAME)
    far = _grid((0.0, 0.0), 1.0, [[0.0, 1.0], [2.0, 3e30]])
    with pytest.raises(MessageError, match=r"z values reach 3e\+30 m .* max_coordinate = 1000000.0"):
        heightfield_from_cloud(cloud_from_heightfield(far, frame_id=FRAME, msgs=msgs), frame_id=FRAME)
    east = _grid((2e6, 0.0), 1.0, np.zeros((2, 2)))
    with pytest.raises(MessageError, match=r"x values reach 2e\+06 m"):
        heightfield_from_cloud(cloud_from_heightfield(east, frame_id=FRAME, msgs=msgs), frame_id=FRAME)
    # Issue 19 item 8: one NaN in a 2 x 2 cloud left no terrain cell, and every plan then failed.
    for heights in ([[0.0, 1.0], [2.0, np.nan]], [[0.0] * 3, [0.0, np.nan, 0.0], [0.0] * 3]):
        cloud = cloud_from_heightfield(_grid((0.0, 0.0), 1.0, heights), frame_id=FRAME, msgs=msgs)
        with pytest.raises(MessageError, match="no cell with four known heights"):
            heightfield_from_cloud(cloud, frame_id=FRAME)
