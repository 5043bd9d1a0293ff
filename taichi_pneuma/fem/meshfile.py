"""Bodies from mesh files: any format meshio reads that has tetrahedra (gmsh .msh, VTK, Abaqus .inp, MED, ...),
the body's cells and each chamber's wall given by named groups (gmsh's physical groups, meshio's cell sets).

    MeshBody(file)             the body: every tetrahedron of the file (4- or 10-node, VTK's node order,
                               which meshio gives whatever the format's own)
    MeshSurface(group)         a chamber's wall: the triangles (3- or 6-node) of the named group
    MeshGeometry(body, ...)    the scene's geometry: body, named chamber walls, element order, clamp, tip and
                               rollers; mesh(budget) reads the file and builds the Mesh (tetmesh.tet_mesh),
                               refusing one past the budget (limits.Budget), whose region tags are the
                               tetrahedra's gmsh physical tags where the file has them

A file is read whole, so it may be at most MAX_MESH_BYTES, and under a memory bound (limits.read_allowance: a
small file whose arrays are compressed, or whose nodes are numbered sparsely, could claim gigabytes); whatever
meshio cannot read, a file that needs more memory, and a file without tetrahedra or without a named group, is
one PneumaInputError naming the file. write_mesh() writes a
tetrahedral Mesh (made in Python, e.g. by tetmesh.tet_mesh from a mesher's arrays) as such a file.
"""

from __future__ import annotations

import functools
import hashlib
import os
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from .. import limits
from ..errors import PneumaInputError, quoted, require, require_distinct
from ..io.registry import key
from ..limits import Budget
from .body import Body, SizeEstimate
from .elements import FAMILIES
from .mesh import Mesh
from .supports import PointSet
from .tetmesh import check_order, tet_mesh

if TYPE_CHECKING:
    import meshio

MAX_MESH_BYTES = 500_000_000
SPARSE_NODES = 4  # a gmsh 2.2 file whose largest node number passes this many times its node count is renumbered
TETRAHEDRA = tuple(f.meshio_cell for f in FAMILIES if f.dim == 3)  # meshio's names of the cells read
TRIANGLES = tuple(f.meshio_cell for f in FAMILIES if f.dim == 2)


@dataclass(frozen=True)
class MeshBody:
    """A body read from the mesh file `file` (kept as an absolute path: a relative one is taken from the
    current directory, a scene file's from the scene file's folder)."""

    file: str = key(doc="the mesh file, relative to the scene file")
    name = "mesh"

    def __post_init__(self):
        require(isinstance(self.file, str) and self.file.strip() != "", f"file = {self.file!r} must name a mesh file")
        object.__setattr__(self, "file", os.path.abspath(self.file))


@dataclass(frozen=True)
class MeshSurface:
    """A chamber wall: the triangles of the mesh file's group `group` (a closed cavity surface, or one left
    open on symmetry planes that roller planes hold)."""

    group: str = key(doc="the group (gmsh physical group) of the wall's triangles")
    name = "mesh_surface"

    def __post_init__(self):
        require(isinstance(self.group, str) and self.group != "", f"group = {self.group!r} must name a group")


def read_mesh(path: str) -> meshio.Mesh:
    """meshio's reading of the file, every failure one PneumaInputError naming it. The last file read is kept, by
    its path and the SHA-256 of its bytes (read_file): the resource check and the build parse it once, and a file
    rewritten since, whatever its size and time stamp, is parsed again. The mesh returned is shared: not to be
    modified."""
    require(
        os.path.isfile(path),
        f"mesh file {quoted(path)} "
        + (
            "is not a regular file (a folder, a FIFO or a device cannot be read as one)"
            if os.path.exists(path)
            else "does not exist"
        ),
    )
    size = os.stat(path).st_size
    require(size <= MAX_MESH_BYTES, f"mesh file {path!r} has {size} bytes; at most {MAX_MESH_BYTES} are read")
    with open(path, "rb") as f:
        digest = hashlib.file_digest(f, "sha256").hexdigest()
    return read_file(path, size, digest)


@functools.lru_cache(maxsize=1)  # a memo of the file's content: its key is the path and the bytes' digest
def read_file(path: str, size: int, digest: str) -> meshio.Mesh:
    """meshio.read of the file, of that size and content (the SHA-256 digest, the memo's key), bounded to
    limits.read_allowance(size) bytes of memory."""
    import meshio  # here and in write_mesh, not at the top: a scene without a mesh file does not load it

    allowance = limits.read_allowance(size)
    try:
        with limits.memory_bound(allowance):
            dense = dense_gmsh22(path)
            if dense is None:
                return meshio.read(path)
            with tempfile.NamedTemporaryFile(suffix=".msh") as copy:  # meshio's gmsh reader needs a file
                copy.write(dense)
                copy.flush()
                return meshio.read(copy.name)
    except PneumaInputError:
        raise
    except MemoryError:
        raise PneumaInputError(
            f"mesh file {path!r} ({size} bytes) needs more than {allowance} bytes of memory to "
            f"read, the most a file of its size may take (compressed arrays that expand, or "
            f"node numbers far larger than the node count)"
        ) from None
    except Exception as exc:  # meshio raises many kinds (ReadError, KeyError, ValueError, ...) on a bad file
        raise PneumaInputError(f"mesh file {path!r} cannot be read by meshio ({type(exc).__name__}: {exc})") from None


