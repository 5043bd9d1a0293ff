"""The software renderer the tests draw with: Taichi's ti.GUI, or Pillow where the backend has no GUI (Quadrants)."""

import pytest

from taichi_pneuma.backend import has_gui

SOFTWARE = "gui" if has_gui() else "pillow"
# the live windows are Taichi's (ti.GUI, GGUI); where the backend has neither they refuse (test_render.py)
needs_window = pytest.mark.skipif(not has_gui(), reason="a live window needs Taichi's ti.GUI, which this backend lacks")
