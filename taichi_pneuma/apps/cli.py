"""The command-line plumbing every app shares: the reference-beam, solver, output and rendering flags and
their checks (before any work), the scene of the flags (--scene, --set), building it with its one-line
description, a ramp run with a line per step and Ctrl-C handled, the render report line, and the exit
codes: 0 done, 1 no equilibrium (or a target not reached, a run lost), 2 bad input (one `error:` line),
128 + signal on Ctrl-C (130), SIGTERM (143) or SIGHUP (129).

The flags are plain data: this module and the apps import the solver, Taichi and the renderers inside
the functions that run, so `--help` answers at once, without Taichi's start-up.
"""

from __future__ import annotations

import argparse
import sys

from .. import __version__, environment, limits, runtime, signals
from ..errors import PneumaInputError, require, require_finite
from ..fem import sizing
from ..fem.elements import FAMILIES
from ..io.units import MEASURES
from ..render import COLOR_FIELDS, RENDERERS
from .progress import step_line
from .quality import (
    AREA_STEP,
    ORDER_WORDS,
    QUALITY,
    QUALITY_3D,
    QUALITY_TOL,
    QUALITY_WALL,
    preset_note,
    with_quality,
)

MEASURE = {2: "area", 3: "volume"}  # what a chamber encloses, by dimension
MAX_ITERATIONS, MAX_CUTS = 40, 8  # the solver's defaults (NewtonOptions.max_iterations, simulate.MAX_CUTS)
# the reference-beam flags' defaults (those of scene.build.reference_scene; tests/test_cli.py checks they agree)
BEAM_DEFAULTS = {"cx": 0.0, "growth": 3.5, "steps": 36, "E": 1e4, "nu": 0.45, "k": 1e5}
# Linear elements lock (too stiff in volume change) from this small-strain Poisson's ratio on: there locking costs a
# chamber's growth 20 % on linear tetrahedra (5 % on triangles) beyond their error at nu = 0.3, 29 % (12 %) at 0.4999
# (docs/3d.md, "The locking warning"); the run's first line says so (locking_note)
LOCKING_POISSON = 0.49


def app_parser(prog: str, doc: str) -> argparse.ArgumentParser:
    """An app's parser: its description is the first paragraph of the app's docstring, defaults shown;
    --version prints the package's version."""
    p = argparse.ArgumentParser(
        prog=prog,
        description=" ".join(doc.split("\n\n")[0].split()),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    p.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    p.add_argument("--list-scenes", action=ListScenes, help="list the shipped scenes, a line each, and exit")
    return p


def add_scene_arguments(p: argparse.ArgumentParser, what: str = "the scene", cy_help: str = "") -> None:
    """--scene, --cy and --set as every app that runs a scene reads them (scene_for); --set changes `what`."""
    p.add_argument(
        "--scene",
        help="a scene file (TOML) or the name of a shipped scene (--list-scenes lists them); "
        "without it the reference beam of the flags (--cy --cx --growth --steps --E --nu --k --max-area "
        "--order), which are then ignored",
    )
    p.add_argument("--cy", type=float, default=0.15, help=cy_help or "reference beam: chamber centre height")
    p.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help=f"change a dotted scene-file key or a short name (cy cx E nu k max_area) of {what}, e.g. "
        "--set chambers[0].center[1]=0.1 (repeatable; the reference beam's keys: reference_beam.toml)",
    )


class ListScenes(argparse.Action):
    """--list-scenes: print every shipped scene with the first sentence of its description (scene/shipped.py), then
    exit 0, as --version does."""

    def __init__(self, option_strings, dest=argparse.SUPPRESS, default=argparse.SUPPRESS, help=None):
        super().__init__(option_strings, dest=dest, default=default, nargs=0, help=help)

    def __call__(self, parser, namespace, values, option_string=None):
        from ..scene.shipped import listing

        print(listing())
        parser.exit()


class GivenQuality(argparse.Action):
    """--quality, remembering that it was given (args.quality_given): only then does it remesh a 3D scene file."""

    def __call__(self, parser, namespace, values, option_string=None):
        namespace.quality, namespace.quality_given = values, True


def factors(table: dict) -> str:
    """A 3D preset table's (bulk, near, order) per quality in words, for --quality's help."""
    words = {
        k: ("uniform" if near is None else f"x{near:.3g}", ORDER_WORDS[o] if o else "its order")
        for k, (_, near, o) in table.items()
    }
    return "; ".join(f"{k} x{table[k][0]:.3g}, {near}, {order}" for k, (near, order) in words.items())


