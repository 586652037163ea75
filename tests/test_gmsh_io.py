"""gmsh meshes: physical parts, the bundled plate with a hole (triangles/quads,
straight/curved cells), a .msh round trip, the caller's gmsh session, errors."""

import xfem_contact  # noqa: F401  (before dolfinx)

# isort: split
from pathlib import Path

import dolfinx.fem
import gmsh
import numpy as np
import pytest
import ufl
from mpi4py import MPI

from xfem_contact.io.gmsh import facets, physical_parts, read_gmsh

GEO = Path(xfem_contact.__file__).parent / "scenes" / "plate_with_hole.geo"
R = 0.15  # hole radius of the bundled geometry (m)
AREA = 1.0 - np.pi * R**2
PARTS = {"bottom": 1, "right": 2, "top": 3, "left": 4, "hole": 5}


def integrate(gm, measure: str, tag: int | None = None) -> float:
    """Global integral of 1 over the mesh (``dx``) or over the facets tagged ``tag``."""
    mesh = gm.mesh
    if measure == "dx":
        m = ufl.dx(domain=mesh)
    else:
        m = ufl.Measure("ds", domain=mesh, subdomain_data=gm.facet_tags)(tag)
    c = dolfinx.fem.Constant(mesh, 1.0)
    return mesh.comm.allreduce(dolfinx.fem.assemble_scalar(dolfinx.fem.form(c * m)))


def test_physical_parts_of_geo():
    assert physical_parts(GEO) == PARTS
    assert physical_parts(str(GEO)) == PARTS
    assert not gmsh.isInitialized()  # the session opened here was closed


@pytest.mark.parametrize("cell", ["triangle", "quadrilateral"])
def test_plate_with_hole_area_and_hole_length(cell):
    errors = {}
    for degree in (1, 2):
        gm = read_gmsh(GEO, MPI.COMM_WORLD, geometry_degree=degree, cell=cell)
        mesh = gm.mesh
        assert mesh.geometry.dim == 2
        assert mesh.topology.cell_type.name == cell
        assert mesh.geometry.cmaps[0].degree == degree
        assert gm.parts == PARTS
        assert np.all(gm.cell_tags.values == 10)
        assert len(facets(gm, "hole")) > 0
        hole = integrate(gm, "ds", gm.parts["hole"])
        errors[degree] = abs(integrate(gm, "dx") - AREA), abs(hole - 2 * np.pi * R)
        for side in ("left", "right", "bottom", "top"):
            assert integrate(gm, "ds", gm.parts[side]) == pytest.approx(1.0, abs=1e-12)
    (area1, hole1), (area2, hole2) = errors[1], errors[2]
    assert area2 < 1e-5 and hole2 < 1e-4  # curved (order-2) cells follow the circle
    assert area1 > 10 * area2 and hole1 > 10 * hole2
    assert area1 < 1e-2 and hole1 < 1e-2


def test_size_sets_the_cell_size():
    coarse = read_gmsh(GEO, MPI.COMM_WORLD, cell="quadrilateral", size=0.2)
    fine = read_gmsh(GEO, MPI.COMM_WORLD, cell="quadrilateral")  # lc = 0.05 in the .geo
    n = [m.mesh.comm.allreduce(m.mesh.topology.index_map(2).size_local) for m in (coarse, fine)]
    assert 20 < n[0] < n[1] / 5


