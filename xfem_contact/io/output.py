"""Results that ParaView and pyvista read, and JSON summaries.

- :func:`write_fields`: VTX (ADIOS2) files of Lagrange functions, plus the
  cell side indicator (-1, 0 = cut, +1) as XDMF, for thresholding per side.
- :func:`write_lips`: a VTK unstructured grid (``.vtu``) made of the uncut cells
  and the curved sub-triangles of the cut cells, each carrying the displacement
  of its own side: the lips of the interface appear separate and discontinuous.
- :func:`write_cut_geometry`: the cut itself (sub-triangles and interface pieces)
  as ``.vtu`` files, for ``xfem-contact show`` and ParaView.
- :func:`write_json`: a JSON summary (numpy values converted), written atomically.
"""

from __future__ import annotations

import json
import os
import pathlib

import dolfinx.fem
import dolfinx.io
import numpy as np

from xfem_contact.fem.cutmesh import CutMesh
from xfem_contact.io.vtu import interface_arrays, lips_arrays, subcell_arrays, write_vtu

#: Compression of the ``.vtu`` files: LZ4 (ParaView >= 5.6 reads it) wrote the
#: 160 x 160 case-2 lips grid in 0.03 s against zlib's 0.13 s (and 0.11 s raw)
VTU_COMPRESSION = "lz4"


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


def _rank_path(path: pathlib.Path, comm) -> pathlib.Path:
    """``path`` with suffix ``_r{rank}`` before the extension when run in parallel."""
    if comm.size > 1:
        path = path.with_name(f"{path.stem}_r{comm.rank}{path.suffix}")
    path.parent.mkdir(parents=True, exist_ok=True)
    return path


def write_lips(
    path: str | pathlib.Path, cut: CutMesh, u_minus, u_plus, fields: dict | None = None
) -> pathlib.Path:
    """Write a ``.vtu`` grid of uncut cells and sub-triangles with each side's displacement.

    The grid is :func:`xfem_contact.io.pictures.deformed_lips_grid` (quadratic cells,
    point data ``u`` in m, cell data ``side``, ``cut``, ``cell``). Local to each
    process: rank ``r`` writes ``path`` with suffix ``_r{r}`` when run in parallel.
    ``u_minus``, ``u_plus``: displacement Functions of sides -1 and +1; ``fields``:
    more point data, name to ``{-1: Function, 1: Function}`` ((discontinuous)
    Lagrange, e.g. ``stress`` and ``von_mises`` of
    :class:`~xfem_contact.mechanics.stress.StressFields`).
    """
    path = _rank_path(pathlib.Path(path), cut.mesh.comm)
    write_vtu(path, lips_arrays(cut, u_minus, u_plus, fields), VTU_COMPRESSION)
    return path


def write_plain(path: str | pathlib.Path, u, fields: dict | None = None) -> pathlib.Path:
    """Write a ``.vtu`` grid of the mesh at the nodes of ``u``'s Lagrange space with point
    data ``u`` (m) and ``fields`` (name to Function, e.g. a discontinuous stress, taken
    at the nodes by interpolation into ``u``'s degree). Local to each process (suffix
    ``_r{rank}`` in parallel)."""
    import dolfinx.plot
    import pyvista

    V = u.function_space
    path = _rank_path(pathlib.Path(path), V.mesh.comm)
    topology, cell_types, x = dolfinx.plot.vtk_mesh(V)
    grid = pyvista.UnstructuredGrid(topology, cell_types, x)
    values = u.x.array.reshape(-1, 2)
    grid.point_data["u"] = np.c_[values, np.zeros(values.shape[0])]
    degree = V.ufl_element().embedded_superdegree
    for name, f in (fields or {}).items():
        shape = f.function_space.value_shape
        nodal = dolfinx.fem.Function(dolfinx.fem.functionspace(V.mesh, ("Lagrange", degree, shape)))
        nodal.interpolate(f)
        grid.point_data[name] = nodal.x.array.reshape(values.shape[0], -1)
    grid.save(path)
    return path


def write_cut_geometry(
    directory: str | pathlib.Path, cut: CutMesh, interface_data: dict | None = None
) -> list[pathlib.Path]:
    """Write ``subcells.vtu`` (the curved sub-triangles of the cut cells, cell data
    ``side``, ``cut``, ``cell``) and ``interface.vtu`` (curved interface pieces, point
    data ``interface_data``: name to an array over its nodes, e.g.
    :func:`~xfem_contact.io.interface_data.interface_point_data`) into ``directory``:
    the cut region only, the uncut cells are in ``result.vtu`` (:func:`write_lips`).

    Local to each process (not collective): in parallel rank ``r`` writes
    ``subcells_r{r}.vtu`` and ``interface_r{r}.vtu``. See :mod:`xfem_contact.io.pictures`.
    """
    directory, comm = pathlib.Path(directory), cut.mesh.comm
    paths = []
    interface = interface_arrays(cut)
    interface = interface._replace(point_data=dict(interface_data or {}))
    for name, arrays in (("subcells", subcell_arrays(cut, uncut=False)), ("interface", interface)):
        path = _rank_path(directory / f"{name}.vtu", comm)
        write_vtu(path, arrays, VTU_COMPRESSION)
        paths.append(path)
    return paths


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
    """Write ``summary`` as indented JSON (numpy arrays and scalars converted), atomically.

    The JSON goes to a temporary file beside ``path``, flushed to disk, then renamed
    over ``path``: a reader finds the old file or the whole new one, never a part, and
    a failure (an unconvertible value, a full disk, the process killed) leaves ``path``
    as it was and no temporary file behind.
    """
    path = pathlib.Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    temporary = path.with_name(f".{path.name}.{os.getpid()}.tmp")  # same folder: a rename
    try:
        with open(temporary, "w") as f:
            json.dump(_jsonable(summary), f, indent=2)
            f.flush()
            os.fsync(f.fileno())
        os.replace(temporary, path)
    except BaseException:
        temporary.unlink(missing_ok=True)
        raise
    return path
