"""The datasets a run's ParaView files hold beside the body (render/paraview.py): its fibres, its sheets and its
obstacles, each a Part whose points are at rest (an obstacle's: its placed position) and whose displacement point
array moves them to a step's positions, as the body's does: one Warp By Vector on the collection moves all.

    fibers     a line cell per cord segment (terms/fibers.py Cords) between its two embedded points; cell data
               tension (the cord's force E A (l / L0 - 1), 0 where slack; in 2D per unit depth), stretch l / L0
               and fiber (the fibre's index in the scene's [[fibers]])
    sheets     a triangle (3D) or segment (2D) per membrane cell (terms/sheets.py: a quadratic facet's linear
               pieces) on the body's nodes; cell data stress (the sheet's Cauchy stress, Membrane.stress, in the
               body's 6-component order), max_stretch (its largest principal stretch) and layer (the index in the
               scene's [[layers]])
    obstacles  each obstacle's surface (3D) or outline (2D) (obstacle_cells); cell data obstacle (the
               index in the scene's [[obstacles]]); displacement: its translation at the step (its keyframes', and
               a held object's height, the history's '<name>.dy')
"""

from __future__ import annotations

import numpy as np

from ..io.units import FORCE, LENGTH, PRESSURE, in_dimension
from ..io.vtk import LINE, POLYGON, TRIANGLE, VtkCell, pad3
from ..terms.fibers import Cords
from ..terms.membrane import Membrane

SYMMETRIC_TENSOR = ((0, 0), (1, 1), (2, 2), (0, 1), (1, 2), (0, 2))  # ParaView's 6-component order


class Part:
    """A dataset beside the body: its name (the PVD's), rest points (k, 3) and cell blocks; data() gives a step's
    point data (displacement) and cell data."""

    name = ""

    def __init__(self, units, points: np.ndarray, cells: list):
        self.units, self.points, self.cells = units, points, cells

    def displacement(self, positions: np.ndarray, step) -> np.ndarray:
        raise NotImplementedError

    def cell_data(self, positions: np.ndarray, step) -> dict[str, np.ndarray]:
        raise NotImplementedError

    def data(self, positions: np.ndarray, step) -> tuple[dict[str, np.ndarray], dict[str, list[np.ndarray]]]:
        """(point data, cell data) of the step (a StepRecord) with the body's nodes at positions (n, d)."""
        point_data = {self.units.label("displacement", LENGTH): self.displacement(positions, step)}
        return point_data, {name: [values] for name, values in self.cell_data(positions, step).items()}


class Fibers(Part):
    """Every fibre's cord segments, one dataset."""

    name = "fibers"

    def __init__(self, built, terms: list[Cords]):
        rest = built.mesh.vertices
        offsets = np.cumsum([0] + [len(t.nodes) for t in terms])
        segments = np.vstack([t.segments + start for t, start in zip(terms, offsets)])
        super().__init__(built.scene.units, pad3(np.vstack([t.points(rest) for t in terms])), [(LINE, segments)])
        self.terms, self.rest = terms, rest
        self.index = np.concatenate([np.full(len(t.segments), i) for i, t in enumerate(terms)]).astype(np.int32)
        self.force = in_dimension(FORCE, built.mesh.dim)

    def displacement(self, positions, step):
        return pad3(np.vstack([t.points(positions - self.rest) for t in self.terms]))

    def cell_data(self, positions, step):
        u = positions - self.rest
        return {
            self.units.label("tension", self.force): np.concatenate([t.tension(u) for t in self.terms]),
            "stretch": np.concatenate([t.lengths(u) / t.rest_length for t in self.terms]),
            "fiber": self.index,
        }


class Sheets(Part):
    """Every layer's membrane cells, one dataset on the body's nodes they use."""

    name = "sheets"

    def __init__(self, built, terms: list[Membrane]):
        mesh = built.mesh
        self.nodes, local = np.unique(np.vstack([t.cells for t in terms]), return_inverse=True)
        cells = local.reshape(-1, mesh.dim)
        super().__init__(
            built.scene.units, pad3(mesh.vertices[self.nodes]), [(TRIANGLE if mesh.dim == 3 else LINE, cells)]
        )
        self.terms, self.rest = terms, mesh.vertices
        self.index = np.concatenate([np.full(len(t.cells), i) for i, t in enumerate(terms)]).astype(np.int32)

    def displacement(self, positions, step):
        return pad3((positions - self.rest)[self.nodes])

    def cell_data(self, positions, step):
        stress, stretch = zip(*(t.stress(positions - self.rest) for t in self.terms))
        sigma = np.concatenate(stress)
        return {
            self.units.label("stress", PRESSURE): np.column_stack([sigma[:, i, j] for i, j in SYMMETRIC_TENSOR]),
            "max_stretch": np.concatenate(stretch),
            "layer": self.index,
        }


def obstacle_cells(shape, dim: int, reach: float, centre: np.ndarray) -> tuple[np.ndarray, VtkCell, np.ndarray]:
    """(points (k, 3), cell type, cells) of an obstacle's shape where it is placed: in 3D the triangles of its
    Shape.surface (reach and centre place a plane's patch), which the 3D frames draw too (render/guides3d.py); in 2D
    its Shape.outline at z = 0, a closed one as a polygon, a plane's line as a segment of half-length reach."""
    if dim == 3:
        surface = shape.surface(reach, centre)
        return surface.points, TRIANGLE, surface.triangles
    points, closed = shape.outline(reach)
    return pad3(points), POLYGON if closed else LINE, np.arange(len(points))[None, :]


class Obstacles(Part):
    """Every obstacle's surface or outline, one dataset. A plane reaches twice the body's largest extent: in 3D
    its patch's half-size, about the point of the plane nearest the body's centre; in 2D its segment's half-length,
    about its point."""

    name = "obstacles"

    def __init__(self, built):
        mesh, self.obstacles = built.mesh, built.scene.obstacles
        reach = 2 * float(np.ptp(mesh.vertices, axis=0).max())
        centre = pad3(mesh.vertices.mean(axis=0)[None, :])[0]
        shapes = [obstacle_cells(o.shape, mesh.dim, reach, centre) for o in self.obstacles]
        starts = np.cumsum([0] + [len(points) for points, _, _ in shapes])
        super().__init__(
            built.scene.units,
            np.vstack([points for points, _, _ in shapes]),
            [(kind, cells + start) for (_, kind, cells), start in zip(shapes, starts)],
        )
        self.counts = np.diff(starts)
        self.index = np.concatenate([np.full(len(cells), i) for i, (_, _, cells) in enumerate(shapes)])

    def displacement(self, positions, step):
        moves = [o.offset(step.step) + (0.0, step.extra.get(f"{o.name}.dy", 0.0), 0.0) for o in self.obstacles]
        return np.repeat(np.array(moves), self.counts, axis=0)

    def cell_data(self, positions, step):
        return {"obstacle": self.index.astype(np.int32)}


def parts(built) -> list[Part]:
    """The parts a built scene has: its fibres, sheets and obstacles, those it has."""
    cords = [t for t in built.model.terms if isinstance(t, Cords)]
    sheets = [t for t in built.model.terms if isinstance(t, Membrane)]
    return (
        ([Fibers(built, cords)] if cords else [])
        + ([Sheets(built, sheets)] if sheets else [])
        + ([Obstacles(built)] if built.scene.obstacles else [])
    )
