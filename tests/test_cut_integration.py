"""Cut-cell integration through UFL forms against exact geometry."""

import dolfinx.fem
import dolfinx.mesh
import numpy as np
import pytest
import ufl
from conftest import unit_square
from dolfinx.fem import assemble_scalar
from mpi4py import MPI

import xfem_contact
from xfem_contact.io.meshes import curved_square
from xfem_contact.quadrature import moment_fitting

CENTRE, RADIUS = np.array([0.51, 0.47]), 0.3


def distance(x):
    """Signed distance to the circle (not a polynomial)."""
    return np.hypot(x[0] - CENTRE[0], x[1] - CENTRE[1]) - RADIUS


def integrate(expr_measure):
    form = xfem_contact.form(expr_measure)
    return form.mesh.comm.allreduce(assemble_scalar(form), op=MPI.SUM)


def one(mesh):
    return dolfinx.fem.Constant(mesh, 1.0)


def disc_errors(cell, distorted, degree, as_function, sizes):
    errors = []
    for n in sizes:
        mesh = unit_square(n, cell, distorted)
        levelset = distance
        if as_function:
            levelset = dolfinx.fem.Function(dolfinx.fem.functionspace(mesh, ("Lagrange", degree)))
            levelset.interpolate(distance)
        cut = xfem_contact.CutMesh(mesh, levelset, degree=degree)
        c = one(mesh)
        inside, outside = integrate(c * cut.dx(-1)), integrate(c * cut.dx(1))
        length = integrate(c * cut.dGamma)
        assert abs(inside + outside - 1.0) < 1e-12
        errors.append((abs(inside - np.pi * RADIUS**2), abs(length - 2 * np.pi * RADIUS)))
    return np.array(errors)


def rate(sizes, errors):
    """Least-squares slope of log(error) against log(h)."""
    return -np.polyfit(np.log(sizes), np.log(errors), 1)[0]


SIZES = [8, 16, 32, 64, 128, 256]


@pytest.mark.parametrize(
    "degree, as_function, min_rate",
    [(1, False, 1.9), (2, False, 3.5), (2, True, 2.8)],
    ids=["degree1", "degree2-callable", "degree2-function"],
)
@pytest.mark.parametrize(
    "cell, distorted",
    [("quadrilateral", False), ("quadrilateral", True), ("triangle", False)],
    ids=["quad", "distorted-quad", "triangle"],
)
def test_disc_area_and_circle_length_rates(cell, distorted, degree, as_function, min_rate):
    errors = disc_errors(cell, distorted, degree, as_function, SIZES)
    area_rate, length_rate = rate(SIZES, errors[:, 0]), rate(SIZES, errors[:, 1])
    print(f"\n{cell} distorted={distorted} degree={degree} function={as_function}")
    for n, (ea, el) in zip(SIZES, errors, strict=False):
        print(f"  N={n:4d}  area error {ea:.3e}  length error {el:.3e}")
    print(f"  rates: area {area_rate:.2f}, length {length_rate:.2f} (required {min_rate})")
    assert area_rate >= min_rate
    assert length_rate >= min_rate


@pytest.mark.mpi
@pytest.mark.parametrize("degree", [1, 2])
def test_straight_interface_exact(cell, degree):
    """A straight interface: areas, a polynomial integral and the length exact."""
    mesh = unit_square(5, cell, distorted=False)
    a, b, c0 = 0.3, 1.0, -0.61  # phi = a x + b y + c0: the line y = 0.61 - 0.3 x
    cut = xfem_contact.CutMesh(mesh, lambda x: a * x[0] + b * x[1] + c0, degree=degree)
    x = ufl.SpatialCoordinate(mesh)
    c = one(mesh)
    below = integrate(c * cut.dx(-1))
    assert below == pytest.approx(0.61 - 0.15, abs=1e-13)
    assert integrate(c * cut.dGamma) == pytest.approx(np.hypot(1.0, a), abs=1e-13)
    # int_{below} x^2 y dx dy with y < 0.61 - 0.3 x
    exact = sum(
        k * v for k, v in [(0.61**2 / 2 / 3, 1), (-2 * 0.61 * 0.3 / 2 / 4, 1), (0.09 / 2 / 5, 1)]
    )
    assert integrate(x[0] ** 2 * x[1] * cut.dx(-1)) == pytest.approx(exact, abs=1e-13)
    n = cut.normal
    # The normal points from side -1 to side +1: (a, b)/|(a, b)|
    nx = integrate(n[0] * cut.dGamma) / np.hypot(1.0, a)
    assert nx == pytest.approx(a / np.hypot(a, b), abs=1e-13)


