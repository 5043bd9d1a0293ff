"""The history's measured columns are one registry (solve/columns.py COLUMNS): a column added there alone reaches
the CSV (its header's unit and its place in the row), the summary's extremes and its plot panel."""

import csv
import dataclasses
import io
import math

import numpy as np
from scenes import small_scene

import taichi_pneuma as tp
from taichi_pneuma.io.units import LENGTH, UNITS
from taichi_pneuma.render.plots import history_panels
from taichi_pneuma.solve import columns


def test_a_new_history_column_is_one_entry(monkeypatch):
    """The tip's distance from rest, |(tip_dx, tip_dy)|, registered as one Column: the CSV gives it in mm after the
    solver's figures, equal to the hypotenuse of the tip's own columns at every step; the summary gives its range
    (0 at rest, the largest distance at the step the tip columns say); the deflection panel draws it, named."""
    distance = columns.Column(
        "tip_distance",
        LENGTH,
        lambda state: float(np.linalg.norm(state.tip[0])),
        extremes=True,
        panel="deflection",
        label="distance from rest",
    )
    monkeypatch.setattr(columns, "COLUMNS", (*columns.COLUMNS, distance))
    result = tp.simulate(dataclasses.replace(small_scene(), units=UNITS["mm-kPa"]))

    header, *rows = list(csv.reader(io.StringIO(result.history_csv())))
    assert header[header.index("max_stretch") + 1 : header.index("max_stretch") + 3] == [
        "tip_distance [mm]",
        "seconds [s]",
    ]
    table = {name: np.array([float(row[header.index(name)]) for row in rows]) for name in header if "tip" in name}
    expected = np.hypot(table["tip_dx [mm]"], table["tip_dy [mm]"])
    np.testing.assert_allclose(table["tip_distance [mm]"], expected, rtol=1e-14, atol=0)
    assert expected[-1] > 0.01  # the ramp moves the tip

    extremes = result.summary()["extremes"]["tip_distance"]
    assert extremes["min"] == 0.0 and extremes["min_step"] == 0
    assert math.isclose(extremes["max"], expected.max(), rel_tol=1e-14)
    assert extremes["max_step"] == int(np.argmax(expected))

    (panel,) = [p for p in history_panels(result) if p.title.startswith("tip deflection")]
    assert panel.title.endswith("and distance from rest")
    assert [label for label, *_ in panel.curves] == ["", "distance from rest"]
    np.testing.assert_array_equal(panel.curves[1][2], result.history["tip_distance"])
