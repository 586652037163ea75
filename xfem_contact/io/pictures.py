"""Pictures of cuts and results with pyvista (off-screen, static PNG).

Renderers take the grids of :mod:`xfem_contact.io.vtk_grids` (re-exported here)
and write PNG files. Nothing here opens a window or needs a display.
"""

from __future__ import annotations

import json
import pathlib
from collections.abc import Callable, Sequence

import numpy as np
import pyvista

from xfem_contact.fem.cutmesh import CutMesh
from xfem_contact.io.vtk_grids import deformed_lips_grid, interface_grid, merge_grids, subcell_grid

__all__ = [
    "auto_scale",
    "render_folder",
    "deformed_lips_grid",
    "interface_grid",
    "merge_grids",
    "plot_cut",
    "plot_deformed",
    "quiet_vtk",
    "render_cut",
    "subcell_grid",
]

# Colours of the sides: (uncut cells, sub-triangles, cell outlines)
SIDE_COLOURS = {-1: ("#c9d9ef", "#3b6fb6", "#1f3f73"), 1: ("#f7dcc6", "#e0823d", "#8a4a17")}


def _surface(grid: pyvista.DataSet, subdivision: int = 3) -> pyvista.PolyData:
    """Linear triangles of (possibly quadratic) 2D cells, curved edges subdivided."""
    return grid.extract_surface(nonlinear_subdivision=subdivision, algorithm="dataset_surface")


def _outlines(grid: pyvista.DataSet, merge: bool = False) -> pyvista.PolyData:
    """Curved outlines of the cells (``merge=False``; nodes are not shared) or of
    the region they cover (``merge=True``).

    For a region, coincident nodes are merged first; edges that still look like
    boundary edges but have the region on both sides (hanging nodes where a
    refined fan of sub-triangles meets a whole cell edge) are dropped.
    """
    surface = _surface(grid)
    if merge:
        surface = surface.clean(
            tolerance=1e-9 * max(grid.length, 1e-300), lines_to_points=False, polys_to_lines=False
        )
    edges = surface.extract_feature_edges(
        boundary_edges=True, feature_edges=False, manifold_edges=False, non_manifold_edges=False
    )
    if not merge or edges.n_cells == 0:
        return edges
    lines = edges.lines.reshape(-1, 3)[:, 1:]
    a, b = edges.points[lines[:, 0]], edges.points[lines[:, 1]]
    mid, normal = 0.5 * (a + b), np.c_[a[:, 1] - b[:, 1], b[:, 0] - a[:, 0], np.zeros(len(a))]
    offset = 1e-3 * normal  # 1e-3 of the segment's length, either side
    inside = (surface.find_containing_cell(mid + offset) >= 0) & (
        surface.find_containing_cell(mid - offset) >= 0
    )
    return edges.extract_cells(np.flatnonzero(~inside)).extract_surface(algorithm=None)


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


def render_cut(
    subcells: pyvista.DataSet,
    interface: pyvista.DataSet | None,
    path: str | pathlib.Path,
    bounds: Sequence[float] | None = None,
    title: str = "cut cells: sub-triangles and interface",
    window_size: tuple[int, int] = (800, 600),
) -> pathlib.Path:
    """PNG of the mesh edges, the curved sub-triangles coloured by side and the interface.

    Args:
        subcells: A :func:`subcell_grid` (or several merged, or read from ``.vtu``).
        interface: An :func:`interface_grid`, or ``None``.
        path: The PNG file.
        bounds: ``(xmin, xmax, ymin, ymax)`` in m to zoom on; default: the whole grid.
        title: Text at the top.
        window_size: Pixels ``(width, height)``.
    """
    plotter = _plotter(window_size)
    side, is_cut = np.asarray(subcells.cell_data["side"]), np.asarray(subcells.cell_data["cut"])
    names = {
        (-1, 0): "side -1: uncut cells",
        (-1, 1): "side -1: sub-triangles",
        (1, 0): "side +1: uncut cells",
        (1, 1): "side +1: sub-triangles",
    }
    legend = []
    dz = 1e-3 * subcells.length
    for (s, c), label in names.items():
        mask = (side == s) & (is_cut == c)
        if not mask.any():
            continue
        part = subcells.extract_cells(np.flatnonzero(mask))
        fill, strong, edge = SIDE_COLOURS[s]
        plotter.add_mesh(_clip(_surface(part), bounds), color=strong if c else fill, lighting=False)
        plotter.add_mesh(
            _lift(_clip(_outlines(part), bounds), dz),
            color=edge if c else "#8c8c8c",
            line_width=1.0 if c else 0.8,
        )
        legend.append((label, strong if c else fill, "patch"))
    if interface is not None and interface.n_cells:
        lines = _lift(_clip(_curves(interface), bounds), 2 * dz)
        plotter.add_mesh(lines, color="black", line_width=3.0)
        legend.append(("interface", "black", "line"))
    _legend(plotter, legend)
    _title(plotter, title)
    box = subcells.bounds if bounds is None else bounds
    _frame(plotter, box, window_size)
    return _save(plotter, path)


