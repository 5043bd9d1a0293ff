"""A sealed chamber under area ("volume") control or pressure control, as Taichi kernels.

The chamber wall is a closed counter-clockwise vertex loop x_0 .. x_{k-1}; its signed area

    A(x) = 1/2 sum_i x_i x x_{i+1}        (2D cross product, indices mod k)

has gradient dA/dx_i = 1/2 (y_{i+1} - y_{i-1}, x_{i-1} - x_{i+1}): half the sum of the outward
normals of the two wall edges at vertex i (outward from the chamber, into the rubber), and the
constant Hessian d2A/dx_i dy_{i+1} = 1/2, d2A/dy_i dx_{i+1} = -1/2 (and symmetric).

Area control (commanded area ratio r, A* = r A_rest):

    E = 1/2 k (A(x) - A*)^2,   dE/dx = -p dA/dx,   p = k (A* - A),
    Hessian  k dA dA^T - p d2A:

a PSD rank-1 Gauss-Newton part, handed to the solver as a low-rank term, plus the load stiffness
-p d2A of the follower pressure, which is indefinite. It does not vanish at equilibrium (there
A - A* = -p/k), so dropping it leaves Newton converging only linearly; it is returned as sparse
triplets unless the solver asks for the PSD Hessian only.

Pressure control (commanded pressure p): the work of a prescribed pressure,

    E = -p A(x),   dE/dx = -p dA/dx,   Hessian -p d2A,

which has no PSD part at all: with psd_only the term contributes nothing (the PSD elastic and
clamp Hessians alone keep projected Newton a descent method), and the exact Hessian is used once
Newton is in its quadratic basin. Both forms apply exactly a uniform pressure p to the wall.
"""


import numpy as np
import taichi as ti

from .base import Indices, Term, Vec2s, int32s, position, vertex_dofs


@ti.kernel
def wall_area(rest: Vec2s, u: Vec2s, loop: Indices, gradient: Vec2s) -> ti.f64:
    """The signed shoelace area A(x) of the wall loop; gradient[i] = dA/dx of loop vertex i."""
    total = 0.0
    k = loop.shape[0]
    for i in range(k):
        here = position(rest, u, loop[i])
        nxt = position(rest, u, loop[(i + 1) % k])
        prv = position(rest, u, loop[(i + k - 1) % k])
        total += 0.5 * here.cross(nxt)
        gradient[i] = 0.5 * ti.Vector([nxt[1] - prv[1], prv[0] - nxt[0]])
    return total


class Chamber(Term):
    """The wall loop of one named chamber: its area, area gradient and the -p d2A load stiffness."""

    control = "chamber"

    def __init__(self, config, loop: np.ndarray, name: str):
        self.config = config
        self.chamber_name = name
        self.name = f"chamber:{name}"
        self.loop_vertices = np.asarray(loop, dtype=np.int64)
        self.loop = int32s(loop)
        self.dofs = vertex_dofs(self.loop_vertices)
        self.n_wall = n = len(loop)
        nxt = np.roll(self.loop_vertices, -1)
        xi, yi, xn, yn = 2 * self.loop_vertices, 2 * self.loop_vertices + 1, 2 * nxt, 2 * nxt + 1
        self._rows = np.concatenate([xi, yn, yi, xn])
        self._cols = np.concatenate([yn, xi, xn, yi])
        self._area_hessian = np.repeat([0.5, 0.5, -0.5, -0.5], n)
        rest = config.rest[self.loop_vertices]
        self.rest_area = 0.5 * float(np.dot(rest[:, 0], np.roll(rest[:, 1], -1)) - np.dot(np.roll(rest[:, 0], -1), rest[:, 1]))

    def area_and_gradient(self) -> tuple[float, np.ndarray]:
        """A(x) and dA/dx on the wall vertices, (k, 2) in loop order."""
        gradient = np.empty((len(self.loop), 2))
        return wall_area(self.config.rest, self.config.u, self.loop, gradient), gradient

    def area(self) -> float:
        """The signed shoelace area A(x) of the wall loop."""
        return self.area_and_gradient()[0]

    def gradient(self) -> np.ndarray:
        """dE/dx = -p dA/dx for both controls, non-zero on the wall vertices only."""
        area, area_gradient = self.area_and_gradient()
        force = np.zeros_like(self.config.u)
        force[self.loop_vertices] = -self.pressure_at(area) * area_gradient
        return force

    def pressure(self) -> float:
        return self.pressure_at(self.area())

    def hessian_pattern(self) -> tuple[np.ndarray, np.ndarray]:
        return self._rows, self._cols

    def hessian_values(self, psd_only: bool = False) -> np.ndarray:
        return np.zeros(len(self._rows)) if psd_only else -self.pressure() * self._area_hessian


class AreaChamber(Chamber):
    """Area control: stiffness k pulls the enclosed area A(x) to target_area = command x rest area."""

    control = "area"

    def __init__(self, config, loop: np.ndarray, stiffness: float, name: str = "main"):
        super().__init__(config, loop, name)
        self.k = float(stiffness)
        self.target_area = self.rest_area

    def set_command(self, ratio: float) -> None:
        """Command the area ratio A* / A_rest."""
        self.target_area = float(ratio) * self.rest_area

    def pressure_at(self, area: float) -> float:
        """p = k (A* - A): positive when the chamber pushes its walls outward."""
        return self.k * (self.target_area - area)

    def energy(self) -> float:
        return 0.5 * self.k * (self.area() - self.target_area) ** 2

    def low_rank(self) -> list[tuple[np.ndarray, np.ndarray, float]]:
        return [(self.dofs, self.area_and_gradient()[1].ravel(), self.k)]


class PressureChamber(Chamber):
    """Pressure control: a prescribed pressure p does work p A(x) on the wall."""

    control = "pressure"

    def __init__(self, config, loop: np.ndarray, name: str = "main"):
        super().__init__(config, loop, name)
        self.prescribed = 0.0

    def set_command(self, pressure: float) -> None:
        """Command the pressure p."""
        self.prescribed = float(pressure)

    def pressure_at(self, area: float) -> float:
        return self.prescribed

    def pressure(self) -> float:
        return self.prescribed

    def energy(self) -> float:
        return -self.prescribed * self.area()