def add_ramp_arguments(p: argparse.ArgumentParser) -> None:
    """The reference-beam, ramp, solver and output flags shared by the apps (all but the chamber height)."""
    p.add_argument("--cx", type=float, default=BEAM_DEFAULTS["cx"], help="chamber centre along the beam")
    p.add_argument("--growth", type=float, default=BEAM_DEFAULTS["growth"], help="final commanded area / rest area")
    p.add_argument(
        "--steps", type=int, default=BEAM_DEFAULTS["steps"], help="commanded areas in the ramp, rest included"
    )
    p.add_argument("--E", type=float, default=BEAM_DEFAULTS["E"], help="Young's modulus")
    p.add_argument("--nu", type=float, default=BEAM_DEFAULTS["nu"], help="Poisson's ratio, in (-1, 0.5)")
    p.add_argument("--k", type=float, default=BEAM_DEFAULTS["k"], help="chamber stiffness (area control penalty)")
    p.add_argument(
        "--quality",
        default="default",
        choices=list(QUALITY),
        action=GivenQuality,
        help="mesh and Newton tolerance, relative to the scene's own [mesh] (the run's first line says what the "
        "preset means for its scene). 2D: draft one rung below the scene, default the scene as written, high one rung "
        "above, accurate two, on the ladder P1 at max area A x r, P1 at A, P2 at A x r, P2 at A, P2 at A / r, P2 at "
        f"A / r^2 (r = {AREA_STEP:.3g}; a linear scene stands on P1 at A, a quadratic one on P2 at A); the reference "
        "beam's: "
        + ", ".join(f"{k} max area {a:g} order {o}" for k, (a, o, _) in QUALITY.items())
        + ". 3D, where --quality is given (without it the scene keeps its [mesh]), the scene's tetrahedron size "
        "(also the grading distance) times, and near the chambers: "
        + factors(QUALITY_3D)
        + "; a body sized through its walls (mesh.through_wall): "
        + factors(QUALITY_WALL)
        + " (a mesh file keeps its tetrahedra: linear at draft, quadratic at high and accurate). Newton tolerance "
        + ", ".join(f"{k} {t:g}" for k, t in QUALITY_TOL.items())
        + ". A quality other than the default adds _QUALITY to the result file names",
    )
    p.add_argument(
        "--max-area", type=float, default=None, help="Triangle's maximum triangle area (overrides --quality)"
    )
    p.add_argument(
        "--order",
        type=int,
        default=None,
        choices=[f.order for f in FAMILIES if f.dim == 2],
        help=", ".join(f"{f.order}: {f.adjective} triangles" for f in FAMILIES if f.dim == 2)
        + " (overrides --quality)",
    )
    p.add_argument(
        "--tol", type=float, default=None, help="Newton tolerance on |gradient| / force scale (overrides --quality)"
    )
    p.add_argument(
        "--max-iterations",
        type=int,
        default=MAX_ITERATIONS,
        help="Newton iterations per solve before it counts as failed",
    )
    p.add_argument(
        "--max-cuts",
        type=int,
        default=MAX_CUTS,
        help="times a non-converging increment may be halved before the run stops",
    )
    p.add_argument(
        "--max-triangles",
        type=int,
        default=limits.MAX_TRIANGLES,
        help="refuse a scene whose mesh is estimated (before meshing) to have more triangles",
    )
    p.add_argument(
        "--max-increments", type=int, default=limits.MAX_INCREMENTS, help="refuse a schedule of more increments"
    )
    p.add_argument("--max-fibers", type=int, default=limits.MAX_FIBERS, help="refuse a scene of more [[fibers]] tables")
    p.add_argument(
        "--max-obstacles", type=int, default=limits.MAX_OBSTACLES, help="refuse a scene of more [[obstacles]] tables"
    )
    p.add_argument("--out", default="out", help="directory for the result files")
    p.add_argument("--arch", default="cpu", choices=sorted(runtime.ARCHES), help="Taichi backend")
    p.add_argument("--quiet", action="store_true", help="no per-step lines, no progress bars")


