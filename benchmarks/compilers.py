"""Taichi against Quadrants (the kernels' two compilers) in one run: pneuma-bench's startup and breakdown sections
run in child processes under each compiler installed (PNEUMA_BACKEND set), side by side.

    python benchmarks/compilers.py [--out DIR]     (writes bench_compilers.md and .json)
"""

import importlib.util
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

from taichi_pneuma.apps.bench import PROCESSES, markdown
from taichi_pneuma.errors import require

sys.path.insert(0, str(Path(__file__).resolve().parent))
from sections import main  # noqa: E402


def compilers() -> tuple[str, dict]:
    """Taichi against Quadrants in one run: for each one installed, in child processes with PNEUMA_BACKEND set,
    the startup section (the main command from an empty and a warm kernel cache) and the breakdown section twice
    (the second's first solve loads every kernel from the warm cache): the first calls of the kernels and the ramp."""
    from taichi_pneuma import backend

    empty, warm = (label for label, _ in PROCESSES[:2])  # the main command --no-video, empty and warm cache
    rows, data = [], {}
    for name in backend.INSTALL:
        if importlib.util.find_spec(name) is None:
            rows.append([name, "not installed"] + [""] * 7)
            continue
        sections = {}
        with tempfile.TemporaryDirectory() as out:
            for section in ("breakdown", "breakdown", "startup"):
                command = [sys.executable, "-m", "taichi_pneuma.apps.bench", "--sections", section, "--out", out]
                proc = subprocess.run(
                    command, env={**os.environ, backend.CHOICE_VARIABLE: name}, capture_output=True, text=True
                )
                require(proc.returncode == 0, f"bench --sections {section} on {name} failed: {proc.stderr[-300:]}")
                sections[section] = json.loads((Path(out) / f"bench_{section}.json").read_text())
        process, ramp = sections["startup"]["data"]["process"], sections["breakdown"]["data"]
        data[name] = {
            "version": sections["breakdown"]["backend"],
            "startup": sections["startup"]["data"],
            "breakdown": ramp,
        }
        rows.append(
            [
                data[name]["version"],
                f"{process[empty]['whole_s']:.2f}",
                f"{process[warm]['whole_s']:.2f}",
                f"{process[warm]['first_increment_s']:.2f}",
                f"{1e3 * ramp['first_call_s']:.0f}",
                f"{1e3 * ramp['ramp_s']:.0f}",
                ramp["iterations"],
                f"{1e3 * ramp['ramp_s'] / ramp['iterations']:.1f}",
                f"{ramp['tip_deflection']:.15f}",
            ]
        )
    header = [
        "compiler",
        "main command, empty cache (s)",
        "warm cache (s)",
        "warm: to first increment (s)",
        "first solve, warm cache (ms)",
        "reference ramp (ms)",
        "Newton iterations",
        "ms/iteration",
        "tip dy",
    ]
    return markdown(header, rows), data


if __name__ == "__main__":
    main("compilers", __doc__, lambda out: compilers())
