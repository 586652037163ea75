"""Compression of cut-cell rules keeps the moments of degree <= q with positive weights."""

import basix
import dolfinx
import numpy as np
import pytest
import ufl
from mpi4py import MPI

import xfem_contact
from xfem_contact import CutMesh
from xfem_contact.quadrature.compression import compress_rules, num_moments
from xfem_contact.quadrature.cut3d_rules import classify_3d, cut_rules_3d


def monomial_moments(rules, q):
    x, y, z = rules.points.T
    return np.array(
        [
            rules.sums(rules.weights * x**a * y**b * z**c)
            for a in range(q + 1)
            for b in range(q + 1 - a)
            for c in range(q + 1 - a - b)
        ]
    )


def sphere_cuts(cell: str, count: int, seed: int = 3):
    """Rules of ``count`` reference cells (P2 tetrahedra or Q2 hexahedra) cut by random
    spheres, at quadrature degree 6."""
    kind = {"tetrahedron": basix.CellType.tetrahedron, "hexahedron": basix.CellType.hexahedron}
    element = basix.create_element(
        basix.ElementFamily.P, kind[cell], 2, basix.LagrangeVariant.gll_warped
    )
    rng = np.random.default_rng(seed)
    centres, radii = rng.uniform(-0.2, 1.2, (40, 3)), rng.uniform(0.3, 1.0, 40)
    phi = ((element.points[None] - centres[:, None]) ** 2).sum(-1) - radii[:, None] ** 2
    phi = phi[classify_3d(cell, 2, phi) == 0][:count]
    assert phi.shape[0] == count
    return cut_rules_3d(cell, 2, phi, 6)


@pytest.mark.parametrize("cell", ["tetrahedron", "hexahedron"])
@pytest.mark.parametrize("q", [0, 2, 4])
def test_compressed_rules_keep_moments(cell, q):
    """Each rule of more than dim P_q points ends with at most dim P_q, all weights
    positive (no negative one to count), the moments of degree <= q those of the full
    rule to 1e-13 relative."""
    cut = sphere_cuts(cell, 3)
    m = num_moments(3, q)
    for rules in (cut.minus, cut.plus, cut.interface):
        small = compress_rules(rules, q)
        assert (np.diff(small.offsets) <= m).all()
        assert np.diff(rules.offsets).max() > m  # something was removed
        assert np.count_nonzero(small.weights <= 0) == 0
        full, kept = monomial_moments(rules, q), monomial_moments(small, q)
        assert np.abs(kept - full).max() <= 1e-13 * np.abs(full).max()
        if rules.normals is not None:
            assert small.normals.shape == small.points.shape
            assert set(map(tuple, small.normals)) <= set(map(tuple, rules.normals))


def test_each_rule_compressed_alone():
    """A rule's compressed points and weights do not depend on the rules compressed with
    it (bit for bit): what makes 1 process equal 2."""
    rules = sphere_cuts("tetrahedron", 6).plus
    together = compress_rules(rules, 2)
    for row in range(rules.num_rules):
        keep = np.arange(rules.num_rules) == row
        alone = compress_rules(rules.select(keep), 2)
        start, stop = together.offsets[row : row + 2]
        assert np.array_equal(alone.points, together.points[start:stop])
        assert np.array_equal(alone.weights, together.weights[start:stop])


def test_keep():
    """Rules of at most ``keep`` points are left as they are."""
    rules = sphere_cuts("tetrahedron", 3).interface
    counts = np.diff(rules.offsets)
    keep = int(np.sort(counts)[1])  # the two smallest rules stay
    small = compress_rules(rules, 2, keep=keep)
    stays = counts <= keep
    assert np.array_equal(np.diff(small.offsets)[stays], counts[stays])
    assert (np.diff(small.offsets)[~stays] <= num_moments(3, 2)).all()
    with pytest.raises(ValueError, match="keep must be >= num_moments = 10"):
        compress_rules(rules, 2, keep=9)


