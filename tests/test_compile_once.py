"""Kernels compile once per process: a new scene, mesh, material or number of chambers compiles no kernel.

Each kernel keeps its compiled instances in a dict keyed by its compile key, `kernel._primal.compiled_kernels`
in Taichi and `kernel._primal.materialized_kernels` in Quadrants; a kernel whose compile key depended on a
mesh (a field's shape, a @ti.data_oriented instance) would gain one per scene.
The kernels are found, not listed: every object with a `_primal` in every module of the package.
"""

import importlib
import pkgutil
from pathlib import Path

import numpy as np
from solid_meshes import box_with_cavity, extruded_beam, scene_of, shell_octant

import taichi_pneuma
from taichi_pneuma import backend
from taichi_pneuma.fem.meshfile import write_mesh
from taichi_pneuma.scene.build import Material, reference_scene
from taichi_pneuma.scene.scenefile import load_scene
from taichi_pneuma.scene.schedule import ChamberSchedule, area_ramp
from taichi_pneuma.solve.newton import NewtonSolver
from taichi_pneuma.solve.simulate import run_schedule

SCENES = Path(__file__).resolve().parents[1] / "taichi_pneuma" / "scenes"


def package_kernels() -> dict[str, object]:
    """Every Taichi kernel defined in the package, by module.name (each once, in the module that defines it)."""
    kernels = {}
    for info in pkgutil.walk_packages(taichi_pneuma.__path__, "taichi_pneuma."):
        module = importlib.import_module(info.name)
        for name, obj in vars(module).items():
            if (
                getattr(obj, "_primal", None) is not None and obj.__module__ == module.__name__
            ):  # Quadrants' funcs: None
                kernels[f"{module.__name__}.{name}"] = obj
    return kernels


INSTANCES = {"taichi": "compiled_kernels", "quadrants": "materialized_kernels"}  # each backend's private dict


def compiled_instances() -> dict[str, int]:
    return {name: len(getattr(kernel._primal, INSTANCES[backend.NAME])) for name, kernel in package_kernels().items()}


def solve_once(built, commands):
    built.set_commands(commands)
    _, record = NewtonSolver(built.model).solve(np.zeros_like(built.mesh.vertices))
    assert record.converged


def test_new_scenes_compile_no_kernel():
    assert len(package_kernels()) >= 10  # the discovery finds the kernels (elastic, chamber, contact, linsolve, ...)
    run_schedule(reference_scene(0.15, growth=1.3, steps=3, max_area=0.01).build())
    before = compiled_instances()
    for name in ("elastic_energy", "elastic_gradient", "elastic_hessian", "inversion_step"):
        assert before[f"taichi_pneuma.terms.elastic.{name}"] >= 1
    # another mesh size, material, chamber stiffness and place; then two and six chambers, area and pressure
    # control; then quadratic elements (the same kernels: element size is a runtime loop bound)
    run_schedule(
        reference_scene(
            -0.1, growth=1.2, steps=3, youngs_modulus=3e4, poisson_ratio=0.3, chamber_stiffness=1e6, max_area=0.02
        ).build()
    )
    solve_once(load_scene(SCENES / "bidirectional.toml").build(), [1.2, 1.1])
    solve_once(load_scene(SCENES / "pneunet_finger.toml").build(), [50.0] * 6)
    run_schedule(reference_scene(0.15, growth=1.2, steps=3, max_area=0.05, chamber_points=32, order=2).build())
    assert compiled_instances() == before


def test_new_3d_scenes_compile_no_kernel(tmp_path):
    """3D kernels compile once per process too (per law and dimension): after one 3D scene, another mesh (a
    mesh file's, with quadratic tetrahedra), material, chamber closure and pressure control compile nothing."""
    beam, _ = extruded_beam(0.1, chamber_points=16)
    run_schedule(scene_of(beam, [area_ramp(1.2, 3, 1e5)], 2).build())
    before = compiled_instances()
    shell = shell_octant(3, 2, order=2)
    solve_once(scene_of(shell, [ChamberSchedule("pressure", ((1, 1.0),))], 1, Material(3e4, 0.3)).build(), [100.0])
    write_mesh(tmp_path / "beam_3d.msh", box_with_cavity(), ("chamber",))
    (tmp_path / "beam_3d.toml").write_text((SCENES / "beam_3d.toml").read_text())
    solve_once(load_scene(tmp_path / "beam_3d.toml").with_value("mesh.order", 2).build(), [1.05])
    assert compiled_instances() == before
