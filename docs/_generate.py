"""The site's pages that are generated from the code and the tracked benchmark results, so that they cannot drift
from what they describe. At build time (docs/conf.py):

- _generated/app_<name>.md: each app's usage and flags, read off its argparse parser (what --help prints);
- _generated/results_<page>.md: the tables under benchmarks/results/ (machine and date included), each with the
  docstring of the code that wrote it and the command that writes it again; a table no page claims lands on the
  performance page;
- api/<package>.md and api/index.md: an automodule directive per module of each subpackage (pkgutil's walk),
  so that a new module is in the reference without an edit here.

Committed (readable in the repository, where the pages that include them are read too; `python docs/_generate.py`
writes them again, tests/test_docs_generated.py checks they are current): the _generated/ pieces above, and

- guide/scene_keys_2d.md and guide/scene_keys_3d.md: every key of the scene file, from
  scene/scenefile.key_reference() (the format's one declaration, scene/scene_keys.py), the 3D body and chamber
  shapes' keys in the second, every other key (those of every scene and of the 2D shapes) in the first.

plain_docstring() reads the docstrings, written as plain text for help() and a terminal, as reStructuredText
(the characters reST would take as markup escaped, indented blocks made literal) for autodoc.
"""

from __future__ import annotations

import ast
import importlib
import os
import pkgutil
import re
from pathlib import Path
from unittest import mock

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
RESULTS = ROOT / "benchmarks" / "results"
APPS = ("inflate", "steer", "reach", "sweep", "optimize", "bench", "serve", "reduce")
SCENE_KEYS = {2: "guide/scene_keys_2d.md", 3: "guide/scene_keys_3d.md"}  # under docs/, committed
REGENERATE = "python docs/_generate.py"
GENERATED = DOCS / "_generated"  # the pieces other pages include (committed)
HELP_WIDTH = 120  # the columns argparse formats an app's usage in (COLUMNS), the same on every machine

