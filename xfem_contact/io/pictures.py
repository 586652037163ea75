"""Pictures of cuts and results with pyvista (off-screen, static PNG).

Renderers take the grids of :mod:`xfem_contact.io.vtk_grids` (re-exported here)
and write PNG files; the drawing helpers they share are in :mod:`xfem_contact.io.render`
(:func:`quiet_vtk` re-exported here). Nothing here opens a window or needs a display.
"""

from __future__ import annotations

import json
import logging
import pathlib
from collections.abc import Sequence

import numpy as np
import pyvista

from xfem_contact.fem.cutmesh import CutMesh
from xfem_contact.io.render import (
    _clip,
    _curves,
    _frame,
    _legend,
    _lift,
    _outlines,
    _plotter,
    _save,
    _surface,
    _title,
    quiet_vtk,
)
from xfem_contact.io.vtk_grids import deformed_lips_grid, interface_grid, merge_grids, subcell_grid

logger = logging.getLogger(__name__)

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


#: The smallest mean cell width (pixels) at which the pictures draw cell edges
EDGE_PIXELS = 4.0


def _cell_pixels(grid: pyvista.DataSet, window_size: tuple[int, int], bounds=None) -> float:
    """The mean cell width of ``grid`` in pixels of a picture of ``window_size`` that
    shows ``bounds`` (default: the grid's)."""
    xmin, xmax, ymin, ymax = grid.bounds[:4]
    width = np.sqrt((xmax - xmin) * (ymax - ymin) / max(grid.n_cells, 1))
    xmin, xmax, ymin, ymax = grid.bounds[:4] if bounds is None else bounds[:4]
    return width * 0.8 * min(window_size) / max(xmax - xmin, ymax - ymin, 1e-300)


def render_cut(
    subcells: pyvista.DataSet,
    interface: pyvista.DataSet | None,
    path: str | pathlib.Path,
    bounds: Sequence[float] | None = None,
    title: str = "cut cells: sub-triangles and interface",
    window_size: tuple[int, int] = (800, 600),
) -> pathlib.Path:
    """PNG of the mesh edges, the curved sub-triangles coloured by side and the interface
    (uncut cells narrower than :data:`EDGE_PIXELS` pixels: their region's outline only).

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
        fine = not c and _cell_pixels(part, window_size, bounds) < EDGE_PIXELS
        plotter.add_mesh(
            _lift(_clip(_outlines(part, merge=fine), bounds), dz),
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
    field: str | None = None,
    label: str = "displacement (m)",
) -> pathlib.Path:
    """PNG of the deformed configuration coloured by ``|u|`` (m) or by a point field.

    Args:
        grid: A grid with point data ``u`` (m, shape ``(npoints, 3)``), e.g. a
            :func:`deformed_lips_grid`; with cell data ``side`` the outline of
            each side (the lips) is drawn separately.
        path: The PNG file.
        scale: Displacement magnification; default :func:`auto_scale` (largest
            displacement 10% of the size). The title states the factor.
        title: Text at the top; `` (displacement x F)`` is appended.
        window_size: Pixels ``(width, height)``.
        edges: Draw the cell outlines (thin) where cells are at least
            :data:`EDGE_PIXELS` pixels wide (finer meshes would turn white).
        bounds: ``(xmin, xmax, ymin, ymax)`` in m (deformed coordinates) to zoom
            on; default: the whole grid, deformed and undeformed.
        field: A scalar point field to colour by (e.g. ``von_mises``, Pa); default
            ``|u|``. The colour bar runs from exact zero to the largest value
            (:func:`colour_range`).
        label: The colour bar's caption.
    """
    if scale is None:
        scale = auto_scale(grid)
    u = np.asarray(grid.point_data["u"])
    warped = grid.warp_by_vector("u", factor=scale)
    if field is None:
        values = np.sqrt((u**2).sum(axis=1))
    else:
        values = np.asarray(grid.point_data[field], dtype=np.float64).reshape(u.shape[0], -1)[:, 0]
    values, clim = colour_range(values)
    warped.point_data["colour"] = values
    plotter = _plotter(window_size)
    # The undeformed outline, for reference
    dz = 1e-3 * grid.length
    reference = _lift(_clip(_outlines(grid, merge=True), bounds), -dz)
    if reference.n_cells:
        plotter.add_mesh(reference, color="#b0b0b0", line_width=1.0)
    plotter.add_mesh(
        _clip(_surface(warped), bounds),
        scalars="colour",
        clim=clim,
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
    plotter.add_text(label, position=(0.74, 0.81), viewport=True, font_size=10, color="black")
    if edges and _cell_pixels(grid, window_size, bounds) >= EDGE_PIXELS:
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


def _friction_law(law: dict) -> bool:
    """Whether an interface's summary entry describes a law with tangential traction."""
    return "friction" in law or law.get("law") == "sticking"


