"""Fuzzing the scene files (Hypothesis): the shipped scenes, mutated (wrong types, missing and extra
keys, NaN and inf, huge, zero and negative numbers, overlapping chambers, odd names, thin arms on the
body, deep keys and nesting, cut-off files, hostile mesh files), either run or stop with one `error:` line, within
TIME_BOUND, with no traceback and no file outside --out.

Each example runs in this process (apps.inflate.main), so its cost is capped: every shipped scene is
first made cheap (max_area 0.02, for a mesh-file body a small mesh file, for a 3D body from shapes tetrahedra
of edge 0.5, 8 mm in a scene in millimetres, and its schedule squeezed
into INCREMENTS increments), and the run
flags (FLAGS) set low resource limits and few Newton iterations, so that a mutation which makes a
scene big or slow is refused by the resource guards, as any such scene would be. A traceback is an
exception escaping main(), which fails the example; stderr and warnings are captured per example.
"""

import copy
import io
import json
import math
import tempfile
import time
import tomllib
import warnings
from contextlib import redirect_stderr, redirect_stdout
from datetime import timedelta
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, note, settings
from hypothesis import strategies as st
from solid_meshes import box_with_cavity, lzma_vtu, moved_up

from taichi_pneuma.apps.inflate import main
from taichi_pneuma.fem.meshfile import write_mesh
from taichi_pneuma.scene.shape_keys import SOLIDS

SCENES = Path(__file__).resolve().parent.parent / "taichi_pneuma" / "scenes"
INCREMENTS = 3
FLAGS = [
    "--no-video",
    "--quiet",
    "--max-triangles",
    "8000",  # blocked_force_3d's cheap fibre: 468 cord segments, 0.026 GB of Hessian, 6.5e3 triangles' worth
    "--max-increments",
    "20",
    "--max-iterations",
    "20",
    "--max-cuts",
    "2",
]
TIME_BOUND = 20.0  # seconds per example (a guarded example takes well under 1 s)

NUMBERS = [math.nan, math.inf, -math.inf, 0, 0.0, -1, -1.0, -0.5, 1e-300, 1e300, -1e300, 10**30, 10**9, 2.5]
WRONG_TYPES = ["text", "", True, [], [1.0], [1, 2, 3], [[0, 1], [2]], {"x": 1}, "1e4"]
# {WORK} becomes the example's own temporary folder: an absolute name that escaped would land there, not in /
ODD_NAMES = [
    "../escaped",
    "../../etc/evil",
    "{WORK}/absolute",
    "a/b",
    "a\\b",
    ".hidden",
    "..",
    ".",
    "",
    " ",
    "x" * 300,
    "naïve",
    "tab\tname",
    "new\nline",
    "nul\u0000",
    "-rf",
    "*",
    "~",
    "$HOME",
    "con",
    "ok_name",
]
EXTRA_KEYS = ["extra", "centre", "Name", "max_area", "E", "ε"]
# a thin arm on the body's right side: quality meshing needs about length / width triangles in it
ARM_WIDTHS, ARM_LENGTHS = [1e-6, 1e-4, 1e-2], [1.0, 10.0, 100.0, 1000.0]
DEEP_KINDS, DEEP_SIZES = ["key", "header", "array", "inline table"], [2, 5, 16, 17, 100, 3000, 100_000]