def dense_gmsh22(path: str) -> bytes | None:
    """The text of a gmsh 2.2 ASCII file whose largest node number passes SPARSE_NODES times its node count, its
    nodes numbered 1..n in their order (the elements' node numbers mapped by a binary search of the sorted
    numbers, no array sized by the largest); None for every other file. meshio's reader maps node numbers
    through an array as long as the largest (one node numbered 4e8 took 1.6 GB)."""
    with open(path, "rb") as f:
        lines = f.read(64).split(b"\n")
        if len(lines) < 2 or lines[0].strip() != b"$MeshFormat" or not lines[1].strip().startswith(b"2.2 0"):
            return None
        f.seek(0)
        data = f.read()
    start, end = data.find(b"$Nodes\n"), data.find(b"\n$EndNodes")
    head, _, body = data[start + 7 : end].partition(b"\n")
    nodes = body.split(b"\n")
    if start < 0 or end < start or not head.strip().isdigit() or len(nodes) != int(head):
        return None  # meshio's reader says what is wrong
    numbers = np.array([int(line.split(None, 1)[0]) for line in nodes])
    if numbers.max(initial=0) <= SPARSE_NODES * len(numbers):
        return None
    order = np.argsort(numbers)
    new: dict[bytes, bytes] = {}  # a cell's node number -> its new number

    def renumber(number: bytes) -> bytes:
        k = np.searchsorted(numbers[order], int(number))
        require(
            k < len(order) and numbers[order[k]] == int(number),
            f"mesh file {path!r}: an element names node {int(number)}, which $Nodes does not list",
        )
        return b"%d" % (order[k] + 1)

    renumbered = [b"%d %s" % (i + 1, line.split(None, 1)[1]) for i, line in enumerate(nodes)]
    first, last = data.find(b"$Elements\n", end), data.find(b"\n$EndElements", end)
    count, _, elements = data[first + 10 : last].partition(b"\n")
    cells = []
    for line in elements.split(b"\n"):
        fields = line.split()
        tagged = 3 + int(fields[2])
        cells.append(b" ".join(fields[:tagged] + [new.setdefault(n, renumber(n)) for n in fields[tagged:]]))
    return b"\n".join(
        [data[: start + 7] + head, *renumbered, data[end + 1 : first + 10] + count, *cells, data[last + 1 :]]
    )


def groups(mesh: meshio.Mesh) -> dict[str, list]:
    """The file's named groups: name -> per cell block the indices of its cells in the group (meshio's cell sets;
    for a gmsh 2.2 file, which meshio gives no cell sets, its physical names and each cell's physical tag)."""
    named = {
        name: [np.asarray([] if ids is None else ids, dtype=np.int64) for ids in sets]
        for name, sets in mesh.cell_sets.items()
        if not name.startswith("gmsh:")
    }
    tags = mesh.cell_data.get("gmsh:physical")
    if not named and tags is not None:
        named = {
            name: [np.flatnonzero(block_tags == tag) for block_tags in tags]
            for name, (tag, _) in mesh.field_data.items()
        }
    return named


def cells_of(mesh: meshio.Mesh, types: tuple[str, ...], group: str | None, path: str) -> tuple[np.ndarray, list]:
    """The cells of one of `types` (all of them, or those of the named group), and their blocks' indices."""
    if group is not None:
        named = groups(mesh)
        require(group in named, f"mesh file {path!r} has no group {group!r} (its groups: {', '.join(named) or 'none'})")
    blocks = [i for i, block in enumerate(mesh.cells) if block.type in types]
    kinds = {mesh.cells[i].type for i in blocks}
    require(len(kinds) <= 1, f"mesh file {path!r} mixes {' and '.join(sorted(kinds))} cells")
    parts = [mesh.cells[i].data if group is None else mesh.cells[i].data[named[group][i]] for i in blocks]
    if not parts:
        return np.zeros((0, 0), dtype=np.int64), blocks
    return np.vstack(parts).astype(np.int64), blocks


def volume_groups(mesh: meshio.Mesh) -> dict[str, int]:
    """The file's named gmsh physical groups of volumes: name -> the physical tag its tetrahedra carry."""
    return {name: int(tag) for name, (tag, dim) in mesh.field_data.items() if int(dim) == 3}