@pytest.mark.parametrize("degree", [1, 2])
def test_runtime_rules_match_moment_fitting(cell, degree):
    """Runtime rules equal the moment-fitting oracle for polynomials on affine cells."""
    mesh = unit_square(6, cell, distorted=False)
    cut = xfem_contact.CutMesh(mesh, distance, degree=degree, quadrature_degree=8)
    x = ufl.SpatialCoordinate(mesh)
    integrand = 1 + x[0] ** 3 - 2 * x[0] * x[1] ** 2 + x[1] ** 4
    for side in (-1, 1):
        rules = cut.side_rules(side)
        weight, measure = moment_fitting.measure_and_weight(mesh, cut.cut_cells, rules, 4)
        oracle = mesh.comm.allreduce(
            assemble_scalar(dolfinx.fem.form(integrand * weight * measure)), op=MPI.SUM
        )
        runtime_only = xfem_contact.CellRules(
            mesh, cut.cut_cells, rules.points, rules.weights, rules.offsets
        )
        runtime = integrate(integrand * runtime_only.measure())
        assert runtime == pytest.approx(oracle, abs=1e-12)


@pytest.mark.mpi
@pytest.mark.parametrize("degree", [1, 2])
def test_boundary_pieces_exact(cell, degree):
    """cut.ds(side, facets): the parts of cut boundary facets, exact lengths and facet normal."""
    mesh = unit_square(5, cell, distorted=False)
    cut = xfem_contact.CutMesh(mesh, lambda x: 0.3 * x[0] + x[1] - 0.61, degree=degree)
    fdim = mesh.topology.dim - 1
    left = dolfinx.mesh.locate_entities_boundary(mesh, fdim, lambda x: np.isclose(x[0], 0.0))
    right = dolfinx.mesh.locate_entities_boundary(mesh, fdim, lambda x: np.isclose(x[0], 1.0))
    c = one(mesh)
    n = ufl.FacetNormal(mesh)
    x = ufl.SpatialCoordinate(mesh)
    assert integrate(c * cut.ds(-1, left)) == pytest.approx(0.61, abs=1e-13)
    assert integrate(c * cut.ds(1, left)) == pytest.approx(0.39, abs=1e-13)
    assert integrate(n[0] * cut.ds(-1, right)) == pytest.approx(0.31, abs=1e-13)
    assert integrate(x[1] * cut.ds(1, right)) == pytest.approx((1 - 0.31**2) / 2, abs=1e-13)
    tags = dolfinx.mesh.meshtags(mesh, fdim, np.sort(left), np.full(left.size, 7, np.int32))
    assert integrate(c * cut.ds(1, tags, 7)) == pytest.approx(0.39, abs=1e-13)
    with pytest.raises(ValueError, match="No facet carries"):
        cut.ds(1, tags, 8)
    # Runtime rules only for the reference facets some cut cell has on the set (the
    # line crosses the left and the right side: one facet each), on any process
    bottom = dolfinx.mesh.locate_entities_boundary(mesh, fdim, lambda x: np.isclose(x[1], 0.0))
    for facets, count in ((left, 1), (bottom, 0)):
        compiled = xfem_contact.form(c * cut.ds(1, facets))
        assert len(compiled._xfem_rules) == count


@pytest.mark.mpi
def test_boundary_measure_ids_agree_across_processes():
    """cut.ds of parts that only rank 0 owns (empty elsewhere): the measure ids, so the
    form signatures, agree on every process (the compile is collective: different forms
    deadlock it), a part given again gets its id again, and the integrals are DOLFINx's
    own over the same facets (sides -1 and +1 together: cut facets included)."""
    mesh = unit_square(6, "triangle")
    comm, fdim = mesh.comm, mesh.topology.dim - 1
    cut = xfem_contact.CutMesh(mesh, lambda x: 0.3 * x[0] + x[1] - 0.61)
    mesh.topology.create_connectivity(fdim, fdim + 1)
    exterior = dolfinx.mesh.exterior_facet_indices(mesh.topology)
    exterior = exterior[exterior < mesh.topology.index_map(fdim).size_local]
    if comm.rank > 0:
        exterior = exterior[:0]
    first, second = exterior[::2], exterior[1::2]
    assert comm.allreduce(second.size, op=MPI.SUM) > 0  # both parts exist (on rank 0)
    measures = [cut.ds(1, first), cut.ds(1, second), cut.ds(1, first.copy()), cut.ds(-1, first)]
    ids = [m.subdomain_id() for m in measures]
    assert comm.allgather(ids) == [ids] * comm.size
    assert len({ids[0], ids[1], ids[3]}) == 3 and ids[2] == ids[0]

    x = ufl.SpatialCoordinate(mesh)
    tagged = np.r_[first, second]
    order = np.argsort(tagged)
    values = np.r_[np.full(first.size, 1), np.full(second.size, 2)].astype(np.int32)[order]
    tags = dolfinx.mesh.meshtags(mesh, fdim, tagged[order], values)
    ds = ufl.ds(domain=mesh, subdomain_data=tags)
    g = 1 + x[0] ** 2 + x[1]
    for tag, facets in ((1, first), (2, second)):
        reference = comm.allreduce(assemble_scalar(dolfinx.fem.form(g * ds(tag))), op=MPI.SUM)
        both = integrate(g * cut.ds(-1, facets) + g * cut.ds(1, facets))
        assert both == pytest.approx(reference, rel=1e-13)