def test_cutmesh_compressed_forms_equal_full():
    """With compression, the forms of a P2 tetrahedron cut (the default) integrate with at
    most dim P_d points per cut cell where d is the integrand's degree, and assemble what
    the full rules assemble: the P2 vector Laplacian (degree 2) on both sides, a P1 mass
    (degree 2) on the interface and a P2 interface mass (degree 4 > 3: full rules)."""
    mesh = dolfinx.mesh.create_unit_cube(MPI.COMM_SELF, 3, 3, 3, dolfinx.mesh.CellType.tetrahedron)

    def sphere(x):
        return np.sqrt(((x - 0.5) ** 2).sum(axis=0)) - 0.3

    cuts = {c: CutMesh(mesh, sphere, degree=2, compression=c) for c in (True, False)}
    assert CutMesh(mesh, sphere, degree=2).compression
    assert CutMesh(mesh, sphere, degree=1).compression  # affine P1: the planar cut's rules
    P2 = dolfinx.fem.functionspace(mesh, ("Lagrange", 2, (3,)))
    P1 = dolfinx.fem.functionspace(mesh, ("Lagrange", 1))
    u, v = ufl.TrialFunction(P2), ufl.TestFunction(P2)
    p, q = ufl.TrialFunction(P1), ufl.TestFunction(P1)
    matrices = {}
    for c, cut in cuts.items():
        K = ufl.inner(ufl.grad(u), ufl.grad(v))
        forms = [
            K * cut.dx(-1) + K * cut.dx(1),
            p * q * cut.dGamma,
            ufl.inner(u, v) * cut.dGamma,
        ]
        matrices[c] = [dolfinx.fem.assemble_matrix(xfem_contact.form(f)).to_dense() for f in forms]
    for compressed, full in zip(matrices[True], matrices[False], strict=True):
        assert np.abs(compressed - full).max() <= 1e-13 * np.abs(full).max()
    cut, ncut = cuts[True], cuts[True].cut_cells.size
    for sid in (1, 2, 3):  # sides and interface, degree 2: dim P_2 = 10, kept up to 20
        (part,) = [p for p in cut.integration_parts(sid, 2) if p.rules is not None]
        full, small = np.diff(cut.rules[sid].offsets), np.diff(part.rules.offsets)
        assert np.array_equal(small[full <= 20], full[full <= 20])
        assert (small[full > 20] <= 10).all() and (full > 20).any()
    (part,) = cut.integration_parts(3, 4)
    assert part.rules.num_points == cut.rules[3].weights.size
    with pytest.raises(ValueError, match=r"^compression: rules are compressed on triangles"):
        hexes = dolfinx.mesh.create_unit_cube(
            MPI.COMM_SELF, 2, 2, 2, dolfinx.mesh.CellType.hexahedron
        )
        CutMesh(hexes, sphere, degree=2, compression=True)
    assert ncut > 0


def test_bad_degree():
    cut = cut_rules_3d("tetrahedron", 1, np.array([[-1.0, 1.0, 1.0, 1.0]]), 2)
    with pytest.raises(ValueError, match="compression degree"):
        compress_rules(cut.minus, -1)


def test_cutmesh_compression_on_triangles():
    """On request, a 2D cut's rules are compressed too, and assemble what the full ones do:
    a P2 load vector (degree 3 with the coordinate) on both sides and the interface."""
    mesh = dolfinx.mesh.create_unit_square(MPI.COMM_SELF, 6, 6)

    def circle(x):
        return np.hypot(x[0] - 0.5, x[1] - 0.5) - 0.3

    vectors = {}
    for compression in (True, False):
        cut = CutMesh(mesh, circle, degree=2, compression=compression)
        v = ufl.TestFunction(dolfinx.fem.functionspace(mesh, ("Lagrange", 2)))
        x = ufl.SpatialCoordinate(mesh)
        form = (1 + x[0]) * v * (cut.dx(-1) + cut.dx(1)) + x[1] * v * cut.dGamma
        vectors[compression] = dolfinx.fem.assemble_vector(xfem_contact.form(form)).array
        (part,) = [p for p in cut.integration_parts(1, 3) if p.rules is not None]
        full = np.diff(cut.rules[1].offsets)
        assert (np.diff(part.rules.offsets) < full).any() == compression
    assert np.abs(vectors[True] - vectors[False]).max() <= 1e-13 * np.abs(vectors[False]).max()


def test_cutmesh_planar_cut_rules_of_the_integrands_degree():
    """P1 tetrahedra with compression: the exact cut's rules of the integrand's degree,
    fewer points, the same integrals on both sides and on each named interface."""
    mesh = dolfinx.mesh.create_unit_cube(MPI.COMM_SELF, 3, 3, 3, dolfinx.mesh.CellType.tetrahedron)
    planes = {
        "low": lambda x: x[2] - 0.31 - 0.1 * x[0],
        "high": lambda x: 0.72 - x[2] + 0.05 * x[1],
    }
    V = dolfinx.fem.functionspace(mesh, ("Lagrange", 2))
    v = ufl.TestFunction(V)
    x = ufl.SpatialCoordinate(mesh)
    vectors, points = {}, {}
    for compression in (True, False):
        cut = CutMesh(mesh, planes, degree=1, quadrature_degree=6, compression=compression)
        form = (1 + x[0]) * v * (cut.dx(-1) + cut.dx(1)) + sum(
            (k + x[1]) * v * cut.interface_measure(name) for k, name in enumerate(planes)
        )
        vectors[compression] = dolfinx.fem.assemble_vector(xfem_contact.form(form)).array
        points[compression] = [
            p.rules.num_points
            for sid in (1, 2, 10, 11)
            for p in cut.integration_parts(sid, 3)
            if p.rules is not None
        ]
    assert np.abs(vectors[True] - vectors[False]).max() <= 1e-13 * np.abs(vectors[False]).max()
    assert all(a < b for a, b in zip(points[True], points[False], strict=True))