@dataclass(frozen=True)
class MeshGeometry(Body):
    """A 3D scene's geometry read from a mesh file: the body, its chambers (name, MeshSurface) in order, the
    element order (1: linear tetrahedra; 2: quadratic, a 4-node mesh given straight midside nodes), and the
    clamp, tip and rollers (as planar.Geometry's)."""

    body: MeshBody
    chambers: tuple
    order: int = 1
    clamp: PointSet | None = None
    tip: PointSet = field(default_factory=lambda: PointSet("right"))
    rollers: tuple = ()

    dim = 3

    def __post_init__(self):
        check_order(self.order)
        self.check_supports()
        require_distinct("chamber names", [name for name, _ in self.chambers])
        for name, shape in self.chambers:
            require(
                isinstance(shape, MeshSurface),
                f"chamber {name!r}: a mesh body's chambers are the mesh file's groups (shape = \"mesh_surface\")",
            )

    def tetrahedra(self) -> tuple[meshio.Mesh, np.ndarray, list]:
        """The file's meshio mesh, its tetrahedra (m, 4 or 10) and their cell blocks."""
        path = self.body.file
        source = read_mesh(path)
        tets, blocks = cells_of(source, TETRAHEDRA, None, path)
        require(len(tets) > 0, f"mesh file {path!r} has no tetrahedra (4- or 10-node)")
        return source, tets, blocks

    def size_estimate(self) -> SizeEstimate:
        """The tetrahedra and nodes of the mesh mesh() builds (nodes: at most, before unused ones are dropped; a
        4-node mesh made quadratic gains a node per edge, about 7 per tetrahedron)."""
        source, tets, _ = self.tetrahedra()
        nodes = len(np.unique(tets))
        return SizeEstimate(len(tets), nodes + (7 * len(tets) if self.order == 2 and tets.shape[1] == 4 else 0))

    def mesh_values(self) -> dict:
        """order: the file gives the rest."""
        return {"order": self.order}

    def mesh(self, budget: Budget = Budget()) -> Mesh:
        """Read the file and build the Mesh; one past the budget (its tetrahedra, each worth its family's weight in
        triangles) is refused, naming the file."""
        path = self.body.file
        source, tets, blocks = self.tetrahedra()
        physical = source.cell_data.get("gmsh:physical")
        regions = None if physical is None else np.concatenate([physical[i] for i in blocks])
        walls = {}
        for name, shape in self.chambers:
            walls[name], _ = cells_of(source, TRIANGLES, shape.group, path)
            require(len(walls[name]) > 0, f"chamber {name!r}: group {shape.group!r} of {path!r} has no triangles")
        try:
            budget.check_mesh(len(tets), self.family.weight, "meshio")
            return tet_mesh(
                source.points,
                tets,
                walls,
                regions=regions,
                order=self.order,
                clamp=self.clamp,
                tip=self.tip,
                rollers=self.rollers,
                region_groups=volume_groups(source),
            )
        except PneumaInputError as exc:
            raise PneumaInputError(f"mesh file {path!r}: {exc}") from None


def write_mesh(path, mesh: Mesh, names: tuple[str, ...]) -> Path:
    """Write the mesh's tetrahedra (group "body") and each chamber's wall (a group named after the chamber, in the
    order of names) as gmsh 2.2 (.msh, physical groups) or Abaqus (.inp, element sets): a file MeshGeometry reads
    back to the same mesh."""
    import meshio

    path = Path(path)
    require(path.suffix in (".msh", ".inp"), f"{path}: write_mesh writes .msh (gmsh 2.2) or .inp (Abaqus) files")
    family = mesh.family
    facets = None if family is None else family.facet_family
    if family is None or facets is None:
        raise PneumaInputError(f"write_mesh writes a 3D body's mesh, not one of {mesh.elements.shape[1]}-node elements")
    cells = [(facets.meshio_cell, wall) for wall in mesh.chambers] + [(family.meshio_cell, mesh.elements)]
    if path.suffix == ".inp":
        sets = {
            name: [np.arange(len(data)) if i == j else np.zeros(0, dtype=np.int64) for j, (_, data) in enumerate(cells)]
            for i, name in enumerate((*names, "body"))
        }
        meshio.write(path, meshio.Mesh(mesh.vertices, cells, cell_sets=sets), file_format="abaqus")
    else:
        tags = [np.full(len(data), i + 2) for i, (_, data) in enumerate(cells[:-1])] + [np.ones(mesh.n_elements, int)]
        groups = {name: np.array([i + 2, 2]) for i, name in enumerate(names)} | {"body": np.array([1, 3])}
        data = {"gmsh:physical": tags, "gmsh:geometrical": tags}
        meshio.write(
            path,
            meshio.Mesh(mesh.vertices, cells, cell_data=data, field_data=groups),
            file_format="gmsh22",
            binary=False,
        )
    return path