# results table stem -> (page, title, (module file, function or None: the docstring that says what it measures),
#                         the command that writes it again)
RESULTS_PAGES = {
    "cad_import": (
        "accuracy",
        "CAD files against the parametric scenes they were drawn from",
        ("benchmarks/cad_import.py", None),
        "python benchmarks/cad_import.py",
    ),
    "surface_repair": (
        "accuracy",
        "Surface repair: gmsh with the project's repair against fTetWild",
        ("benchmarks/surface_repair.py", None),
        "python benchmarks/surface_repair.py --tetwild-python V/bin/python",
    ),
    "reduced": (
        "performance",
        "A reduced-order model (POD + ECSW) against the full model",
        ("benchmarks/reduced.py", None),
        "python benchmarks/reduced.py --full-3d",
    ),
    "live_reduced": (
        "performance",
        "The live views on a reduced model against the full model",
        ("benchmarks/live_reduced.py", None),
        "xvfb-run -a python benchmarks/live_reduced.py",
    ),
    "reach_reduced": (
        "performance",
        "Inverse control on a reduced model (pneuma-reach --reduced) against the full Reacher",
        ("benchmarks/reach_reduced.py", None),
        "python benchmarks/reach_reduced.py --3d",
    ),
    "bench_startup": (
        "performance",
        "Start-up: kernels compile once; rendering against solving",
        ("taichi_pneuma/apps/bench.py", "startup"),
        "pneuma-bench --sections startup",
    ),
    "bench_breakdown": (
        "performance",
        "Where the time of the reference ramp goes",
        ("taichi_pneuma/apps/bench.py", "breakdown"),
        "pneuma-bench --sections breakdown",
    ),
    "bench_backends": (
        "performance",
        "Linear-solver backends",
        ("benchmarks/backends.py", "backends"),
        "python benchmarks/backends.py --out benchmarks/results",
    ),
    "bench_scaling": (
        "performance",
        "Scaling with the mesh size",
        ("benchmarks/scaling.py", "scaling"),
        "python benchmarks/scaling.py --out benchmarks/results",
    ),
    "scenes": (
        "scenes",
        "Every shipped scene as shipped: its exit status, increments, Newton iterations and headline figures",
        ("benchmarks/scenes.py", None),
        "python benchmarks/scenes.py",
    ),
    "bench_solid": (
        "performance",
        "3D: the cost of a Newton iteration on tetrahedra",
        ("benchmarks/solid.py", "solid"),
        "python benchmarks/solid.py --out benchmarks/results",
    ),
    "bench_presets_3d": (
        "performance",
        "3D presets on the shipped 3D scenes: time and error",
        ("taichi_pneuma/apps/bench.py", "presets_3d"),
        "pneuma-bench --sections presets_3d",
    ),
    "bench_sweep": (
        "performance",
        "Design studies: throughput on a process pool and on Ray",
        ("benchmarks/sweep.py", None),
        "python benchmarks/sweep.py --out benchmarks/results",
    ),
    "optimize_vs_grid": (
        "optimize",
        "The design optimiser against a 100-point grid: the 2D beam",
        ("benchmarks/optimize_vs_grid.py", None),
        "python benchmarks/optimize_vs_grid.py --problem 2d",
    ),
    "optimize_vs_grid_3d": (
        "optimize",
        "The design optimiser against a 100-point grid: the 3D fibre actuator (coarse mesh)",
        ("benchmarks/optimize_vs_grid.py", None),
        "python benchmarks/optimize_vs_grid.py --problem 3d --no-ray --refined-only",
    ),
    "render3d": (
        "performance",
        "3D meshing and rendering",
        ("benchmarks/render3d.py", None),
        "python -m benchmarks.render3d --out benchmarks/results",
    ),
    "render3d_live": (
        "performance",
        "3D: the interactive loop without a window",
        ("benchmarks/render3d.py", None),
        "python -m benchmarks.render3d --only-live --out benchmarks/results",
    ),
    "render3d_live_p2": (
        "performance",
        "3D: the interactive loop on quadratic tetrahedra",
        ("benchmarks/render3d.py", None),
        "python -m benchmarks.render3d --only-live --order 2 --out benchmarks/results",
    ),
    "scale_3d": (
        "performance",
        "3D at scale: 200k linear and 50k quadratic tetrahedra",
        ("benchmarks/scale_3d.py", None),
        "python -m benchmarks.scale_3d --out benchmarks/results",
    ),
    "bench_accuracy": (
        "accuracy",
        "Accuracy against time: linear or quadratic triangles",
        ("benchmarks/accuracy.py", "accuracy"),
        "python benchmarks/accuracy.py --out benchmarks/results",
    ),
    "bench_incompressible": (
        "accuracy",
        "Near-incompressible rubber",
        ("benchmarks/incompressible.py", "incompressible"),
        "python benchmarks/incompressible.py --out benchmarks/results",
    ),
    "plane_strain_3d": (
        "accuracy",
        "Plane strain in 3D: tetrahedra against triangles",
        ("benchmarks/plane_strain_3d.py", None),
        "python benchmarks/plane_strain_3d.py --out benchmarks/results",
    ),
    "plane_strain_3d_a0.005": (
        "accuracy",
        "Plane strain in 3D: the converged values, by extrapolation",
        ("benchmarks/plane_strain_3d.py", None),
        "python benchmarks/plane_strain_3d.py --max-area 0.005 --out benchmarks/results",
    ),
    "accuracy_3d": (
        "accuracy",
        "What accuracy costs in 3D: linear or quadratic tetrahedra",
        ("benchmarks/accuracy_3d.py", None),
        "python benchmarks/accuracy_3d.py",
    ),
    "web_viewers": (
        "performance",
        "The live page's library: viser against trame, a coloured mesh sent to headless Chromium",
        ("benchmarks/web_viewers.py", None),
        "python -m benchmarks.web_viewers --trame-python PATH/TO/TRAME-VENV/bin/python",
    ),
    "live_page": (
        "performance",
        "The live page against the native windows: frames per second while a slider is dragged",
        ("benchmarks/live_page.py", None),
        "xvfb-run -a python benchmarks/live_page.py --repeat 2 --out benchmarks/results",
    ),
    "pneunet_vs_fiber": (
        "accuracy",
        "A PneuNet against the fibre-reinforced actuator: same length, silicone, sheet and ramp",
        ("benchmarks/pneunet_vs_fiber.py", None),
        "python benchmarks/pneunet_vs_fiber.py",
    ),
    "actuators": (
        "accuracy",
        "The shipped 3D actuators: bending angle, blocked force and twist against pressure, converged references",
        ("benchmarks/actuators.py", None),
        "python benchmarks/actuators.py",
    ),
    "threads": (
        "performance",
        "What the second core buys, per phase",
        ("benchmarks/threads.py", None),
        "python benchmarks/threads.py",
    ),
    "skfem_3d": (
        "performance",
        "3D against scikit-fem + SciPy: the beam_3d scene's mesh and ramp",
        ("benchmarks/skfem_3d.py", None),
        "python benchmarks/skfem_3d.py",
    ),
    "skfem_3d_coarse": (
        "performance",
        "3D against scikit-fem + SciPy: the same model, mesh and ramp",
        ("benchmarks/skfem_3d.py", None),
        "python benchmarks/skfem_3d.py --coarse",
    ),
    "ngsolve_3d": (
        "performance",
        "3D against NGSolve per Newton iteration, on the same meshes",
        ("benchmarks/ngsolve_3d.py", None),
        "python benchmarks/ngsolve_3d.py --repeats 1",
    ),
    "fibers": (
        "performance",
        "What tension-only fibres cost per Newton iteration, and branch sweeps by low-rank updates",
        ("benchmarks/fibers.py", None),
        "python benchmarks/fibers.py",
    ),
    "contact": (
        "performance",
        "What surface contact costs: ipctk against this project's Taichi kernels, and a 3D ramp with and without it",
        ("benchmarks/contact.py", None),
        "python benchmarks/contact.py",
    ),
    "amg_options": (
        "performance",
        "3D: multigrid options for quadratic tetrahedra",
        ("benchmarks/amg_options.py", None),
        "python benchmarks/amg_options.py",
    ),
    "stability": (
        "stability",
        "The hard cases",
        ("benchmarks/stability.py", None),
        "python benchmarks/stability.py --out benchmarks/results",
    ),
}


