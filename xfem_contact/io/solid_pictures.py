"""Pictures of a 3D run folder with pyvista (off-screen, static PNG).

From the grids a 3D scene run writes (:mod:`xfem_contact.io.solid_grids`): the deformed
body cut open by a plane through its centre (both sides, each with its own displacement,
magnified), coloured by ``|u|`` or by the von Mises stress, with the interface in it; the
cut (both sides cut open, the pieces of the cut cells, half the interface in front); and the
whole interface surface coloured by a point field of its laws' state (the contact
pressure ``lambda_n``, the tangential traction ``|lambda_t|``). Nothing here opens a
window or needs a display.
"""

from __future__ import annotations

import pathlib

import numpy as np
import pyvista

from xfem_contact.io.render import _plotter, _save, _title

#: The plane the body is cut open by: its normal (the camera looks from that side)
CLIP_NORMAL = (0.0, -1.0, 0.0)
#: The colour of the interface surface
INTERFACE_COLOUR = "#e8c547"
#: VTK types of 3D cells (tetrahedron, voxel, hexahedron, wedge, pyramid and quadratic ones)
SOLID_TYPES = (10, 11, 12, 13, 14, 24, 25, 29)

_BAR = {
    "vertical": True,
    "position_x": 0.83,
    "position_y": 0.12,
    "width": 0.05,
    "height": 0.66,
    "color": "black",
    "fmt": "%.2e",
    "label_font_size": 12,
    "title": "",
}


def is_solid(grid: pyvista.DataSet) -> bool:
    """Whether ``grid`` holds 3D cells (a 3D run's ``result.vtu``)."""
    return bool(grid.n_cells) and bool(np.isin(np.asarray(grid.celltypes), SOLID_TYPES).any())


def _camera(plotter: pyvista.Plotter, grid: pyvista.DataSet) -> None:
    """A view from the clipped side, a little from the right and from above."""
    bounds = np.asarray(grid.bounds).reshape(3, 2)
    centre, size = bounds.mean(axis=1), float(np.linalg.norm(np.ptp(bounds, axis=1)))
    normal, up = np.asarray(CLIP_NORMAL), np.array([0.0, 0.0, 1.0])
    view = normal + 0.55 * np.cross(up, normal) + 0.6 * up
    position = centre + 1.7 * size * view / np.linalg.norm(view)
    plotter.camera_position = [tuple(position), tuple(centre), tuple(up)]


def _colour_limits(values: np.ndarray) -> tuple[float, float]:
    """The colour range of ``values``: their range, widened to 1 % of their size about
    them when it is below 1e-6 of it (a uniform field, up to rounding)."""
    low, high = float(values.min()), float(values.max())
    size = max(abs(low), abs(high))
    if high - low > 1e-6 * size:
        return low, high
    middle, half = 0.5 * (low + high), 0.01 * size if size > 0 else 1.0
    return middle - half, middle + half


def _colour_bar_label(plotter: pyvista.Plotter, label: str) -> None:
    plotter.add_text(label, position=(0.74, 0.82), viewport=True, font_size=10, color="black")


def plot_clipped(
    grid: pyvista.DataSet,
    path: str | pathlib.Path,
    interface: pyvista.DataSet | None = None,
    scale: float | None = None,
    field: str | None = None,
    label: str = "displacement (m)",
    title: str = "deformed",
    window_size: tuple[int, int] = (900, 700),
) -> pathlib.Path:
    """PNG of the deformed body cut open by the plane through its centre normal to
    :data:`CLIP_NORMAL`, coloured by ``|u|`` (m) or by the scalar point field ``field``
    (e.g. ``von_mises``, Pa), with the section of the ``interface`` grid (point data
    ``u``: side -1's displacement) deformed, in white.

    Args:
        grid: A 3D grid with point data ``u`` (m, ``(npoints, 3)``), e.g. ``result.vtu``.
        path: The PNG file.
        scale: Displacement magnification; default: the largest ``|u|`` 10 % of the
            body's largest extent. The title states it.
    """
    u = np.asarray(grid.point_data["u"])
    magnitude = np.sqrt((u**2).sum(axis=1))
    bounds = np.asarray(grid.bounds).reshape(3, 2)
    size = float(np.ptp(bounds, axis=1).max())
    if scale is None:
        scale = 0.1 * size / magnitude.max() if magnitude.size and magnitude.max() > 0 else 1.0
    values = magnitude if field is None else np.asarray(grid.point_data[field]).reshape(-1)
    body = grid.copy()
    body.point_data["colour"] = values
    centre = bounds.mean(axis=1)
    clipped = body.clip(normal=CLIP_NORMAL, origin=tuple(centre), invert=True)
    warped = clipped.warp_by_vector("u", factor=scale)
    plotter = _plotter(window_size)
    plotter.add_mesh(
        warped,
        scalars="colour",
        clim=_colour_limits(values),
        cmap="viridis",
        show_edges=False,
        scalar_bar_args=_BAR,
    )
    if interface is not None and interface.n_cells and "u" in interface.point_data:
        rim = interface.slice(normal=CLIP_NORMAL, origin=tuple(centre))
        if rim.n_cells:  # the section of the interface, deformed with side -1
            rim = rim.warp_by_vector("u", factor=scale)
            rim.points -= 1e-3 * size * np.asarray(CLIP_NORMAL)  # over the cut face
            plotter.add_mesh(rim, color="white", line_width=2.0)
    _colour_bar_label(plotter, label)
    _camera(plotter, grid)
    _title(plotter, f"{title} (displacement x {scale:.3g})")
    return _save(plotter, path)


