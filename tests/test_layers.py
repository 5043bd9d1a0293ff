"""The package's layers, read from its own imports: every import (lazy ones inside functions too) goes to the same
layer or a lower one, and no two modules import each other, directly or around a loop. docs/architecture.md draws
the same order."""

import ast
from pathlib import Path

import pytest

import taichi_pneuma

PACKAGE = Path(taichi_pneuma.__file__).parent

# bottom to top: a module may import from its own layer and the layers listed before it
LAYERS = (
    ("errors", "signals", "environment"),
    ("io", "limits", "backend"),
    ("materials", "runtime"),
    ("fem",),
    ("terms",),
    ("scene",),
    ("solve",),
    ("render",),
    ("result",),
    ("control", "reduce"),
    ("realtime",),
    ("api", "__init__"),
    ("study",),
    ("apps",),
)
RANK = {part: rank for rank, layer in enumerate(LAYERS) for part in layer}


def module_name(path: Path) -> str:
    parts = ("taichi_pneuma", *path.relative_to(PACKAGE).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def part_of(module: str) -> str:
    """The top-level part of the package a module belongs to: 'fem' for taichi_pneuma.fem.mesh, '__init__' for the
    package itself."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else "__init__"


def imported(source: str, module: str, is_package: bool, modules) -> set[str]:
    """The package's modules the source of `module` imports (lazy imports inside functions too); a name imported
    from a package that is one of `modules` counts as that submodule."""
    package = module if is_package else module.rsplit(".", 1)[0]
    targets = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            targets.update(a.name for a in node.names if a.name.startswith("taichi_pneuma"))
        elif isinstance(node, ast.ImportFrom):
            base = package.split(".")[: len(package.split(".")) - node.level + 1] if node.level else []
            origin = ".".join([*base, node.module] if node.module else base)
            if origin.startswith("taichi_pneuma"):
                targets.update(f"{origin}.{a.name}" if f"{origin}.{a.name}" in modules else origin for a in node.names)
    return targets - {module}


def imports() -> dict[str, set[str]]:
    """Every module of the package -> the package's modules it imports."""
    modules = {module_name(p): p for p in PACKAGE.rglob("*.py")}
    return {
        module: imported(path.read_text(encoding="utf-8"), module, path.name == "__init__.py", modules)
        for module, path in modules.items()
    }


def test_every_part_of_the_package_has_a_layer():
    assert {part_of(module) for module in imports()} == set(RANK)


def test_no_module_imports_from_a_higher_layer():
    upward = [
        f"{module} -> {target}"
        for module, targets in imports().items()
        for target in targets
        if RANK[part_of(target)] > RANK[part_of(module)]
    ]
    assert upward == []


def test_no_modules_import_each_other_around_a_loop():
    graph = imports()
    done, loops = set(), []

    def visit(module, path):
        if module in path:
            loops.append(path[path.index(module) :] + [module])
            return
        if module in done:
            return
        for target in sorted(graph.get(module, ())):
            visit(target, path + [module])
        done.add(module)

    for module in sorted(graph):
        visit(module, [])
    assert loops == []


@pytest.mark.parametrize(
    "source, expected",
    [
        ("from ..fem.mesh import Mesh", {"taichi_pneuma.fem.mesh"}),
        ("from .. import limits", {"taichi_pneuma.limits"}),
        ("def f():\n    from ..result import Result", {"taichi_pneuma.result"}),
        ("from .frames import Track", {"taichi_pneuma.render.frames"}),
        ("import numpy", set()),
    ],
)
def test_the_import_reader_resolves_relative_and_lazy_imports(source, expected):
    modules = {"taichi_pneuma.fem.mesh", "taichi_pneuma.limits", "taichi_pneuma.result", "taichi_pneuma.render.frames"}
    assert imported(source, "taichi_pneuma.render.probe", False, modules) == expected