def write_all(out: Path) -> None:
    """Write every generated page: out/ holds the pieces other pages include, out/../api the API reference."""
    out.mkdir(exist_ok=True)
    for name in APPS:
        write_if_changed(out / f"app_{name}.md", app_page(name))
    for page, text in results_pages().items():
        write_if_changed(out / f"results_{page}.md", text)
    api = out.parent / "api"
    api.mkdir(exist_ok=True)
    packages = api_packages()
    for package in packages:
        write_if_changed(api / f"{package}.md", f"# {package}\n\n" + api_page(package))
    write_if_changed(api / "index.md", API_INDEX + "\n".join(packages) + "\n```\n")


def write_if_changed(path: Path, text: str) -> None:
    """Rewrite a page only when it changed, so that Sphinx rebuilds only what changed."""
    if not path.exists() or path.read_text() != text:
        path.write_text(text)


def cell(text) -> str:
    """A Markdown table cell: pipes escaped, on one line."""
    return " ".join(str(text).split()).replace("|", "\\|") or " "


def table(header: list[str], rows: list[list]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    return "\n".join(lines + ["| " + " | ".join(cell(c) for c in row) + " |" for row in rows]) + "\n"


def app_page(name: str) -> str:
    """Usage and a table of every flag of pneuma-<name>, from its parser."""
    import argparse

    parser = importlib.import_module(f"taichi_pneuma.apps.{name}").parser()
    with mock.patch.dict(os.environ, {"COLUMNS": str(HELP_WIDTH)}):
        formatter = parser._get_formatter()
        usage = parser.format_usage().strip()
    rows = []
    for action in parser._actions:
        if isinstance(action, argparse._HelpAction) or not action.option_strings:
            continue
        flag = ", ".join(action.option_strings)
        if action.choices:
            flag += " {" + ",".join(map(str, action.choices)) + "}"
        elif action.nargs != 0:
            flag += " " + formatter._format_args(action, action.metavar or action.dest.upper())
        default = "" if action.default in (None, argparse.SUPPRESS, [], False) else f"`{action.default}`"
        help_text = formatter._expand_help(action) if action.help else ""
        help_text = re.sub(r"\s*\(default: .*\)$", "", help_text)
        rows.append([f"`{flag}`", default, help_text])
    return f"```text\n{usage}\n```\n\n{parser.description}\n\n" + table(["flag", "default", "what it does"], rows)


def committed_pages() -> dict[Path, str]:
    """The committed generated pages (SCENE_KEYS and the _generated/ pieces) by path, with their text now."""
    pages = {DOCS / name: scene_keys_page(dim) for dim, name in SCENE_KEYS.items()}
    pages.update({GENERATED / f"app_{name}.md": app_page(name) for name in APPS})
    pages.update({GENERATED / f"results_{page}.md": text for page, text in results_pages().items()})
    return pages


def write_committed() -> list[Path]:
    """Write the committed generated pages (committed_pages); return their paths."""
    GENERATED.mkdir(exist_ok=True)
    for path, text in committed_pages().items():
        write_if_changed(path, text)
    return list(committed_pages())


def key_dimensions(keys: list) -> list[int]:
    """Each key's table: 3 for a key of a 3D body or chamber shape (a variant of body.shape or chambers[].shape
    other than the declaration's PLANAR_BODIES and PLANAR_CHAMBERS) or of a table inside one, 2 for the others
    (the 2D shapes' keys and those of every scene)."""
    from taichi_pneuma.scene.shape_keys import PLANAR_BODIES, PLANAR_CHAMBERS

    planar = {"body.shape": PLANAR_BODIES, "chambers[].shape": PLANAR_CHAMBERS}
    enclosing: list[tuple[str, int]] = []  # the shape variant's keys this key lies inside, with their dimension
    dims = []
    for k in keys:
        enclosing = [(key, dim) for key, dim in enclosing if k.key.startswith((key + ".", key + "[]"))]
        tag, _, value = k.when.partition(" = ")
        own = (2 if value.strip('"') in planar[tag] else 3) if tag in planar else None
        dim = enclosing[-1][1] if enclosing else own
        if dim is not None:
            enclosing.append((k.key, dim))
        dims.append(dim or 2)
    return dims


def scene_keys_page(dim: int) -> str:
    """The table of the scene file's keys of SCENE_KEYS[dim] (key_dimensions), with what the columns mean."""
    from taichi_pneuma.io.units import si_text
    from taichi_pneuma.scene.scenefile import key_reference

    def default(k) -> str:
        if not k.default:
            return ""
        if not k.unit or k.default in ("required", "none"):
            return f"`{k.default}`"
        return f"`{k.default}` ({'SI, converted' if k.scaled else 'unitless scenes only'})"

    keys = key_reference()
    rows = [
        [
            f"`{k.key}`",
            k.type,
            default(k),
            si_text(k.unit) if k.unit else "",
            k.allowed,
            f"`{k.when}`" if k.when else "",
            k.doc,
        ]
        for k, d in zip(keys, key_dimensions(keys))
        if d == dim
    ]
    other = Path(SCENE_KEYS[5 - dim]).name
    which = (
        f"{len(rows)} keys: those of every scene, which apply to 2D and 3D bodies alike, and those of the 2D body "
        f"and chamber shapes; the 3D shapes' keys are in {other}."
        if dim == 2
        else f"{len(rows)} keys of the 3D body and chamber shapes (a mesh file, the solids meshed by gmsh, a 2D "
        f"shape extruded, the PneuNet generator); the keys of every scene, which apply to 3D bodies too, are in "
        f"{other}."
    )
    return (
        f"<!-- written by `{REGENERATE}` from the scene file's declaration (scene/scene_keys.py): do not edit -->\n\n"
        f"{which} A key with a unit takes the scene's units (`units = ...`; the unit column gives the "
        f"SI one). Its default is in SI, converted into the scene's units; a numerical default (a penalty "
        f"stiffness, a barrier distance, a mesh size: 'unitless scenes only') is for unitless scenes, and a "
        f"scene with units gives the key.\n\n"
        + table(["key", "type", "default", "unit", "allowed", "applies when", "meaning"], rows)
    )


def docstring_of(path: str, function: str | None) -> str:
    """The docstring of a module (function None) or of one of its functions, read without importing it."""
    module = ast.parse((ROOT / path).read_text())
    if function is None:
        return ast.get_docstring(module) or ""
    found = [n for n in module.body if isinstance(n, ast.FunctionDef) and n.name == function]
    return ast.get_docstring(found[0]) if found else ""


def results_pages() -> dict[str, str]:
    pages: dict[str, list[str]] = {"performance": [], "accuracy": [], "stability": [], "scenes": [], "optimize": []}
    for path in sorted(RESULTS.glob("*.md")):
        page, title, (source, function), command = RESULTS_PAGES.get(
            path.stem, ("performance", path.stem, (None, None), "the script named in its JSON")
        )
        about = docstring_of(source, function) if source else ""
        first = " ".join(about.split("\n\n")[0].split())
        lines = [
            f"## {title}",
            "",
            first,
            "",
            f"Written by `{command}` to `benchmarks/results/{path.name}` (with `.json`):",
            "",
            path.read_text().strip(),
            "",
        ]
        picture = path.with_suffix(".png")
        if picture.exists():  # (the path as seen from the pages that include this one, in docs/)
            lines += [f"![{title}](../benchmarks/results/{picture.name})", ""]
        pages[page].append("\n".join(lines))
    return {page: "\n".join(sections) for page, sections in pages.items()}


API_INDEX = """# API reference

From the docstrings, module by module. The public names are those of `taichi_pneuma` (`tp.simulate`,
`tp.load_scene`, `tp.reference_scene`, `tp.Result`, `tp.Scene`, ...): {doc}`../guide/python_api` shows
them at work. The subpackages hold the parts a new term, law, chamber kind or element plugs into
({doc}`../extending`).

```{toctree}
:maxdepth: 1

"""


def api_packages() -> list[str]:
    import taichi_pneuma

    return ["taichi_pneuma"] + sorted(
        f"taichi_pneuma.{m.name}"
        for m in pkgutil.iter_modules(taichi_pneuma.__path__)
        if m.ispkg and m.name != "scenes"
    )


def api_page(package: str) -> str:
    """An automodule directive for the package (the top level: its own modules) or each module inside it."""
    module = importlib.import_module(package)
    if package == "taichi_pneuma":
        names = ["taichi_pneuma"] + sorted(
            f"taichi_pneuma.{m.name}"
            for m in pkgutil.iter_modules(module.__path__)
            if not m.ispkg and not m.name.startswith("_")
        )
    else:
        names = sorted(
            m.name
            for m in pkgutil.walk_packages(module.__path__, package + ".")
            if not m.name.rsplit(".", 1)[1].startswith("_")
        )
    # the top level re-exports names documented in their own modules: described here, indexed there
    return "\n".join(
        f"## {name}\n\n```{{eval-rst}}\n.. automodule:: {name}\n"
        + ("   :no-members:\n" if name == "taichi_pneuma" else "")
        + "```\n"
        for name in names
    )


INLINE = [
    (re.compile(r"\\"), r"\\\\"),
    (re.compile(r"\|"), r"\\|"),
    (re.compile(r"\*"), r"\\*"),
    (re.compile(r"(?<=\w)_(?=\W|$)"), r"\\_"),
    (re.compile(r"`"), r"\\`"),
]


def escape(line: str) -> str:
    for pattern, replacement in INLINE:
        line = pattern.sub(replacement, line)
    return line


def indent_of(line: str) -> int:
    return len(line) - len(line.lstrip())


def plain_docstring(app, what, name, obj, options, lines: list[str]) -> None:
    """Read a plain-text docstring as reST: inline markup characters escaped; a line indented deeper than the
    text (other than a list item's continuation) starts a literal block (an example, an equation laid out in
    columns) that ends where the indentation does; a list ('- ' items) gets the blank lines around it that
    reST wants."""
    out: list[str] = []
    literal, in_list = None, False
    for line in lines:
        depth = len(line) - len(line.lstrip())
        if literal is not None and (not line.strip() or depth >= literal):
            out.append(line)
            continue
        if literal is not None:
            literal = None
            out.append("")
        if not line.strip():
            in_list = False
            out.append(line)
            continue
        item = depth == 0 and line.startswith("- ")
        if depth > 0 and not (in_list and depth == 2):
            out += ([""] if out and out[-1].strip() else []) + ["::", ""]
            literal, in_list = depth, False
            out.append(line)
            continue
        if item != in_list and depth == 0 and out and out[-1].strip():
            out.append("")  # a list starts or ends
        in_list = item or (in_list and depth == 2)
        out.append(escape(line))
    lines[:] = out


if __name__ == "__main__":
    import sys

    sys.path.insert(0, str(ROOT))  # the package of this checkout, before an installed one
    for path in write_committed():
        print(f"wrote {path.relative_to(ROOT)}")
