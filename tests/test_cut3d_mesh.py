"""CutMesh on tetrahedra and hexahedra: plane cuts of the unit cube exact (side moments,
interface moments, normal, cut boundary faces), a sphere converging, several named
interfaces, updates, 1 rank = 2 ranks, and bad input refused in one line."""

import xfem_contact  # noqa: F401  (before dolfinx)

# isort: split
import basix.ufl
import dolfinx.fem
import dolfinx.mesh
import numpy as np
import pytest
import ufl
from conftest import CELLS_3D
from cut3d_reference import box_edges, box_planes, box_vertices, clip, exponents, simplex_moments
from mpi4py import MPI

from xfem_contact import CutMesh
from xfem_contact.geometry.levelset import InterfaceError

EXPONENTS = exponents(2)
NORMAL = np.array([1.0, 2.0, 2.5]) / np.linalg.norm([1.0, 2.0, 2.5])
OFFSET = 0.47
R = 0.3  # sphere radius (m), centred in the unit cube


def cube(n: int, cell: str, comm=MPI.COMM_WORLD) -> dolfinx.mesh.Mesh:
    return dolfinx.mesh.create_unit_cube(comm, n, n, n, CELLS_3D[cell])


def plane(x: np.ndarray) -> np.ndarray:
    return NORMAL @ x[:3] - OFFSET


def total(mesh, integrand) -> float:
    """Global integral of a form built by :func:`xfem_contact.form`."""
    form = xfem_contact.form(integrand)
    return mesh.comm.allreduce(dolfinx.fem.assemble_scalar(form))


def moments(mesh, measure) -> np.ndarray:
    """``int x^a y^b z^c`` over ``measure`` for :data:`EXPONENTS`, one compiled form: the
    monomials dotted with a Constant that selects one at a time."""
    x = ufl.SpatialCoordinate(mesh)
    pick = dolfinx.fem.Constant(mesh, np.zeros(len(EXPONENTS)))
    monomials = ufl.as_vector([x[0] ** a * x[1] ** b * x[2] ** c for a, b, c in EXPONENTS])
    form = xfem_contact.form(ufl.dot(pick, monomials) * measure)
    out = []
    for k in range(len(EXPONENTS)):
        pick.value[:] = np.eye(len(EXPONENTS))[k]
        out.append(mesh.comm.allreduce(dolfinx.fem.assemble_scalar(form)))
    return np.array(out)


def exact_plane_moments() -> dict[int, np.ndarray]:
    """Moments of both sides and of the section of the unit cube by :func:`plane`
    (independent reference: clipped polytope, closed-form simplex integrals)."""
    lo, hi = (0.0, 0.0, 0.0), (1.0, 1.0, 1.0)
    out = {}
    for side in (-1, 1):
        tets, face = clip(
            box_planes(lo, hi), box_vertices(lo, hi), box_edges(), (NORMAL, -OFFSET), side
        )
        out[side] = simplex_moments(tets, EXPONENTS)
    out[0] = simplex_moments(face, EXPONENTS)
    return out


def square_side_area(u: float, v: float, c: float) -> float:
    """Area of ``{(s, t) in [0, 1]^2 : u s + v t < c}`` for ``u, v > 0`` (inclusion-exclusion
    of the corner triangles)."""
    corners = [(0, 0, 1.0), (1, 0, -1.0), (0, 1, -1.0), (1, 1, 1.0)]
    return sum(sign * max(c - u * s - v * t, 0.0) ** 2 for s, t, sign in corners) / (2 * u * v)


@pytest.mark.mpi
@pytest.mark.parametrize("cell", list(CELLS_3D))
def test_plane_cut_of_the_unit_cube_is_exact(cell):
    mesh = cube(3, cell)
    cut = CutMesh(mesh, plane, degree=1)
    exact = exact_plane_moments()
    for key, measure in ((-1, cut.dx(-1)), (1, cut.dx(1)), (0, cut.dGamma)):
        assert np.abs(moments(mesh, measure) - exact[key]).max() <= 1e-13, key
    n = ufl.as_vector(NORMAL.tolist())
    assert total(mesh, ufl.inner(cut.normal - n, cut.normal - n) * cut.dGamma) <= 1e-26


