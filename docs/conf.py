"""Sphinx configuration of the drd_planner docs (MyST Markdown pages, API by autodoc).

Build: ``sphinx-build -W --keep-going -b html docs build/docs`` from the repository root (the test job of
``scripts/run.sh`` does, warnings as errors).
"""

from __future__ import annotations

import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
REPO = DOCS.parent
# The checked-out sources first (not another install of the packages), then the docs' own extension.
for folder in (DOCS / "_ext", REPO / "ros2_ws/src/drd_msgs_py", REPO / "ros2_ws/src/drd_planner"):
    sys.path.insert(0, str(folder))

project = "drd_planner"
author = "drd_planner maintainers"
copyright = "drd_planner maintainers"

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",
    "drd_parameters",
]
source_suffix = {".md": "markdown"}
root_doc = "index"
# table1.md is included into results.md (its headings start at level 2), not a page of its own.
exclude_patterns = ["_build", "table1.md"]

myst_enable_extensions = ["colon_fence"]
myst_heading_anchors = 3

autodoc_member_order = "bysource"
autodoc_typehints = "description"
autodoc_default_options = {"members": True, "show-inheritance": True}
napoleon_google_docstring = True
napoleon_numpy_docstring = False

html_theme = "alabaster"
html_title = "drd_planner"
html_static_path: list[str] = []
