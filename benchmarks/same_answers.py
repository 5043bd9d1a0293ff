"""Old against new: every figure of two runs of benchmarks/scenes.py (each shipped scene as shipped, one process
each) compared, scene by scene.

Each scene's summary JSON is walked and every number in it compared (timings, which differ from run to run, left
out: any key under a key with "seconds", "_s" or "per_second" in its name, and the scene's file hash), as
|new - old| <= rtol |old| + atol * (the largest magnitude of that scene's figures): the solver's tolerance (Newton
stops at a relative residual of 1e-6; multi-threaded assembly changes the last digits from run to run). A figure in
one run and not in the other, a scene that exits differently or one the new run lacks is a difference too (a scene
only the new run has is listed as added).

    python benchmarks/scenes.py --out /tmp/old     (on the old tree)
    python benchmarks/scenes.py --out /tmp/new     (on the new tree)
    python benchmarks/same_answers.py /tmp/old/scenes.json /tmp/new/scenes.json [--rtol 1e-5]

Prints a line per scene (its largest relative difference and where) and exits 1 if any scene differs.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

TIMINGS = ("seconds", "_s", "per_second", "sha256", "fps")


def numbers(value, path: str = "") -> dict[str, float]:
    """Every number in a JSON value by its dotted path (timings left out)."""
    if isinstance(value, bool) or value is None or isinstance(value, str):
        return {path: value} if isinstance(value, bool | str) and "sha256" not in path else {}
    if isinstance(value, int | float):
        return {} if any(t in part for part in path.split(".") for t in TIMINGS) else {path: float(value)}
    if isinstance(value, dict):
        return {k: v for key, item in value.items() for k, v in numbers(item, f"{path}.{key}" if path else key).items()}
    if isinstance(value, list):
        return {k: v for i, item in enumerate(value) for k, v in numbers(item, f"{path}[{i}]").items()}
    return {}


def compare(old: dict, new: dict, rtol: float, atol: float) -> tuple[bool, str]:
    """Whether two runs of one scene agree, and a line saying by how much."""
    if old.get("exit") != new.get("exit"):
        return False, f"exit {old.get('exit')} -> {new.get('exit')}"
    a, b = numbers(old.get("summary") or {}), numbers(new.get("summary") or {})
    if set(a) != set(b):
        return False, f"figures differ: only old {sorted(set(a) - set(b))[:3]}, only new {sorted(set(b) - set(a))[:3]}"
    scale = max((abs(v) for v in a.values() if isinstance(v, float)), default=0.0)
    worst, where, same = 0.0, "", True
    for key, x in a.items():
        y = b[key]
        if not isinstance(x, float) or not isinstance(y, float):
            if x != y:
                return False, f"{key}: {x!r} -> {y!r}"
            continue
        gap = abs(y - x)
        same &= gap <= rtol * abs(x) + atol * scale
        relative = gap / max(abs(x), atol * scale, 1e-300)
        if relative > worst:
            worst, where = relative, f"{key} {x:.9g} -> {y:.9g}"
    return same, f"{len(a)} figures, largest relative difference {worst:.2e}" + (f" ({where})" if where else "")


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("old")
    p.add_argument("new")
    p.add_argument("--rtol", type=float, default=1e-5)
    p.add_argument("--atol", type=float, default=1e-8, help="a fraction of the scene's largest figure")
    args = p.parse_args()
    runs = [{r["scene"]: r for r in json.loads(Path(path).read_text())["runs"]} for path in (args.old, args.new)]
    differing = 0
    for scene in sorted(set(runs[0]) | set(runs[1])):
        if scene not in runs[0]:
            print(f"{scene}: only in the new run (a scene added)")
            continue
        if scene not in runs[1]:
            print(f"{scene}: only in the old run (a scene lost)")
            differing += 1
            continue
        same, line = compare(runs[0][scene], runs[1][scene], args.rtol, args.atol)
        differing += not same
        print(f"{scene}: {'same' if same else 'DIFFERS'}; {line}")
    print(f"{len(set(runs[0]) & set(runs[1]))} scenes compared, {differing} differ")
    return 1 if differing else 0


if __name__ == "__main__":
    sys.exit(main())