def colour_range(values: np.ndarray, tiny: float = 1e-12) -> tuple[np.ndarray, tuple]:
    """``values`` with ``|x| < tiny * max|x|`` set to exact 0, and a colour range that
    starts at exact 0 for values of one sign (``(0, max)`` or ``(min, 0)``), else
    ``(min, max)``; ``(0, 1)`` for all zeros."""
    values = np.array(values, dtype=np.float64)
    top = float(np.abs(values).max()) if values.size else 0.0
    values[np.abs(values) < tiny * top] = 0.0
    if top == 0.0:
        return values, (0.0, 1.0)
    low, high = float(values.min()), float(values.max())
    return values, (min(low, 0.0), max(high, 0.0))


def render_folder(
    folder: str | pathlib.Path,
) -> list[pathlib.Path]:
    """Render the results of a scene run folder to PNG (serial; reads the files).

    Writes ``result.png`` (deformed configuration, from ``result*.vtu``),
    ``von_mises.png`` (the same coloured by the von Mises stress), ``cut.png`` (uncut
    cells and sub-triangles from ``result*.vtu``, the interface from
    ``interface*.vtu``), ``pressure.png`` (``lambda_n`` of the interface samples of
    ``summary.json``) and, for friction laws, ``traction.png`` (the tangential traction
    with each point's stick / slip status); one plot per interface when there are
    several (``pressure_NAME.png``, ``traction_NAME.png``); for a crack ``lips.png``
    (opening, slip and multipliers along its lips). A 3D run's pictures are
    :func:`~xfem_contact.io.solid_pictures.render_solid`'s. A picture whose data is
    missing is skipped with an INFO record on this module's logger, as is each file
    written.

    Raises:
        FileNotFoundError: if the folder holds no ``result*.vtu``.
    """
    from xfem_contact.io.plots import (
        interface_abscissa,
        plot_lips,
        plot_pressure,
        plot_traction,
    )
    from xfem_contact.io.solid_pictures import is_solid, render_solid

    say = logger.info
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
    if is_solid(grid):  # a 3D run
        written = render_solid(folder, grid, summary, name)
        for path in written:
            say(f"wrote {path}")
        return written
    # large kinematics: the true deformed configuration (a magnified rotation shrinks)
    large = summary.get("effects", {}).get("kinematics") == "large"
    written.append(
        plot_deformed(
            grid, folder / "result.png", title=f"{name}: deformed", scale=1.0 if large else None
        )
    )
    if "von_mises" in grid.point_data:
        written.append(
            plot_deformed(
                grid,
                folder / "von_mises.png",
                title=f"{name}: von Mises stress",
                scale=1.0 if large else None,
                field="von_mises",
                label="von Mises (Pa)",
            )
        )
    else:
        say(f"skipped von_mises.png: no von_mises in the result*.vtu of {folder}")
    interface_files = sorted(folder.glob("interface*.vtu"))
    if interface_files and "cut" in grid.cell_data:
        pieces = [g for g in (pyvista.read(p) for p in interface_files) if g.n_cells]
        written.append(
            render_cut(
                grid,
                merge_grids(pieces) if pieces else None,
                folder / "cut.png",
                title=f"{name}: cut cells and interface",
            )
        )
    else:
        say(f"skipped cut.png: no interface*.vtu of a cut run in {folder}")
    interfaces = summary.get("interfaces") or {}
    if len(interfaces) > 1:  # one plot per interface
        plots = {f"pressure_{k}.png": (k, v.get("samples")) for k, v in interfaces.items()}
    else:
        plots = {"pressure.png": (None, summary.get("interface_samples"))}
    for file, (interface, samples) in plots.items():
        law = interfaces.get(interface, next(iter(interfaces.values()), {})) if interfaces else {}
        if isinstance(samples, dict) and samples.get("lambda_t") and _friction_law(law):
            s, label = interface_abscissa(samples["x"], samples["y"])
            written.append(
                plot_traction(
                    s,
                    samples,
                    folder / file.replace("pressure", "traction"),
                    friction=law.get("friction"),
                    xlabel=label,
                    title=f"{name}: "
                    + (f"{interface}, " if interface else "")
                    + "tangential traction",
                )
            )
        if not (isinstance(samples, dict) and samples.get("lambda_n")):
            say(f"skipped {file}: summary.json has no interface samples with lambda_n")
            continue
        s, label = interface_abscissa(samples["x"], samples["y"])
        written.append(
            plot_pressure(
                s,
                samples["lambda_n"],
                folder / file,
                xlabel=label,
                title=f"{name}: " + (f"{interface}, " if interface else "") + "contact pressure",
                applied=samples.get("P_n"),
            )
        )
    cracks = summary.get("cracks") or {}
    for crack, entry in cracks.items():
        file = "lips.png" if len(cracks) == 1 else f"lips_{crack}.png"
        title = f"{name}: {crack}, opening and slip of the lips"
        written.append(plot_lips(entry["lips"], folder / file, entry["abscissa"], title))
    for path in written:
        say(f"wrote {path}")
    return written