@pytest.mark.mpi
@pytest.mark.parametrize("cell", list(CELLS_3D))
def test_cut_boundary_faces_are_exact(cell):
    """``cut.ds(side, facets)`` on each face of the cube: the areas of its two sides, as
    the integral of ``FacetNormal . e`` with ``e`` the face's outward normal."""
    mesh = cube(3, cell)
    cut = CutMesh(mesh, plane, degree=1)
    outward = dolfinx.fem.Constant(mesh, np.zeros(3))
    forms = {}
    for axis in range(3):
        u, v = np.delete(NORMAL, axis)
        for value in (0.0, 1.0):
            facets = dolfinx.mesh.locate_entities_boundary(
                mesh, 2, lambda x, a=axis, c=value: np.isclose(x[a], c)
            )
            minus = square_side_area(u, v, OFFSET - NORMAL[axis] * value)
            outward.value[:] = np.eye(3)[axis] * (1.0 if value else -1.0)
            for side, exact in ((-1, minus), (1, 1.0 - minus)):
                measure = cut.ds(side, facets)
                key = (side, measure.subdomain_id())
                integrand = ufl.dot(ufl.FacetNormal(mesh), outward)
                forms.setdefault(key, xfem_contact.form(integrand * measure))
                area = mesh.comm.allreduce(dolfinx.fem.assemble_scalar(forms[key]))
                assert abs(area - exact) <= 1e-13, (axis, value, side, area, exact)


@pytest.mark.parametrize("cell", list(CELLS_3D))
def test_sphere_from_a_degree_2_function_converges(cell):
    """A P2/Q2 level-set Function of the sphere: volume and area errors small and falling."""
    errors = []
    for n in (4, 8):
        mesh = cube(n, cell)
        phi = dolfinx.fem.Function(dolfinx.fem.functionspace(mesh, ("Lagrange", 2)))
        phi.interpolate(lambda x: np.sqrt(((x - 0.5) ** 2).sum(axis=0)) - R)
        cut = CutMesh(mesh, phi, degree=2)
        volume = total(mesh, 1.0 * cut.dx(-1))
        area = total(mesh, 1.0 * cut.dGamma)
        errors.append(
            (abs(volume / (4 / 3 * np.pi * R**3) - 1), abs(area / (4 * np.pi * R**2) - 1))
        )
    (v4, a4), (v8, a8) = errors
    assert v8 < 5e-4 and a8 < 5e-4, errors
    assert v8 < v4 / 2.5 and a8 < a4 / 2.5, errors


@pytest.mark.mpi
def test_named_interfaces_and_update():
    """Two planes as named interfaces: each one's area, both sides' volumes; an update
    moves them and the same compiled forms integrate on the new cut."""
    mesh = cube(5, "tetrahedron")

    def planes(low, high):
        return {"low": lambda x: x[2] - low, "high": lambda x: high - x[2]}

    cut = CutMesh(mesh, planes(0.3, 0.7), degree=1)
    assert cut.interface_names == ("low", "high")
    one = dolfinx.fem.Constant(mesh, 1.0)
    forms = {
        "minus": one * cut.dx(-1),
        "low": one * cut.interface_measure("low"),
        "high": one * cut.interface_measure("high"),
    }
    assert total(mesh, forms["minus"]) == pytest.approx(0.6, abs=1e-13)
    assert total(mesh, forms["low"]) == pytest.approx(1.0, abs=1e-13)
    assert total(mesh, forms["high"]) == pytest.approx(1.0, abs=1e-13)
    first = cut.state
    assert cut.update(planes(0.25, 0.9)) is cut.state and cut.revision == 1
    assert first.revision == 0 and first.cut_cells.size > 0
    assert total(mesh, forms["minus"]) == pytest.approx(0.35, abs=1e-13)
    assert total(mesh, forms["low"]) == pytest.approx(1.0, abs=1e-13)


