"""Pictures: the cut grids (areas, lengths, lips), the PNGs, ``xfem-contact show``."""

import json
import pathlib

import xfem_contact  # noqa: F401  (loads DOLFINx's MPI first when the wheel is used)

# isort: split
import basix
import dolfinx.fem
import matplotlib.image
import numpy as np
import pytest
from conftest import unit_square
from mpi4py import MPI

from xfem_contact.fem.cutmesh import CutMesh
from xfem_contact.fem.forms import form
from xfem_contact.io import pictures, vtk_grids
from xfem_contact.io.outlines import region_outline
from xfem_contact.io.output import write_cut_geometry, write_lips
from xfem_contact.io.plots import interface_abscissa, plot_pressure
from xfem_contact.scenes import cli

CENTRE, RADIUS = (0.51, 0.47), 0.3


def disc(x):
    return np.hypot(x[0] - CENTRE[0], x[1] - CENTRE[1]) - RADIUS


def total(value: float) -> float:
    return MPI.COMM_WORLD.allreduce(value, op=MPI.SUM)


def assemble(integrand) -> float:
    return total(dolfinx.fem.assemble_scalar(form(integrand)))


def quadratic_triangle_areas(grid) -> np.ndarray:
    """Exact areas (m^2) of VTK 6-node triangles (P2 maps), one per cell."""
    nodes = grid.cells.reshape(-1, 7)[:, 1:][:, np.argsort(vtk_grids.P2_TO_VTK)]  # basix order
    X, w = basix.make_quadrature(basix.CellType.triangle, 4)
    element = basix.create_element(basix.ElementFamily.P, basix.CellType.triangle, 2)
    dN = element.tabulate(1, X)[1:, :, :, 0]  # (2, q, 6)
    J = np.einsum("kqi,cid->cqdk", dN, grid.points[nodes][:, :, :2])
    return np.abs(np.linalg.det(J)) @ w


def quadratic_edge_lengths(grid) -> np.ndarray:
    """Lengths (m) of VTK quadratic edges (nodes a, b, mid), one per cell."""
    nodes = grid.cells.reshape(-1, 4)[:, 1:]
    t, w = np.polynomial.legendre.leggauss(12)
    t, w = 0.5 * (t + 1), 0.5 * w
    dN = np.c_[4 * t - 3, 4 * t - 1, 4 - 8 * t]  # d/dt of (1-t)(1-2t), t(2t-1), 4t(1-t)
    tangent = np.einsum("qi,cid->cqd", dN, grid.points[nodes])
    return np.linalg.norm(tangent, axis=2) @ w


def not_blank(path) -> bool:
    image = matplotlib.image.imread(str(path))
    return image.ndim == 3 and float(image[..., :3].var()) > 1e-3


@pytest.mark.mpi
def test_subcell_grid_covers_the_domain(cell):
    mesh = unit_square(8, cell)
    cut = CutMesh(mesh, disc, degree=2)
    grid = pictures.subcell_grid(cut)
    g = cut.geometry
    uncut = int(np.sum(cut.cell_sides != 0))
    assert grid.n_cells == uncut + g.tri_minus.shape[0] + g.tri_plus.shape[0]
    side, is_cut = np.asarray(grid.cell_data["side"]), np.asarray(grid.cell_data["cut"])
    assert set(np.unique(side)) <= {-1, 1}
    assert np.sum(is_cut) == g.tri_minus.shape[0] + g.tri_plus.shape[0]
    assert np.sum((side == -1) & (is_cut == 1)) == g.tri_minus.shape[0]
    # VTK's sizes of quadratic cells (through their mid-nodes) tile the square exactly
    sizes = np.asarray(grid.compute_cell_sizes(length=False, volume=False)["Area"])
    assert abs(total(sizes.sum()) - 1.0) < 1e-10
    # The curved sub-triangles are the ones the quadrature integrates (affine cells)
    minus_cut = grid.extract_cells(np.flatnonzero((side == -1) & (is_cut == 1)))
    area_minus = total(
        quadratic_triangle_areas(minus_cut).sum() + sizes[(side == -1) & (is_cut == 0)].sum()
    )
    one = dolfinx.fem.Constant(mesh, 1.0)
    assert abs(area_minus - assemble(one * cut.dx(-1))) < 1e-12
    assert abs(area_minus - np.pi * RADIUS**2) < 1e-4


def polyline_length(poly) -> float:
    """Total length (m) of a PolyData's polylines."""
    lines, points, length, i = poly.lines, poly.points, 0.0, 0
    while i < len(lines):
        nodes = lines[i + 1 : i + 1 + lines[i]]
        length += np.linalg.norm(np.diff(points[nodes], axis=0), axis=1).sum()
        i += lines[i] + 1
    return length