def cheap(scene: dict) -> dict:
    """The scene with a coarse mesh (triangles of 0.02 on a body 4 long, scaled with the body's size: a scene in
    millimetres is 10 times larger) and its keyframes squeezed into INCREMENTS increments."""
    scene = copy.deepcopy(scene)
    body = scene["body"]
    if body["shape"] == "mesh":  # a mesh file's body: a small one instead
        body["file"], scene["mesh"] = str(SMALL_MESH), {}
    elif body["shape"] in (*SOLIDS, "extrusion", "pneunet"):  # a 3D body from shapes: coarse tetrahedra
        # in millimetres, 4 mm: a fibre wound at mid-wall of a 2 mm wall must stay inside the facets, sample points
        # and the segments between them (8 mm facets cut 1 mm into the 8 mm radius); fibres sampled every 2 mm (a
        # 4 mm chord cuts the chamber's corner where a winding turns from the base to the arch), wound half as often
        # at twice the pitch: their cord segments' Hessian blocks within FLAGS' memory budget
        millimetres = scene.get("units") == "mm-kPa"
        scene["mesh"] = {"size": 4.0, "near_chambers": 4.0} if millimetres else {"size": 0.5}
        for fiber in scene.get("fibers", []) if millimetres else []:
            fiber["spacing"] = 2.0
            if "pitch" in fiber["path"]:
                fiber["path"]["pitch"], fiber["path"]["turns"] = 2 * fiber["path"]["pitch"], fiber["path"]["turns"] / 2
    else:
        corners = [
            np.array(r["center"]) + np.array(r["size"]) * sign / 2
            for r in body.get("rectangles", [])
            for sign in (-1, 1)
        ]  # a union of rectangles: their corners
        points = np.array(body.get("points", corners))
        length = max(body["size"]) if "size" in body else float(np.ptp(points, axis=0).max())
        scene["mesh"] = {"max_area": 0.02 * (length / 4.0) ** 2}
    n = scene["schedule"]["increments"]
    scene["schedule"]["increments"] = INCREMENTS
    for chamber in scene["chambers"]:
        squeezed = {round(INCREMENTS * step / n): value for step, value in chamber["keyframes"]}
        chamber["keyframes"] = [[step, value] for step, value in squeezed.items()]
    return scene


MESHES = tempfile.TemporaryDirectory()  # removed when the test process ends
SMALL_MESH = write_mesh(Path(MESHES.name) / "box.msh", box_with_cavity(), ("chamber",))
SPARSE_MESH = Path(MESHES.name) / "sparse.msh"  # the same box, its nodes numbered from 4e9
SPARSE_MESH.write_text(moved_up(SMALL_MESH.read_text(), 4_000_000_000))
# a mesh body's file: a folder, a name too long, sparse node numbers, a 0.1 MB file claiming 0.5 GB (issue 28)
MESH_FILES = [MESHES.name, "x" * 5000, str(SPARSE_MESH), str(lzma_vtu(Path(MESHES.name) / "bomb.vtu", blocks=8))]
# balloon_syringe driven otherwise: one of the three is enough; beam_3d_ellipsoid is beam_3d's body from shapes
# (pneunet_3d fuzzes the 3D shapes and gmsh); fiber_bending_3d is blocked_force_3d without its plate (and its cheap
# ramp, bending freely, costs four times as much); gripper_2d_friction and gripper_2d_lift are gripper_2d's body (their
# ramps past the cheap one's steps); finger_curl's growth to 5.2 times in three increments finds no equilibrium;
# pneunet_fast_3d is pneunet_3d's generator with a slit; fiber_bending_step and pneunet_stl are fiber_bending_3d's and
# pneunet_3d's bodies read from CAD files (their bad inputs: tests/test_cad.py, tests/test_surface_import.py)
SAME_BODY = {
    "fiber_bending_step",
    "pneunet_stl",
    "balloon_volume",
    "balloon_pressure",
    "beam_3d_ellipsoid",
    "fiber_bending_3d",
    "gripper_2d_friction",
    "gripper_2d_lift",
    "finger_curl",
    "pneunet_fast_3d",
}
BASES = {
    path.stem: cheap(tomllib.loads(path.read_text()))
    for path in sorted(SCENES.glob("*.toml"))
    if path.stem not in SAME_BODY
}