def plot_surface_field(
    surface: pyvista.DataSet,
    path: str | pathlib.Path,
    field: str,
    label: str,
    title: str,
    window_size: tuple[int, int] = (900, 700),
) -> pathlib.Path:
    """PNG of the interface surface (``interface.vtu``) coloured by the point field
    ``field`` (a vector is drawn by its length), seen from the side of
    :data:`CLIP_NORMAL`, from the right and from above."""
    values = np.asarray(surface.point_data[field])
    if values.ndim == 2:
        values = np.sqrt((values**2).sum(axis=1))
    shown = surface.copy()
    shown.point_data["colour"] = values
    plotter = _plotter(window_size)
    plotter.add_mesh(
        shown.extract_surface(algorithm="dataset_surface").clean(),
        scalars="colour",
        clim=_colour_limits(values),
        cmap="coolwarm",
        smooth_shading=True,
        scalar_bar_args=_BAR,
    )
    _colour_bar_label(plotter, label)
    _camera(plotter, surface)
    _title(plotter, title)
    return _save(plotter, path)


def plot_cut_solid(
    grid: pyvista.DataSet,
    path: str | pathlib.Path,
    interface: pyvista.DataSet | None = None,
    title: str = "cut",
    window_size: tuple[int, int] = (900, 700),
) -> pathlib.Path:
    """PNG of a 3D cut: both sides of ``grid`` (cell data ``side``, ``cut``; e.g.
    ``result.vtu``, undeformed) cut open by the plane through its centre normal to
    :data:`CLIP_NORMAL`, their uncut cells light and the pieces of the cut cells dark,
    with the edges of the pieces, and the upper half of the ``interface`` surface in front
    of the plane."""
    from xfem_contact.io.pictures import SIDE_COLOURS
    from xfem_contact.io.render import _legend

    bounds = np.asarray(grid.bounds).reshape(3, 2)
    centre = tuple(bounds.mean(axis=1))
    plotter = _plotter(window_size)
    side, cut = np.asarray(grid.cell_data["side"]), np.asarray(grid.cell_data["cut"])
    for s in (-1, 1):
        for c, shade in ((0, 0), (1, 1)):
            cells = np.flatnonzero((side == s) & (cut == c))
            if cells.size == 0:
                continue
            part = grid.extract_cells(cells).clip(normal=CLIP_NORMAL, origin=centre, invert=True)
            if part.n_cells:
                colour, edges = SIDE_COLOURS[s][shade], bool(c)
                plotter.add_mesh(part, color=colour, show_edges=edges, ambient=0.45, diffuse=0.6)
    if interface is not None and interface.n_cells:  # its upper half, in front of the plane
        front = interface.clip(normal=CLIP_NORMAL, origin=centre, invert=False)
        front = front.clip(normal=(0.0, 0.0, -1.0), origin=centre, invert=True)
        if front.n_cells:
            plotter.add_mesh(front, color=INTERFACE_COLOUR, smooth_shading=True)
    _legend(
        plotter,
        [
            ("side -1", SIDE_COLOURS[-1][0], "patch"),
            ("side -1, cut cells", SIDE_COLOURS[-1][1], "patch"),
            ("side +1", SIDE_COLOURS[1][0], "patch"),
            ("side +1, cut cells", SIDE_COLOURS[1][1], "patch"),
            ("interface", INTERFACE_COLOUR, "patch"),
        ],
    )
    _camera(plotter, grid)
    _title(plotter, title)
    return _save(plotter, path)


def render_solid(
    folder: pathlib.Path, grid: pyvista.DataSet, summary: dict, name: str
) -> list[pathlib.Path]:
    """The pictures of a 3D run folder (``grid``: its ``result*.vtu`` merged):
    ``result.png`` and ``von_mises.png`` (:func:`plot_clipped`), ``cut.png``
    (:func:`plot_cut_solid`), and of the interface laws' state ``pressure.png``
    (``lambda_n``) and, for friction laws, ``traction.png`` (``|lambda_t|``) on the
    interface surface (:func:`plot_surface_field`)."""
    from xfem_contact.io.vtk_grids import merge_grids

    pieces = [pyvista.read(p) for p in sorted(folder.glob("interface*.vtu"))]
    pieces = [g for g in pieces if g.n_cells]
    interface = merge_grids(pieces) if pieces else None
    written = [plot_clipped(grid, folder / "result.png", interface, title=f"{name}: deformed")]
    if "von_mises" in grid.point_data:
        written.append(
            plot_clipped(
                grid,
                folder / "von_mises.png",
                interface,
                field="von_mises",
                label="von Mises (Pa)",
                title=f"{name}: von Mises stress",
            )
        )
    if interface is None:
        return written
    written.append(
        plot_cut_solid(grid, folder / "cut.png", interface, f"{name}: cut cells and interface")
    )
    laws = (summary.get("interfaces") or {}).values()
    friction = any("friction" in law or law.get("law") == "sticking" for law in laws)
    plots = [("lambda_n", "pressure.png", "lambda_n (Pa)", "contact pressure lambda_n")]
    if friction:
        plots.append(("lambda_t", "traction.png", "|lambda_t| (Pa)", "tangential traction"))
    for field, file, label, what in plots:
        if field in interface.point_data:
            title = f"{name}: {what} on the interface"
            written.append(plot_surface_field(interface, folder / file, field, label, title))
    return written