@pytest.mark.mpi
@pytest.mark.parallel
@pytest.mark.parametrize("cell", list(CELLS_3D))
@pytest.mark.parametrize("degree, exact", [(1, None), (2, None), (2, True)])
def test_one_rank_equals_two(cell, degree, exact):
    """Volumes, areas and an assembled vector (gathered, sorted by dof position) of a
    sphere cut by a P1/Q1 or P2/Q2 level set (also on its exact zero set) agree on all
    ranks and on one to 1e-13 (on tetrahedra with the default compressed rules)."""
    results = {}
    for comm in (MPI.COMM_WORLD, MPI.COMM_SELF):
        mesh = cube(4, cell, comm)
        sphere = lambda x: np.sqrt(((x - 0.5) ** 2).sum(axis=0)) - R  # noqa: E731
        cut = CutMesh(mesh, sphere, degree=degree, exact_zero_set=exact)
        V = dolfinx.fem.functionspace(mesh, ("Lagrange", 2))
        v = ufl.TestFunction(V)
        x = ufl.SpatialCoordinate(mesh)
        b = dolfinx.fem.assemble_vector(
            xfem_contact.form((1 + x[0]) * v * cut.dx(-1) + x[1] * v * cut.dGamma + v * cut.dx(1))
        )
        b.scatter_reverse(dolfinx.la.InsertMode.add)
        owned = V.dofmap.index_map.size_local
        points = np.concatenate(comm.allgather(V.tabulate_dof_coordinates()[:owned]))
        values = np.concatenate(comm.allgather(b.array[:owned]))
        order = np.lexsort(np.round(points, 10).T[::-1])
        results[comm.size] = (
            total(mesh, 1.0 * cut.dx(-1)),
            total(mesh, 1.0 * cut.dx(1)),
            total(mesh, 1.0 * cut.dGamma),
            values[order],
        )
    many, one = results[MPI.COMM_WORLD.size], results[1]
    for a, b in zip(many[:3], one[:3], strict=True):
        assert abs(a - b) <= 1e-13 * abs(b)
    assert np.abs(many[3] - one[3]).max() <= 1e-13 * np.abs(one[3]).max()


def mixed_mesh() -> dolfinx.mesh.Mesh:
    """A hexahedron with a prism on top (serial, one process's cells)."""
    x = np.array(
        [[i, j, k] for k in (0, 1) for j in (0, 1) for i in (0, 1)]
        + [[0, 0, 2], [1, 0, 2], [0, 1, 2]],
        dtype=np.float64,
    )
    cells = [np.arange(8, dtype=np.int64), np.array([4, 5, 6, 8, 9, 10], dtype=np.int64)]
    kinds = [dolfinx.mesh.CellType.hexahedron, dolfinx.mesh.CellType.prism]
    elements = [dolfinx.fem.coordinate_element(k, 1)._cpp_object for k in kinds]
    partitioner = dolfinx.cpp.mesh.create_cell_partitioner(dolfinx.mesh.GhostMode.none, 2)
    cpp = dolfinx.cpp.mesh.create_mesh(MPI.COMM_SELF, cells, elements, x, partitioner, 2)
    return dolfinx.mesh.Mesh(cpp, None)


def pyramid_mesh() -> dolfinx.mesh.Mesh:
    element = ufl.Mesh(basix.ufl.element("Lagrange", "pyramid", 1, shape=(3,)))
    x = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0], [0, 0, 1]], dtype=np.float64)
    return dolfinx.mesh.create_mesh(MPI.COMM_SELF, np.array([[0, 1, 2, 3, 4]]), element, x)