def test_update_reuses_compiled_forms():
    """A moved interface: new rules, same compiled kernels."""
    from xfem_contact.fem import forms

    mesh = unit_square(8, "quadrilateral")
    cut = xfem_contact.CutMesh(mesh, lambda x: np.hypot(x[0] - 0.5, x[1] - 0.5) - 0.2)
    c = one(mesh)
    area = integrate(c * cut.dx(-1))
    compiled = forms.compiled_forms()
    cut.update(lambda x: np.hypot(x[0] - 0.45, x[1] - 0.5) - 0.3)
    moved = integrate(c * cut.dx(-1))
    assert forms.compiled_forms() == compiled
    assert area == pytest.approx(np.pi * 0.04, rel=1e-3)
    assert moved == pytest.approx(np.pi * 0.09, rel=1e-3)


def test_bad_level_sets_raise():
    mesh = unit_square(4, "triangle")
    with pytest.raises(ValueError, match="never crosses"):
        xfem_contact.CutMesh(mesh, lambda x: 1.0 + x[0])
    with pytest.raises(ValueError, match="NaN"):
        xfem_contact.CutMesh(mesh, lambda x: np.where(x[0] > 0.5, np.nan, x[0] - 0.3))
    with pytest.raises(ValueError, match="degree"):
        xfem_contact.CutMesh(mesh, lambda x: x[0] - 0.3, degree=3)


def test_curved_q2_cells_disc_area():
    """Curved 9-node parent cells: disc area and circle length converge at high order."""
    sizes = [8, 16, 32, 64]
    errors = []
    for n in sizes:
        mesh = curved_square(MPI.COMM_WORLD, n)
        cut = xfem_contact.CutMesh(mesh, distance, degree=2)
        c = one(mesh)
        assert integrate(c * cut.dx(-1)) + integrate(c * cut.dx(1)) == pytest.approx(
            integrate(c * ufl.dx(domain=mesh)), abs=1e-12
        )
        errors.append(
            (
                abs(integrate(c * cut.dx(-1)) - np.pi * RADIUS**2),
                abs(integrate(c * cut.dGamma) - 2 * np.pi * RADIUS),
            )
        )
    errors = np.array(errors)
    print("\ncurved Q2 cells: area/length errors", errors.tolist())
    assert rate(sizes, errors[:, 0]) >= 3.5
    assert rate(sizes, errors[:, 1]) >= 3.5


@pytest.mark.mpi
@pytest.mark.parallel
def test_parallel_equals_serial_integrals():
    """Disc area, circle length and a polynomial moment: this communicator vs each
    process alone, to 1e-12."""
    values = []
    for comm in (MPI.COMM_WORLD, MPI.COMM_SELF):
        mesh = dolfinx.mesh.create_unit_square(comm, 16, 16, dolfinx.mesh.CellType.quadrilateral)
        cut = xfem_contact.CutMesh(mesh, distance, degree=2)
        x = ufl.SpatialCoordinate(mesh)
        c = one(mesh)
        values.append(
            [
                integrate(c * cut.dx(-1)),
                integrate(c * cut.dGamma),
                integrate(x[0] * x[1] ** 2 * cut.dx(1)),
            ]
        )
    assert np.allclose(values[0], values[1], rtol=0, atol=1e-12)


@pytest.mark.parametrize(
    "levelset, message",
    [
        (lambda x: 1.0, r"Interface 'interface': the level set must return one value per point"),
        (lambda x: np.array([x[0], x[1]]), r"returned shape \(2, "),
        (lambda x: x[0] + 2.0, r"Interface 'interface': The interface does not cross the mesh"),
        (lambda x: np.full(x.shape[1], np.nan), r"Interface 'interface': .*NaN"),
        ({"a": lambda x: x[0] - 0.5, "b": lambda x: x[0] + 3.0}, "Interface 'b': .*never crosses"),
    ],
)
def test_a_bad_level_set_is_refused_naming_its_interface(levelset, message):
    mesh = dolfinx.mesh.create_unit_square(MPI.COMM_WORLD, 4, 4)
    with pytest.raises(ValueError, match=message):
        xfem_contact.CutMesh(mesh, levelset)
