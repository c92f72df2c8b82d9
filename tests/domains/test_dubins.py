"""Tests of the Dubins module: known answers, both heading ranges, optimality against an independent solver.

The golden tables were captured from the two former implementations (``helicopter_dubins`` in the signed
range, the SE(2) module in the unsigned range) before they were merged; the merged module reproduced them
bit for bit on 6000 random cases and on every SE(2) primitive of 96 parameter sets.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from drd_planner.domains.dubins import DubinsPath, dubins_path, wrap_angle
from drd_planner.exceptions import ProblemError

R = 100.0
TWO_PI = 2.0 * math.pi

Pose = tuple[float, float, float]

# (start, end, word, segments, pose at the middle of the path): radius 100, signed headings.
SIGNED = [
    (
        (105.499, -171.406, -1.197248),
        (179.68, 297.481, -2.247924),
        "LSL",
        (260.97676186398616, 374.4192685642912, 262.2741688539725),
        [326.96248125919766, 34.83464394253676, 1.4125196186398616],
    ),
    (
        (-252.765, -191.506, -0.881865),
        (-198.228, 53.256, 0.733923),
        "RLR",
        (51.76719734075039, 453.2958641198609, 239.94986677911047),
        [-35.68012044379145, -197.50805258883003, 1.8078556943836013],
    ),
    (
        (-236.769, 39.439, -3.112504),
        (-20.928, 285.373, 1.881364),
        "LRL",
        (18.442244479646575, 428.31913443737017, 280.9451592397649),
        [-266.35457647829685, 234.45018334014972, -0.09900649401139106],
    ),
    (
        (58.093, -104.79, -1.845096),
        (-34.365, -133.175, 2.35593),
        "LRL",
        (137.7327905560017, 480.6324034881366, 134.68368221417623),
        [92.37833956651174, -406.33325331536923, -2.8556845701715385],
    ),
    (
        (-172.106, -135.453, 1.930081),
        (-138.981, -139.162, -2.696229),
        "LRL",
        (41.22628472022094, 535.1288032125341, 31.271518492313177),
        [-94.38005922323293, 64.84310425435987, -0.2835263377209225],
    ),
    (
        (-19.675, -141.477, 2.443795),
        (-128.209, 164.26, -0.080143),
        "LSR",
        (7.929775748378032, 206.50438964257424, 260.3235757483781),
        [-211.20710787681026, -1.5714440008098993, 2.293645705696651],
    ),
]
# The same for radius 0.3, unsigned headings.
UNSIGNED = [
    (
        (-0.064, 0.93, 5.643729),
        (-0.842, -0.51, 1.161051),
        "RSR",
        (0.35163299170418716, 1.3579573575850914, 0.9931704082958129),
        [-0.19007158223655718, -0.3531705720817957, 4.47161902765271],
    ),
    (
        (0.811, 0.108, 2.335202),
        (0.668, -0.302, 4.282959),
        "RSL",
        (1.486181730462583, 0.44597454247209506, 0.18555323830870707),
        [1.3065272299434278, 0.4259279158616986, 5.088871455107277],
    ),
    (
        (-0.543, -0.952, 4.373845),
        (-0.326, -0.316, 1.733159),
        "LSR",
        (1.2057742806143796, 0.5547943652606867, 0.11302448846050388),
        [0.02100609555804378, -1.1566090144056143, 1.2133149167130313],
    ),
    (
        (-0.497, 0.14, 2.097681),
        (-0.149, -0.596, 3.174012),
        "RSR",
        (1.060429061060974, 0.5922975999319168, 0.5016272310929021),
        [0.06186817756230251, 0.314249210701656, 4.846102770309673],
    ),
    (
        (0.171, -0.159, 2.534931),
        (0.888, -0.904, 2.048782),
        "LSL",
        (0.8853116146023732, 0.8897383002097906, 0.8537992775515028),
        [0.08515942855821448, -0.9220703642982782, 5.485969715341244],
    ),
    (
        (0.038, 0.197, 0.265748),
        (-0.517, -0.891, 0.048574),
        "RSL",
        (1.072454695551491, 0.5561037938472081, 1.007302495551491),
        [-0.17526843197855985, -0.34734265646141876, 2.974084322007949],
    ),
]


@pytest.mark.parametrize(("start", "end", "word", "segments", "middle"), SIGNED)
def test_signed_golden_cases(start: Pose, end: Pose, word: str, segments: tuple, middle: list) -> None:
    path = dubins_path(start, end, radius=R)
    assert path.word == word
    assert path.segments == pytest.approx(segments, rel=1e-12, abs=1e-12)
    assert path.sample(np.linspace(0.0, path.length, 5))[2] == pytest.approx(middle, rel=1e-12, abs=1e-12)


@pytest.mark.parametrize(("start", "end", "word", "segments", "middle"), UNSIGNED)
def test_unsigned_golden_cases(start: Pose, end: Pose, word: str, segments: tuple, middle: list) -> None:
    path = dubins_path(start, end, radius=0.3, headings="unsigned")
    assert path.word == word
    assert path.segments == pytest.approx(segments, rel=1e-12, abs=1e-12)
    assert path.sample(np.linspace(0.0, path.length, 5))[2] == pytest.approx(middle, rel=1e-12, abs=1e-12)


# --------------------------------------------------------------------------------------------------
# An independent solver: turning circles and their tangents, both CCC branches


def _centre(pose: Pose, turn: float, radius: float) -> np.ndarray:
    """Centre of the turning circle of ``pose``; ``turn`` +1 left, -1 right."""
    x, y, h = pose
    return np.array([x - turn * radius * math.sin(h), y + turn * radius * math.cos(h)])


def _csc(start: Pose, end: Pose, s1: float, s2: float, radius: float) -> float:
    """Length of the arc-straight-arc path with turns ``s1``, ``s2`` (inf when it does not exist)."""
    c1, c2 = _centre(start, s1, radius), _centre(end, s2, radius)
    k = radius * (s2 - s1)
    span = c2 - c1
    straight2 = float(span @ span) - k * k
    if straight2 < 0.0:
        return math.inf
    straight = math.sqrt(straight2)
    phi = math.atan2(span[1], span[0]) - math.atan2(k, straight)
    first = math.remainder(s1 * (phi - start[2]), TWO_PI) % TWO_PI
    last = math.remainder(s2 * (end[2] - phi), TWO_PI) % TWO_PI
    return radius * (first + last) + straight


def _ccc(start: Pose, end: Pose, s: float, radius: float) -> float:
    """Shortest arc-arc-arc path turning ``s``, ``-s``, ``s`` over both middle circles (inf if none)."""
    c1, c3 = _centre(start, s, radius), _centre(end, s, radius)
    span = c3 - c1
    dist = math.hypot(*span)
    if dist > 4.0 * radius or dist == 0.0:
        return math.inf
    theta, alpha = math.atan2(span[1], span[0]), math.acos(dist / (4.0 * radius))
    best = math.inf
    for sign in (1.0, -1.0):
        c2 = c1 + 2.0 * radius * np.array([math.cos(theta + sign * alpha), math.sin(theta + sign * alpha)])
        # the tangent points are the midpoints, and a pose p on circle c turning s has
        # p = c + s r (sin h, -cos h), so (sin h, -cos h) = s (p - c) / r
        n1, n2 = (c2 - c1) / (2.0 * radius), (c2 - c3) / (2.0 * radius)
        h1 = math.atan2(s * n1[0], -s * n1[1])
        h2 = math.atan2(s * n2[0], -s * n2[1])
        arcs = (s * (h1 - start[2]), -s * (h2 - h1), s * (end[2] - h2))
        best = min(best, radius * sum(a % TWO_PI for a in arcs))
    return best


def _brute_force_length(start: Pose, end: Pose, radius: float) -> float:
    """The shortest of all CSC and CCC candidates, built from circles and tangents."""
    lengths = [_csc(start, end, s1, s2, radius) for s1 in (1.0, -1.0) for s2 in (1.0, -1.0)]
    lengths += [_ccc(start, end, s, radius) for s in (1.0, -1.0)]
    return min(lengths)


@pytest.mark.parametrize("headings", ["signed", "unsigned"])
def test_lengths_match_an_independent_tangent_construction(headings: str) -> None:
    rng = np.random.default_rng(5)
    for _ in range(300):
        start = (*rng.uniform(-2.0, 2.0, 2), rng.uniform(-math.pi, 2 * math.pi))
        end = (*rng.uniform(-2.0, 2.0, 2), rng.uniform(-math.pi, 2 * math.pi))
        radius = float(rng.uniform(0.2, 1.5))
        path = dubins_path(start, end, radius=radius, headings=headings)  # type: ignore[arg-type]
        assert path.length == pytest.approx(_brute_force_length(start, end, radius), abs=1e-9)


# --------------------------------------------------------------------------------------------------
# Known answers and invariants


@pytest.mark.parametrize(
    ("end", "length", "word"),
    [
        ((100.0, 0.0, 0.0), 100.0, None),  # straight
        ((100.0, 100.0, math.pi / 2), math.pi * R / 2, None),  # left quarter circle
        ((100.0, -100.0, -math.pi / 2), math.pi * R / 2, None),  # right quarter circle
        ((0.0, 200.0, math.pi), math.pi * R, None),  # left half circle
        ((150.0, 100.0, math.pi / 2), 50.0 + math.pi * R / 2, "LSL"),  # straight then quarter circle
    ],
)
def test_known_lengths(end: Pose, length: float, word: str | None) -> None:
    path = dubins_path((0.0, 0.0, 0.0), end, radius=R)
    assert path.length == pytest.approx(length, abs=1e-9)
    if word is not None:
        assert path.word == word
    ex, ey, eh = path.end()
    assert (ex, ey) == pytest.approx(end[:2], abs=1e-9)
    assert float(wrap_angle(eh - end[2])) == pytest.approx(0.0, abs=1e-9)


@pytest.mark.parametrize(
    ("goal", "length", "centre"),
    [
        ((0.3, 0.0, 0.0), 0.3, None),  # straight ahead
        ((0.1, 0.1, math.pi / 2), math.pi * 0.1 / 2, (0.0, 0.1)),  # quarter circle to the left
        ((0.1, -0.1, -math.pi / 2), math.pi * 0.1 / 2, (0.0, -0.1)),  # quarter circle to the right
        ((0.0, 0.2, math.pi), math.pi * 0.1, (0.0, 0.1)),  # half circle to the left
    ],
)
def test_unsigned_samples_lie_on_the_turning_circle(goal: Pose, length: float, centre: tuple | None) -> None:
    path = dubins_path((0.0, 0.0, 0.0), goal, radius=0.1, headings="unsigned")
    assert path.length == pytest.approx(length, abs=1e-12)
    end = path.end()
    assert end[:2] == pytest.approx(goal[:2], abs=1e-12)
    assert math.remainder(end[2] - goal[2], TWO_PI) == pytest.approx(0.0, abs=1e-12)
    pts = path.sample_evenly(0.005)
    assert np.all((pts[:, 2] >= 0.0) & (pts[:, 2] < TWO_PI))
    if centre is None:
        assert np.allclose(pts[:, 1], 0.0)
        assert np.allclose(pts[:, 2], 0.0)
    else:
        assert np.allclose(np.hypot(pts[:, 0] - centre[0], pts[:, 1] - centre[1]), 0.1, atol=1e-12)


def test_lane_change_is_a_symmetric_s_curve() -> None:
    # (0,0,0) -> (150, 50, 0): arc theta, straight s, arc -theta with 2R(1 - cos t) + s sin t = 50 and
    # 2R sin t + s cos t = 150; solve for t by bisection and compare the total length 2 R t + s.
    def lateral(t: float) -> float:
        s = (150.0 - 2 * R * math.sin(t)) / math.cos(t)
        return 2 * R * (1 - math.cos(t)) + s * math.sin(t) - 50.0

    lo, hi = 1e-6, 0.8
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if lateral(mid) < 0 else (lo, mid)
    t = 0.5 * (lo + hi)
    s = (150.0 - 2 * R * math.sin(t)) / math.cos(t)
    path = dubins_path((0.0, 0.0, 0.0), (150.0, 50.0, 0.0), radius=R)
    assert path.word == "LSR"
    assert path.segments == pytest.approx((R * t, s, R * t), abs=1e-6)
    assert path.turning == pytest.approx(2 * t, abs=1e-9)


def test_random_poses_reach_their_goal_with_bounded_curvature() -> None:
    rng = np.random.default_rng(7)
    for _ in range(200):
        start = (*rng.uniform(-300, 300, 2), rng.uniform(-math.pi, math.pi))
        end = (*rng.uniform(-300, 300, 2), rng.uniform(-math.pi, math.pi))
        path = dubins_path(start, end, radius=R)
        assert path.length >= math.hypot(end[0] - start[0], end[1] - start[1]) - 1e-9
        poses = path.sample(np.linspace(0.0, path.length, 400))
        assert poses[0, :2] == pytest.approx(start[:2], abs=1e-9)
        assert poses[-1, :2] == pytest.approx(end[:2], abs=1e-6)
        assert np.all((poses[:, 2] >= -math.pi) & (poses[:, 2] < math.pi))
        # heading changes by at most ds / R between samples (curvature bound), positions follow headings
        ds = path.length / 399
        dh = np.abs(wrap_angle(np.diff(poses[:, 2])))
        assert np.all(dh <= ds / R + 1e-9)
        step = np.linalg.norm(np.diff(poses[:, :2], axis=0), axis=1)
        assert np.all(step <= ds + 1e-9)


def test_even_samples_respect_the_spacing() -> None:
    rng = np.random.default_rng(11)
    for _ in range(300):
        a = (*rng.uniform(-1, 1, 2), rng.uniform(0, TWO_PI))
        b = (*rng.uniform(-1, 1, 2), rng.uniform(0, TWO_PI))
        radius = float(rng.uniform(0.05, 0.5))
        path = dubins_path(a, b, radius=radius, headings="unsigned")
        pts = path.sample_evenly(0.01)
        assert pts.shape[0] == max(2, math.ceil(path.length / 0.01 - 1e-9) + 1)
        assert pts[0] == pytest.approx(a, abs=1e-12)
        assert pts[-1, :2] == pytest.approx(b[:2], abs=1e-9)
        step = np.linalg.norm(np.diff(pts[:, :2], axis=0), axis=1)
        assert step.max() <= 0.01 + 1e-12


def test_both_ranges_give_the_same_curve() -> None:
    rng = np.random.default_rng(3)
    for _ in range(100):
        a = (*rng.uniform(-1, 1, 2), rng.uniform(0, TWO_PI))
        b = (*rng.uniform(-1, 1, 2), rng.uniform(0, TWO_PI))
        signed = dubins_path(a, b, radius=0.2)
        unsigned = dubins_path(a, b, radius=0.2, headings="unsigned")
        assert signed.word == unsigned.word
        assert signed.segments == pytest.approx(unsigned.segments, abs=1e-12)
        s = np.linspace(0.0, signed.length, 20)
        p, q = signed.sample(s), unsigned.sample(s)
        assert p[:, :2] == pytest.approx(q[:, :2], abs=1e-12)
        assert np.allclose(wrap_angle(p[:, 2] - q[:, 2]), 0.0, atol=1e-12)


def test_wrap_angle_ranges() -> None:
    angles = np.array([-3 * math.pi, -math.pi, -0.5, 0.0, math.pi, 7.0])
    assert np.allclose(wrap_angle(angles), [-math.pi, -math.pi, -0.5, 0.0, -math.pi, 7.0 - TWO_PI])
    assert np.allclose(wrap_angle(angles, "unsigned"), [math.pi, math.pi, TWO_PI - 0.5, 0.0, math.pi, 7.0 - TWO_PI])


def test_rejects_bad_input() -> None:
    with pytest.raises(ProblemError):
        dubins_path((0.0, 0.0, 0.0), (1.0, 0.0, 0.0), radius=0.0)
    with pytest.raises(ProblemError):
        dubins_path((0.0, 0.0, 0.0), (math.nan, 0.0, 0.0), radius=1.0)
    with pytest.raises(ProblemError, match="spacing"):
        DubinsPath((0.0, 0.0, 0.0), "LSL", (0.0, 1.0, 0.0), 1.0).sample_evenly(0.0)