def plot_cut(
    cut: CutMesh,
    path: str | pathlib.Path,
    bounds: Sequence[float] | None = None,
    title: str = "cut cells: sub-triangles and interface",
    window_size: tuple[int, int] = (800, 600),
) -> pathlib.Path:
    """:func:`render_cut` of this process's :func:`subcell_grid` and :func:`interface_grid`.

    In parallel each rank draws its own cells: give each rank its own ``path``, or
    write the grids with :func:`xfem_contact.io.output.write_cut_geometry` and render
    them merged (``xfem-contact show``).
    """
    return render_cut(subcell_grid(cut), interface_grid(cut), path, bounds, title, window_size)


def auto_scale(grid: pyvista.DataSet, fraction: float = 0.1) -> float:
    """Displacement factor that makes the largest ``|u|`` ``fraction`` of the grid's
    largest extent (dimensionless; 1 when ``u`` vanishes)."""
    u = np.asarray(grid.point_data["u"])
    umax = float(np.sqrt((u**2).sum(axis=1)).max()) if u.size else 0.0
    xmin, xmax, ymin, ymax = grid.bounds[:4]
    size = max(xmax - xmin, ymax - ymin)
    return fraction * size / umax if umax > 0 else 1.0


def plot_deformed(
    grid: pyvista.DataSet,
    path: str | pathlib.Path,
    scale: float | None = None,
    title: str = "deformed configuration",
    window_size: tuple[int, int] = (800, 600),
    edges: bool = True,
    bounds: Sequence[float] | None = None,
) -> pathlib.Path:
    """PNG of the deformed configuration coloured by ``|u|`` (m).

    Args:
        grid: A grid with point data ``u`` (m, shape ``(npoints, 3)``), e.g. a
            :func:`deformed_lips_grid`; with cell data ``side`` the outline of
            each side (the lips) is drawn separately.
        path: The PNG file.
        scale: Displacement magnification; default :func:`auto_scale` (largest
            displacement 10% of the size). The title states the factor.
        title: Text at the top; `` (displacement x F)`` is appended.
        window_size: Pixels ``(width, height)``.
        edges: Draw the cell outlines (thin).
        bounds: ``(xmin, xmax, ymin, ymax)`` in m (deformed coordinates) to zoom
            on; default: the whole grid, deformed and undeformed.
    """
    if scale is None:
        scale = auto_scale(grid)
    u = np.asarray(grid.point_data["u"])
    warped = grid.warp_by_vector("u", factor=scale)
    magnitude = np.sqrt((u**2).sum(axis=1))
    warped.point_data["|u| (m)"] = magnitude
    plotter = _plotter(window_size)
    # The undeformed outline, for reference
    dz = 1e-3 * grid.length
    reference = _lift(_clip(_outlines(grid, merge=True), bounds), -dz)
    if reference.n_cells:
        plotter.add_mesh(reference, color="#b0b0b0", line_width=1.0)
    plotter.add_mesh(
        _clip(_surface(warped), bounds),
        scalars="|u| (m)",
        clim=(float(magnitude.min()), float(magnitude.max())),
        cmap="viridis",
        lighting=False,
        scalar_bar_args={
            "title": "",
            "vertical": True,
            "position_x": 0.8,
            "position_y": 0.1,
            "width": 0.06,
            "height": 0.68,
            "color": "black",
            "fmt": "%.2e",
            "label_font_size": 12,
        },
    )
    plotter.add_text(
        "displacement (m)", position=(0.74, 0.81), viewport=True, font_size=10, color="black"
    )
    if edges:
        lines = _lift(_clip(_outlines(warped), bounds), dz)
        plotter.add_mesh(lines, color="white", line_width=0.5, opacity=0.35)
    sides = np.asarray(warped.cell_data["side"]) if "side" in warped.cell_data else None
    if sides is None:
        regions = [warped]
    else:
        regions = [
            warped.extract_cells(np.flatnonzero(sides == s)) for s in (-1, 1) if (sides == s).any()
        ]
    for region in regions:
        lines = _lift(_clip(_outlines(region, merge=True), bounds), 2 * dz)
        if lines.n_cells:
            plotter.add_mesh(lines, color="black", line_width=2.0)
    _title(plotter, f"{title} (displacement x {scale:.3g})")
    if bounds is None:
        bounds = (
            min(grid.bounds[0], warped.bounds[0]),
            max(grid.bounds[1], warped.bounds[1]),
            min(grid.bounds[2], warped.bounds[2]),
            max(grid.bounds[3], warped.bounds[3]),
        )
    _frame(plotter, bounds, window_size)
    return _save(plotter, path)


