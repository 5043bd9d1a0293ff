"""Kernels compile once per process: a new scene, mesh, material or number of chambers compiles no kernel.

Taichi keeps each kernel's compiled instances in `kernel._primal.compiled_kernels`; a kernel whose
compile key depended on a mesh (a field's shape, a @ti.data_oriented instance) would gain one per scene.
"""

from pathlib import Path

import numpy as np

from taichi_pneuma.solve import linsolve
from taichi_pneuma.io.scenefile import load_scene
from taichi_pneuma.scene import reference_scene
from taichi_pneuma.solve.newton import NewtonSolver
from taichi_pneuma.solve.simulate import run_schedule
from taichi_pneuma.terms import contact, elastic
from taichi_pneuma.terms.chambers import wall

SCENES = Path(__file__).resolve().parents[1] / "taichi_pneuma" / "scenes"


def compiled_instances() -> dict[str, int]:
    """Compiled instances of every Taichi kernel defined in the package's kernel modules, by name."""
    return {f"{module.__name__}.{name}": len(obj._primal.compiled_kernels)
            for module in (elastic, wall, contact, linsolve)
            for name, obj in vars(module).items() if hasattr(obj, "_primal")}


def solve_once(built, commands):
    built.set_commands(commands)
    _, record = NewtonSolver(built.model).solve(np.zeros_like(built.mesh.vertices))
    assert record.converged


def test_new_scenes_compile_no_kernel():
    run_schedule(reference_scene(0.15, growth=1.3, steps=3, max_area=0.01).build())
    before = compiled_instances()
    used = ["elastic_energy", "elastic_gradient", "elastic_hessian", "inversion_step", "wall_area"]
    assert all(before[f"taichi_pneuma.terms.{'chambers.wall' if k == 'wall_area' else 'elastic'}.{k}"] == 1 for k in used)
    # another mesh size, material, chamber stiffness and place; then two and six chambers, area and pressure control
    run_schedule(reference_scene(-0.1, growth=1.2, steps=3, youngs_modulus=3e4, poisson_ratio=0.3,
                                 chamber_stiffness=1e6, max_area=0.02).build())
    solve_once(load_scene(SCENES / "bidirectional.toml").build(), [1.2, 1.1])
    solve_once(load_scene(SCENES / "pneunet_finger.toml").build(), [50.0] * 6)
    assert compiled_instances() == before
