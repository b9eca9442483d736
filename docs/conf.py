"""Sphinx configuration of bt_nav's documentation site (``make docs``; CI builds it with warnings as errors).

The pages are Markdown (MyST, as py_trees and rosdoc2 read it); the reference pages (parameters, commands,
worlds, the judges' checks) are generated from the code when the build starts (``_ext/bt_nav_reference.py``).
"""

from __future__ import annotations

import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
sys.path[:0] = [str(DOCS / "_ext"), str(DOCS.parent), str(DOCS.parent / "sim")]

project = "bt_nav"
author = "bt_nav developers"
copyright = "2026, bt_nav developers"  # noqa: A001 - Sphinx's name
extensions = ["myst_parser", "bt_nav_reference"]
source_suffix = {".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build", "tree/*.dot"]
myst_enable_extensions = ["colon_fence"]
myst_heading_anchors = 4
html_theme = "alabaster"
html_title = "bt_nav"
html_static_path: list[str] = []
