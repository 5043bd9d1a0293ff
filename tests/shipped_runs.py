"""Running a shipped scene through `pneuma-inflate --scene NAME` and checking what it wrote (test_shipped_runs.py
for the 2D scenes, test_shipped_runs_3d.py for the 3D ones: two files, so the two test workers share them)."""

import json

import imageio.v3 as iio
import imageio_ffmpeg
import numpy as np
from renderers import SOFTWARE

import taichi_pneuma as tp
from taichi_pneuma.apps.cli import MIN_FRAME_3D
from taichi_pneuma.apps.inflate import main
from taichi_pneuma.fem.self_intersection import surface_crossing
from taichi_pneuma.scene.shipped import shipped

DIMENSIONS = {name: tp.load_scene(name).dim for name in shipped()}
SIZE = {2: (192, 96), 3: MIN_FRAME_3D}  # the smallest 3D frame the apps take


def runs_and_writes_its_pictures(name: str, flags: list[str], out, capsys) -> None:
    """The shipped scene `name` with flags exits 0 and writes its frame PNG (of --size), plot PNG and video (a frame
    per step); its summary has every step converged, each chamber's term, fibres where it has them and a contact
    entry per obstacle, all the ramp's steps or, declared (schedule.ends_at_limit_point), a stop at its limit point;
    and at every saved step (its states npz), no two pieces of the body's surface cross and no obstacle overlaps the
    body (apart_at_every_step)."""
    scene = tp.load_scene(name)
    width, height = SIZE[scene.dim]
    code = main(
        ["--scene", name, *flags, "--renderer", SOFTWARE, "--size", f"{width}x{height}", "--quiet", "--out", str(out)]
    )
    printed = capsys.readouterr()
    assert code == 0, printed.err
    (path,) = out.glob(f"{name}*_summary.json")  # a run with --set names them in its stem
    summary, stem = json.loads(path.read_text()), path.name[: -len("_summary.json")]
    assert summary["all_converged"] and summary["steps"] >= 2
    if scene.ends_at_limit_point:  # balloon_pressure: it ends at its pressure peak, short of its last increment
        assert summary["stopped"]["reason"] == "limit point" and "stopped at the limit point" in printed.out
    else:
        assert "stopped" not in summary and summary["steps"] == scene.increments + 1
    chambers = {f"chamber:{chamber}" for chamber, _ in scene.geometry.chambers}
    assert chambers <= set(summary["terms"]) and ("fibers" in summary["terms"]) == bool(scene.fibers)
    assert len(summary["contact"]) >= len(scene.obstacles)
    ran = tp.load_scene(out / f"{stem}_scene.toml")  # the scene as run: its --set flags (a coarser mesh) applied
    apart_at_every_step(ran, np.load(out / f"{stem}_states.npz")["positions"], out / f"{stem}_history.csv")
    assert imageio_ffmpeg.count_frames_and_secs(str(out / f"{stem}.mp4"))[0] == summary["steps"]
    assert iio.imread(out / f"{stem}.png").shape == (height, width, 3)
    assert iio.imread(out / f"{stem}_plot.png").ndim == 3


def apart_at_every_step(scene, positions: np.ndarray, history) -> None:
    """The geometric check at every step k of a run's node positions (steps, n, d): no two pieces of the body's
    surface that share no node cross (surface_crossing), and each obstacle, where its keyframes (a held object: its
    height, the history's '<name>.dy') put it at step k, overlaps no piece of the surface nor lies inside the body
    (ObstacleContact.overlap)."""
    built = scene.build()
    rest = built.model.config.rest
    lines = history.read_text().splitlines()
    names = [column.split(" ")[0] for column in lines[0].split(",")]
    rows = [line.split(",") for line in lines[1:]]
    heights = {
        o.name: [float(row[names.index(f"{o.name}.dy")]) for row in rows]
        for o in scene.obstacles
        if f"{o.name}.dy" in names
    }
    for k, x in enumerate(positions):
        crossing = surface_crossing(x, built.surface_pieces)
        assert crossing is None, f"step {k}: pieces {crossing.first} and {crossing.second} cross"
        built.model.set_displacements(x - rest)
        for term, spec in zip(built.obstacles, scene.obstacles, strict=True):
            height = heights[spec.name][k] if spec.name in heights else 0.0
            term.set_offset(spec.offset(float(k)) + np.array([0.0, height, 0.0]))
            assert term.overlap() is None, f"step {k}: {term.overlap()}"