@pytest.mark.parametrize("cell", ["triangle", "quadrilateral"])
def test_region_outline_is_the_interface_and_the_boundary(cell):
    """Each side's outline of the sub-cell grid: the interface (side -1) and the
    interface plus the square's boundary (side +1), against the cut's own interface
    length. The triangles' fans divide edges that their neighbours keep whole (hanging
    nodes): without dropping the overlapping edges side +1 measures 1.25 m more."""
    mesh = unit_square(8, cell, comm=MPI.COMM_SELF)
    cut = CutMesh(mesh, disc, degree=2)
    interface = dolfinx.fem.assemble_scalar(form(dolfinx.fem.Constant(mesh, 1.0) * cut.dGamma))
    grid = pictures.subcell_grid(cut)
    side = np.asarray(grid.cell_data["side"])
    for s, expected in ((-1, interface), (1, 4.0 + interface)):
        outline = region_outline(grid.extract_cells(np.flatnonzero(side == s)))
        assert abs(polyline_length(outline) - expected) < 5e-4 * expected


@pytest.mark.mpi
def test_interface_grid_length():
    mesh = unit_square(16, "quadrilateral")
    cut = CutMesh(mesh, disc, degree=2)
    grid = pictures.interface_grid(cut)
    assert grid.n_cells == cut.geometry.seg.shape[0]
    assert "cell" in grid.cell_data
    length = total(quadratic_edge_lengths(grid).sum())
    assert abs(length - 2 * np.pi * RADIUS) < 1e-5 * 2 * np.pi * RADIUS
    one = dolfinx.fem.Constant(mesh, 1.0)
    assert abs(length - assemble(one * cut.dGamma)) < 1e-9


@pytest.mark.mpi
def test_lips_grid_carries_each_sides_field(tmp_path_factory, cell):
    mesh = unit_square(6, cell)
    cut = CutMesh(mesh, disc, degree=2)
    V = dolfinx.fem.functionspace(mesh, ("Lagrange", 2, (2,)))
    u_minus, u_plus = dolfinx.fem.Function(V), dolfinx.fem.Function(V)
    u_minus.interpolate(lambda x: np.stack([x[0] * x[1], x[1] ** 2]))
    u_plus.interpolate(lambda x: np.stack([np.ones_like(x[0]), -x[0]]))
    grid = pictures.deformed_lips_grid(cut, u_minus, u_plus)
    x, y = grid.points[:, 0], grid.points[:, 1]
    side = np.zeros(grid.n_points, dtype=np.int8)  # each point belongs to one side
    cell_side = np.repeat(np.asarray(grid.cell_data["side"]), np.diff(grid.cell_offsets))
    side[grid.cell_connectivity] = cell_side
    assert np.all(side[grid.cell_connectivity] == cell_side)
    # the uncut cells of a side share their nodes: one point per vertex, edge, centre
    nodes_per_cell = np.diff(grid.cell_offsets)
    for s in (-1, 1):
        cells = (np.asarray(grid.cell_data["cut"]) == 0) & (grid.cell_data["side"] == s)
        nodes = np.unique(grid.cell_connectivity[np.repeat(cells, nodes_per_cell)])
        assert nodes.size <= nodes_per_cell[cells].sum()
        assert np.unique(grid.points[nodes].round(12), axis=0).shape[0] == nodes.size
    exact = np.where(side[:, None] == -1, np.c_[x * y, y**2], np.c_[np.ones_like(x), -x])
    assert np.abs(grid.point_data["u"][:, :2] - exact).max() < 1e-12
    assert np.all(grid.point_data["u"][:, 2] == 0)

    folder = pathlib.Path(MPI.COMM_WORLD.bcast(str(tmp_path_factory.mktemp("lips")), root=0))
    path = write_lips(folder / "lips.vtu", cut, u_minus, u_plus)
    paths = write_cut_geometry(folder, cut)
    if MPI.COMM_WORLD.size > 1:
        rank = MPI.COMM_WORLD.rank
        assert [p.name for p in [path, *paths]] == [
            f"lips_r{rank}.vtu",
            f"subcells_r{rank}.vtu",
            f"interface_r{rank}.vtu",
        ]
    import pyvista

    if MPI.COMM_WORLD.size > 1:  # the pieces of every process, as ParaView opens them
        whole = pyvista.read(folder / "lips.pvtu")
        assert whole.n_cells == MPI.COMM_WORLD.allreduce(grid.n_cells)
        assert set(whole.point_data.keys()) == {"u"}
        assert set(whole.cell_data.keys()) == {"side", "cut", "cell"}

    back = pyvista.read(path)  # written by VTK directly: the same grid as pyvista's
    assert np.array_equal(back.points, grid.points)
    assert np.array_equal(back.cells, grid.cells)
    assert np.array_equal(back.celltypes, grid.celltypes)
    for name in ("side", "cut", "cell"):
        assert np.array_equal(back.cell_data[name], grid.cell_data[name])
    assert np.array_equal(back.point_data["u"], grid.point_data["u"])
    subcells, interface = (pyvista.read(p) for p in paths)  # the cut region only
    is_cut = np.asarray(grid.cell_data["cut"]) == 1
    assert subcells.n_cells == is_cut.sum() and np.all(subcells.cell_data["cut"] == 1)
    assert np.allclose(subcells.points, grid.extract_cells(np.flatnonzero(is_cut)).points)
    assert "u" not in subcells.point_data
    assert interface.n_cells == cut.geometry.seg.shape[0]
    assert set(interface.cell_data.keys()) == {"cell"}


