"""Stress intensity factors by the domain interaction integral (mechanics/fracture) on
exact fields: Williams fields on a mesh whose edges follow the crack (one measure, two
subdomains, duplicated nodes), the lip term on a Griffith crack with loaded faces, and
the same K on 1 and 2 ranks.

Measured (n = 32 squares in two triangles on [-1, 1]^2, exact field as UFL, quadrature
degree 10, rings 2.4h..6.4h to 4.8h..12.8h): K_I, K_II within 4e-11 relative, ring-to-ring
spread below 4e-11, J = G to 2.4e-11; P2 interpolants of the same fields: 3.4e-5 (side
fields on two subdomains and one Function on duplicated nodes agree to 1e-12); loaded
faces with the graded lip rule: 3.8e-11; 2 ranks = serial to 1.3e-15."""

import xfem_contact  # noqa: F401  (before dolfinx)

# isort: split
import math

import basix.ufl
import dolfinx.fem
import dolfinx.mesh
import numpy as np
import pytest
import ufl
from mpi4py import MPI

from xfem_contact.io.meshes import ghosted_partitioner
from xfem_contact.mechanics.fracture import (
    NUMPY,
    UFL,
    GriffithCrack,
    InteractionIntegral,
    Lip,
    Piece,
    WilliamsField,
    effective_modulus,
    graded_facet_measure,
    scaled_rings,
    spread,
    tip_frame,
)
from xfem_contact.mechanics.fracture import interaction as interaction_module
from xfem_contact.mechanics.fracture.williams import to_global_vector
from xfem_contact.mechanics.materials import Material

MATERIAL = Material(210e9, 0.3, "strain")
N = 32
H = 2.0 / N
RINGS = scaled_rings([(2.4, 6.4), (3.4, 9.4), (4.8, 12.8)], H)
DEGREE = 10
ANGLE = 0.3  # the mesh and the crack turned by this angle (rad) about the tip
TIP = np.array([0.1, -0.05])
DIRECTION = np.array([math.cos(ANGLE), math.sin(ANGLE)])
CASES = {"mode I": (1e6, 0.0), "mode II": (0.0, 1e6), "mixed": (1e6, -0.6e6)}


def slit_square(n: int, crack: tuple[float, float], comm=MPI.COMM_WORLD):
    """Triangles on [-1, 1]^2 (n even), turned by ANGLE about the origin and moved to TIP,
    with a crack on the mesh line y = 0 for x in ``crack`` (before the move): the nodes
    strictly inside it are duplicated for the cells below. Cells tagged 1 (above) and 2
    (below); exterior facets on the crack tagged 1 (upper lip) and 2 (lower lip).
    Collective (built on rank 0)."""
    s = np.linspace(-1.0, 1.0, n + 1)
    X, Y = np.meshgrid(s, s, indexing="xy")
    x = np.c_[X.ravel(), Y.ravel()]
    node = np.arange((n + 1) ** 2).reshape(n + 1, n + 1)  # [j, i]
    quads = np.array(
        [
            [node[j, i], node[j, i + 1], node[j + 1, i + 1], node[j + 1, i]]
            for j in range(n)
            for i in range(n)
        ]
    )
    cells = np.r_[quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]]
    on_crack = np.flatnonzero(
        (np.abs(x[:, 1]) < 1e-12) & (x[:, 0] > crack[0] + 1e-12) & (x[:, 0] < crack[1] - 1e-12)
    )
    copies = dict(zip(on_crack, len(x) + np.arange(len(on_crack)), strict=True))
    below = x[cells].mean(axis=1)[:, 1] < 0.0
    cells[below] = np.vectorize(lambda v: copies.get(v, v))(cells[below])
    x = np.r_[x, x[on_crack]]
    c, s_ = math.cos(ANGLE), math.sin(ANGLE)
    x = x @ np.array([[c, s_], [-s_, c]]) + TIP
    if comm.rank != 0:
        x, cells = np.zeros((0, 2)), np.zeros((0, 3), dtype=np.int64)
    element = basix.ufl.element("Lagrange", "triangle", 1, shape=(2,))
    mesh = dolfinx.mesh.create_mesh(
        comm, cells.astype(np.int64), element, x, partitioner=ghosted_partitioner()
    )

    def local_y(p):
        return (p[:, 1] - TIP[1]) * c - (p[:, 0] - TIP[0]) * s_

    tdim = 2
    mesh.topology.create_connectivity(tdim - 1, tdim)
    n_cells = mesh.topology.index_map(tdim).size_local + mesh.topology.index_map(tdim).num_ghosts
    all_cells = np.arange(n_cells, dtype=np.int32)
    centroids = dolfinx.mesh.compute_midpoints(mesh, tdim, all_cells)
    cell_tags = dolfinx.mesh.meshtags(
        mesh, tdim, all_cells, np.where(local_y(centroids) > 0, 1, 2).astype(np.int32)
    )
    facets = dolfinx.mesh.exterior_facet_indices(mesh.topology)
    lips = facets[np.abs(local_y(dolfinx.mesh.compute_midpoints(mesh, tdim - 1, facets))) < 1e-9]
    f2c = mesh.topology.connectivity(tdim - 1, tdim)
    owner = np.array([f2c.links(f)[0] for f in lips], dtype=np.int32)
    lip_side = np.where(local_y(centroids[owner]) > 0, 1, 2).astype(np.int32)
    facet_tags = dolfinx.mesh.meshtags(mesh, tdim - 1, lips, lip_side)
    return mesh, cell_tags, facet_tags


