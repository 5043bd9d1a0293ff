"""The result of a run: its records (solve/records.py) and what is made from them, the summary, the files
(history CSV, states npz, scene TOML, ParaView) and the pictures (video, plot)."""

from __future__ import annotations

import csv
import hashlib
import io
from dataclasses import fields
from pathlib import Path

import numpy as np

from . import limits
from .fem.tip import COLUMNS as TIP_COLUMNS
from .io.output import lock_stem, prepare_directory, save_json, save_npz, save_text, write_atomic
from .signals import holding
from .solve.columns import history_dimensions
from .solve.records import Run

ELEMENTS = {2: "triangles", 3: "tetrahedra"}  # the summary's element count, by dimension


def scene_sha256(*scenes) -> str:
    """The SHA-256 (hex) of the scenes' TOML as run (Scene.to_toml(), concatenated): a summary's scene_sha256."""
    return hashlib.sha256("".join(scene.to_toml() for scene in scenes).encode()).hexdigest()


def tip_place(scene) -> str:
    """Where the tip displacement is measured, in words: 'the right edge' (the tip's side; in 3D 'face'), or
    'the tip (box [x0, y0, x1, y1])' for a [tip] box."""
    tip = scene.geometry.tip
    if tip.box is not None:
        return f"the tip (box [{', '.join(f'{v:g}' for v in tip.box)}])"
    return f"the {tip.side} {'edge' if scene.dim == 2 else 'face'}"


