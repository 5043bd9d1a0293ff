"""A sealed chamber under area ("volume") control, as Taichi kernels.

The chamber wall is a closed counter-clockwise vertex loop x_0 .. x_{k-1}; its signed area

    A(x) = 1/2 sum_i x_i x x_{i+1}        (2D cross product, indices mod k)

has gradient dA/dx_i = 1/2 (y_{i+1} - y_{i-1}, x_{i-1} - x_{i+1}): half the sum of the outward
normals of the two wall edges at vertex i (outward from the chamber, into the rubber). The term

    E = 1/2 k (A(x) - A*)^2,   dE/dx = k (A - A*) dA/dx = -p dA/dx,   p = k (A* - A),

is therefore exactly a uniform pressure p on the wall. Its Hessian is

    k dA dA^T  -  p d2A,     d2A/dx_i dy_{i+1} = 1/2,  d2A/dy_i dx_{i+1} = -1/2  (and symmetric),

a PSD rank-1 Gauss-Newton part, handed to the solver as a low-rank term, plus the load stiffness
-p d2A of the follower pressure, which is indefinite. It does not vanish at equilibrium (there
A - A* = -p/k), so dropping it leaves Newton converging only linearly; it is returned as sparse
triplets unless the solver asks for the PSD (Gauss-Newton) Hessian only.
"""


import numpy as np
import taichi as ti

from .base import Term, vertex_dofs


@ti.data_oriented
class AreaChamber(Term):
    """Area control of one chamber: stiffness k pulls the enclosed area A(x) to target_area."""

    name = "chamber"

    def __init__(self, config, loop: np.ndarray, stiffness: float, target_area: float):
        self.config = config
        self.k = float(stiffness)
        self.target_area = float(target_area)
        self.loop_vertices = np.asarray(loop, dtype=np.int64)
        n = len(loop)
        self.n_wall = n
        self.loop = ti.field(ti.i32, n)
        self.loop.from_numpy(self.loop_vertices.astype(np.int32))
        self.area_gradient = ti.Vector.field(2, ti.f64, n)
        self.force = ti.Vector.field(2, ti.f64, config.n_vertices)
        self.current_area = ti.field(ti.f64, ())
        self.target = ti.field(ti.f64, ())
        self.dofs = vertex_dofs(self.loop_vertices)
        nxt = np.roll(self.loop_vertices, -1)
        xi, yi, xn, yn = 2 * self.loop_vertices, 2 * self.loop_vertices + 1, 2 * nxt, 2 * nxt + 1
        self._rows = np.concatenate([xi, yn, yi, xn])
        self._cols = np.concatenate([yn, xi, xn, yi])
        self._area_hessian = np.repeat([0.5, 0.5, -0.5, -0.5], n)

    @ti.kernel
    def area(self) -> ti.f64:
        """The signed shoelace area A(x) of the wall loop."""
        total = 0.0
        for i in range(self.n_wall):
            total += 0.5 * self.config.x(self.loop[i]).cross(self.config.x(self.loop[(i + 1) % self.n_wall]))
        return total

    @ti.kernel
    def _compute_area_gradient(self):
        for i in range(self.n_wall):
            nxt = self.config.x(self.loop[(i + 1) % self.n_wall])
            prv = self.config.x(self.loop[(i + self.n_wall - 1) % self.n_wall])
            self.area_gradient[i] = 0.5 * ti.Vector([nxt[1] - prv[1], prv[0] - nxt[0]])

    @ti.kernel
    def _compute_force(self):
        """dE/dx = -p dA/dx on the wall vertices (the only non-zero rows of the force field)."""
        self.current_area[None] = 0.0
        for i in range(self.n_wall):
            x = self.config.x(self.loop[i])
            nxt = self.config.x(self.loop[(i + 1) % self.n_wall])
            prv = self.config.x(self.loop[(i + self.n_wall - 1) % self.n_wall])
            self.current_area[None] += 0.5 * x.cross(nxt)
            self.area_gradient[i] = 0.5 * ti.Vector([nxt[1] - prv[1], prv[0] - nxt[0]])
        pressure = self.k * (self.target[None] - self.current_area[None])
        for i in range(self.n_wall):
            self.force[self.loop[i]] = -pressure * self.area_gradient[i]

    def pressure(self) -> float:
        """p = k (A* - A): positive when the chamber pushes its walls outward."""
        return self.k * (self.target_area - self.area())

    def energy(self) -> float:
        return 0.5 * self.k * (self.area() - self.target_area) ** 2

    def gradient(self) -> np.ndarray:
        self.target[None] = self.target_area
        self._compute_force()
        return self.force.to_numpy()

    def hessian_pattern(self) -> tuple[np.ndarray, np.ndarray]:
        return self._rows, self._cols

    def hessian_values(self, psd_only: bool = False) -> np.ndarray:
        return np.zeros(len(self._rows)) if psd_only else -self.pressure() * self._area_hessian

    def low_rank(self) -> list[tuple[np.ndarray, np.ndarray, float]]:
        self._compute_area_gradient()
        return [(self.dofs, self.area_gradient.to_numpy().ravel(), self.k)]