def test_bad_input_is_refused_in_one_line():
    prisms = dolfinx.mesh.create_box(
        MPI.COMM_SELF, [[0, 0, 0], [1, 1, 1]], [2, 2, 2], dolfinx.mesh.CellType.prism
    )
    cases = [
        (prisms, plane, r"^mesh: cells of kind 'prism' cannot be cut; valid: \["),
        (pyramid_mesh(), plane, r"^mesh: cells of kind 'pyramid' cannot be cut"),
        (mixed_mesh(), plane, r"^mesh: a mixed-topology mesh \(hexahedron \+ prism\)"),
        (cube(2, "tetrahedron"), lambda x: x - 0.5, r"one value per point.*3D mesh.*shape \(3, "),
        (
            cube(2, "hexahedron"),
            lambda x: ((x - np.array([[0.5], [0.5]])) ** 2).sum(axis=0) - 0.1,
            r"failed on points x of shape \(3, \d+\) \(a 3D mesh: x\[0\], x\[1\], x\[2\]",
        ),
        (
            cube(2, "tetrahedron"),
            lambda x: np.where(x[0] > 0.9, np.nan, x[2] - 0.3),
            r"NaN or inf at 9 node\(s\), e.g. at x = \(1, 0, 0\): give one",
        ),
    ]
    for mesh, levelset, message in cases:
        with pytest.raises(ValueError, match=message) as error:
            CutMesh(mesh, levelset, degree=1)
        assert "\n" not in str(error.value)

    def cone(x):  # apex at (0.3, 0.3, 0.3): a singular point of the zero set
        return ((x - 0.3) ** 2 * np.array([[1.0], [1.0], [-1.0]])).sum(axis=0)

    for cell, where in (
        ("hexahedron", r"\(0\.25, 0\.25, 0\.25\) \(local cell \d+\)"),
        ("tetrahedron", r"\(.*\) \(local cell \d+\)"),
    ):
        with pytest.raises(ValueError, match=f"^{cell} at {where}: the level set has a singular"):
            CutMesh(cube(2, cell, MPI.COMM_SELF), cone, degree=2)
    mesh = cube(2, "tetrahedron")
    with pytest.raises(ValueError, match="^tangent: cracks are cut on triangle") as error:
        CutMesh(mesh, plane, tangent=plane)
    vector = dolfinx.fem.Function(dolfinx.fem.functionspace(mesh, ("Lagrange", 1, (3,))))
    with pytest.raises(InterfaceError, match=r"levelset: a Function of value shape \(3,\) is"):
        CutMesh(mesh, vector)
    other = dolfinx.fem.Function(dolfinx.fem.functionspace(cube(2, "hexahedron"), ("P", 2)))
    with pytest.raises(InterfaceError, match="levelset: the Function lives on another mesh"):
        CutMesh(mesh, other)


def test_a_bad_callable_is_refused_in_one_line():
    """2D callables on a 3D mesh where they can be told (one that reads x[0], x[1] only is
    a cylinder, a valid 3D level set), and a callable that is finite at the nodes but not
    at the points of a cut cell where the rules evaluate it."""
    mesh = cube(2, "tetrahedron")
    hint = r"failed on points x of shape \(3, \d+\) \(a 3D mesh: x\[0\], x\[1\], x\[2\]"
    cases = [
        (lambda x: np.hypot(*x) - 0.5, hint + r".*read-only\): output array is read-only"),
        (lambda x: (lambda a, b: a + b - 1.0)(*x), hint),
        (lambda x: x.T @ np.array([1.0, 1.0]) - 1.0, hint),
        (lambda x: x[2:] - 0.3, r"one value per point, shape \(\d+,\) .*returned shape \(1, "),
    ]
    for levelset, message in cases:
        with pytest.raises(ValueError, match=message) as error:
            CutMesh(mesh, levelset, degree=2)
        assert "\n" not in str(error.value)

    def holes(x):  # finite on the grid of spacing 1/8 (the P2 nodes of cube(4)), NaN between
        on_grid = np.abs(8 * x[0] - np.round(8 * x[0])) < 1e-9
        return np.where(on_grid, x[2] - 0.3, np.nan)

    for cell in CELLS_3D:
        with pytest.raises(ValueError, match=r"NaN or inf at x = \(.*\), a point of a cut cell"):
            CutMesh(cube(4, cell), holes, degree=2, exact_zero_set=True)
    with pytest.raises(ValueError, match=r"^exact_zero_set: a P1/Q1 cut in 3D follows"):
        CutMesh(mesh, plane, degree=1, exact_zero_set=True)
    phi = dolfinx.fem.Function(dolfinx.fem.functionspace(mesh, ("Lagrange", 2)))
    phi.interpolate(plane)
    with pytest.raises(ValueError, match=r"^exact_zero_set=True: the level set is a Function"):
        CutMesh(mesh, phi, degree=2, exact_zero_set=True)