def relative(results, K):
    scale = max(abs(K[0]), abs(K[1]))
    return max(max(abs(r.K_I - K[0]), abs(r.K_II - K[1])) / scale for r in results)


def williams(K, side=0):
    field = WilliamsField(tip_frame(TIP, DIRECTION), *K, MATERIAL.E, MATERIAL.nu, MATERIAL.plane)
    return lambda x, ops=UFL: field.displacement(x, ops, side)


def report(name, results, K):
    G_K = [r.G for r in results]
    print(
        f"\n{name}: K error {relative(results, K):.2e}, spread {spread(results)},"
        f" J/G - 1 {max(abs(r.J / g - 1) for r, g in zip(results, G_K, strict=True)):.2e}"
    )


@pytest.mark.parametrize("case", CASES)
def test_exact_williams_field_gives_K_to_1e8(case):
    K = CASES[case]
    mesh, cells, _ = slit_square(N, (-2.0, 0.0))
    x = ufl.SpatialCoordinate(mesh)
    dx = ufl.Measure("dx", mesh, subdomain_data=cells)
    # the exact field on each side (two subdomains): one measure each
    pieces = [Piece(williams(K, side)(x), dx(tag)) for side, tag in ((1, 1), (-1, 2))]
    integral = InteractionIntegral(
        pieces, MATERIAL, TIP, DIRECTION, RINGS, quadrature_degree=DEGREE
    )
    results = integral.evaluate()
    report(case, results, K)
    assert relative(results, K) < 1e-8
    for r in results:
        assert r.J == pytest.approx(r.G, rel=1e-8)
        assert r.G == pytest.approx(
            (K[0] ** 2 + K[1] ** 2) / effective_modulus(210e9, 0.3, "strain"), rel=1e-8
        )
    assert max(spread(results).values()) < 1e-8


def test_P2_interpolants_on_two_subdomains_and_duplicated_nodes_agree():
    K = CASES["mixed"]
    mesh, cells, _ = slit_square(N, (-2.0, 0.0))
    dx = ufl.Measure("dx", mesh, subdomain_data=cells)
    V = dolfinx.fem.functionspace(mesh, ("Lagrange", 2, (2,)))
    sides, whole = [], dolfinx.fem.Function(V)
    for side, tag in ((1, 1), (-1, 2)):
        u = dolfinx.fem.Function(V)
        u.interpolate(lambda x, s=side: williams(K, s)(x, ops=NUMPY))
        sides.append(Piece(u, dx(tag)))
        whole.interpolate(lambda x, s=side: williams(K, s)(x, ops=NUMPY), cells0=cells.find(tag))
    two = InteractionIntegral(sides, MATERIAL, TIP, DIRECTION, RINGS).evaluate()
    one = InteractionIntegral([Piece(whole, ufl.dx)], MATERIAL, TIP, DIRECTION, RINGS).evaluate()
    report("P2, two subdomains", two, K)
    for a, b in zip(one, two, strict=True):
        assert a.K_I == pytest.approx(b.K_I, rel=1e-12) and a.K_II == pytest.approx(
            b.K_II, rel=1e-12
        )
    assert 1e-9 < relative(two, K) < 1e-3  # interpolation error, not exact


