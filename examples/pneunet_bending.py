"""A PneuNet-style actuator's bending angle against pressure, in mm and kPa (taichi_pneuma/scenes/pneunet_mm_kpa.toml).

    python examples/pneunet_bending.py [OUT]        (default OUT: out; writes OUT/pneunet_bending.csv and .png)
    python examples/pneunet_bending.py OUT --study  (also the mesh study: P1 and P2 triangles at three sizes)

The bending angle is minus the tip's rotation (the right edge's least-squares rotation, degrees): the actuator
curls towards its paper layer. The study refines the mesh with the paper band kept at half a triangle's height
(so that it always holds the triangles whose edge lies on the bottom: an inextensible line, not a plate).
"""

import csv
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import taichi_pneuma as tp  # noqa: E402

SCENE = Path(__file__).resolve().parent.parent / "taichi_pneuma" / "scenes" / "pneunet_mm_kpa.toml"
STUDY = [(1, 0.8), (1, 0.4), (1, 0.2), (2, 0.8), (2, 0.4)]  # (element order, max triangle area mm^2)


def bending(scene) -> tuple[np.ndarray, np.ndarray, tp.Result]:
    """(pressure kPa, bending angle deg) at every step of the scene's ramp, and the run."""
    result = tp.simulate(scene)
    if not result.converged:
        sys.exit(f"{scene.name}: a step did not converge")
    return result.pressure[:, 0], 0.0 - result.history["tip_rotation"], result


def refined(scene, order: int, max_area: float):
    """The scene meshed with elements of `order` no larger than max_area, its paper band half a triangle high."""
    band = 0.5 * np.sqrt(np.sqrt(3.0) * max_area)  # an equilateral triangle of area A is sqrt(sqrt(3) A) high
    return scene.with_values({"mesh.order": order, "mesh.max_area": max_area, "material.regions[0].box[3]": band})


def main(out: Path, study: bool) -> None:
    out.mkdir(parents=True, exist_ok=True)
    scene = tp.load_scene(SCENE)
    pressure, angle, result = bending(scene)
    runs = {f"shipped (P{scene.geometry.order}, {scene.geometry.max_area:g} mm^2)": angle}
    if study:
        for order, area in STUDY:
            runs[f"P{order}, {area:g} mm^2"] = bending(refined(scene, order, area))[1]
    with open(out / "pneunet_bending.csv", "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(["pressure [kPa]", *(f"bending angle [deg] {name}" for name in runs)])
        writer.writerows(np.column_stack([pressure, *runs.values()]).round(4).tolist())
    fig, ax = plt.subplots(figsize=(6, 4), layout="constrained")
    for name, values in runs.items():
        ax.plot(pressure, values, "o-" if name.startswith("shipped") else ".--", label=name)
    ax.set(
        xlabel="pressure [kPa]",
        ylabel="bending angle (tip rotation) [deg]",
        title="PneuNet section: Elastosil M4601, paper layer (plane strain)",
    )
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize="small")
    fig.savefig(out / "pneunet_bending.png", dpi=100)
    for p, a in zip(pressure, angle):
        print(f"p = {p:6.1f} kPa: bending angle {a:6.2f} deg")
    print(
        f"wrote {out / 'pneunet_bending.csv'}, {out / 'pneunet_bending.png'} ({result.seconds:.1f} s for the shipped "
        f"scene, {result.mesh.n_vertices} nodes)"
    )


if __name__ == "__main__":
    arguments = [a for a in sys.argv[1:] if a != "--study"]
    main(Path(arguments[0] if arguments else "out"), "--study" in sys.argv[1:])