@pytest.mark.parametrize("cell", list(CELLS_3D))
def test_a_callable_level_set_is_cut_on_its_exact_zero_set(cell):
    """The sphere as a callable and as its P2/Q2 interpolant (the same cells, boxes and
    axes): by default the callable is cut as its interpolant; with ``exact_zero_set``,
    Saye's rules follow the exact sphere, and the volume and area errors fall well below
    the interpolant's."""
    mesh = cube(8, cell)
    sphere = lambda x: np.sqrt(((x - 0.5) ** 2).sum(axis=0)) - R  # noqa: E731
    phi = dolfinx.fem.Function(dolfinx.fem.functionspace(mesh, ("Lagrange", 2)))
    phi.interpolate(sphere)
    errors = {}
    for name, levelset, exact in (
        ("function", phi, None),
        ("callable", sphere, None),
        ("exact", sphere, True),
    ):
        cut = CutMesh(mesh, levelset, degree=2, exact_zero_set=exact)
        volume = total(mesh, 1.0 * cut.dx(-1))
        area = total(mesh, 1.0 * cut.dGamma)
        errors[name] = np.array(
            [volume / (4 / 3 * np.pi * R**3) - 1, area / (4 * np.pi * R**2) - 1]
        )
    print(errors)
    np.testing.assert_allclose(errors["callable"], errors["function"], rtol=1e-9)
    assert (np.abs(errors["exact"]) <= np.abs(errors["function"]) / 4).all(), errors
    assert (np.abs(errors["exact"]) <= 2e-5).all(), errors


def test_level_set_dof_points_do_not_depend_on_the_cell():
    """A level-set dof point gets the same bits from every cell that holds it, whatever
    the cell's vertex order (else 1 and 2 ranks break the ties of Saye's choice of axes
    differently)."""
    from xfem_contact.geometry.levelset import canonical_dof_points

    for cell in CELLS_3D:
        mesh = cube(3, cell, MPI.COMM_SELF)
        mesh.geometry.x[:] = mesh.geometry.x * np.array([0.3, 0.7, 1.1]) + 0.1  # inexact sums
        V = dolfinx.fem.functionspace(mesh, ("Lagrange", 2))
        points = canonical_dof_points(mesh, V)
        by_dof = np.zeros((V.dofmap.index_map.size_local, 3))
        by_dof[V.dofmap.list] = points
        assert np.array_equal(by_dof[V.dofmap.list], points), cell  # the same bits in all cells


def test_picture_of_a_3d_cut(tmp_path):
    """plot_cut_3d writes a PNG that shows side -1, side +1 and the interface."""
    import pyvista

    from xfem_contact.io.cut3d_pictures import INTERFACE_COLOUR, plot_cut_3d
    from xfem_contact.io.pictures import SIDE_COLOURS

    mesh = cube(4, "hexahedron", MPI.COMM_SELF)
    cut = CutMesh(mesh, lambda x: np.sqrt(((x - 0.5) ** 2).sum(axis=0)) - R, degree=2)
    path = plot_cut_3d(cut, tmp_path / "cut.png", window_size=(400, 300))
    png = pyvista.read(str(path))
    image = png.point_data[png.point_data.keys()[0]][:, :3].astype(float)
    for colour in (INTERFACE_COLOUR, SIDE_COLOURS[-1][1]):
        rgb = np.array(pyvista.Color(colour).int_rgb, dtype=float)
        near = np.linalg.norm(image - rgb, axis=1) < 60  # shaded, not the exact colour
        # the interface: 0.475 % of the pixels, in part under the rule points drawn on it
        assert near.mean() > 0.003, colour


@pytest.mark.mpi
def test_a_refusal_on_one_process_is_raised_on_all():
    """The cone's apex lies in one cell, owned by one process: all raise, none waits."""

    def cone(x):
        return ((x - 0.3) ** 2 * np.array([[1.0], [1.0], [-1.0]])).sum(axis=0)

    with pytest.raises(ValueError, match=r"^hexahedron at \(0\.375, 0\.375, 0\.375\)"):
        CutMesh(cube(4, "hexahedron"), cone, degree=2)


@pytest.mark.parametrize("cell", list(CELLS_3D))
def test_cut_boundary_faces_of_a_curved_interface(cell):
    """A sphere centred on the face z = 0 (P2/Q2 level set): the face's side -1 is a disc
    (the 2D cutter on the face's restricted level set), and the two sides make the face."""
    mesh = cube(8, cell)
    cut = CutMesh(mesh, lambda x: np.sqrt((x[0] - 0.5) ** 2 + (x[1] - 0.5) ** 2 + x[2] ** 2) - R)
    facets = dolfinx.mesh.locate_entities_boundary(mesh, 2, lambda x: np.isclose(x[2], 0.0))
    disc, rest = (total(mesh, 1.0 * cut.ds(side, facets)) for side in (-1, 1))
    assert abs(disc / (np.pi * R**2) - 1) < 5e-4
    assert abs(disc + rest - 1) < 1e-14
