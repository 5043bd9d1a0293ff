"""Every shipped 3D scene runs through `pneuma-inflate --scene NAME` on a coarser mesh (COARSER: its gmsh lengths
about doubled, quadratic tetrahedra made linear; beam_3d's mesh file is its own; gripper_3d's quadratic, its fingers
locking on linear ones, so that they would never reach the ball), with its ramp, chambers, fibres, layers and
obstacles as shipped, exits 0 and writes its pictures (shipped_runs.py)."""

import pytest
from shipped_runs import DIMENSIONS, runs_and_writes_its_pictures


def mesh(size: float, near: float, distance: float, order: int | None = None) -> list[str]:
    """The --set flags of a 3D body's gmsh lengths (and element order)."""
    keys = {"size": size, "near_chambers": near, "distance": distance, **({} if order is None else {"order": order})}
    return [flag for key, value in keys.items() for flag in ("--set", f"mesh.{key}={value}")]


COARSER = {
    "beam_3d_ellipsoid": mesh(0.4, 0.2, 0.4, order=1),
    "blocked_force_3d": mesh(12, 6, 6, order=1),
    "fiber_bending_3d": mesh(12, 6, 6, order=1),  # near_chambers replaces the scene's through_wall
    "fiber_bending_step": mesh(12, 6, 6, order=1),  # (the STEP part of fiber_bending_3d)
    "fiber_twist_3d": mesh(6, 4, 4, order=1),
    "gripper_3d": ["--set", "mesh.size=8"],
    "pneunet_3d": mesh(0.5, 0.5, 0.5, order=1),
    "pneunet_fast_3d": mesh(0.5, 0.5, 0.5, order=1),
    "pneunet_stl": mesh(0.5, 0.5, 0.5, order=1),  # (the STL surface of pneunet_3d)
}


@pytest.mark.parametrize("name", [name for name, dim in DIMENSIONS.items() if dim == 3])
def test_every_shipped_3d_scene_exits_0_and_writes_its_pictures(name, tmp_path, capsys):
    runs_and_writes_its_pictures(name, COARSER.get(name, []), tmp_path, capsys)
