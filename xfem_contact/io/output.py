"""Results that ParaView and pyvista read, and JSON summaries.

- :func:`write_fields`: VTX (ADIOS2) files of Lagrange functions, plus the
  cell side indicator (-1, 0 = cut, +1) as XDMF, for thresholding per side.
- :func:`write_lips`: a VTK unstructured grid (``.vtu``) made of the uncut cells
  and the curved sub-triangles of the cut cells, each carrying the displacement
  of its own side: the lips of the interface appear separate and discontinuous.
- :func:`write_cut_geometry`: the cut itself (sub-triangles and interface pieces)
  as ``.vtu`` files, for ``xfem-contact show`` and ParaView.

In parallel every ``.vtu`` is written in pieces, one per process (``NAME_r{rank}.vtu``),
and rank 0 writes ``NAME.pvtu``, the file ParaView opens
(:func:`~xfem_contact.io.series.write_grid`); time series of such grids are
:class:`~xfem_contact.io.series.StepSeries`.
- :func:`write_json`: a JSON summary (numpy values converted), written atomically.
"""

from __future__ import annotations

import json
import os
import pathlib

import dolfinx.io
import numpy as np

from xfem_contact.fem.cutmesh import CutMesh
from xfem_contact.io.series import write_grid
from xfem_contact.io.vtu import interface_arrays, lips_arrays, plain_arrays, subcell_arrays

#: Compression of the ``.vtu`` files (:func:`~xfem_contact.io.vtu.write_vtu`): none, the
#: arrays raw, written with numpy without importing VTK (larger files than ``"lz4"``'s)
VTU_COMPRESSION = "none"


def write_fields(directory: str | pathlib.Path, name: str, functions: list) -> list[pathlib.Path]:
    """Write Lagrange ``functions`` (same space) to ``directory/name.bp`` (VTX). Collective."""
    directory = pathlib.Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    path = directory / f"{name}.bp"
    mesh = functions[0].function_space.mesh
    with dolfinx.io.VTXWriter(mesh.comm, path, functions, engine="BP4") as writer:
        writer.write(0.0)
    return [path]


def write_solution(directory: str | pathlib.Path, problem) -> list:
    """Write a contact problem's solution ``problem.w`` as VTX: each side's displacement
    (m) to ``directory/displacement.bp``, the multipliers (Pa) to ``multiplier.bp``.
    Returns the three fields ``u_minus``, ``u_plus`` and ``multiplier``. Collective."""
    names = ("u_minus", "u_plus", "multiplier")
    fields = [problem.space.field(problem.w, i, name) for i, name in enumerate(names)]
    write_fields(directory, "displacement", fields[:2])
    write_fields(directory, "multiplier", fields[2:])
    return fields


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


def write_lips(
    path: str | pathlib.Path, cut: CutMesh, u_minus, u_plus, fields: dict | None = None
) -> pathlib.Path:
    """Write a ``.vtu`` grid of uncut cells and sub-triangles with each side's displacement.

    The grid is :func:`xfem_contact.io.pictures.deformed_lips_grid` (quadratic cells,
    point data ``u`` in m, cell data ``side``, ``cut``, ``cell``); on a 3D mesh
    :func:`~xfem_contact.io.solid_grids.lips_arrays_3d`'s (linear cells, the cut cells
    split into tetrahedra and wedges on each side). Collective: in
    parallel rank ``r`` writes its cells to ``path`` with suffix ``_r{r}`` and rank 0
    the ``.pvtu`` of the pieces. ``u_minus``, ``u_plus``: displacement Functions of sides
    -1 and +1; ``fields``: more point data, name to ``{-1: Function, 1: Function}``
    ((discontinuous) Lagrange, e.g. ``stress`` and ``von_mises`` of
    :class:`~xfem_contact.mechanics.stress.StressFields`). Returns this process's file.
    """
    arrays = lips_grid_arrays(cut, u_minus, u_plus, fields)
    return write_grid(path, arrays, cut.mesh.comm, VTU_COMPRESSION)


