"""VTK grids of cut meshes and results as arrays, and ``.vtu`` files written from them.

Every grid is local to its process (each rank builds its own owned cells).
Points are shared only among the uncut cells of one side; each sub-triangle
carries its own nodes, and no point is shared between the sides, so fields may
jump across the interface (the two lips). Coordinates are physical (the mesh's
units, m in the paper's cases), padded with ``z = 0``.

- Uncut cells are quadratic VTK cells (6-node triangles, 9-node biquadratic
  quadrilaterals) whose nodes are the parent cell's P2/Q2 reference lattice
  pushed through the cell map: exact for affine and Q2 geometry. A lattice node
  is a vertex, an edge midpoint or the cell centre, numbered once per side (a
  quarter of the points of one node set per cell on quadrilaterals), and a field
  is evaluated there once.
- Sub-triangles of cut cells are 6-node VTK triangles: the nodes of
  ``cut.geometry.tri_minus`` / ``tri_plus`` (parent reference coordinates)
  pushed through the cell map. On affine parents this is the exact curved
  sub-triangle used by the quadrature; on curved parents its P2 interpolant.
- Interface pieces are 3-node VTK quadratic edges (``cut.geometry.seg``).

Cell data: ``side`` (-1 for ``phi < 0``, +1), ``cut`` (1 on sub-triangles, 0 on
uncut cells), ``cell`` (local index of the parent cell).

:func:`write_vtu` writes uncompressed files with numpy alone and compressed ones with
VTK's own Python modules (never pyvista); :mod:`xfem_contact.io.vtk_grids` makes
pyvista objects of the same arrays.
"""

from __future__ import annotations

import html
from typing import NamedTuple

import basix
import numpy as np
import numpy.typing as npt

from xfem_contact.fem.cutmesh import CutMesh
from xfem_contact.fem.evaluation import cell_dofs, evaluate_lattice, evaluate_reference

#: VTK cell types (``vtkCellType.h``)
QUADRATIC_EDGE, QUADRATIC_TRIANGLE, BIQUADRATIC_QUAD = 21, 22, 28
LAGRANGE_TRIANGLE, LAGRANGE_QUADRILATERAL = 69, 70
_NODES = {QUADRATIC_EDGE: 3, QUADRATIC_TRIANGLE: 6, BIQUADRATIC_QUAD: 9}
_NODES |= {5: 3, 10: 4, 12: 8, 13: 6}  # linear triangle, tetrahedron, hexahedron, wedge

# Reference nodes of the uncut cells' quadratic lattice, in VTK node order
_LATTICE = {
    "triangle": (
        np.array([[0, 0], [1, 0], [0, 1], [0.5, 0], [0.5, 0.5], [0, 0.5]], dtype=np.float64),
        QUADRATIC_TRIANGLE,
    ),
    "quadrilateral": (
        np.array(
            [[0, 0], [1, 0], [1, 1], [0, 1], [0.5, 0], [1, 0.5], [0.5, 1], [0, 0.5], [0.5, 0.5]],
            dtype=np.float64,
        ),
        BIQUADRATIC_QUAD,
    ),
}
# Basix P2 triangle (vertices, then mid-nodes of edges (1,2), (0,2), (0,1)) -> VTK
# (vertices, then mid-nodes of edges (0,1), (1,2), (2,0))
P2_TO_VTK = np.array([0, 1, 2, 5, 3, 4])


class _Block(NamedTuple):
    """Cells of one kind: parent cells ``(n,)``, reference nodes ``(n, k, tdim)`` in VTK order."""

    side: int
    cut: int
    cells: npt.NDArray[np.int32]
    X: npt.NDArray[np.float64]
    vtk_type: int


def _blocks(cut: CutMesh, uncut: bool = True) -> list[_Block]:
    """Sub-triangles of both sides, and (``uncut``) the uncut cells (owned cells of
    this process)."""
    lattice, vtk_type = _LATTICE[cut.mesh.topology.cell_name()]
    g = cut.geometry
    blocks = []
    for side, tri, rows in ((-1, g.tri_minus, g.tri_minus_cell), (1, g.tri_plus, g.tri_plus_cell)):
        if uncut:
            cells = np.flatnonzero(cut.cell_sides == side).astype(np.int32)
            X = np.broadcast_to(lattice, (cells.size, *lattice.shape))
            blocks.append(_Block(side, 0, cells, X, vtk_type))
        blocks.append(
            _Block(
                side,
                1,
                cut.cut_cells[rows].astype(np.int32),
                tri[:, P2_TO_VTK],
                QUADRATIC_TRIANGLE,
            )
        )
    return blocks


