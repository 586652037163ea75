"""Low-level pyvista drawing for the pictures: surfaces, outlines, clipping, framing, text.

The helpers behind :mod:`xfem_contact.io.pictures`: they turn (possibly quadratic) 2D
grids into drawable polygons and lines, place a 2D parallel camera, draw a legend and
a title, and save an off-screen plotter to PNG. Nothing here opens a window. The
underscored helpers are private to :mod:`xfem_contact.io`; :func:`quiet_vtk` is public
and re-exported by :mod:`xfem_contact.io.pictures`.
"""

from __future__ import annotations

import pathlib
from collections.abc import Sequence

import numpy as np
import pyvista

from xfem_contact.io.outlines import cell_outlines, region_outline


def _surface(grid: pyvista.DataSet, subdivision: int = 3) -> pyvista.PolyData:
    """Straight (degree-1) triangles of (possibly quadratic) 2D cells, curved edges subdivided."""
    return grid.extract_surface(nonlinear_subdivision=subdivision, algorithm="dataset_surface")


def _outlines(grid: pyvista.DataSet, merge: bool = False) -> pyvista.PolyData:
    """Curved outlines of the cells (``merge=False``) or of the region they cover
    (``merge=True``, hanging nodes of cut cells handled:
    :func:`~xfem_contact.io.outlines.region_outline`)."""
    return region_outline(grid) if merge else cell_outlines(grid)


def _clip(poly: pyvista.PolyData, bounds: Sequence[float] | None) -> pyvista.PolyData:
    """The part of ``poly`` inside ``bounds = (xmin, xmax, ymin, ymax)`` (all if ``None``)."""
    if bounds is None:
        return poly
    xmin, xmax, ymin, ymax = (float(b) for b in bounds[:4])
    for normal, origin in (
        ((1.0, 0.0, 0.0), (xmax, 0.0, 0.0)),
        ((-1.0, 0.0, 0.0), (xmin, 0.0, 0.0)),
        ((0.0, 1.0, 0.0), (0.0, ymax, 0.0)),
        ((0.0, -1.0, 0.0), (0.0, ymin, 0.0)),
    ):
        if poly.n_cells == 0:
            break
        poly = poly.clip(normal=normal, origin=origin)
    return poly


def _lift(poly: pyvista.DataSet, dz: float) -> pyvista.DataSet:
    """A copy moved by ``dz`` towards the camera (lines drawn over coplanar faces)."""
    poly = poly.copy()
    poly.points[:, 2] += dz
    return poly


def _curves(grid: pyvista.DataSet, samples: int = 8) -> pyvista.PolyData:
    """Polylines through quadratic edges (nodes ``a, b, mid``), ``samples`` pieces each."""
    cells = grid.cells.reshape(-1, 4)[:, 1:] if grid.n_cells else np.zeros((0, 3), int)
    t = np.linspace(0.0, 1.0, samples + 1)
    basis = np.c_[(1 - t) * (1 - 2 * t), t * (2 * t - 1), 4 * t * (1 - t)]  # (samples+1, 3)
    xyz = np.einsum("tj,ejd->etd", basis, grid.points[cells]).reshape(-1, 3)
    m = samples + 1
    lines = np.c_[np.full(cells.shape[0], m), np.arange(cells.shape[0] * m).reshape(-1, m)]
    return pyvista.PolyData(xyz, lines=lines.ravel())


def _frame(
    plotter: pyvista.Plotter,
    bounds: Sequence[float],
    window_size: tuple[int, int],
    right_margin: float = 0.3,
) -> None:
    """2D parallel view of ``bounds = (xmin, xmax, ymin, ymax)`` in the left part of
    the window (the right ``right_margin`` fraction is kept for a legend or colour bar)."""
    xmin, xmax, ymin, ymax = (float(b) for b in bounds[:4])
    width, height = max(xmax - xmin, 1e-300), max(ymax - ymin, 1e-300)
    aspect = window_size[0] / window_size[1]
    fill_x, fill_y = 1.0 - right_margin - 0.04, 0.82  # fractions of the window
    scale = max(height / (2 * fill_y), width / (2 * fill_x * aspect))  # half view height
    view_width = 2 * scale * aspect
    cx = xmin - 0.03 * view_width + view_width / 2
    cy = 0.5 * (ymin + ymax) + 0.04 * scale  # a little room above for the title
    plotter.enable_parallel_projection()
    camera = plotter.camera
    camera.focal_point = (cx, cy, 0.0)
    camera.position = (cx, cy, 10.0 * max(width, height))
    camera.up = (0.0, 1.0, 0.0)
    camera.parallel_scale = scale
    plotter.renderer.ResetCameraClippingRange()


def _legend(plotter: pyvista.Plotter, entries: list[tuple[str, str, str]]) -> None:
    """Legend in the window's top right: ``(label, colour, "patch" | "line")`` entries,
    labels in black (VTK's legend box would colour them like their symbol)."""
    from vtkmodules.vtkRenderingCore import vtkActor2D, vtkCoordinate, vtkPolyDataMapper2D

    x, top, dy = 0.725, 0.86, 0.055
    for i, (label, colour, kind) in enumerate(entries):
        y = top - i * dy
        h = 0.018 if kind == "patch" else 0.004
        w = 0.035
        corners = np.array([[x, y - h, 0], [x + w, y - h, 0], [x + w, y + h, 0], [x, y + h, 0]])
        for mesh, rgb in (
            (pyvista.PolyData(corners, faces=[4, 0, 1, 2, 3]), pyvista.Color(colour).float_rgb),
            (pyvista.PolyData(corners, lines=[5, 0, 1, 2, 3, 0]), (0.35, 0.35, 0.35)),
        ):
            coordinate = vtkCoordinate()
            coordinate.SetCoordinateSystemToNormalizedViewport()
            mapper = vtkPolyDataMapper2D()
            mapper.SetInputData(mesh)
            mapper.SetTransformCoordinate(coordinate)
            actor = vtkActor2D()
            actor.SetMapper(mapper)
            actor.GetProperty().SetColor(rgb)
            plotter.add_actor(actor)
        text = plotter.add_text(
            label, position=(x + 0.045, y), viewport=True, font_size=8, color="black"
        )
        text.GetTextProperty().SetVerticalJustificationToCentered()


def _title(plotter: pyvista.Plotter, text: str, width: int = 52) -> None:
    """Title at the top; a long one is broken before its last " (" (or wrapped)."""
    if len(text) > width:
        cut = text.rfind(" (")
        if 0 < cut:
            text = text[:cut] + "\n" + text[cut + 1 :]
        else:
            import textwrap

            text = "\n".join(textwrap.wrap(text, width))
    plotter.add_text(
        text, position="upper_edge", font_size=11 if "\n" not in text else 10, color="black"
    )


def quiet_vtk() -> None:
    """Let VTK print errors only (process-wide). Hides the harmless "bad X server
    connection" warning VTK prints when it renders off-screen without a display."""
    from vtkmodules.vtkCommonCore import vtkLogger

    vtkLogger.SetStderrVerbosity(vtkLogger.VERBOSITY_ERROR)


def _plotter(window_size: tuple[int, int]) -> pyvista.Plotter:
    plotter = pyvista.Plotter(off_screen=True, window_size=list(window_size))
    plotter.set_background("white")
    return plotter


def _save(plotter: pyvista.Plotter, path: str | pathlib.Path) -> pathlib.Path:
    path = pathlib.Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    plotter.screenshot(str(path))
    plotter.close()
    return path