def toml_value(value) -> str:
    """value as a TOML value (inline tables and arrays; JSON's string escapes are TOML's)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return "nan" if math.isnan(value) else {math.inf: "inf", -math.inf: "-inf"}.get(value, repr(value))
    if isinstance(value, (int, str)):
        return json.dumps(value, ensure_ascii=False)
    if isinstance(value, list):
        return "[" + ", ".join(map(toml_value, value)) + "]"
    return "{" + ", ".join(f"{json.dumps(k, ensure_ascii=False)} = {toml_value(v)}" for k, v in value.items()) + "}"


def to_toml(scene: dict) -> str:
    return "".join(f"{json.dumps(k, ensure_ascii=False)} = {toml_value(v)}\n" for k, v in scene.items())


def paths(node, prefix=()):
    """Every (path, value) below node: dict keys and list indices, containers included."""
    items = node.items() if isinstance(node, dict) else enumerate(node) if isinstance(node, list) else ()
    for key, value in items:
        yield prefix + (key,), value
        yield from paths(value, prefix + (key,))


def mutate(scene: dict, draw) -> str:
    """Apply one mutation to scene (in place), choosing with draw(strategy); return what it did."""
    kind = draw(
        st.sampled_from(
            ["value", "value", "scale", "delete", "extra", "name", "overlap", "length", "thin", "mesh file"]
        )
    )
    chambers = scene.get("chambers")
    if kind == "mesh file":
        if not isinstance(scene.get("body"), dict) or scene["body"].get("shape") != "mesh":
            return "mesh file (no mesh body)"
        scene["body"]["file"] = draw(st.sampled_from(MESH_FILES))
        return f"mesh file {scene['body']['file'][:100]!r}"
    if kind == "thin":
        return thin_arm(scene, draw(st.sampled_from(ARM_WIDTHS)), draw(st.sampled_from(ARM_LENGTHS)))
    if kind == "name":
        owner = draw(
            st.sampled_from(
                [scene] + [c for c in chambers if isinstance(c, dict)] if isinstance(chambers, list) else [scene]
            )
        )
        owner["name"] = draw(st.sampled_from(ODD_NAMES))
        return f"{'scene' if owner is scene else 'chamber'} name = {owner['name']!r}"
    if kind == "overlap":
        if not isinstance(chambers, list) or not chambers:
            return "overlap (no chambers)"
        copied = copy.deepcopy(chambers[0])
        if isinstance(copied, dict):
            copied["name"] = "copy"
        chambers.append(copied)
        return "overlap: chambers[0] duplicated"
    fits = {
        "value": lambda v: True,
        "delete": lambda v: True,
        "extra": lambda v: isinstance(v, dict),
        "scale": lambda v: isinstance(v, (int, float)) and not isinstance(v, bool),
        "length": lambda v: isinstance(v, list),
    }[kind]
    candidates = [
        (path, value) for path, value in [((), scene)] * (kind == "extra") + list(paths(scene)) if fits(value)
    ]
    if not candidates:
        return f"{kind} (nothing to mutate)"
    path, value = draw(st.sampled_from(candidates))
    if kind == "extra":
        extra = draw(st.sampled_from(EXTRA_KEYS))
        value[extra] = copy.deepcopy(draw(st.sampled_from(NUMBERS + WRONG_TYPES)))
        return f"extra {extra!r} = {value[extra]!r} in {path}"
    if kind == "length":
        if value and draw(st.booleans()):
            value.pop()
        else:
            value.append(copy.deepcopy(value[-1]) if value else 1.0)
        return f"length at {path}: {value!r}"
    parent = scene
    for key in path[:-1]:
        parent = parent[key]
    if kind == "delete":
        del parent[path[-1]]
        return f"delete {path}"
    if kind == "scale":
        parent[path[-1]] = value * draw(st.sampled_from([-1, 0, 1e-6, 1e-3, 0.5, 2, 1e3, 1e6]))
    else:
        parent[path[-1]] = copy.deepcopy(draw(st.sampled_from(NUMBERS + WRONG_TYPES)))
    return f"{kind} at {path}: {parent[path[-1]]!r}"


def thin_arm(scene: dict, width: float, length: float) -> str:
    """Make a rectangle body a polygon with an arm of the given width and length on its right side."""
    body = scene.get("body")
    try:
        (cx, cy), (w, h) = body.get("center", [0.0, 0.0]), body["size"]
        x0, x1, y0, y1 = cx - w / 2, cx + w / 2, cy - h / 2, cy + h / 2
        assert body["shape"] == "rectangle" and all(math.isfinite(v) for v in (x0, x1, y0, y1))
    except (AssertionError, AttributeError, KeyError, TypeError, ValueError):
        return "thin (no rectangle body)"
    scene["body"] = {
        "shape": "polygon",
        "points": [
            [x0, y0],
            [x1, y0],
            [x1, cy - width / 2],
            [x1 + length, cy - width / 2],
            [x1 + length, cy + width / 2],
            [x1, cy + width / 2],
            [x1, y1],
            [x0, y1],
        ],
    }
    return f"thin arm {width:g} x {length:g}"


def deep(kind: str, n: int) -> str:
    """A top-level TOML line nesting n deep: a dotted key or table header of n parts, or n nested arrays
    or inline tables."""
    if kind == "key":
        return "a" + ".a" * (n - 1) + " = 1\n"
    if kind == "header":
        return "[" + ".".join(["x"] * n) + "]\n"
    if kind == "array":
        return "deep = " + "[" * n + "]" * n + "\n"
    return "deep = " + "{a = " * n + "1" + "}" * n + "\n"


def scene_text(draw) -> tuple[str, bytes]:
    """A mutated shipped scene: its description and the TOML file bytes (sometimes with a deep line added,
    sometimes cut off)."""
    base = draw(st.sampled_from(sorted(BASES)))
    scene = copy.deepcopy(BASES[base])
    done = [mutate(scene, draw) for _ in range(draw(st.integers(1, 3)))]
    text = to_toml(scene).encode()
    if draw(st.integers(0, 9)) == 0:
        kind, n = draw(st.sampled_from(DEEP_KINDS)), draw(st.sampled_from(DEEP_SIZES))
        text += deep(kind, n).encode()
        done.append(f"deep {kind} of {n}")
    if draw(st.integers(0, 9)) == 0:
        text = text[: draw(st.integers(0, len(text)))]
        done.append("cut off")
    return f"{base}: " + "; ".join(done), text


def run_in_sandbox(text: bytes) -> tuple[int, list[str], list[str], float]:
    """Run the inflate app on a scene file in a fresh directory; return (exit code, the lines it wrote
    to stderr and the warnings it raised, files written outside --out, seconds)."""
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        scene, out = work / "sandbox" / "scene.toml", work / "sandbox" / "out"
        scene.parent.mkdir()
        scene.write_bytes(text.replace(b"{WORK}", str(work).encode()))
        err = io.StringIO()
        start = time.perf_counter()
        with warnings.catch_warnings(record=True) as caught, redirect_stderr(err), redirect_stdout(io.StringIO()):
            warnings.simplefilter("always")  # as a user would see them
            code = main(["--scene", str(scene), "--out", str(out), *FLAGS])
        seconds = time.perf_counter() - start
        lines = [line for line in err.getvalue().splitlines() if line.strip()]
        lines += [f"{w.category.__name__}: {w.message}" for w in caught]
        outside = [str(p) for p in work.rglob("*") if p.is_file() and p != scene and out not in p.parents]
        if code == 0:
            names = sorted(p.name for p in out.iterdir())
            endings = (
                "_history.csv",
                "_states.npz",
                "_summary.json",
                "_scene.toml",
                ".pvd",
                "_vtk",
            )  # --no-video: no PNG
            assert len(names) == len(endings) and all(any(n.endswith(e) for n in names) for e in endings), names
        return code, lines, outside, seconds


@pytest.fixture(scope="module")
def bases_outcomes():
    """Every cheap base scene run once: (exit code, stderr lines, files outside --out) by name. This also
    loads every kernel before the timed examples."""
    return {name: run_in_sandbox(to_toml(scene).encode())[:3] for name, scene in BASES.items()}


def test_cheap_bases_run(bases_outcomes):
    assert bases_outcomes == {name: (0, [], []) for name in BASES}


@settings(
    max_examples=100,
    deadline=timedelta(seconds=TIME_BOUND),
    derandomize=True,
    database=None,
    suppress_health_check=[HealthCheck.too_slow],
)
@given(st.data())
def test_mutated_scene_files_run_or_stop_with_one_error_line(bases_outcomes, data):
    description, text = scene_text(data.draw)
    note(description)
    code, lines, outside, seconds = run_in_sandbox(text)
    assert not outside, f"files written outside --out: {outside}"
    assert seconds < TIME_BOUND
    if code == 0:
        assert lines == []
    else:
        assert code in (1, 2) and len(lines) == 1 and lines[0].startswith("error: "), (code, lines)
