"""Bodies and chambers from CAD files: a solid of a STEP or IGES file, read by gmsh's OpenCASCADE kernel.

StepPart(file, solid, metre) is a 3D shape like those of fem/solids.py (build(occ) adds it to the gmsh model and
returns its volume's tag), so a body or a chamber read from a CAD file is meshed, graded near its chambers, cut by
roller planes, given curved quadratic tetrahedra and cached exactly as the parametric shapes are
(solid_geometry.SolidGeometry). A chamber is a solid of its own (in the body's file or another one), subtracted from
the body by the mesher's fragment: the cavity is what the chamber solid and the body share.

    the solid   a STEP file names its solids (the labels a CAD tool exports: build123d's `label`, CadQuery's
                assembly names, a SolidWorks body's name); gmsh names each imported volume by its label path,
                "Shapes/actuator/chamber/chamber", and `solid` is matched against that path's last part. Without
                `solid` the file must hold exactly one solid. An IGES file has no names: one solid per file.
    its units   a STEP file states its length unit; OpenCASCADE converts the part to metres on reading
                (Geometry.OCCTargetUnit = "M") and the part is scaled by 1 / metre into the scene's length unit
                (metre: the scene's length unit in metres, 1e-3 for mm; a scene file's parts are given its units').
                A scene without units has no unit to convert into: a part without metre is refused when it is built.
                An IGES file's unit is its header's (millimetres when it states none).
    its content the part's SHA-256 (content) is one of its fields, so the mesh cache (gmsh_cache.py) keys a mesh
                by the file's bytes, not by its name: an edited file is meshed afresh.

A file is refused in one line when it is missing, not a regular file, larger than MAX_CAD_BYTES, of another
extension, unreadable by OpenCASCADE, without a closed solid, without the named solid (the line lists the names it
has), or with several solids where none is named.
"""

from __future__ import annotations

import hashlib
import os
from dataclasses import dataclass, field

from ..errors import PneumaInputError, quoted, require
from ..io.inputs import read_input
from ..io.registry import internal, key
from .gmsh_session import gmsh_module

MAX_CAD_BYTES = 50_000_000
CAD_SUFFIXES = (".step", ".stp", ".iges", ".igs")


@dataclass(frozen=True)
class StepPart:
    """A solid of a STEP or IGES file (module docstring): file (kept as an absolute path, a scene file's relative to
    its folder), solid (its name; None: the file's only solid), metre (the scene's length unit in metres: the part
    is converted into it)."""

    file: str = key(doc="the CAD file, relative to the scene file")
    solid: str | None = key(None, "the solid's name (its label in the file); none: the file's only solid")
    metre: float | None = internal()  # from the scene's units (scene/scene_keys.py in_units)
    content: str = field(init=False, default="")  # the file's SHA-256: the mesh cache's key reads it
    name = "step"

    def __post_init__(self):
        require(isinstance(self.file, str) and self.file.strip() != "", f"file = {self.file!r} must name a CAD file")
        path = os.path.abspath(self.file)
        require(
            path.lower().endswith(CAD_SUFFIXES),
            f"file = {quoted(self.file)}: a CAD part is read from a {', '.join(CAD_SUFFIXES)} file",
        )
        data = read_input(path, MAX_CAD_BYTES, "CAD file")
        object.__setattr__(self, "file", path)
        object.__setattr__(self, "content", hashlib.sha256(data).hexdigest())

    def build(self, occ) -> int:
        """Import the file (in metres), keep the named solid (or the only one), drop the rest, scale it into the
        scene's unit; its volume's tag."""
        gmsh = gmsh_module()
        units, labels = (
            gmsh.option.getString("Geometry.OCCTargetUnit"),
            gmsh.option.getNumber("Geometry.OCCImportLabels"),
        )
        gmsh.option.setString("Geometry.OCCTargetUnit", "M")
        gmsh.option.setNumber("Geometry.OCCImportLabels", 1)
        try:
            imported = occ.importShapes(self.file, highestDimOnly=False)
        except Exception as exc:
            raise PneumaInputError(f"CAD file {quoted(self.file)} cannot be read by OpenCASCADE ({exc})") from None
        finally:
            gmsh.option.setString("Geometry.OCCTargetUnit", units)
            gmsh.option.setNumber("Geometry.OCCImportLabels", labels)
        occ.synchronize()
        volumes = [tag for dim, tag in imported if dim == 3]
        require(
            volumes,
            f"CAD file {quoted(self.file)} has no closed solid (only surfaces or curves: export a solid body, "
            f"not a surface model)",
        )
        names = {tag: gmsh.model.getEntityName(3, tag).rsplit("/", 1)[-1] for tag in volumes}
        if self.solid is None:
            require(
                len(volumes) == 1,
                f"CAD file {quoted(self.file)} has {len(volumes)} solids ({described(names)}): name the one "
                f"meant (solid = ...)",
            )
            kept = volumes[0]
        else:
            matching = [tag for tag in volumes if names[tag] == self.solid]
            require(
                len(matching) == 1,
                f"solid = {self.solid!r}: CAD file {quoted(self.file)} has "
                + ("several solids of that name" if matching else f"no solid of that name ({described(names)})"),
            )
            kept = matching[0]
        dropped = [(dim, tag) for dim, tag in imported if (dim, tag) != (3, kept)]
        if dropped:
            occ.remove(dropped, recursive=True)
        require(
            self.metre is not None,
            f"file = {quoted(self.file)}: a CAD file's lengths have units; give the scene units "
            f'(units = "mm-kPa" or "SI") to read them in',
        )
        scale = 1.0 / float(self.metre or 1.0)
        occ.dilate([(3, kept)], 0.0, 0.0, 0.0, scale, scale, scale)
        return kept


def described(names: dict[int, str]) -> str:
    """The solids' names in a refusal: "body, chamber", unnamed ones counted."""
    named = [name for name in names.values() if name]
    unnamed = len(names) - len(named)
    return ", ".join(named + ([f"{unnamed} unnamed"] if unnamed else [])) or "none named"
