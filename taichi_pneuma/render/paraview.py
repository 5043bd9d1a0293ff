"""ParaView output: one VTU file per step and a PVD collection indexing them by step.

    <out>/<stem>.pvd                     the collection: open this in ParaView (timestep = step)
    <out>/<stem>_vtk/<stem>_0000.vtu     step 0, 1, ... each written whole (output.write_atomic)

The PVD is rewritten after every step, so a run that stops early leaves its finished steps readable;
VTU files of the same stem left in the folder by an earlier run, and the .partial files of one killed
while writing, are removed when a series starts. The folder is an output.Subfolder: a link or a file at
its name is refused before any step is solved, and no link in it is followed.
Each VTU holds the rest mesh (in 2D points padded with z = 0; linear triangles, or quadratic ones as VTK's
6-node triangle, whose midside-node order 01, 12, 20 the mesh shares; in 3D tetrahedra, 4-node or VTK's
10-node, whose node order the mesh shares, followed by the chamber walls' triangles, each its chamber's
index in the cell field chamber, -1 on the tetrahedra, and NaN in the other cell fields) and
- point data: displacement (x, y, 0; x, y, z in 3D): ParaView's Warp By Vector with it shows the deformed body;
  chamber: the index (scene order) of the chamber whose wall the vertex is on, -1 elsewhere;
  contact_force (x, y, 0), summed over the contact terms, when the scene has contact;
- cell data (fields.py: element means over the quadrature points): det_F, max_stretch, stress (Cauchy,
  6 components in ParaView's symmetric-tensor order XX, YY, ZZ, XY, YZ, XZ; ZZ the plane-strain
  out-of-plane stress) and von_mises (of that stress);
- field data: the step's history row (per chamber <name>.command/.area/.area_ratio/.pressure, tip_dx,
  tip_dy, tip_rotation, solver figures), one value each.
In a scene with units every array's name carries its unit (io/units.py): "displacement [mm]",
"stress [kPa]", "main.pressure [kPa]".
The text of each file: io/vtk.py.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from ..fem.fields import ElementFields
from ..io.output import Subfolder, held_private_folder, save_text, write_atomic
from ..io.units import FORCE, LENGTH, PRESSURE, history_dimensions, in_dimension
from ..io.vtk import pad3, pvd_text, vtu_text

SYMMETRIC_TENSOR = ((0, 0), (1, 1), (2, 2), (0, 1), (1, 2), (0, 2))  # ParaView's 6-component order


class VtkSeries:
    """Writes the VTU of each step as it comes (write()) and keeps <stem>.pvd indexing those written."""

    def __init__(self, directory: str | Path, stem: str, built):
        mesh = built.mesh
        self.directory, self.stem, self.mesh = Path(directory), stem, mesh
        self._folder = Subfolder(self.directory, f"{stem}_vtk")
        self.folder = self._folder.path
        stale = re.compile(
            rf"{re.escape(stem)}_\d{{4,}}\.vtu|\..*\.partial.*"
        )  # an earlier run's steps, a killed write
        for name in self._folder.names():
            if stale.fullmatch(name):
                self._folder.remove(name)
        self.pvd = self.directory / f"{stem}.pvd"
        self._scratch = held_private_folder(self, self.directory, f"{stem}_vtk")  # every step's VTU and PVD
        self.scene = built.scene
        self.material = built.elastic.law, built.elastic.parameters
        self.fields = ElementFields(mesh.vertices, mesh.elements)
        self.points = pad3(mesh.vertices)
        self.cells = [(mesh.family, mesh.elements)]
        walls = mesh.family.facet_family  # a 3D mesh's chamber walls are facets; a 2D one's are node loops
        self.walls = [] if walls is None else [(walls, np.vstack(mesh.chambers))]
        if self.walls:
            self.wall_chamber = np.concatenate([np.full(len(w), i) for i, w in enumerate(mesh.chambers)])
        self.chamber = np.full(mesh.n_vertices, -1, dtype=np.int32)
        for index, loop in enumerate(mesh.chambers):
            self.chamber[loop] = index
        self.entries: list[tuple[float, str]] = []

    def write(self, step, positions: np.ndarray, contact_force: np.ndarray | None = None) -> Path:
        """Write step (a simulate.StepRecord) at positions (n, d); return the VTU's path."""
        mesh = self.mesh
        fields = self.fields.at(positions, *self.material)
        stress = np.column_stack([fields["stress"][:, i, j] for i, j in SYMMETRIC_TENSOR])
        units = self.scene.units
        point_data = {units.label("displacement", LENGTH): pad3(positions - mesh.vertices), "chamber": self.chamber}
        if contact_force is not None:
            point_data[units.label("contact_force", in_dimension(FORCE, mesh.dim))] = pad3(contact_force)
        element_data = {
            "det_F": fields["det_F"],
            "max_stretch": fields["max_stretch"],
            units.label("stress", PRESSURE): stress,
            units.label("von_mises", PRESSURE): fields["von_mises"],
        }
        cell_data: dict[str, list[np.ndarray]]
        if self.walls:  # the chamber walls' triangles: their chamber, and no element field
            cell_data = {
                name: [values, np.full((len(self.wall_chamber), *values.shape[1:]), np.nan)]
                for name, values in element_data.items()
            }
            cell_data["chamber"] = [np.full(mesh.n_elements, -1), self.wall_chamber]
        else:
            cell_data = {name: [values] for name, values in element_data.items()}
        dimensions = history_dimensions(self.scene, step.contact, mesh.dim)
        row = {units.label(name, dimensions.get(name, "")): value for name, value in step.row().items()}
        text = vtu_text(self.points, self.cells + self.walls, point_data, cell_data, row)
        path = self.folder / f"{self.stem}_{step.step:04d}.vtu"
        write_atomic(path, lambda tmp: tmp.write_text(text, encoding="utf-8"), self._folder, self._scratch)
        self.entries.append((float(step.step), f"{self.folder.name}/{path.name}"))
        save_text(self.pvd, pvd_text(self.entries), self._scratch)
        return path

    def write_all(self, result) -> Path:
        """Write every step of a run (a solve.records.Run or a Result); return the PVD's path."""
        forces = result.contact_forces
        for i, step in enumerate(result.steps):
            self.write(step, result.positions[i], None if forces is None else forces[i])
        return self.pvd
