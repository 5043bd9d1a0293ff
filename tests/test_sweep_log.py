"""pneuma-sweep's log shows a swept value as a person typed it, not with np.linspace's round-off; the CSV keeps the
exact value the run used."""

import csv

import numpy as np

from taichi_pneuma.apps import sweep
from taichi_pneuma.study.table import shown


def test_a_linspace_value_is_printed_to_12_digits_and_kept_exact_in_the_csv(tmp_path, capsys):
    middle = np.linspace(-0.5, 0.65, 3)[1].item()
    assert middle != 0.075 and abs(middle - 0.075) < 1e-15  # the round-off this is about (0.07499999999999996)
    # the ends put the chamber outside the beam: two error rows at once, one tiny run at cy = 0.075
    flags = ["--vary", "cy=-0.5:0.65:3", "--max-area", "0.02", "--growth", "1.2", "--steps", "2", "--workers", "1"]
    assert sweep.main([*flags, "--out", str(tmp_path), "--name", "s"]) == 0
    printed = capsys.readouterr().out
    assert "  cy = 0.075: tip dy" in printed and "  cy = -0.5: error:" in printed and "  cy = 0.65: error:" in printed
    assert "0.0749999" not in printed
    with open(tmp_path / "s.csv", newline="") as table:
        values = sorted(float(row["chambers[0].center[1]"]) for row in csv.DictReader(table))
    assert values == [-0.5, middle, 0.65]  # every digit kept


def test_shown_values_are_rounded_to_12_significant_digits_only_where_they_are_floats():
    assert shown(0.1 + 0.2) == "0.3" and shown(1 / 3) == "0.333333333333" and shown(2e-7) == "2e-07"
    assert shown(10_000) == "10000" and shown(True) == "True" and shown("soft") == "soft"
    assert shown([0.07499999999999998, 3]) == "[0.075, 3]"
