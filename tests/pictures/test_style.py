"""The plan picture's palette: matplotlib colours, the benchmark's edge colours, the extra's install command."""

from __future__ import annotations

import pytest

from drd_planner.bench.extras import install_hint
from drd_planner.bench.plots import COLOURS as BENCH_COLOURS
from drd_planner.pictures.style import (
    COLOURS,
    DPI,
    EXTRA_COLOURS,
    PLOTS_INSTALL_HINT,
    TERRAIN_CMAP,
    TERRAIN_CMAP_TOP,
)


def test_edge_colours_match_the_benchmark_figures() -> None:
    # A plan picture and a Fig. 3 panel read alike: the copy must not drift from bench.plots.
    assert COLOURS == BENCH_COLOURS


def test_every_colour_is_a_distinct_matplotlib_colour() -> None:
    colors = pytest.importorskip("matplotlib.colors")
    every = [*COLOURS.values(), *EXTRA_COLOURS.values()]
    assert all(colors.is_color_like(c) for c in every)
    assert len({colors.to_hex(c) for c in every}) == len(every)
    cmaps = pytest.importorskip("matplotlib").colormaps
    assert TERRAIN_CMAP in cmaps
    assert 0.0 < TERRAIN_CMAP_TOP <= 1.0
    assert DPI > 0


def test_install_hint_is_the_plots_extra() -> None:
    assert PLOTS_INSTALL_HINT == install_hint("plots")
