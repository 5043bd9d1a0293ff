"""One thin-walled chamber with a limit point, driven four ways: its pressure-volume curves in one plot.

    python examples/balloon_curves.py [OUT]      (OUT: a directory, default out; writes balloon_curves.png and
                                                  balloon_curves.csv there, and prints what each drive did)

The shipped scenes taichi_pneuma/scenes/balloon_{volume,syringe,pressure}.toml are one body: a thin V-shaped wall
dented into its chamber, which pops out past a pressure peak. Volume control and the syringe follow the
whole curve through the pressure drop; the pressure regulator stops at the peak (no equilibrium near past
it); the same syringe through a dead volume of 3e5 mm^3 per mm of depth holds so much air that it is too soft
to hold the wall past the peak, and stops there too (docs/chambers.md).
"""

import csv
import sys
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import taichi_pneuma as tp
from taichi_pneuma.solve.simulate import RampFailed

SCENES = Path(__file__).resolve().parent.parent / "taichi_pneuma" / "scenes"
DRIVES = {  # label: (scene, changed keys)
    "volume control": ("balloon_volume.toml", {}),
    "syringe, dead volume 20": ("balloon_syringe.toml", {}),
    "pressure regulator": ("balloon_pressure.toml", {}),
    "syringe, dead volume 3e5": (
        "balloon_syringe.toml",
        {"chambers[0].dead_volume": 3e5, "chambers[0].syringe_volume": 300.0, "chambers[0].keyframes": [[36, 250.0]]},
    ),
}

out = Path(sys.argv[1] if len(sys.argv) > 1 else "out")
out.mkdir(parents=True, exist_ok=True)
fig, ax = plt.subplots(figsize=(7, 4.5), layout="constrained")
rows, curves = [], {}
for (label, (file, keys)), style in zip(DRIVES.items(), ("-", ".--", "o", "x")):
    try:
        result, stop = tp.simulate(tp.load_scene(SCENES / file).with_values(keys)), None
    except RampFailed as failure:
        result, stop = failure.result, str(failure)
    volume, pressure = result.area[:, 0], result.pressure[:, 0]
    falls = np.flatnonzero(np.diff(pressure) < 0)
    peak = falls[0] if len(falls) else len(pressure) - 1  # the limit point: where the pressure first falls
    print(
        f"{label}: {len(result.steps) - 1} increments, peak {pressure[peak]:.4f} kPa at {volume[peak]:.1f} mm^2, "
        + (
            f"stopped: {stop}"
            if stop
            else f"then down to {pressure[peak:].min():.4f} kPa; last {pressure[-1]:.4f} kPa at {volume[-1]:.1f} mm^2"
        )
    )
    curves[label] = volume, pressure
    ax.plot(volume, pressure, style, ms=4, label=label + (" (stops)" if stop else ""))
    rows += [
        {"drive": label, "step": s.step, "command": c[0], "volume": v, "pressure": p, "apex_dy": s.tip_dy}
        for s, c, v, p in zip(result.steps, result.command, volume, pressure)
    ]
volume, pressure = curves["volume control"]  # where a regulator at the peak pressure would snap the wall to
peak = np.flatnonzero(np.diff(pressure) < 0)[0]
rising = np.flatnonzero(np.diff(pressure) > 0)
after = rising[rising > peak][0]
landing = np.interp(pressure[peak], pressure[after:], volume[after:])
ax.annotate("", (landing, pressure[peak]), (volume[peak], pressure[peak]), arrowprops={"arrowstyle": "->", "ls": ":"})
ax.text((volume[peak] + landing) / 2, pressure[peak], "snap under pressure control", ha="center", va="bottom")
ax.set(
    xlabel="chamber volume per unit depth (mm^3 / mm)",
    ylabel="chamber pressure (kPa)",
    title="a dented thin wall pops out: its pressure peaks, drops, and rises again",
)
ax.grid(True, alpha=0.3)
ax.legend()
fig.savefig(out / "balloon_curves.png", dpi=100)
with open(out / "balloon_curves.csv", "w", newline="") as f:
    writer = csv.DictWriter(f, fieldnames=list(rows[0]))
    writer.writeheader()
    writer.writerows(rows)
print(f"wrote {out / 'balloon_curves.png'}, {out / 'balloon_curves.csv'}")
