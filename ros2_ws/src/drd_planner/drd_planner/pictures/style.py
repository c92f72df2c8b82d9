"""The plan picture's colours, colour maps and resolution (its own palette, apart from the benchmark figures').

The four edge colours are those of the benchmark's figures (:mod:`drd_planner.bench.plots`), so a plan
picture and a Fig. 3 panel read alike; they are kept here so that the product's pictures import nothing from
the benchmark package. matplotlib colour specs throughout.
"""

from __future__ import annotations

__all__ = ["COLOURS", "DPI", "EXTRA_COLOURS", "PLOTS_INSTALL_HINT", "TERRAIN_CMAP", "TERRAIN_CMAP_TOP"]

#: Resolution of the figure and of the written PNGs (dots per inch): labels are placed in its pixels.
DPI = 150
#: Edge colours: library edges not checked, checked free, checked blocked, and the plan.
COLOURS = {"unchecked": "#c8c8c8", "free": "#2ca02c", "blocked": "#d62728", "path": "#1f4fd8"}
#: Colours of what else a picture shows: wires, solids, terrain and the arm.
EXTRA_COLOURS = {
    "wire": "#1a1a1a",
    "solid": "#7b3294",
    "terrain_line": "#6b4f2a",
    "terrain_fill": "#c9ad85",
    "arm": "#555555",
}
#: Terrain colour map, of which the light part up to :data:`TERRAIN_CMAP_TOP` is used.
TERRAIN_CMAP = "YlOrBr"
TERRAIN_CMAP_TOP = 0.55
#: What installs matplotlib (the package's ``plots`` extra) into an editable checkout.
PLOTS_INSTALL_HINT = "pip install -e 'ros2_ws/src/drd_planner[plots]'"