def test_lip_term_on_a_griffith_crack_with_loaded_faces():
    """Pressure p and shear tau on the faces of a crack (-a, a) in an unloaded plate:
    K_I = p sqrt(pi a), K_II = tau sqrt(pi a) at the tip (a, 0), with the lip term;
    without it the K are off by O(1)."""
    a, p, tau = 0.5, 2e6, 0.7e6
    mesh, cells, facets = slit_square(N, (-2 * a, 0.0))  # tips at (-1, 0), (0, 0)
    x = ufl.SpatialCoordinate(mesh)
    center = TIP - a * DIRECTION
    crack = GriffithCrack(
        a, (0.0, p, tau), center=tuple(center), direction=tuple(DIRECTION), far_field=False
    )
    E, nu = MATERIAL.E, MATERIAL.nu
    u = crack.displacement(x, E, nu, ops=UFL)
    K = crack.stress_intensity_factors
    # Gauss rules on the lips converge as 1/degree (the aux gradient is r^-1/2 there): 2.1e-2
    # at degree 10, 6.4e-3 at 40; the graded rule: 1e-10
    ds = graded_facet_measure(ufl.Measure("ds", mesh, subdomain_data=facets))
    t_upper = ufl.as_vector(to_global_vector((tau, p), crack.frame))  # sigma n on the upper face
    lips = [
        Lip(t_upper, crack.displacement(x, E, nu, ops=UFL, side=1), ds(1), 1),
        Lip(-t_upper, crack.displacement(x, E, nu, ops=UFL, side=-1), ds(2), -1),
    ]
    rings = scaled_rings([(2.4, 6.4), (3.4, 7.4)], H)
    loaded = InteractionIntegral(
        [Piece(u, ufl.dx)], MATERIAL, TIP, DIRECTION, rings, lips, quadrature_degree=DEGREE
    )
    results = loaded.evaluate()
    report("loaded faces", results, K)
    assert relative(results, K) < 1e-8
    for r in results:
        assert r.J == pytest.approx(r.G, rel=1e-8)
    free = InteractionIntegral(
        [Piece(u, ufl.dx)], MATERIAL, TIP, DIRECTION, rings, quadrature_degree=DEGREE
    )
    assert relative(free.evaluate(), K) > 0.1


def test_the_check_fails_without_the_W_term(monkeypatch):
    """Guard: the interaction integral with its W term dropped misses K by far."""

    def no_W(grad_a, sigma_a, grad_b, sigma_b, d, grad_q):
        return ufl.dot(grad_b * d, sigma_a * grad_q) + ufl.dot(grad_a * d, sigma_b * grad_q)

    monkeypatch.setattr(interaction_module, "flux", no_W)
    K = CASES["mixed"]
    mesh, _, _ = slit_square(16, (-2.0, 0.0))
    u = williams(K)(ufl.SpatialCoordinate(mesh))
    rings = scaled_rings([(2.4, 6.4)], 2.0 / 16)
    results = InteractionIntegral([Piece(u, ufl.dx)], MATERIAL, TIP, DIRECTION, rings).evaluate()
    assert relative(results, K) > 0.1


