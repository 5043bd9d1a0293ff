"""ParaView output: per step a VTU file of the body and one of each part beside it (its fibres, sheets and
obstacles, those the scene has: render/paraview_parts.py), and a PVD collection indexing them.

    <out>/<stem>.pvd                          the collection: open this in ParaView
    <out>/<stem>_vtk/<stem>_0000.vtu          the body at step 0, 1, ... each written whole (output.write_atomic)
    <out>/<stem>_vtk/<stem>_fibers_0000.vtu   the fibres (and _sheets_, _obstacles_) at step 0, 1, ...

The PVD lists per step the body as part 0 and the scene's parts as parts 1, 2, ... in the order fibers, sheets,
obstacles (each DataSet also names its part: name="body", "fibers", ...), so ParaView reads each step as one
multiblock dataset. Its timestep is the first chamber's pressure when that chamber is pressure-controlled and its
schedule strictly increases it over the steps (a pressure ramp: the time axis reads in the scene's pressure unit),
else the step index (a deflating, holding or non-pressure schedule: a PVD's timesteps must increase); the step and
every chamber's pressure are in each body file's field data either way.
The PVD is rewritten after every step, so a run that stops early leaves its finished steps readable;
VTU files of the same stem left in the folder by an earlier run, and the .partial files of one killed
while writing, are removed when a series starts. The folder is an output.Subfolder: a link or a file at
its name is refused before any step is solved, and no link in it is followed.
Each body VTU holds the rest mesh (in 2D points padded with z = 0; linear triangles, or quadratic ones as VTK's
6-node triangle, whose midside-node order 01, 12, 20 the mesh shares; in 3D tetrahedra, 4-node or VTK's
10-node, whose node order the mesh shares, followed by the chamber walls' triangles, each its chamber's
index in the cell field chamber, -1 on the tetrahedra, and NaN in the other cell fields) and
- point data: displacement (x, y, 0; x, y, z in 3D): ParaView's Warp By Vector with it shows the deformed body
  (and the parts, whose points are at rest too, each with its displacement);
  chamber: the index (scene order) of the chamber whose wall the vertex is on, -1 elsewhere;
  contact_force (x, y, 0), summed over the contact terms, when the scene has contact;
- cell data (fields.py: element means over the quadrature points): det_F, max_stretch, stress (Cauchy,
  6 components in ParaView's symmetric-tensor order XX, YY, ZZ, XY, YZ, XZ; ZZ the plane-strain
  out-of-plane stress) and von_mises (of that stress);
- field data: the step's history row (per chamber <name>.command/.area/.area_ratio/.pressure, tip_dx,
  tip_dy, tip_rotation, solver figures), one value each.
In a scene with units every array's name carries its unit (io/units.py): "displacement [mm]",
"stress [kPa]", "main.pressure [kPa]", a 3D fibre's "tension [mN]".
The text of each file: io/vtk.py.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from ..io.output import Subfolder, held_private_folder, save_text, write_atomic
from ..io.units import FORCE, LENGTH, PRESSURE, in_dimension
from ..io.vtk import pad3, pvd_text, vtu_text
from ..solve.columns import history_dimensions
from .paraview_parts import SYMMETRIC_TENSOR, parts


def pressure_timesteps(scene) -> list[float] | None:
    """The PVD's timestep of each step 0 .. increments: the first chamber's commanded pressure where it is
    pressure-controlled and strictly increases over them, else None (the step index is the timestep)."""
    schedule = scene.schedule
    if not schedule.chambers or schedule.chambers[0].kind.dimension != PRESSURE:
        return None
    values = [schedule.chambers[0].command(s) for s in range(schedule.increments + 1)]
    return values if all(b > a for a, b in zip(values, values[1:])) else None


class VtkSeries:
    """Writes the VTU of each step as it comes (write()) and keeps <stem>.pvd indexing those written."""

    def __init__(self, directory: str | Path, stem: str, built):
        mesh = built.mesh
        self.directory, self.stem, self.mesh = Path(directory), stem, mesh
        self._folder = Subfolder(self.directory, f"{stem}_vtk")
        self.folder = self._folder.path
        stale = re.compile(
            rf"{re.escape(stem)}(_fibers|_sheets|_obstacles)?_\d{{4,}}\.vtu|\..*\.partial.*"
        )  # an earlier run's steps, a killed write
        for name in self._folder.names():
            if stale.fullmatch(name):
                self._folder.remove(name)
        self.pvd = self.directory / f"{stem}.pvd"
        self._scratch = held_private_folder(self, self.directory, f"{stem}_vtk")  # every step's VTU and PVD
        self.scene = built.scene
        self.material = built.elastic.law, built.elastic.parameters
        self.fields = mesh.fields
        self.points = pad3(mesh.vertices)
        self.cells = [(mesh.family, mesh.elements)]
        walls = (
            mesh.family.facet_family if mesh.dim == 3 else None
        )  # a 3D mesh's chamber walls are facets; a 2D one's are node loops
        self.walls = [] if walls is None else [(walls, np.vstack(mesh.chambers))]
        if self.walls:
            self.wall_chamber = np.concatenate([np.full(len(w), i) for i, w in enumerate(mesh.chambers)])
        self.chamber = np.full(mesh.n_vertices, -1, dtype=np.int32)
        for index, loop in enumerate(mesh.chambers):
            self.chamber[loop] = index
        self.parts = parts(built)
        self.timesteps = pressure_timesteps(built.scene)
        self.entries: list[tuple[float, int, str, str]] = []  # (timestep, part, name, file) (io/vtk.py pvd_text)

    def write(self, step, positions: np.ndarray, contact_force: np.ndarray | None = None) -> Path:
        """Write step (a simulate.StepRecord) at positions (n, d): the body's VTU and each part's; return the
        body's path."""
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
        timestep = float(step.step) if self.timesteps is None else self.timesteps[step.step]
        path = self._save(f"{self.stem}_{step.step:04d}.vtu", text, timestep, 0, "body")
        for index, part in enumerate(self.parts, 1):
            point_data, cell_data = part.data(positions, step)
            text = vtu_text(part.points, part.cells, point_data, cell_data, {})
            self._save(f"{self.stem}_{part.name}_{step.step:04d}.vtu", text, timestep, index, part.name)
        save_text(self.pvd, pvd_text(self.entries), self._scratch)
        return path

    def _save(self, name: str, text: str, timestep: float, part: int, what: str) -> Path:
        """Write one VTU of the folder and list it in the entries."""
        path = self.folder / name
        write_atomic(path, lambda tmp: tmp.write_text(text, encoding="utf-8"), self._folder, self._scratch)
        self.entries.append((timestep, part, what, f"{self.folder.name}/{name}"))
        return path

    def write_all(self, result) -> Path:
        """Write every step of a run (a solve.records.Run or a Result); return the PVD's path."""
        forces = result.contact_forces
        for i, step in enumerate(result.steps):
            self.write(step, result.positions[i], None if forces is None else forces[i])
        return self.pvd