def add_video_arguments(p: argparse.ArgumentParser, size: str) -> None:
    """The rendering flags shared by the apps."""
    p.add_argument(
        "--video",
        default=None,
        help="video file (.mp4 H.264 or .gif; its directory is created); default <out>/<name>.mp4",
    )
    p.add_argument("--fps", type=float, default=12.0, help="video frames per second (one frame per step)")
    p.add_argument("--size", default=size, help="frame size WIDTHxHEIGHT in pixels")
    p.add_argument(
        "--renderer",
        default="auto",
        choices=RENDERERS,
        help="gui: ti.GUI's software rasteriser; ggui: Taichi's GGUI (needs Vulkan); pillow: Pillow, no "
        "Taichi GUI; auto: ti.GUI, the faster of the two wherever measured (docs/performance.md), "
        "else Pillow where the backend has no GUI",
    )
    p.add_argument(
        "--no-video",
        action="store_true",
        help="no pictures: no video, no frame PNG, no plot PNG (and no renderer or matplotlib started); "
        "the history, states, scene, summary and ParaView files are still written",
    )
    p.add_argument(
        "--color",
        default="stretch",
        choices=["none", *COLOR_FIELDS],
        help="colour the body by a field: the largest principal stretch, det F, or none (mesh edges)",
    )
    p.add_argument(
        "--max-frame-pixels", type=int, default=limits.MAX_FRAME_PIXELS, help="refuse a --size of more pixels per frame"
    )


MIN_FRAME_3D = (384, 192)  # the smallest 3D frame tests/test_shipped_runs_3d.py draws every shipped 3D scene in


def rendering_flags(args: argparse.Namespace, dim: int = 2) -> tuple[int, int]:
    """Check the rendering flags before any work (a 3D scene's frame at least MIN_FRAME_3D: its header, colour bar
    and trace panel beside a view of 64 x 64 pixels), and create the directory of --video (so a path in a new
    directory works, and one that cannot be written fails now, not after the solve); return --size
    'WIDTHxHEIGHT' as (width, height)."""
    from pathlib import Path

    from ..io.output import prepare_directory
    from ..render.video import check_video, frame_size

    check_video(args.video or "default.mp4", args.fps)
    width, height = frame_size(args.size, "--size")
    limits.check_frame(width, height, args.max_frame_pixels)
    if dim == 3 and not args.no_video:
        require(
            width >= MIN_FRAME_3D[0] and height >= MIN_FRAME_3D[1],
            f"--size {width}x{height} is too small for a 3D scene's frame: use at least "
            f"{MIN_FRAME_3D[0]}x{MIN_FRAME_3D[1]} (its header, colour bar and trace panel beside the 3D view)",
        )
    if args.video and not args.no_video:
        prepare_directory(Path(args.video).parent)
    return width, height


def newton_options(args: argparse.Namespace):
    from ..solve.newton import NewtonOptions

    return NewtonOptions(tol=args.tol, max_iterations=args.max_iterations)


def check_flags(args: argparse.Namespace) -> None:
    """Validate the solver flags; --max-area and --tol not given take their values from --quality."""
    max_area, order, tol = QUALITY[args.quality]
    args.max_area = max_area if args.max_area is None else args.max_area
    args.order = order if args.order is None else args.order
    args.tol = tol if args.tol is None else args.tol
    for name in ("cx", "growth", "E", "nu", "k", "max_area", "tol"):
        require_finite(f"--{name.replace('_', '-')}", getattr(args, name))
    newton_options(args)  # validates --tol and --max-iterations
    require(args.max_cuts >= 0, f"--max-cuts = {args.max_cuts!r} must be >= 0")
    for name in ("max_triangles", "max_increments", "max_fibers", "max_obstacles", "max_frame_pixels"):
        if hasattr(args, name):  # (an app without video, pneuma-serve, has no --max-frame-pixels)
            require(getattr(args, name) >= 1, f"--{name.replace('_', '-')} = {getattr(args, name)!r} must be >= 1")
    from ..scene.schedule import area_ramp

    area_ramp(args.growth, args.steps)  # validates growth and steps before any work


def scene_for(args: argparse.Namespace, cy: float):
    """The validated reference scene of the flags with its chamber at height cy (PneumaInputError on bad flags)."""
    from ..scene.build import reference_scene

    check_flags(args)
    scene = reference_scene(
        require_finite("--cy", cy),
        args.cx,
        args.growth,
        args.steps,
        args.E,
        args.nu,
        args.k,
        args.max_area,
        order=args.order,
    )
    check_scene(scene, args)
    return scene