def _lattice_keys(cut: CutMesh, cells: npt.NDArray[np.int32], lattice: np.ndarray) -> np.ndarray:
    """A key per lattice node of each cell, ``(len(cells), k)`` int64, equal for the
    nodes that coincide in neighbouring cells: a vertex is keyed by its vertex, an
    edge midpoint by the edge's two vertices, any other node by its cell (local
    numbering of this process)."""
    mesh = cut.mesh
    celltype = mesh.basix_cell()
    ref, edges = basix.geometry(celltype), basix.topology(celltype)[1]
    vertices = mesh.topology.connectivity(mesh.topology.dim, 0).array
    vertices = vertices.reshape(-1, ref.shape[0])[cells].astype(np.int64)
    nv = np.int64(mesh.topology.index_map(0).size_local + mesh.topology.index_map(0).num_ghosts)
    keys = np.empty((cells.size, lattice.shape[0]), dtype=np.int64)
    for j, X in enumerate(lattice):
        at_vertex = np.flatnonzero(np.all(np.isclose(ref, X), axis=1))
        at_edge = [e for e in edges if np.allclose(ref[e].mean(axis=0), X)]
        if at_vertex.size:
            keys[:, j] = vertices[:, at_vertex[0]]
        elif at_edge:
            a, b = vertices[:, at_edge[0][0]], vertices[:, at_edge[0][1]]
            keys[:, j] = nv + np.minimum(a, b) * nv + np.maximum(a, b)
        else:
            keys[:, j] = nv + nv * nv + cells
    return keys