def test_pngs_are_written_and_not_blank(tmp_path):
    mesh = unit_square(8, "quadrilateral")
    cut = CutMesh(mesh, disc, degree=2)
    assert not_blank(pictures.plot_cut(cut, tmp_path / "cut.png"))
    zoom = pictures.plot_cut(cut, tmp_path / "zoom.png", bounds=(0.1, 0.5, 0.1, 0.5))
    assert not_blank(zoom)
    V = dolfinx.fem.functionspace(mesh, ("Lagrange", 2, (2,)))
    u_minus, u_plus = dolfinx.fem.Function(V), dolfinx.fem.Function(V)
    u_minus.interpolate(lambda x: np.stack([1e-6 * x[0], 0 * x[1]]))
    u_plus.interpolate(lambda x: np.stack([0 * x[0], -1e-6 * x[1] ** 2]))
    grid = pictures.deformed_lips_grid(cut, u_minus, u_plus)
    assert pictures.auto_scale(grid) == pytest.approx(0.1 / 1e-6)
    assert not_blank(pictures.plot_deformed(grid, tmp_path / "deformed.png"))
    theta = -np.pi + (np.arange(50) + 0.5) * 2 * np.pi / 50
    s, label = interface_abscissa(0.5 + 0.2 * np.cos(theta), 0.5 + 0.2 * np.sin(theta))
    assert "angle" in label and np.allclose(s, np.degrees(theta))
    png = plot_pressure(s, -1.5 + 0.5 * np.cos(2 * theta), tmp_path / "p.png", exact=-1.5)
    assert not_blank(png)
    s, label = interface_abscissa(np.linspace(0, 1, 5), np.full(5, 2.0))
    assert "along" in label and np.allclose(np.abs(s), [0.5, 0.25, 0, 0.25, 0.5])


def test_show_renders_a_run_folder(tmp_path, capsys):
    from test_scenes import base

    from xfem_contact.scenes.run import run
    from xfem_contact.scenes.scene import load_scene

    data = base(law="frictionless")
    data["loads"] = [
        {"part": "boundary", "type": "displacement", "value": [0.0, 0.0]},
        {"type": "body_force", "value": [0.0, -1e3], "side": -1},
    ]
    scene = load_scene(data)
    out = tmp_path / "run"
    run(scene, out)  # writes the PNGs itself ([outputs] png = true)
    for name in ("subcells.vtu", "interface.vtu"):
        assert (out / name).exists()
    for name in ("result.png", "cut.png", "pressure.png"):
        assert not_blank(out / name)
        (out / name).unlink()  # show must write them again
    summary = json.loads((out / "summary.json").read_text())
    assert len(summary["interface_samples"]["lambda_n"]) > 0
    assert cli.main(["show", str(out)]) == 0
    printed = capsys.readouterr().out
    for name in ("result.png", "cut.png", "pressure.png"):
        assert f"wrote {out / name}" in printed
        assert not_blank(out / name)

    # Optional files missing: those pictures are skipped with a line saying so
    for path in out.glob("interface*.vtu"):
        path.unlink()
    summary.pop("interface_samples", None)
    (out / "summary.json").write_text(json.dumps(summary))
    assert cli.main(["show", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "skipped cut.png" in printed and "skipped pressure.png" in printed


def test_show_without_results_is_a_clear_error(tmp_path, capsys):
    assert cli.main(["show", str(tmp_path)]) == 2
    assert "no result*.vtu" in capsys.readouterr().err
