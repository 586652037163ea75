"""A picture of a 3D cut with pyvista (off-screen, static PNG).

The cut cells are split into linear sub-cells (``2^levels`` per edge, matching on shared
faces) carrying the level-set interpolant ``phi_h`` (P1/P2 or Q1/Q2) at their vertices.
Drawn: side -1 (``phi_h < 0``) and side +1 (those sub-cells clipped at ``phi_h = 0``, and
the uncut cells) cut away in front of a plane through (about) the centre of the mesh, so
that both sides show inside, with the sections of the cut cells (where the runtime rules
are) on that plane; the upper half of the interface (the zero surface of the piecewise
linear ``phi_h`` of the sub-cells) in front of the plane; and on it points of the
interface rules, pushed to physical coordinates (at most :data:`MAX_POINTS`), which lie
on that surface. Nothing here opens a window or needs a display.
"""

from __future__ import annotations

import pathlib

import dolfinx.plot
import numpy as np
import pyvista

from xfem_contact.fem.cutmesh import CutMesh
from xfem_contact.io.pictures import SIDE_COLOURS
from xfem_contact.io.render import _legend, _plotter, _save, _title
from xfem_contact.io.solid_grids import reference_subcells
from xfem_contact.io.solid_pictures import INTERFACE_COLOUR

__all__ = ["plot_cut_3d"]

POINT_COLOUR = "#202020"
EDGE_COLOUR = "#404040"
#: At most this many interface rule points are drawn (a random choice, seeded; more hide
#: the interface in a small picture)
MAX_POINTS = 500


def _cut_cell_grid(cut: CutMesh, levels: int) -> pyvista.UnstructuredGrid:
    """The cut cells refined ``2^levels`` times per edge into linear cells, with
    ``phi_h`` at their vertices (the same values at the vertices two cells share)."""
    sub, vtk_type = reference_subcells(cut.mesh.topology.cell_name(), levels)
    m, nv = sub.shape[:2]
    X = np.tile(sub.reshape(-1, 3), (cut.cut_cells.size, 1))
    cells = np.repeat(cut.cut_cells, m * nv)
    connectivity = np.arange(X.shape[0]).reshape(-1, nv)
    grid = pyvista.UnstructuredGrid(
        {pyvista.CellType(vtk_type): connectivity},
        cut.maps.push_forward(cells, X).astype(np.float64),
    )
    grid.point_data["phi"] = cut.maps.values(cells, X)
    return grid


def _side_cells(cut: CutMesh, side: int) -> pyvista.UnstructuredGrid:
    """The uncut cells of ``side`` (owned), as linear cells."""
    cells = np.flatnonzero(cut.cell_sides == side).astype(np.int32)
    return pyvista.UnstructuredGrid(*dolfinx.plot.vtk_mesh(cut.mesh, 3, cells))


def plot_cut_3d(
    cut: CutMesh,
    path: str | pathlib.Path,
    *,
    normal: tuple[float, float, float] = (0.0, -1.0, 0.0),
    window_size: tuple[int, int] = (1000, 800),
    levels: int = 2,
    title: str | None = None,
) -> pathlib.Path:
    """Draw a 3D cut to a PNG (see the module) and return its path.

    Args:
        cut: A cut tetrahedron or hexahedron mesh.
        path: The PNG file (its folder is made).
        normal: The sides are cut away on this side of the plane through the mesh's
            centre, where the camera looks from and the interface is drawn.
        window_size: Pixels ``(width, height)``.
        levels: Each cut cell is drawn as ``8^levels`` linear sub-cells.
        title: Text at the top; default: the cell kind, the degree and the counts.

    Draws the cells of this process (call it on one process, or on a serial mesh).
    """
    if cut.mesh.topology.dim != 3:
        raise ValueError(
            f"plot_cut_3d draws 3D cuts; this mesh has dimension {cut.mesh.topology.dim}"
        )
    refined = _cut_cell_grid(cut, levels)
    normal = np.asarray(normal, dtype=float) / np.linalg.norm(normal)
    bounds = np.array(cut.mesh.geometry.x).reshape(-1, 3)
    size = np.linalg.norm(np.ptp(bounds, axis=0))
    centre = 0.5 * (bounds.min(axis=0) + bounds.max(axis=0)) + 0.03 * size * normal
    plane = {"normal": tuple(normal), "origin": tuple(centre)}
    up = np.array([0.0, 0.0, 1.0]) if abs(normal[2]) < 0.9 else np.array([0.0, 1.0, 0.0])
    plotter = _plotter(window_size)
    for side in (-1, 1):  # both sides behind the plane, cut open
        part = refined.clip_scalar(scalars="phi", value=0.0, invert=side == -1)
        part = part.merge(_side_cells(cut, side)).clip(**plane, invert=True)
        if part.n_cells:
            colour = SIDE_COLOURS[side][1 if side == -1 else 0]
            plotter.add_mesh(part, color=colour, ambient=0.45, diffuse=0.6, specular=0.0)
    cells = pyvista.UnstructuredGrid(*dolfinx.plot.vtk_mesh(cut.mesh, 3, cut.cut_cells))
    section = cells.slice(**plane).extract_all_edges()
    if section.n_points:  # the cut cells, where the runtime rules are, on the plane
        section.points += 2e-3 * size * normal
        plotter.add_mesh(section, color=EDGE_COLOUR, line_width=1.0)
    cap = {"normal": tuple(-up), "origin": tuple(centre + 0.02 * size * up), "invert": True}
    front = refined.contour([0.0], scalars="phi").clip(**plane, invert=False).clip(**cap)
    if front.n_points:  # the upper half of the interface in front of the plane
        plotter.add_mesh(front, color=INTERFACE_COLOUR, smooth_shading=True)
    rules = cut.interface_rules
    if rules.weights.size:
        x = cut.maps.push_forward(cut.cut_cells[rules.point_rows], rules.points)
        x = x[((x - centre) @ normal >= 0.0) & ((x - centre) @ up >= 0.02 * size)]
        x = x[np.random.default_rng(0).permutation(len(x))[:MAX_POINTS]]
        if len(x):
            plotter.add_points(x, color=POINT_COLOUR, point_size=3.0)
    side = np.cross(up, normal)
    view = normal + 0.55 * side + 0.6 * up
    position = centre + 1.9 * size * view / np.linalg.norm(view)
    plotter.camera_position = [tuple(position), tuple(centre), tuple(up)]
    _legend(
        plotter,
        [
            ("side -1", SIDE_COLOURS[-1][1], "patch"),
            ("side +1", SIDE_COLOURS[1][0], "patch"),
            ("interface", INTERFACE_COLOUR, "patch"),
            ("cut cells", EDGE_COLOUR, "line"),
        ],
    )
    if title is None:
        cell = cut.mesh.topology.cell_name()
        kind = ("P" if cell == "tetrahedron" else "Q") + str(cut.degree)
        title = f"{cell} mesh, {kind} level set ({cut.num_cut_cells_global} cut cells)"
    _title(plotter, title)
    return _save(plotter, path)
