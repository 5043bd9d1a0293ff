"""A study's table: one CSV row per run, its columns the varied keys, the run's figures, converged, seconds and
error. A value is written as a cell a spreadsheet shows as it is and read back exactly (cell, uncell); a study run
again reads its rows back (read_done) and keeps those a run could have made, so that only the others run again.
"""

from __future__ import annotations

import csv
import io
import json
import math
import os
from pathlib import Path

from ..errors import PneumaInputError, require
from ..fem.tip import COLUMNS as TIP_COLUMNS
from ..io.inputs import read_input
from ..io.output import FORMULA, write_atomic

MAX_CELL = 10_000  # characters of a varied value in the CSV (csv reads fields of at most 131,072)
MAX_RECORD_BYTES = 256_000_000  # the most of a study's CSV or JSON read back


def is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def cell(value) -> str:
    """CSV text of a value: '' for none, words as they are, numbers and booleans as JSON (exact floats); a
    word a spreadsheet would read as a formula (starting with one of FORMULA), or that reads as JSON, as a
    JSON string ("=1+1" in quotes): uncell reads every one back."""
    if value is None:
        return ""
    if not isinstance(value, str):
        return json.dumps(value)
    return json.dumps(value, ensure_ascii=False) if value.startswith(FORMULA) or uncell(value) != value else value


def shown(value) -> str:
    """A varied value as the log and the figure show it: a float to 12 significant digits (np.linspace's round-off,
    0.07499999999999998, shown as 0.075), a list item by item, anything else as str; the CSV and the JSON keep
    every digit (cell)."""
    if isinstance(value, float):
        return f"{value:.12g}"
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(shown(item) for item in value) + "]"
    return str(value)


def uncell(text: str):
    """The value of a CSV cell (cell's inverse)."""
    if text == "":
        return None
    try:
        return json.loads(text)
    except (ValueError, RecursionError):
        return text


def run_key(values: dict) -> tuple:
    return tuple(cell(v) for v in values.values())


def table_columns(keys: list[str], base) -> list[str]:
    """The CSV's columns for a study of the Scene `base` varying `keys`: the keys, the tip's figures (tip_dz and the
    twist tip_twist for a 3D body), the blocked force (a scene with obstacles), each chamber's area ratio and peak
    pressure (named after the base scene's chambers), then converged, iterations, increments, vertices, seconds
    and error."""
    tip = [*TIP_COLUMNS[:2], "tip_rotation", *TIP_COLUMNS[2 : base.dim]]
    tip += (["tip_twist"] if base.dim == 3 else []) + (["blocked_force"] if base.obstacles else [])
    figures = tip + [f"{c}.{f}" for c in base.chamber_names for f in ("area_ratio", "peak_pressure")]
    return keys + figures + ["converged", "iterations", "increments", "vertices", "seconds", "error"]


def write_table(path: Path, columns: list[str], rows: list[dict]) -> Path:
    """The CSV of these rows, written whole (or not at all)."""
    writer_rows = [[cell(row.get(c)) for c in columns] for row in rows]

    def write(tmp):
        with open(tmp, "w", newline="", encoding="utf-8") as f:
            csv.writer(f).writerows([columns] + writer_rows)

    return write_atomic(path, write)


def read_done(
    table: Path, record: Path, identity: dict, columns: list[str], keys: list[str], retry_failed: bool = False
) -> dict[tuple, dict]:
    """Rows of a previous run of a study, by their values (the cells of `keys`): none where there is no table;
    refused where the table's columns or its JSON record's `identity` entries are not the study's. The CSV and
    JSON are read back within MAX_RECORD_BYTES and not through a link; a row that is not one the study writes (a
    cut-off last line, a tampered one: a figure that is no finite number) is dropped, so that its run runs
    again, and so is a failed one if retry_failed."""
    if not os.path.lexists(table):
        return {}
    try:
        previous = json.loads(read_input(record, MAX_RECORD_BYTES, "study record", follow_links=False))
        same = isinstance(previous, dict) and all(previous.get(k) == v for k, v in identity.items())
        text = read_input(table, MAX_RECORD_BYTES, "study table", follow_links=False).decode("utf-8")
        reader = csv.DictReader(io.StringIO(text, newline=""))
        same = same and reader.fieldnames == columns
        rows = [row for row in reader if None not in row.values() and None not in row]
    except (PneumaInputError, ValueError, RecursionError, csv.Error):
        same = False
    require(
        same,
        f"{table} holds another study (other keys, base scene or solver options), or it or its "
        f"JSON is missing, damaged or not a plain file; give another --name or --out, or delete it",
    )
    done = {}
    for raw in rows:
        row = {k: uncell(v) for k, v in raw.items()}
        if well_formed(row, columns, keys) and not (retry_failed and row["error"] is not None):
            done[tuple(raw[k] for k in keys)] = row
    return done


def well_formed(row: dict, columns: list[str], keys: list[str]) -> bool:
    """Whether a row read back is one run_task could have made: its figures finite numbers (or empty, for
    a run that failed before any step), converged a boolean, the error a string."""
    figures = columns[len(keys) : -1]
    numbers = [row[k] for k in figures if k != "converged"]
    if not all(v is None or (is_number(v) and math.isfinite(v)) for v in numbers):
        return False
    if row["error"] is None:
        return row["converged"] in (True, False) and None not in numbers
    return row["converged"] in (None, True, False) and isinstance(row["error"], str)