def check_scene(scene, args: argparse.Namespace) -> None:
    """Refuse a scene past the limits of the flags (sizing.check_scene): --max-triangles, --max-increments,
    --max-fibers, --max-obstacles."""
    sizing.check_scene(scene, args.max_triangles, args.max_increments, args.max_fibers, args.max_obstacles)


def locking_note(scene, mesh) -> str:
    """'; warning: ...' naming the fix where the scene's elements are known to lock, else '': linear elements
    (order 1: plane-strain triangles, tetrahedra) whose volumetric part is evaluated per element (volumetric =
    "element") in a material whose small-strain Poisson's ratio (Law.poisson_ratio; for the isochoric laws
    (3 K - 2 mu0) / (2 (3 K + mu0)), so K / mu0 >= 49.7) reaches LOCKING_POISSON somewhere in the body (to 1e-9:
    a K made from nu = 0.49, as the presets', gives nu back to round-off)."""
    import numpy as np

    from ..result import ELEMENTS

    law, rows = scene.law_parameters()
    ratios = law.poisson_ratio(np.vstack(rows))
    if mesh.order != 1 or scene.volumetric != "element" or ratios is None or ratios.max() < LOCKING_POISSON - 1e-9:
        return ""
    return (
        f"; warning: linear {ELEMENTS[mesh.dim]} lock at nu = {ratios.max():.4g} (>= {LOCKING_POISSON:g}): too "
        f"stiff in volume change, their chambers inflate too little (or need too much pressure); use quadratic "
        f'elements ([mesh] order = 2, --order 2), or volumetric = "nodal" with an isochoric law'
    )


def scene_file(args: argparse.Namespace):
    """The scene of --scene with its --quality preset (with_quality; the line saying what the preset means for it
    printed first) and every --set applied."""
    from ..api import load_scene

    scene, said = with_quality(load_scene(args.scene), args)
    meshed = [text for text in args.set if text.partition("=")[0].strip().startswith(("mesh.", "max_area"))]
    if said:
        print(said + (f"; then --set {', '.join(meshed)}" if meshed else ""))
    return apply_set(scene, args.set)


def scene_of_flags(args: argparse.Namespace):
    """The validated scene of the flags: --scene (or the reference beam of the flags, its chamber at --cy)
    with every --set applied, then checked against the resource limits (which --set may have raised)."""
    if args.scene:
        check_flags(args)
        scene = scene_file(args)
    else:
        scene = apply_set(scene_for(args, args.cy), args.set)
    check_scene(scene, args)
    return scene


def budget(args: argparse.Namespace) -> limits.Budget:
    """The budget meshes and terms are made in: --max-triangles."""
    return limits.Budget(args.max_triangles)


def build(scene, args: argparse.Namespace):
    """Mesh the scene and build its terms in the budget of --max-triangles, and print the mesh size, the supports,
    the terms (and, where a --quality preset of args made the mesh, its measured error: preset_note) and each
    chamber's rest area."""
    from ..scene.build import describe_supports

    built = scene.build(budget(args))
    mesh = built.mesh
    kind = mesh.family.words
    print(
        f"scene {scene.name}: mesh {mesh.n_vertices} {'vertices' if mesh.order == 1 else 'nodes'}, "
        f"{mesh.n_elements} {kind}; {describe_supports(mesh, scene.effects)}; "
        f"terms: {', '.join(built.model.term_names())}{preset_note(scene, args)}{locking_note(scene, mesh)}"
    )
    for chamber in built.chambers:
        control = MEASURE[mesh.dim] if chamber.kind.name == "area" else chamber.kind.name  # "volume" in 3D
        print(
            f"chamber {chamber.chamber_name}: {control} control, wall {chamber.n_wall} vertices, "
            f"rest {MEASURE[mesh.dim]} {chamber.rest_area:.3f}{scene.units.suffix(MEASURES[mesh.dim])}"
        )
    return built


