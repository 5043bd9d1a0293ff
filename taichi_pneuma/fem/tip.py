"""What a run reads off the tip: the mean displacement of the mesh's tip nodes (the geometry's named tip; the
right edge, in 3D the right face, by default), a d-vector, and their rigid rotation in the x-y plane (in 3D the
bend angle about z); in 3D also their twist about the x axis (the body's axis)."""

from __future__ import annotations

import math

import numpy as np

COLUMNS = ("tip_dx", "tip_dy", "tip_dz")  # the history's names of the tip displacement's components, by axis


def tip_rotation(rest: np.ndarray, current: np.ndarray) -> float:
    """Least-squares rigid rotation (degrees) taking the centred rest points to the centred current ones:
    theta = atan2(sum r x c, sum r . c), r and c the centred rest and current points (k, 2)."""
    r, c = rest - rest.mean(axis=0), current - current.mean(axis=0)
    return math.degrees(math.atan2(float(np.sum(r[:, 0] * c[:, 1] - r[:, 1] * c[:, 0])), float(np.sum(r * c))))


def tip_twist(rest: np.ndarray, current: np.ndarray) -> float:
    """The twist (degrees) of a 3D tip about the x axis: the least-squares rigid rotation (tip_rotation) of the tip
    points' (y, z) coordinates, rest (k, 3) to current (k, 3). Positive by the right-hand rule about +x: counter-
    clockwise seen from +x looking back down the axis (y turning towards z)."""
    return tip_rotation(rest[:, 1:3], current[:, 1:3])


def tip_twist_of(mesh, u: np.ndarray) -> float | None:
    """The twist (tip_twist) of the mesh's tip nodes at displacements u (n, 3); None in 2D (no twist)."""
    if mesh.dim == 2:
        return None
    rest = mesh.vertices[mesh.tip]
    return tip_twist(rest, rest + u[mesh.tip])


def tip_measures(mesh, u: np.ndarray) -> tuple[np.ndarray, float]:
    """(displacement (d,), rotation in degrees) of the tip: the mean displacement of the mesh's tip nodes and
    their rigid rotation in the x-y plane, u the (n, d) displacements."""
    rest, moved = mesh.vertices[mesh.tip, :2], u[mesh.tip, :2]
    return u[mesh.tip].mean(axis=0).astype(float), tip_rotation(rest, rest + moved)


def tip_outputs(mesh, u: np.ndarray) -> np.ndarray:
    """The tip outputs in the order of a sensitivity's rows (solve/sensitivity.py): dx, dy, the rotation in
    degrees, then (3D) dz."""
    tip, rotation = tip_measures(mesh, u)
    return np.array([*tip[:2], rotation, *tip[2:]])