def render_folder(
    folder: str | pathlib.Path, log: Callable[[str], None] | None = None
) -> list[pathlib.Path]:
    """Render the results of a scene run folder to PNG (serial; reads the files).

    Writes ``result.png`` (deformed configuration, from ``result*.vtu``),
    ``cut.png`` (sub-triangles and interface, from ``subcells*.vtu`` and
    ``interface*.vtu``) and ``pressure.png`` (``lambda_n`` of the
    ``interface_samples`` of ``summary.json``); a picture whose data is missing is
    skipped with a ``log`` line.

    Raises:
        FileNotFoundError: if the folder holds no ``result*.vtu``.
    """
    from xfem_contact.io.plots import interface_abscissa, plot_pressure

    say = log or (lambda line: None)
    folder = pathlib.Path(folder)
    results = sorted(folder.glob("result*.vtu"))
    if not results:
        raise FileNotFoundError(
            f"no result*.vtu in {folder} (run a scene with --out {folder} first)"
        )
    summary_path = folder / "summary.json"
    summary = json.loads(summary_path.read_text()) if summary_path.exists() else {}
    name = summary.get("scene", folder.name)
    quiet_vtk()
    written = []
    grid = merge_grids([pyvista.read(p) for p in results])
    written.append(plot_deformed(grid, folder / "result.png", title=f"{name}: deformed"))
    subcells = sorted(folder.glob("subcells*.vtu"))
    if subcells:
        pieces = [pyvista.read(p) for p in sorted(folder.glob("interface*.vtu"))]
        pieces = [g for g in pieces if g.n_cells]
        written.append(
            render_cut(
                merge_grids([pyvista.read(p) for p in subcells]),
                merge_grids(pieces) if pieces else None,
                folder / "cut.png",
                title=f"{name}: cut cells and interface",
            )
        )
    else:
        say(f"skipped cut.png: no subcells*.vtu in {folder}")
    samples = summary.get("interface_samples")
    if isinstance(samples, dict) and samples.get("lambda_n"):
        s, label = interface_abscissa(samples["x"], samples["y"])
        written.append(
            plot_pressure(
                s,
                samples["lambda_n"],
                folder / "pressure.png",
                xlabel=label,
                title=f"{name}: contact pressure",
                applied=samples.get("P_n"),
            )
        )
    else:
        say(
            "skipped pressure.png: summary.json has no interface_samples with lambda_n "
            "(contact scenes only)"
        )
    for path in written:
        say(f"wrote {path}")
    return written
