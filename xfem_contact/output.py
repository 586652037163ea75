"""Results that ParaView and pyvista read, and JSON summaries.

- :func:`write_fields`: VTX (ADIOS2) files of Lagrange functions, plus the
  cell side indicator (-1, 0 = cut, +1) as XDMF, for thresholding per side.
- :func:`write_lips`: a VTK unstructured grid (``.vtu``) made of the uncut cells
  and the curved sub-triangles of the cut cells, each carrying the displacement
  of its own side: the lips of the interface appear separate and discontinuous.
- :func:`write_json`: a JSON summary (numpy values converted).
"""

from __future__ import annotations

import json
import pathlib

import dolfinx.fem
import dolfinx.io
import numpy as np

from xfem_contact.cutmesh import CutMesh
from xfem_contact.evaluation import evaluate_reference


def write_fields(directory: str | pathlib.Path, name: str, functions: list) -> list[pathlib.Path]:
    """Write Lagrange ``functions`` (same space) to ``directory/name.bp`` (VTX). Collective."""
    directory = pathlib.Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    path = directory / f"{name}.bp"
    mesh = functions[0].function_space.mesh
    with dolfinx.io.VTXWriter(mesh.comm, path, functions, engine="BP4") as writer:
        writer.write(0.0)
    return [path]


def write_sides(directory: str | pathlib.Path, cut: CutMesh) -> pathlib.Path:
    """Write the cell side indicator (DG0: -1, 0 for cut, +1) to ``sides.xdmf``. Collective."""
    directory = pathlib.Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    side = cut.side_indicator()
    path = directory / "sides.xdmf"
    with dolfinx.io.XDMFFile(cut.mesh.comm, path, "w") as f:
        f.write_mesh(cut.mesh)
        f.write_function(side)
    return path


def write_lips(path: str | pathlib.Path, cut: CutMesh, u_minus, u_plus) -> pathlib.Path:
    """Write a ``.vtu`` grid of uncut cells and sub-triangles with each side's displacement.

    Local to each process: rank ``r`` writes ``path`` with suffix ``_r{r}`` when
    run in parallel. ``u_minus``, ``u_plus``: displacement Functions (collapsed).
    """
    import basix
    import pyvista

    mesh = cut.mesh
    tdim = mesh.topology.dim
    path = pathlib.Path(path)
    if mesh.comm.size > 1:
        path = path.with_name(f"{path.stem}_r{mesh.comm.rank}{path.suffix}")
    path.parent.mkdir(parents=True, exist_ok=True)
    ref = {"triangle": np.array([[0, 1, 2]]), "quadrilateral": np.array([[0, 1, 3], [0, 3, 2]])}
    ref_vertices = basix.geometry(mesh.basix_cell())
    split = ref[mesh.topology.cell_name()]
    points, values, sides, triangles = [], [], [], []
    for side, u in ((-1, u_minus), (1, u_plus)):
        cells = np.flatnonzero(cut.cell_sides == side).astype(np.int32)
        X = np.tile(ref_vertices[split.ravel()], (cells.size, 1))
        c = np.repeat(cells, split.size)
        tri_geom, tri_cell = (
            (cut.geometry.tri_minus, cut.geometry.tri_minus_cell)
            if side == -1
            else (cut.geometry.tri_plus, cut.geometry.tri_plus_cell)
        )
        X = np.concatenate([X, tri_geom[:, :3].reshape(-1, tdim)])
        c = np.concatenate([c, np.repeat(cut.cut_cells[tri_cell], 3)])
        points.append(cut.maps.push_forward(c, X))
        values.append(evaluate_reference(u, c, X))
        sides.append(np.full(X.shape[0] // 3, side))
    start = 0
    for p in points:
        triangles.append(start + np.arange(p.shape[0]).reshape(-1, 3))
        start += p.shape[0]
    xyz = np.concatenate(points)
    xyz = np.c_[xyz, np.zeros((xyz.shape[0], 3 - xyz.shape[1]))]
    tri = np.concatenate(triangles)
    cells = np.c_[np.full(tri.shape[0], 3), tri].ravel()
    grid = pyvista.UnstructuredGrid(cells, np.full(tri.shape[0], pyvista.CellType.TRIANGLE), xyz)
    u = np.concatenate(values)
    grid.point_data["u"] = np.c_[u, np.zeros((u.shape[0], 3 - u.shape[1]))]
    grid.cell_data["side"] = np.concatenate(sides)
    grid.save(path)
    return path


def _jsonable(value):
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return _jsonable(value.tolist())
    if isinstance(value, np.generic):
        return value.item()
    return value


def write_json(path: str | pathlib.Path, summary: dict) -> pathlib.Path:
    """Write ``summary`` as indented JSON (numpy arrays and scalars converted)."""
    path = pathlib.Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(_jsonable(summary), indent=2))
    return path
