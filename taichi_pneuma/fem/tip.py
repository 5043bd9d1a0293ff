"""What a run reads off the tip: the mean displacement of the mesh's tip nodes (the geometry's named tip; the
right edge, in 3D the right face, by default), a d-vector, and their rigid rotation in the x-y plane (in 3D the
bend angle about z); in 3D also their twist about the x axis (the body's axis).

An angle is the whole turn from rest, not its remainder within one turn: a finger that curls clockwise through
250 degrees reads -250, not +110, and one that curls through 400 degrees reads -400. One state's points give an
angle only modulo 360 degrees (atan2), so each is continued from the angle of the state before it, `near`: of the
angles congruent to the measured theta modulo 360, the one nearest to near, near + ((theta - near + 180) mod 360 -
180). Along a ramp the state before is the step before (rest: 0), so the angle is the sum of the steps' turns,
each read the shorter way round: right as long as no one step turns the tip through half a turn or more.
"""

from __future__ import annotations

import math

import numpy as np

COLUMNS = ("tip_dx", "tip_dy", "tip_dz")  # the history's names of the tip displacement's components, by axis


def continued(angle: float, near: float) -> float:
    """The angle (degrees) congruent to `angle` modulo 360 that is nearest to `near` (the module docstring):
    near + ((angle - near + 180) mod 360 - 180)."""
    return near + ((angle - near + 180.0) % 360.0 - 180.0)


def tip_rotation(rest: np.ndarray, current: np.ndarray, near: float = 0.0) -> float:
    """Least-squares rigid rotation (degrees) taking the centred rest points to the centred current ones:
    theta = atan2(sum r x c, sum r . c), r and c the centred rest and current points (k, 2), continued from the
    angle `near` of the state before (continued: the theta + 360 n nearest to it)."""
    r, c = rest - rest.mean(axis=0), current - current.mean(axis=0)
    theta = math.degrees(math.atan2(float(np.sum(r[:, 0] * c[:, 1] - r[:, 1] * c[:, 0])), float(np.sum(r * c))))
    return continued(theta, near)


def tip_twist(rest: np.ndarray, current: np.ndarray, near: float = 0.0) -> float:
    """The twist (degrees) of a 3D tip about the x axis: the least-squares rigid rotation (tip_rotation) of the tip
    points' (y, z) coordinates, rest (k, 3) to current (k, 3), continued from the twist `near` of the state before.
    Positive by the right-hand rule about +x: counter-clockwise seen from +x looking back down the axis (y turning
    towards z)."""
    return tip_rotation(rest[:, 1:3], current[:, 1:3], near)


def tip_twist_of(mesh, u: np.ndarray, near: float = 0.0) -> float | None:
    """The twist (tip_twist, continued from `near`) of the mesh's tip nodes at displacements u (n, 3); None in 2D
    (no twist)."""
    if mesh.dim == 2:
        return None
    rest = mesh.vertices[mesh.tip]
    return tip_twist(rest, rest + u[mesh.tip], near)


def tip_measures(mesh, u: np.ndarray, near: float = 0.0) -> tuple[np.ndarray, float]:
    """(displacement (d,), rotation in degrees) of the tip: the mean displacement of the mesh's tip nodes and
    their rigid rotation in the x-y plane, continued from the rotation `near` of the state before; u the (n, d)
    displacements."""
    rest, moved = mesh.vertices[mesh.tip, :2], u[mesh.tip, :2]
    return u[mesh.tip].mean(axis=0).astype(float), tip_rotation(rest, rest + moved, near)


def tip_outputs(mesh, u: np.ndarray) -> np.ndarray:
    """The tip outputs in the order of a sensitivity's rows (solve/sensitivity.py): dx, dy, the rotation in
    degrees, then (3D) dz."""
    tip, rotation = tip_measures(mesh, u)
    return np.array([*tip[:2], rotation, *tip[2:]])
