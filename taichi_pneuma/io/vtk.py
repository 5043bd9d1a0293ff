"""The VTK XML formats ParaView reads, written as text: an unstructured grid (vtu_text: points, cell blocks,
point, cell and field data) and a collection of them by time step (pvd_text). The VTU is written as meshio writes
it uncompressed: each array inline, base64 of a UInt32 byte count followed by the values in the machine's byte
order; the field data as ASCII values. What a run's files hold: render/paraview.py."""

from __future__ import annotations

import base64
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol
from xml.sax.saxutils import quoteattr

import numpy as np


def pad3(vectors: np.ndarray) -> np.ndarray:
    """(n, 2) -> (n, 3) with z = 0; (n, 3) as is."""
    return vectors if vectors.shape[1] == 3 else np.column_stack([vectors, np.zeros(len(vectors))])


XML_TYPES = {np.dtype(t): name for t, name in ((np.float64, "Float64"), (np.int32, "Int32"), (np.int64, "Int64"))}


def data_array(name: str, values: np.ndarray) -> str:
    """A binary DataArray (uncompressed: zlib would take 5x longer than the write itself, for files half the size):
    base64 of the UInt32 byte count and the values; a column count for an (n, k) array."""
    values = np.ascontiguousarray(values, dtype=values.dtype.newbyteorder("="))
    raw = values.tobytes()
    components = f' NumberOfComponents="{values.shape[1]}"' if values.ndim == 2 else ""
    return (
        f'<DataArray type="{XML_TYPES[values.dtype]}" Name={quoteattr(name)}{components} format="binary">\n'
        f"{base64.b64encode(np.uint32(len(raw)).tobytes() + raw).decode()}\n</DataArray>\n"
    )


class CellFamily(Protocol):
    """What a cell block's element family (fem.elements.ElementFamily) tells the VTU: its VTK cell type number."""

    @property
    def vtk_cell(self) -> int: ...


@dataclass(frozen=True)
class VtkCell:
    """A VTK cell type by its number, for the cells that are no element family's: the parts beside the body."""

    vtk_cell: int


LINE, POLY_LINE, TRIANGLE, POLYGON = (VtkCell(n) for n in (3, 4, 5, 7))  # a polyline and a polygon: any node count


def vtu_text(
    points: np.ndarray,
    cells: Sequence[tuple[CellFamily, np.ndarray]],
    point_data: dict[str, np.ndarray],
    cell_data: dict[str, list[np.ndarray]],
    field_data: dict[str, float],
) -> str:
    """A VTU file: points (n, 3), cell blocks (element family: its vtk_cell, (m, k) nodes), point arrays, cell arrays
    (one per block) and one Float64 value per field-data name."""
    fields = "".join(
        f'<DataArray type="Float64" Name={quoteattr(name)} NumberOfTuples="1" format="ascii">'
        f"{float(value)!r}</DataArray>"
        for name, value in field_data.items()
    )
    connectivity = np.concatenate([nodes.ravel() for _, nodes in cells]).astype(np.int64)
    offsets = np.cumsum(np.concatenate([np.full(len(nodes), nodes.shape[1]) for _, nodes in cells])).astype(np.int64)
    types = np.concatenate([np.full(len(nodes), family.vtk_cell) for family, nodes in cells]).astype(np.int64)
    order = "LittleEndian" if sys.byteorder == "little" else "BigEndian"
    return "".join(
        [
            f'<?xml version="1.0"?>\n<VTKFile type="UnstructuredGrid" version="0.1" byte_order="{order}">\n',
            f"<UnstructuredGrid><FieldData>{fields}</FieldData>\n",
            f'<Piece NumberOfPoints="{len(points)}" NumberOfCells="{len(types)}">\n<Points>\n',
            data_array("Points", points),
            "</Points>\n<Cells>\n",
            data_array("connectivity", connectivity),
            data_array("offsets", offsets),
            data_array("types", types),
            "</Cells>\n<PointData>\n",
            *(data_array(name, values) for name, values in point_data.items()),
            "</PointData>\n<CellData>\n",
            *(data_array(name, np.concatenate(blocks)) for name, blocks in cell_data.items()),
            "</CellData>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n",
        ]
    )


def pvd_text(entries: Sequence[tuple[float, int, str, str]]) -> str:
    """A PVD collection of (timestep, part, name, relative file name) entries: the files of one timestep with parts
    0, 1, ... are read as the blocks of one multiblock dataset, each named by its name attribute."""
    rows = "".join(
        f'    <DataSet timestep="{t!r}" part="{part}" name={quoteattr(name)} file={quoteattr(file)}/>\n'
        for t, part, name, file in entries
    )
    return (
        f'<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1">\n  <Collection>\n{rows}'
        f"  </Collection>\n</VTKFile>\n"
    )