class Result(Run):
    """A run (solve.records.Run: the built scene, its steps and positions, the figures read off them) with what
    is made from it: the summary, the history CSV and states npz, ParaView files, a video, a plot. One type for
    all runs: a ramp (tp.simulate), the steps a stopped ramp did (tp.RampFailed.result), the frames of a
    sequence of reaches (inverse.frames).

    Its arrays, with d = 2 for a plane body and 3 for a solid one, and n the mesh's nodes (mesh.n_vertices: its
    corners, and on a quadratic (P2) mesh its midside nodes too, in the order of mesh.vertices):
    positions (steps, n, d): the node positions per step, rest state first; displacements (steps, n, d): the
    same from the rest mesh; contact_forces (steps, n, d): the summed contact force per node (None without
    contact); command, area, area_ratio, pressure (steps, chambers): per chamber, in chamber_names' order;
    obstacle_positions() (steps, obstacles, 3): each obstacle's placed point; mesh.vertices (n, d): the rest
    nodes.
    """

    @classmethod
    def of(cls, run: Run) -> Result:
        """The Result of a run's records (the same objects, not copies)."""
        return run if isinstance(run, Result) else cls(**{f.name: getattr(run, f.name) for f in fields(run)})

    def summary(self, interrupted: bool = False) -> dict:
        """The figures of the run (the summary JSON); interrupted: the run was stopped after these steps. Besides
        the last step's values (contact: per contact term (fx, fy, magnitude), in 3D contact_fz; clamp: the clamp's
        reaction force and moment, StepRecord.clamp, when there is a clamp): extremes() (each with its step), the
        largest principal stretch over the run, its step and the scene's max_stretch (past which a run warns)."""
        final = self.steps[-1]
        stretch = self.history["max_stretch"]
        iterations, seconds = self.history["iterations"][1:], self.history["seconds"][1:]
        return {
            "scene": self.scene.name,
            "scene_sha256": scene_sha256(self.scene),
            "terms": self.built.model.term_names(),
            "vertices": self.mesh.n_vertices,
            ELEMENTS[self.mesh.dim]: self.mesh.n_elements,
            "element_order": self.mesh.order,
            "chambers": {
                name: {
                    "control": c.control,
                    "rest_area": c.area / c.area_ratio,
                    "final_area": c.area,
                    "area_ratio": c.area_ratio,
                    "final_pressure": c.pressure,
                    "peak_pressure": float(np.abs(self.history[f"{name}.pressure"]).max()),
                }
                for name, c in final.chambers.items()
            },
            "tip_at": tip_place(self.scene),
            "tip_deflection": self.tip_deflection,
            **{c: float(v) for c, v in zip(TIP_COLUMNS[2:], final.tip[2:])},
            "tip_rotation_deg": final.tip_rotation,
            **({} if final.tip_twist is None else {"tip_twist_deg": final.tip_twist}),
            **({} if final.blocked_force is None else {"blocked_force": final.blocked_force}),
            "peak_pressure": self.peak_pressure,
            "contact": final.contact,
            **({"contact_fz": final.contact_fz} if final.contact_fz else {}),
            **({"clamp": final.clamp} if final.clamp else {}),
            "extremes": self.extremes(),
            "max_stretch": float(stretch.max()),
            "max_stretch_step": int(self.history["step"][np.argmax(stretch)]),
            "max_stretch_limit": self.scene.max_stretch,
            "all_converged": self.converged,
            "max_residual": float(self.history["residual"].max()),
            "min_det_F": float(self.history["min_det"].min()),
            "newton_iterations_total": int(iterations.sum()),
            "newton_iterations_max": int(iterations.max(initial=0)),
            **(
                {}
                if not self.newton
                else {
                    "newton": {
                        "linear_solver": self.newton["linear_solver"],
                        "chord_steps": self.newton["chord_steps"],
                        "phase_seconds": dict(self.newton["phase_seconds"]),
                    }
                }
            ),
            "increment_cuts": int(self.history["cuts"].sum()),
            "wall_seconds": self.seconds,
            "solve_seconds_per_step": float(seconds.mean()) if len(seconds) else 0.0,
            "steps": len(self.steps),
            "interrupted": interrupted,
            "units": self.scene.units.summary(self.mesh.dim),
        }

    def obstacle_positions(self) -> np.ndarray:
        """(steps, obstacles, 3): each obstacle's placed point (a plane's point, the other shapes' centre) moved by
        its keyframes' translation at each step, and a held object's by its height (its '<name>.dy' column) (a 2D
        scene's z is 0)."""
        return np.array(
            [
                [
                    o.shape.parameters()[:3] + o.offset(step.step) + (0.0, step.extra.get(f"{o.name}.dy", 0.0), 0.0)
                    for o in self.scene.obstacles
                ]
                for step in self.steps
            ]
        ).reshape(len(self.steps), len(self.scene.obstacles), 3)

    def history_csv(self) -> str:
        """The history as CSV text: a header (the columns' names, each with its unit in a scene with units:
        "main.pressure [kPa]"), then one row per step (StepRecord.row)."""
        buffer = io.StringIO()
        rows = [s.row() for s in self.steps]
        columns = list(rows[0]) if rows else ["step"]
        dimensions = history_dimensions(self.scene, self.steps[0].contact if self.steps else (), self.mesh.dim)
        writer = csv.writer(buffer)
        writer.writerow([self.scene.units.label(c, dimensions.get(c, "")) for c in columns])
        writer.writerows([[row[c] for c in columns] for row in rows])
        return buffer.getvalue()

    def save_history(self, directory, stem: str | None = None) -> list[Path]:
        """Write <stem>_history.csv and <stem>_states.npz (also for a partial run); return their paths.

        The npz holds positions (steps, n, d), rest, triangles (in 3D: tetrahedra and surface, the body's
        boundary triangles), pinned, tip, boundary, chamber_names and one chamber_loop_<i> per chamber
        (in 3D its wall's triangles), command / area / pressure as (steps, chambers), and, where the
        scene has them, contact_forces (steps, n, d), ground_height, obstacle_names and obstacle_positions
        (steps, obstacles, 3).
        """
        out, stem = prepare_directory(directory), stem or self.scene.name
        mesh = self.mesh
        cells = (
            {"triangles": mesh.elements} if mesh.dim == 2 else {"tetrahedra": mesh.elements, "surface": mesh.surface}
        )
        arrays = dict(
            positions=self.positions,
            rest=mesh.vertices,
            **cells,
            pinned=mesh.pinned,
            tip=mesh.tip,
            boundary=mesh.boundary,
            chamber_names=np.array(self.chamber_names),
            **{f"chamber_loop_{i}": loop for i, loop in enumerate(mesh.chambers)},
            command=self.command,
            area=self.area,
            pressure=self.pressure,
        )
        if self.contact_forces is not None:
            arrays["contact_forces"] = self.contact_forces
        if self.ground_height is not None:
            arrays["ground_height"] = np.array(self.ground_height)
        if self.scene.obstacles:
            arrays["obstacle_names"] = np.array([o.name for o in self.scene.obstacles])
            arrays["obstacle_positions"] = self.obstacle_positions()
        with holding(), lock_stem(out, stem):
            return [
                save_text(out / f"{stem}_history.csv", self.history_csv()),
                save_npz(out / f"{stem}_states.npz", **arrays),
            ]

    def save(
        self, directory, stem: str | None = None, vtk: bool = True, extra: dict | None = None, plot: bool = True
    ) -> list[Path]:
        """Write the result files under directory, named <stem>_* (default: the scene's name, or, where the folder
        holds another scene's files of that name (its <name>_scene.toml differs), the name and the first 8 hex
        digits of this scene's scene_sha256: a changed scene never overwrites another's results): history CSV,
        states npz, the plot PNG (unless plot is False), the scene TOML, the summary JSON (with `extra`
        merged in) and, unless vtk is False, the ParaView files <stem>.pvd + <stem>_vtk/*.vtu. Returns the
        paths written. They are written under the stem's lock (output.lock_stem: another process writing
        the same stem there is refused), and a signal meanwhile waits for them (signals.holding)."""
        from .render.paraview import VtkSeries

        out = prepare_directory(directory)
        if stem is None:
            stem, text = self.scene.name, self.scene.to_toml()
            other = out / f"{stem}_scene.toml"
            if other.is_file() and other.read_text() != text:
                stem = f"{stem}_{scene_sha256(self.scene)[:8]}"
        with holding(), lock_stem(out, stem):  # a signal meanwhile waits for the files; no other run writes them
            written = self.save_history(out, stem)
            if vtk:
                written.append(VtkSeries(out, stem, self.built).write_all(self))
            if plot:
                from .render.plots import save_history_png  # matplotlib: 0.6 s of imports a run without a plot skips

                # titled by the stem, which names what the run changed of the scene
                written.append(write_atomic(out / f"{stem}_plot.png", lambda tmp: save_history_png(self, tmp, stem)))
            written.append(save_text(out / f"{stem}_scene.toml", self.scene.to_toml()))
            written.append(save_json(out / f"{stem}_summary.json", {**self.summary(), **(extra or {})}))
        return written

    def video(
        self,
        path,
        png=None,
        size=(960, 384),
        fps: float = 12.0,
        color: str = "stretch",
        renderer: str = "auto",
        trace: bool = True,
        quiet: bool = True,
        log=print,
        png_step: int | None = None,
        max_frame_pixels: int = limits.MAX_FRAME_PIXELS,
    ):
        """Render one frame per step into path (.mp4 or .gif; its directory is created), and frame png_step
        (default peak_step(), the most deformed) into png if given. size: (width, height) or '960x384';
        color: 'stretch', 'detF' or 'none'; renderer: 'auto', 'ggui', 'gui' or 'pillow'. A 3D run is drawn in
        3D (render.frames3d: the body opened by a section to show its chambers; 'auto' and 'ggui' GGUI's 3D
        scene, falling back to the NumPy rasteriser for 'auto', which 'gui' and 'pillow' take). Returns a
        video.Export. A size of more than max_frame_pixels pixels is refused (PneumaInputError), as the commands'
        --max-frame-pixels does."""
        from .render.video import frame_size

        limits.check_frame(*frame_size(size), max_frame_pixels, "size", "video's max_frame_pixels")
        png_frame = self.peak_step() if png_step is None else png_step
        if self.mesh.dim == 3:
            from .render.frames3d import Track3D, render_video_3d

            return render_video_3d(
                Track3D.from_result(self, color),
                path,
                png,
                size,
                fps,
                renderer,
                trace=trace,
                quiet=quiet,
                log=log,
                png_frame=png_frame,
            )
        from .render.video import render_video

        return render_video(
            [self], path, png, size, fps, color, renderer, trace, quiet=quiet, log=log, png_frame=png_frame
        )

    def plot(self):
        """The history as a matplotlib Figure with axes (plots.py): pressure against area ratio, the chambers'
        responses against the command, and the tip's (deflection, bending angle, extension, blocked force) against
        the driving pressure or the step; only the panels that change over the run. A notebook shows it as a PNG;
        in a script, fig.savefig("x.png")."""
        from .render.plots import history_figure

        return history_figure(self)