def _shared_lattice(cut: CutMesh, b: _Block, fields: dict) -> tuple:
    """Points ``(m, 3)``, node indices per cell ``(n, k)`` and values (name to ``(m, c)``)
    of ``fields`` (name to Function) at the lattice nodes of ``b``'s cells, each node once
    (a discontinuous field takes the value of the cell that first meets the node)."""
    lattice = np.ascontiguousarray(b.X[0])
    keys = _lattice_keys(cut, b.cells, lattice)
    _, first, ids = np.unique(keys.ravel(), return_index=True, return_inverse=True)
    cell_of, node_of = b.cells[first // lattice.shape[0]], first % lattice.shape[0]
    points = np.zeros((first.size, 3))
    values = {name: None for name in fields}
    for j in range(lattice.shape[0]):  # the nodes first met as lattice node j
        rows = np.flatnonzero(node_of == j)
        X = lattice[j : j + 1]
        points[rows] = _pad3(cut.maps.push_forward_lattice(cell_of[rows], X))
        for name, field in fields.items():
            v = _evaluate(field, cell_of[rows], X, lattice=True)
            if values[name] is None:
                values[name] = np.zeros((first.size, v.shape[1]))
            values[name][rows] = v
    return points, ids.reshape(keys.shape), values


def _evaluate(field, cells: np.ndarray, X: np.ndarray, lattice: bool) -> np.ndarray:
    """Values ``(m, c)`` of a Lagrange or discontinuous Lagrange ``field`` at reference
    points (``X`` the same in every cell when ``lattice``); vectors padded to 3
    components. A degree-0 field is its cell value."""
    if field.function_space.ufl_element().embedded_superdegree == 0:
        V = field.function_space
        values = field.x.array[cell_dofs(V, cells)].reshape(cells.size, -1)
        values = np.repeat(values, 1 if not lattice else X.shape[0], axis=0)
    else:
        values = (evaluate_lattice if lattice else evaluate_reference)(field, cells, X)
    return _pad3(values) if values.shape[1] == 2 else values


def _pad3(a: np.ndarray) -> np.ndarray:
    """``(m, d)`` -> ``(m, 3)`` with zero columns."""
    return np.c_[a, np.zeros((a.shape[0], 3 - a.shape[1]))]


class GridArrays(NamedTuple):
    """A grid as arrays: ``points`` (m, 3) (m), ``cells`` in VTK's legacy layout (for
    each cell its number of nodes, then their indices), ``types`` (VTK cell types,
    uint8), ``cell_data`` and ``point_data`` (name to array)."""

    points: np.ndarray
    cells: np.ndarray
    types: np.ndarray
    cell_data: dict
    point_data: dict


def grid_arrays(cut: CutMesh, blocks: list[_Block], fields: dict | None = None) -> GridArrays:
    """Arrays of ``blocks`` (nodes shared within a block of uncut cells only);
    ``fields[name][side]``: a (discontinuous) Lagrange Function evaluated as point data
    ``name`` on the cells of that side (2-vectors padded to 3 components)."""
    tdim = cut.mesh.topology.dim
    fields = fields or {}
    points, connectivity, types, data = [], [], [], {"side": [], "cut": [], "cell": []}
    values = {name: [] for name in fields}
    start = 0
    for b in blocks:
        n, k = b.X.shape[:2]
        if n == 0:
            continue
        here = {name: by_side[b.side] for name, by_side in fields.items()}
        if b.X.strides[0] == 0:  # the same lattice in every cell: nodes shared
            xs, ids, vs = _shared_lattice(cut, b, here)
            points.append(xs)
            for name, v in vs.items():
                values[name].append(v)
        else:
            cells = np.repeat(b.cells, k)
            X = np.ascontiguousarray(b.X.reshape(-1, tdim))
            points.append(_pad3(cut.maps.push_forward(cells, X)))
            for name, field in here.items():
                values[name].append(_evaluate(field, cells, X, lattice=False))
            ids = np.arange(n * k).reshape(n, k)
        connectivity.append(np.c_[np.full(n, k), start + ids].ravel())
        types.append(np.full(n, b.vtk_type, dtype=np.uint8))
        data["side"].append(np.full(n, b.side, dtype=np.int8))
        data["cut"].append(np.full(n, b.cut, dtype=np.int8))
        data["cell"].append(b.cells.astype(np.int32))
        start += points[-1].shape[0]
    if not points:
        empty = {"side": np.int8, "cut": np.int8, "cell": np.int32}
        return GridArrays(
            np.zeros((0, 3)),
            np.zeros(0, dtype=np.int64),
            np.zeros(0, dtype=np.uint8),
            {name: np.zeros(0, dtype=dtype) for name, dtype in empty.items()},
            {},
        )
    return GridArrays(
        np.concatenate(points),
        np.concatenate(connectivity),
        np.concatenate(types),
        {name: np.concatenate(parts) for name, parts in data.items()},
        {name: np.concatenate(parts) for name, parts in values.items()},
    )


def lips_arrays(cut: CutMesh, u_minus, u_plus, fields: dict | None = None) -> GridArrays:
    """Uncut cells and sub-triangles with point data ``u`` (m), each side's own, and
    the ``fields`` given (name to ``{-1: Function, 1: Function}``, e.g. ``stress``)."""
    return grid_arrays(cut, _blocks(cut), {"u": {-1: u_minus, 1: u_plus}} | (fields or {}))


def subcell_arrays(cut: CutMesh, uncut: bool = True) -> GridArrays:
    """Curved sub-triangles of the cut cells and (``uncut``) the uncut cells (this
    process's cells)."""
    return grid_arrays(cut, _blocks(cut, uncut))


def interface_arrays(cut: CutMesh) -> GridArrays:
    """The curved interface pieces as 3-node quadratic edges, cell data ``cell``."""
    g = cut.geometry
    cells = cut.cut_cells[g.seg_cell].astype(np.int32)
    arrays = grid_arrays(cut, [_Block(0, 1, cells, g.seg, QUADRATIC_EDGE)])
    return arrays._replace(cell_data={"cell": arrays.cell_data["cell"]})


def plain_arrays(u, fields: dict | None = None) -> GridArrays:
    """The mesh at the nodes of ``u``'s Lagrange space (degree-1 cells for degree 1,
    quadratic ones for 2, VTK Lagrange cells above) with point data ``u`` (m, padded to
    3 components) and ``fields`` (name to Function, e.g. a discontinuous stress,
    interpolated into ``u``'s degree). This process's cells."""
    import dolfinx.fem
    import dolfinx.plot

    V = u.function_space
    topology, cell_types, x = dolfinx.plot.vtk_mesh(V)
    values = u.x.array.reshape(x.shape[0], -1)
    point_data = {"u": _pad3(values) if values.shape[1] == 2 else values}
    degree = V.ufl_element().embedded_superdegree
    for name, f in (fields or {}).items():
        shape = f.function_space.value_shape
        nodal = dolfinx.fem.Function(dolfinx.fem.functionspace(V.mesh, ("Lagrange", degree, shape)))
        nodal.interpolate(f)
        point_data[name] = nodal.x.array.reshape(x.shape[0], -1)
    types = np.asarray(cell_types, dtype=np.uint8)
    if degree == 2:  # VTK's Lagrange cells of order 2 are its quadratic cells, same order
        types = np.where(types == LAGRANGE_TRIANGLE, QUADRATIC_TRIANGLE, types)
        types = np.where(types == LAGRANGE_QUADRILATERAL, BIQUADRATIC_QUAD, types)
    return GridArrays(
        np.asarray(x, dtype=np.float64),
        np.asarray(topology, dtype=np.int64),
        types.astype(np.uint8),
        {},
        point_data,
    )


def _node_counts(arrays: GridArrays) -> np.ndarray:
    """Nodes per cell of ``arrays`` (its legacy layout): the VTK type's, or, for cells of
    one type (e.g. VTK Lagrange cells), the count of the first cell."""
    if arrays.types.size and np.all(arrays.types == arrays.types[0]):
        return np.full(arrays.types.size, arrays.cells[0], dtype=np.int64)
    table = np.zeros(max(_NODES) + 1, dtype=np.int64)
    table[list(_NODES)] = list(_NODES.values())
    return table[arrays.types]


#: VTK XML type names of the numpy dtypes a grid's arrays may have
VTK_TYPES = {
    np.dtype(np.int8): "Int8",
    np.dtype(np.uint8): "UInt8",
    np.dtype(np.int32): "Int32",
    np.dtype(np.int64): "Int64",
    np.dtype(np.float32): "Float32",
    np.dtype(np.float64): "Float64",
}

#: Compressions of :func:`write_vtu`: ``none`` is written here with numpy; ``lz4`` and
#: ``zlib`` by VTK's XML writer (whose import takes a few tenths of a second)
COMPRESSIONS = ("none", "lz4", "zlib")


def vtk_type(name: str, values: np.ndarray) -> str:
    """The VTK XML type name of the array ``values`` of data ``name``."""
    try:
        return VTK_TYPES[np.asarray(values).dtype]
    except KeyError:
        raise ValueError(
            f"array {name!r}: dtype {np.asarray(values).dtype} has no VTK XML type "
            f"(valid: {', '.join(str(t) for t in VTK_TYPES)})"
        ) from None


def quoteattr(text: str) -> str:
    """``text`` as a quoted XML attribute value (``&``, ``<``, ``>`` and quotes escaped;
    :func:`xml.sax.saxutils.quoteattr`'s job without importing its ``urllib``)."""
    return f'"{html.escape(text, quote=True)}"'


def write_vtu(path, arrays: GridArrays, compression: str = "none") -> None:
    """Write ``arrays`` as a VTK XML unstructured grid (binary). Not collective.

    Args:
        path: The ``.vtu`` file.
        arrays: The grid.
        compression: ``"none"``: the arrays raw after the XML (VTK's appended raw
            encoding, written with numpy, no VTK import); ``"lz4"`` or ``"zlib"``: blocks
            compressed by VTK's writer (smaller files, a VTK import).
    """
    if compression not in COMPRESSIONS:
        raise ValueError(
            f"compression {compression!r} is not one of {', '.join(map(repr, COMPRESSIONS))}"
        )
    if compression == "none":
        _write_raw(path, arrays)
    else:
        _write_compressed(path, arrays, compression)


def _cell_arrays(arrays: GridArrays) -> tuple[np.ndarray, np.ndarray]:
    """``(connectivity, offsets)`` (int64) of the cells of ``arrays``, VTK's XML layout:
    the node indices of all cells, and where each cell's end; the legacy counts dropped."""
    nodes = _node_counts(arrays)
    offsets = np.cumsum(nodes)
    keep = np.ones(arrays.cells.size, dtype=bool)
    keep[offsets - nodes + np.arange(nodes.size)] = False  # the legacy counts
    return np.ascontiguousarray(arrays.cells[keep], dtype=np.int64), offsets.astype(np.int64)


def _write_raw(path, arrays: GridArrays) -> None:
    """:func:`write_vtu` without compression: the XML header, then each array's byte
    count (UInt64) and bytes (little endian) in VTK's appended raw encoding."""
    connectivity, offsets = _cell_arrays(arrays)
    sections = [
        ("PointData", list(arrays.point_data.items())),
        ("CellData", list(arrays.cell_data.items())),
        ("Points", [("Points", arrays.points)]),
        ("Cells", [("connectivity", connectivity), ("offsets", offsets), ("types", arrays.types)]),
    ]
    lines = [
        '<?xml version="1.0"?>',
        '<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian" '
        'header_type="UInt64">',
        "  <UnstructuredGrid>",
        f'    <Piece NumberOfPoints="{arrays.points.shape[0]}" '
        f'NumberOfCells="{arrays.types.size}">',
    ]
    blocks, at = [], 0
    for tag, data in sections:
        lines.append(f"      <{tag}>")
        for name, values in data:
            values = np.ascontiguousarray(values)
            kind = vtk_type(name, values)
            values = values.astype(values.dtype.newbyteorder("<"), copy=False)
            components = 1 if values.ndim == 1 else int(np.prod(values.shape[1:]))
            lines.append(
                f'        <DataArray type="{kind}" Name={quoteattr(name)} '
                f'NumberOfComponents="{components}" format="appended" offset="{at}"/>'
            )
            blocks += [np.array([values.nbytes], dtype="<u8"), values]
            at += 8 + values.nbytes
        lines.append(f"      </{tag}>")
    lines += ["    </Piece>", "  </UnstructuredGrid>", '  <AppendedData encoding="raw">', "   _"]
    with open(path, "wb") as f:
        f.write("\n".join(lines).encode())
        for block in blocks:
            f.write(memoryview(block).cast("B"))
        f.write(b"\n  </AppendedData>\n</VTKFile>\n")


def _write_compressed(path, arrays: GridArrays, compression: str) -> None:
    """:func:`write_vtu` through VTK's XML writer, blocks compressed with ``compression``."""
    from vtkmodules.util.numpy_support import numpy_to_vtk, numpy_to_vtkIdTypeArray
    from vtkmodules.vtkCommonCore import VTK_UNSIGNED_CHAR, vtkPoints
    from vtkmodules.vtkCommonDataModel import vtkCellArray, vtkUnstructuredGrid
    from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridWriter

    grid = vtkUnstructuredGrid()
    points = vtkPoints()
    points.SetData(numpy_to_vtk(np.ascontiguousarray(arrays.points, dtype=np.float64), deep=True))
    grid.SetPoints(points)
    connectivity, ends = _cell_arrays(arrays)
    cells = vtkCellArray()
    cells.SetData(
        numpy_to_vtkIdTypeArray(np.r_[np.int64(0), ends], deep=True),
        numpy_to_vtkIdTypeArray(connectivity, deep=True),
    )
    types = numpy_to_vtk(arrays.types, deep=True, array_type=VTK_UNSIGNED_CHAR)
    grid.SetCells(types, cells)
    parts = ((grid.GetCellData(), arrays.cell_data), (grid.GetPointData(), arrays.point_data))
    for target, data in parts:
        for name, values in data.items():
            array = numpy_to_vtk(np.ascontiguousarray(values), deep=True)
            array.SetName(name)
            target.AddArray(array)
    writer = vtkXMLUnstructuredGridWriter()
    writer.SetFileName(str(path))
    writer.SetInputData(grid)
    writer.SetDataModeToBinary()
    compressors = {"lz4": writer.SetCompressorTypeToLZ4, "zlib": writer.SetCompressorTypeToZLib}
    compressors[compression]()
    if not writer.Write():
        raise OSError(f"could not write {path}")