def test_msh_round_trip(tmp_path):
    msh = tmp_path / "plate.msh"
    gmsh.initialize(interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.merge(str(GEO))
        gmsh.model.mesh.setSize(gmsh.model.getEntities(0), 0.1)
        gmsh.model.mesh.generate(2)
        gmsh.model.mesh.setOrder(2)
        gmsh.write(str(msh))
    finally:
        gmsh.finalize()
    assert physical_parts(msh) == PARTS
    from_msh = read_gmsh(msh, MPI.COMM_SELF)
    from_geo = read_gmsh(GEO, MPI.COMM_SELF, geometry_degree=2, size=0.1)
    assert from_msh.mesh.geometry.cmaps[0].degree == 2
    assert from_msh.parts == PARTS
    assert integrate(from_msh, "dx") == pytest.approx(integrate(from_geo, "dx"), abs=1e-12)
    hole = integrate(from_msh, "ds", from_msh.parts["hole"])
    assert hole == pytest.approx(2 * np.pi * R, abs=1e-3)


def test_caller_gmsh_session_is_kept():
    gmsh.initialize(interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.option.setNumber("Mesh.Algorithm", 5)
        gmsh.model.add("mine")
        gmsh.model.occ.addRectangle(0, 0, 0, 1, 1)
        gmsh.model.occ.synchronize()
        assert physical_parts(GEO) == PARTS
        gm = read_gmsh(GEO, MPI.COMM_SELF, cell="quadrilateral", size=0.2)
        assert gm.mesh.topology.cell_type.name == "quadrilateral"
        assert gmsh.isInitialized()
        assert gmsh.model.getCurrent() == "mine"
        assert gmsh.model.getEntities(2) == [(2, 1)]
        assert gmsh.option.getNumber("Mesh.Algorithm") == 5
        assert gmsh.option.getNumber("Mesh.RecombineAll") == 0
    finally:
        gmsh.finalize()


def test_errors(tmp_path):
    with pytest.raises(FileNotFoundError, match="not found"):
        physical_parts(tmp_path / "missing.geo")
    with pytest.raises(FileNotFoundError, match="not found"):
        read_gmsh(tmp_path / "missing.msh", MPI.COMM_SELF)
    stl = tmp_path / "plate.stl"
    stl.write_text("solid plate\nendsolid plate\n")
    with pytest.raises(ValueError, match=r"\.geo or \.msh"):
        physical_parts(stl)
    with pytest.raises(ValueError, match=r"\.geo or \.msh"):
        read_gmsh(stl, MPI.COMM_SELF)
    no_cells = tmp_path / "no_cells.geo"
    no_cells.write_text(GEO.read_text().replace('Physical Surface("plate", 10) = {1};', ""))
    with pytest.raises(ValueError, match="no 2-D physical group"):
        physical_parts(no_cells)
    with pytest.raises(ValueError, match="no 2-D physical group"):
        read_gmsh(no_cells, MPI.COMM_SELF)
    broken = tmp_path / "broken.geo"
    broken.write_text("Point(1) = {0, 0, 0;\n")
    with pytest.raises(ValueError, match="gmsh cannot read .*syntax error"):
        physical_parts(broken)
    with pytest.raises(ValueError, match="cell must be"):
        read_gmsh(GEO, MPI.COMM_SELF, cell="hexahedron")
    with pytest.raises(ValueError, match="geometry_degree"):
        read_gmsh(GEO, MPI.COMM_SELF, geometry_degree=3)
    gm = read_gmsh(GEO, MPI.COMM_SELF, size=0.2)
    with pytest.raises(ValueError, match="'notch'.*'hole'"):
        facets(gm, "notch")


@pytest.mark.mpi
def test_distributed_area():
    comm = MPI.COMM_WORLD
    gm = read_gmsh(GEO, comm, geometry_degree=2, cell="quadrilateral")
    assert gm.mesh.comm.size == comm.size
    assert gm.parts == PARTS
    assert abs(integrate(gm, "dx") - AREA) < 1e-5
    assert integrate(gm, "ds", gm.parts["hole"]) == pytest.approx(2 * np.pi * R, abs=1e-4)
    # an error found on rank 0 is raised on every rank (no rank left waiting)
    with pytest.raises(FileNotFoundError):
        read_gmsh("missing.geo", comm)


BALL = """SetFactory("OpenCASCADE");
Sphere(1) = {0, 0, 0, 0.5};
Physical Volume("ball", 7) = {1};
Physical Surface("skin", 3) = {1};
"""
BOX = """SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 1, 1, 1};
Physical Volume("box", 1) = {1};
Physical Surface("bottom", 5) = {5};
Physical Surface("top", 6) = {6};
"""
HEXES = """Point(1) = {0, 0, 0}; Point(2) = {1, 0, 0}; Point(3) = {1, 1, 0}; Point(4) = {0, 1, 0};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 1};
Curve Loop(1) = {1, 2, 3, 4}; Plane Surface(1) = {1};
Transfinite Curve{1, 2, 3, 4} = 4; Transfinite Surface{1}; Recombine Surface{1};
out[] = Extrude {0, 0, 1} {Surface{1}; Layers{3}; Recombine;};
Physical Volume("box", 1) = {out[1]};
Physical Surface("bottom", 5) = {1};
Physical Surface("top", 6) = {out[0]};
"""


@pytest.mark.mpi
def test_3d_meshes_with_physical_groups(tmp_path):
    """Volumes with physical groups: a ball (curved 10-node tetrahedra follow the sphere),
    a box of tetrahedra and one of hexahedra, cut by a plane through CutMesh: the tagged
    faces' areas on each side are exact."""
    from xfem_contact import CutMesh, form

    files = {}
    for name, text in (("ball", BALL), ("box", BOX), ("hexes", HEXES)):
        files[name] = tmp_path / f"{name}.geo"
        files[name].write_text(text)
    assert physical_parts(files["ball"]) == {"skin": 3}
    errors = {}
    for degree in (1, 2):
        gm = read_gmsh(files["ball"], MPI.COMM_WORLD, geometry_degree=degree, size=0.25)
        assert gm.mesh.geometry.dim == 3 and gm.mesh.topology.cell_name() == "tetrahedron"
        assert np.all(gm.cell_tags.values == 7)
        errors[degree] = (
            abs(integrate(gm, "dx") - np.pi / 6),
            abs(integrate(gm, "ds", gm.parts["skin"]) - np.pi),
        )
    print(f"ball volume / area errors, h = 0.25: P1 {errors[1]}, P2 {errors[2]}")
    assert errors[2][0] < errors[1][0] / 10 and errors[2][1] < errors[1][1] / 10, errors
    with pytest.raises(ValueError, match=r"cell must be one of \('tetrahedron', 'hexahedron'\)"):
        read_gmsh(files["box"], MPI.COMM_SELF, cell="quadrilateral")
    with pytest.raises(ValueError, match=r"not hexahedrons only \(make the \.geo recombine"):
        read_gmsh(files["box"], MPI.COMM_SELF, cell="hexahedron")
    n, c = np.array([0.3, 0.4, 0.5]), 0.55  # the plane n.x = c cuts bottom and top
    for name, cell in (("box", "tetrahedron"), ("hexes", "hexahedron")):
        gm = read_gmsh(files[name], MPI.COMM_WORLD, cell=cell, size=0.3)
        assert gm.mesh.topology.cell_name() == cell and gm.parts == {"bottom": 5, "top": 6}
        cut = CutMesh(gm.mesh, lambda x: n @ x - c, degree=1)
        for part, z in (("bottom", 0.0), ("top", 1.0)):
            m = c - n[2] * z  # {0.3 x + 0.4 y < m} in the unit square: corner triangles
            corners = [(0, 0, 1), (1, 0, -1), (0, 1, -1), (1, 1, 1)]
            exact = sum(k * max(m - n[0] * i - n[1] * j, 0) ** 2 for i, j, k in corners)
            exact /= 2 * n[0] * n[1]
            tags = gm.facet_tags
            area = form(1.0 * cut.ds(-1, tags, gm.parts[part]))
            area = gm.mesh.comm.allreduce(dolfinx.fem.assemble_scalar(area))
            assert area == pytest.approx(exact, abs=1e-13), (name, part)