def solve(args: argparse.Namespace, built, label: str = "solving", vtk=None):
    """Run the scene's schedule, printing a line per step, with a progress bar on a terminal only (the
    lines go through the bar, tqdm.write; piped or logged output gets the lines alone), and one `warning:`
    line (also with --quiet) at the first step whose largest principal stretch passes the scene's max_stretch, and
    one at the first past the range of data a material preset of the scene was fitted to (Scene.fitted_stretch);
    write each step's VTU as it is solved if vtk is given. Returns an api.Result.

    Raises RampFailed when an increment fails after its cuts, RampInterrupted (its .signum the signal)
    after the increment during which Ctrl-C, SIGTERM or SIGHUP came (signals.stopping); both carry the
    steps done (.result)."""
    from tqdm import tqdm

    from ..api import simulate
    from ..solve.simulate import RampInterrupted

    increments, units, limit = built.scene.increments, built.scene.units, built.scene.max_stretch
    bar = tqdm(total=increments + 1, desc=label, unit="step", disable=True if args.quiet else None, leave=False)
    past: list[int] = []  # the step that first passed the scene's max_stretch
    fit = built.scene.fitted_stretch()  # (stretch, preset): the range of a preset's data
    extrapolated: list[int] = []  # the step that first passed it

    def progress(step, positions, contact_force):
        if vtk is not None:
            vtk.write(step, positions, contact_force)
        bar.update()
        if step.max_stretch > limit and not past:
            past.append(step.step)
            tqdm.write(
                f"warning: step {step.step}: the largest principal stretch {step.max_stretch:.2f} is past "
                f"max_stretch = {limit:g} (schedule.max_stretch): the material model is not meant for it, its "
                f"results from here on are extrapolated",
                file=sys.stderr,
            )
        if fit is not None and step.max_stretch > fit[0] and not extrapolated:
            extrapolated.append(step.step)
            tqdm.write(
                f"warning: step {step.step}: the largest principal stretch {step.max_stretch:.2f} is past "
                f"{fit[0]:g} (engineering strain {100 * (fit[0] - 1):.0f} %), the largest in the data preset "
                f"{fit[1]!r} was fitted to: its stresses are extrapolated from here on (docs/materials.md)",
                file=sys.stderr,
            )
        if not args.quiet:
            tqdm.write(step_line(step, increments, units))

    with bar, signals.stopping() as interrupted:
        try:
            return simulate(
                built,
                tol=args.tol,
                max_iterations=args.max_iterations,
                max_cuts=args.max_cuts,
                progress=progress,
                stop=interrupted.is_set,
            )
        except RampInterrupted as exc:
            exc.signum = interrupted.signum  # read by signals.name_of()
            raise


def render_report(export, seconds_per_step: float) -> str:
    return (
        f"video: {export.frames} frames {export.width}x{export.height}; rendering {export.ms_per_frame:.1f} "
        f"ms/frame vs solving {1000 * seconds_per_step:.0f} ms/step"
    )


def set_values(assignments: list[str]) -> dict:
    """{dotted key: value} of every --set KEY=VALUE."""
    from ..scene.dotted_edits import parse_assignment

    return dict(parse_assignment(text) for text in assignments)


def apply_set(scene, assignments: list[str]):
    """The scene with every --set KEY=VALUE applied (validated once, like a scene file)."""
    if not assignments:
        return scene
    values = set_values(assignments)
    try:
        return scene.with_values(values)
    except PneumaInputError as exc:
        raise PneumaInputError(f"--set: {exc}") from None


def exit_code(app_run, args: argparse.Namespace) -> int:
    """Run an app; bad input (the environment's PNEUMA_* variables checked first) is one line and exit 2, a
    ramp (or a reach's start) with no equilibrium one line and exit 1, Ctrl-C, SIGTERM or SIGHUP one line and
    exit 128 + the signal (130, 143, 129, as shells report it): all three raise signals.Interrupted during the
    run, or stop a ramp within a Newton iteration (a signal after the last solve waits for the files).

    NumPy's floating-point warnings (overflow, invalid value) are silenced: a huge input value overflows
    harmlessly in a check that then refuses it, and a solve that produces NaN or inf fails its own checks."""
    import numpy as np

    try:
        environment.check_environment()  # first: the modules imported next load the backend PNEUMA_BACKEND names
    except PneumaInputError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    from ..solve.simulate import NoEquilibrium, RampFailed, RampInterrupted

    try:
        with np.errstate(all="ignore"), signals.interrupting():
            summary = app_run(args)
    except PneumaInputError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except (RampFailed, NoEquilibrium) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    except RampInterrupted as exc:
        print(f"error: {exc} ({signals.name_of(exc)})", file=sys.stderr)
        return signals.exit_code_of(exc)
    except KeyboardInterrupt as exc:
        print(f"error: interrupted ({signals.name_of(exc)})", file=sys.stderr)
        return signals.exit_code_of(exc)
    finally:
        signals.finished()
    return 0 if summary["all_converged"] else 1
