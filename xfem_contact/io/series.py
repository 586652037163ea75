"""The files ParaView opens whole: a grid written in pieces by several processes
(``.pvtu``) and a time series of grids (``.pvd``).

- :func:`write_grid`: one grid of :class:`~xfem_contact.io.vtu.GridArrays`, each process's
  cells. Serial: ``NAME.vtu``. In parallel rank ``r`` writes ``NAME_r{r}.vtu`` and rank 0
  ``NAME.pvtu``, which lists the pieces that have cells and declares their arrays.
- :class:`StepSeries`: a grid per load step in ``NAME_steps/`` and ``NAME.pvd`` listing
  them with their pseudo-times, rewritten (atomically) after every step, so that an
  interrupted run leaves a readable series of the steps done.

Plain XML written here; the pieces are :func:`~xfem_contact.io.vtu.write_vtu`'s. No
pyvista import.
"""

from __future__ import annotations

import os
import pathlib

import numpy as np

from xfem_contact.io.vtu import GridArrays, quoteattr, vtk_type, write_vtu


def _declarations(data: dict) -> list[tuple[str, str, int]]:
    """``(name, VTK type, components)`` of each array of ``data`` (name to array)."""
    found = []
    for name, values in data.items():
        values = np.asarray(values)
        components = 1 if values.ndim == 1 else int(values.shape[1])
        found.append((name, vtk_type(name, values), components))
    return found


def _replace_text(path: pathlib.Path, text: str) -> None:
    """Write ``text`` to ``path`` through a temporary file renamed over it."""
    temporary = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        temporary.write_text(text)
        os.replace(temporary, path)
    except BaseException:
        temporary.unlink(missing_ok=True)
        raise


def declarations(arrays: GridArrays) -> tuple[list, list]:
    """``(point data, cell data)`` of ``arrays``, each a list of ``(name, VTK type,
    components)``."""
    return _declarations(arrays.point_data), _declarations(arrays.cell_data)


def pvtu_text(pieces: list[str], arrays: tuple[list, list]) -> str:
    """The ``.pvtu`` of ``pieces`` (file names relative to it) with the arrays
    :func:`declarations` gives of any piece that has cells."""

    def block(tag: str, declared: list) -> list[str]:
        rows = [f"    <{tag}>"]
        for name, kind, components in declared:
            rows.append(
                f'      <PDataArray type="{kind}" Name={quoteattr(name)} '
                f'NumberOfComponents="{components}"/>'
            )
        return [*rows, f"    </{tag}>"]

    lines = [
        '<?xml version="1.0"?>',
        '<VTKFile type="PUnstructuredGrid" version="1.0" byte_order="LittleEndian" '
        'header_type="UInt64">',
        '  <PUnstructuredGrid GhostLevel="0">',
        *block("PPointData", arrays[0]),
        *block("PCellData", arrays[1]),
        "    <PPoints>",
        '      <PDataArray type="Float64" Name="Points" NumberOfComponents="3"/>',
        "    </PPoints>",
        *(f"    <Piece Source={quoteattr(piece)}/>" for piece in pieces),
        "  </PUnstructuredGrid>",
        "</VTKFile>",
    ]
    return "\n".join(lines) + "\n"


def write_grid(
    path: str | pathlib.Path, arrays: GridArrays, comm, compression: str = "none"
) -> pathlib.Path:
    """Write this process's ``arrays`` as ``path`` (a ``.vtu``); in parallel as the piece
    ``path`` with suffix ``_r{rank}``, and rank 0 writes :func:`opened` ``(path)``, the
    ``.pvtu`` naming the pieces that have cells. Collective.

    Returns:
        This process's file (``path`` or its piece).
    """
    path = pathlib.Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    if comm.size == 1:
        write_vtu(path, arrays, compression)
        return path
    piece = path.with_name(f"{path.stem}_r{comm.rank}{path.suffix}")
    write_vtu(piece, arrays, compression)
    # every piece's name, whether it has cells, and its arrays (an empty one has none)
    pieces = comm.gather((piece.name, arrays.types.size > 0, declarations(arrays)), root=0)
    if comm.rank == 0:
        filled = [p for p in pieces if p[1]] or pieces[:1]
        _replace_text(opened(path, comm), pvtu_text([p[0] for p in filled], filled[0][2]))
    comm.barrier()  # the .pvtu is on disk before any process goes on
    return piece


def opened(path: str | pathlib.Path, comm) -> pathlib.Path:
    """The file ParaView opens for the grid :func:`write_grid` writes at ``path``:
    ``path`` in serial, ``path`` with suffix ``.pvtu`` in parallel."""
    path = pathlib.Path(path)
    return path if comm.size == 1 else path.with_suffix(".pvtu")


def pvd_text(entries: list[tuple[float, str]]) -> str:
    """The ``.pvd`` of ``entries``: ``(time, file relative to the .pvd)``, one data set
    per time."""
    lines = [
        '<?xml version="1.0"?>',
        '<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">',
        "  <Collection>",
        *(
            f'    <DataSet timestep="{t!r}" group="" part="0" file={quoteattr(name)}/>'
            for t, name in entries
        ),
        "  </Collection>",
        "</VTKFile>",
    ]
    return "\n".join(lines) + "\n"


class StepSeries:
    """A grid per load step and the ``.pvd`` of them, for ParaView. Collective (the
    construction removes the files of a former series of that name).

    Args:
        directory: The output folder; the steps go to ``directory/NAME_steps/``
            (``NAME_000001.vtu``, or ``.pvtu`` and pieces in parallel), the series to
            ``directory/NAME.pvd``.
        name: The grid's name, e.g. ``result``.
        comm: The communicator of the processes that write pieces.
        compression: Of the ``.vtu`` pieces (:func:`~xfem_contact.io.vtu.write_vtu`).
    """

    def __init__(self, directory: str | pathlib.Path, name: str, comm, compression: str = "none"):
        self.directory, self.name, self.comm = pathlib.Path(directory), name, comm
        self.compression = compression
        #: ``(time, file)`` of the steps written, files relative to :attr:`path`
        self.entries: list[tuple[float, str]] = []
        if comm.rank == 0:  # a former run's steps and series
            self.path.unlink(missing_ok=True)
            for old in self.folder.glob(f"{name}_*.*vtu"):
                old.unlink()
        comm.barrier()

    @property
    def folder(self) -> pathlib.Path:
        """The folder of the steps' files."""
        return self.directory / f"{self.name}_steps"

    @property
    def path(self) -> pathlib.Path:
        """The ``.pvd`` file."""
        return self.directory / f"{self.name}.pvd"

    def write(self, t: float, arrays: GridArrays) -> pathlib.Path:
        """Write the step at pseudo-time ``t`` (this process's ``arrays``) and rewrite the
        ``.pvd``. Collective. Returns the step's file (``.vtu`` or ``.pvtu``)."""
        k = len(self.entries) + 1
        step = self.folder / f"{self.name}_{k:06d}.vtu"
        write_grid(step, arrays, self.comm, self.compression)
        written = opened(step, self.comm)
        self.entries.append((float(t), written.relative_to(self.directory).as_posix()))
        if self.comm.rank == 0:
            _replace_text(self.path, pvd_text(self.entries))
        return written