def lips_grid_arrays(cut: CutMesh, u_minus, u_plus, fields: dict | None = None):
    """The grid of :func:`write_lips`: :func:`~xfem_contact.io.vtu.lips_arrays`, or on a
    3D cut :func:`~xfem_contact.io.solid_grids.lips_arrays_3d`."""
    if cut.geometry is None:  # a 3D cut keeps no sub-cells
        from xfem_contact.io.solid_grids import lips_arrays_3d

        return lips_arrays_3d(cut, u_minus, u_plus, fields)
    return lips_arrays(cut, u_minus, u_plus, fields)


def subcell_grid_arrays(cut: CutMesh):
    """The cut cells' pieces of :func:`write_cut_geometry`: the curved sub-triangles
    (:func:`~xfem_contact.io.vtu.subcell_arrays`), or on a 3D cut
    :func:`~xfem_contact.io.solid_grids.subcell_arrays_3d`."""
    if cut.geometry is None:
        from xfem_contact.io.solid_grids import subcell_arrays_3d

        return subcell_arrays_3d(cut)
    return subcell_arrays(cut, uncut=False)


def write_plain(path: str | pathlib.Path, u, fields: dict | None = None) -> pathlib.Path:
    """Write a ``.vtu`` grid of the mesh at the nodes of ``u``'s Lagrange space with point
    data ``u`` (m) and ``fields`` (name to Function, e.g. a discontinuous stress, taken
    at the nodes by interpolation into ``u``'s degree): :func:`~xfem_contact.io.vtu.plain_arrays`.
    Collective (pieces and ``.pvtu`` in parallel, as :func:`write_lips`)."""
    arrays = plain_arrays(u, fields)
    return write_grid(path, arrays, u.function_space.mesh.comm, VTU_COMPRESSION)


def write_cut_geometry(
    directory: str | pathlib.Path,
    cut: CutMesh,
    interface_data: dict | None = None,
    u_minus=None,
) -> list[pathlib.Path]:
    """Write ``subcells.vtu`` (the curved sub-triangles of the cut cells, cell data
    ``side``, ``cut``, ``cell``) and ``interface.vtu`` (curved interface pieces, point
    data ``interface_data``: name to an array over its nodes, e.g.
    :func:`~xfem_contact.io.interface_data.interface_point_data`) into ``directory``:
    the cut region only, the uncut cells are in ``result.vtu`` (:func:`write_lips`). On a
    3D mesh the pieces are :mod:`~xfem_contact.io.solid_grids`' (tetrahedra and wedges,
    interface triangles), and ``u_minus`` (side -1's displacement, if given) is point data
    ``u`` of the interface (to draw it deformed).

    Collective: in parallel rank ``r`` writes ``subcells_r{r}.vtu`` and
    ``interface_r{r}.vtu``, rank 0 ``subcells.pvtu`` and ``interface.pvtu``. Returns this
    process's files. See :mod:`xfem_contact.io.pictures`.
    """
    directory, comm = pathlib.Path(directory), cut.mesh.comm
    paths = []
    for name, arrays in (
        ("subcells", subcell_grid_arrays(cut)),
        ("interface", interface_grid_arrays(cut, interface_data, u_minus)),
    ):
        paths.append(write_grid(directory / f"{name}.vtu", arrays, comm, VTU_COMPRESSION))
    return paths


def interface_grid_arrays(cut: CutMesh, interface_data: dict | None = None, u_minus=None):
    """:func:`~xfem_contact.io.vtu.interface_arrays` (in 3D
    :func:`~xfem_contact.io.solid_grids.interface_arrays_3d`, with point data ``u`` of
    side -1's displacement ``u_minus`` if given) with point data ``interface_data`` (name
    to an array over its nodes)."""
    if cut.geometry is None:
        from xfem_contact.io.solid_grids import interface_arrays_3d

        arrays = interface_arrays_3d(cut, u_minus)
    else:
        arrays = interface_arrays(cut)
    return arrays._replace(point_data=arrays.point_data | dict(interface_data or {}))


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