def _K_on(comm):
    K = CASES["mixed"]
    mesh, cells, _ = slit_square(N, (-2.0, 0.0), comm)
    V = dolfinx.fem.functionspace(mesh, ("Lagrange", 2, (2,)))
    u = dolfinx.fem.Function(V)  # one field on duplicated nodes, each side's own branch
    for side, tag in ((1, 1), (-1, 2)):
        u.interpolate(lambda x, s=side: williams(K, s)(x, ops=NUMPY), cells0=cells.find(tag))
    results = InteractionIntegral([Piece(u, ufl.dx)], MATERIAL, TIP, DIRECTION, RINGS).evaluate()
    assert relative(results, K) < 1e-4
    return np.array([[r.K_I, r.K_II, r.J] for r in results])


@pytest.mark.mpi
@pytest.mark.parallel
def test_parallel_K_equal_serial():
    """All ranks report the same K, equal to a serial run's to 1e-10."""
    here = _K_on(MPI.COMM_WORLD)
    serial = _K_on(MPI.COMM_SELF)
    gathered = MPI.COMM_WORLD.allgather(here)
    for other in gathered:
        np.testing.assert_array_equal(other, here)
    np.testing.assert_allclose(here, serial, rtol=1e-10)


def test_bad_input_is_refused():
    mesh, _, _ = slit_square(8, (-2.0, 0.0))
    u = williams(CASES["mode I"])(ufl.SpatialCoordinate(mesh))
    h = 2.0 / 8
    with pytest.raises(ValueError, match="r_inf = .* does not cover the cells at the tip"):
        InteractionIntegral([Piece(u, ufl.dx)], MATERIAL, TIP, DIRECTION, [(0.1 * h, 3 * h)])
    with pytest.raises(ValueError, match="reaches the mesh boundary"):
        InteractionIntegral([Piece(u, ufl.dx)], MATERIAL, TIP, DIRECTION, [(2 * h, 1.5)])
    with pytest.raises(ValueError, match="lies in no cell"):
        InteractionIntegral([Piece(u, ufl.dx)], MATERIAL, (5.0, 5.0), DIRECTION, [(2 * h, 3 * h)])
    with pytest.raises(ValueError, match="0 <= r_inf < r_sup"):
        InteractionIntegral([Piece(u, ufl.dx)], MATERIAL, TIP, DIRECTION, [(3 * h, 2 * h)])
    with pytest.raises(ValueError, match="rings must hold"):
        InteractionIntegral([Piece(u, ufl.dx)], MATERIAL, TIP, DIRECTION, [])
    with pytest.raises(ValueError, match="pieces must hold"):
        InteractionIntegral([], MATERIAL, TIP, DIRECTION, [(2 * h, 3 * h)])
    with pytest.raises(ValueError, match="lip's side"):
        lip = Lip(ufl.as_vector([0.0, 0.0]), u, ufl.ds, 0)
        InteractionIntegral([Piece(u, ufl.dx)], MATERIAL, TIP, DIRECTION, [(2 * h, 3 * h)], [lip])
    with pytest.raises(ValueError, match="must be a facet measure"):
        graded_facet_measure(ufl.dx)
    with pytest.raises(ValueError, match="ring shape"):
        scaled_rings([(2, 3)], h, shape="cosine")


def test_moduli_as_constants():
    """A bound Moduli enters as Constants: a new E changes K (u fixed) with no new form."""
    from xfem_contact.fem.forms import compiled_forms
    from xfem_contact.mechanics.materials import Moduli

    K = CASES["mixed"]
    mesh, _, _ = slit_square(16, (-2.0, 0.0))
    moduli = Moduli(MATERIAL, mesh)
    u = williams(K)(ufl.SpatialCoordinate(mesh))
    rings = scaled_rings([(2.4, 6.4)], 2.0 / 16)
    integral = InteractionIntegral(
        [Piece(u, ufl.dx)], moduli, TIP, DIRECTION, rings, quadrature_degree=DEGREE
    )
    assert relative(integral.evaluate(), K) < 1e-8
    forms = compiled_forms()
    moduli.E = 2 * MATERIAL.E
    (doubled,) = integral.evaluate()
    assert compiled_forms() == forms
    assert doubled.K_I == pytest.approx(2 * K[0], rel=1e-8)
    assert doubled.K_II == pytest.approx(2 * K[1], rel=1e-8)
