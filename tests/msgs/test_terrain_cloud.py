"""PointCloud2 <-> heightfield: round trip, NaN as unknown, and every refusal."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from drd_msgs_py.exceptions import MessageError
from drd_msgs_py.terrain import cloud_from_heightfield, heightfield_from_cloud
from drd_planner.geometry.terrain import Heightfield

FRAME = "map"


def _terrain() -> Heightfield:
    rng = np.random.default_rng(0)
    heights = rng.uniform(0, 40, (7, 9))
    heights[2, 3] = np.nan
    return Heightfield((-100.0, 250.0), 25.0, heights)


def test_round_trip_keeps_the_grid_and_float32_heights(msgs: Any) -> None:
    terrain = _terrain()
    cloud = cloud_from_heightfield(terrain, frame_id=FRAME, stamp=(3, 0), msgs=msgs)
    assert (cloud.height, cloud.width, cloud.point_step) == (7, 9, 12)
    back = heightfield_from_cloud(cloud, frame_id=FRAME)
    assert back.shape == terrain.shape and back.cell_size == pytest.approx(25.0)
    np.testing.assert_allclose(back.origin, terrain.origin)
    np.testing.assert_array_equal(np.isnan(back.heights), np.isnan(terrain.heights))
    known = ~np.isnan(terrain.heights)
    np.testing.assert_allclose(back.heights[known], terrain.heights[known].astype(np.float32))


def _with(msgs: Any, **fields: Any) -> Any:
    cloud = cloud_from_heightfield(_terrain(), frame_id=FRAME, msgs=msgs)
    values = {name: getattr(cloud, name) for name in ("header", "height", "width", "fields", "is_bigendian")}
    values |= {name: getattr(cloud, name) for name in ("point_step", "row_step", "data", "is_dense")}
    values["data"] = np.asarray(
        bytearray(bytes(memoryview(values["data"])))
        if not isinstance(values["data"], np.ndarray)
        else values["data"],
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
