"""A level set given as a function on P2 tetrahedra: the bound of its distance from the
interpolant, and the rules of its exact zero set where that zero set leaves a thin lens
in boxes on which the interpolant keeps one sign."""

import basix
import numpy as np
import pytest
from cut3d_reference import sphere_area_in_polytope, tet_planes

from xfem_contact.geometry.exact_margin import SAFETY, exact_margin
from xfem_contact.geometry.simplex_bernstein import lattice_to_bernstein
from xfem_contact.quadrature.curved_tet_rules import classify_p2_tets, p2_tet_cut_rules

#: A cell of the Kuhn mesh of n = 32 and the sphere R = 0.3 about a shifted centre (the
#: bench's sphere, centre 2 of 8): the exact sphere crosses the edge of the P2 node with
#: value -1.1e-4 next to it, in a lens that the interpolant's boxes certify as one side.
LENS_CELL = np.array(
    [[0.28125, 0.5, 0.71875], [0.3125, 0.5, 0.71875], [0.3125, 0.5, 0.75], [0.3125, 0.53125, 0.75]]
)
LENS_CENTRE = np.array([0.5189573679927244, 0.52279676753075, 0.5169882809832944])
RADIUS = 0.3


def p2_nodes() -> np.ndarray:
    element = basix.create_element(
        basix.ElementFamily.P, basix.CellType.tetrahedron, 2, basix.LagrangeVariant.gll_warped
    )
    return element.points


def sphere_on(vertices: np.ndarray, centre: np.ndarray):
    """P2 nodal values ``(1, 10)``, the exact level set as ``(rows, X) -> (m,)``, the
    Jacobian ``(3, 3)`` and ``|det J|`` of the sphere's signed distance on one cell."""
    J = (vertices[1:] - vertices[0]).T

    def exact(rows, X):
        return np.linalg.norm(vertices[0] + X @ J.T - centre, axis=1) - RADIUS

    phi = exact(np.zeros(10, int), p2_nodes())[None]
    return phi, exact, J, abs(np.linalg.det(J))


def test_margin_bounds_a_cubic_and_vanishes_for_quadratics():
    """For a cubic level set the interpolation error is the cubic's: its largest value
    on the tetrahedron is within the bound (sampled densely), and the bound is SAFETY
    times the largest Bernstein coefficient, at most 8x the largest value. A quadratic
    has margin 0."""
    rng = np.random.default_rng(3)
    X = rng.dirichlet(np.ones(4), size=20000)[:, 1:]
    for _ in range(5):
        a = rng.normal(size=4)

        def cubic(rows, Y, a=a):
            return (
                a[0] * Y[:, 0] * Y[:, 1] * Y[:, 2]
                + a[1] * Y[:, 0] ** 3
                + a[2] * Y[:, 1] ** 2
                + a[3]
            )

        phi = cubic(np.zeros(10, int), p2_nodes())[None]
        margin = exact_margin(phi, cubic)[0]
        P2 = basix.create_element(
            basix.ElementFamily.P, basix.CellType.tetrahedron, 2, basix.LagrangeVariant.gll_warped
        ).tabulate(0, X)[0, :, :, 0]
        largest = np.abs(cubic(None, X) - P2 @ phi[0]).max()
        assert largest <= margin / SAFETY * (1 + 1e-12)
        assert margin / SAFETY <= 8.0 * largest
    quadratic = lambda rows, Y: Y[:, 0] ** 2 - Y[:, 1] * Y[:, 2] + 0.3  # noqa: E731
    phi = quadratic(np.zeros(10, int), p2_nodes())[None]
    assert exact_margin(phi, quadratic)[0] <= 1e-15


def test_bernstein_coefficients_of_exact_lattice_values_are_exact():
    """The lattice-to-Bernstein matrices are exact rationals rounded once: a constant
    error of 1 (or 7) and the linear error ``x + y`` have Bernstein coefficients at most
    exactly 1 (7, 1), so the margin is exactly SAFETY times that; P2's matrix has the
    entries 1, 2 and -1/2 of ``2 phi_mid - (phi_a + phi_b) / 2``."""
    phi = np.zeros((3, 10))
    for c in (1.0, 7.0):
        margin = exact_margin(phi, lambda rows, X, c=c: np.full(len(rows), c))
        assert (margin == SAFETY * c).all(), margin - SAFETY * c
    margin = exact_margin(phi, lambda rows, X: X[:, 0] + X[:, 1])
    assert (margin == SAFETY).all(), margin - SAFETY
    T = lattice_to_bernstein(2)
    assert set(np.unique(T)) == {-0.5, 0.0, 1.0, 2.0}
    assert (T.sum(axis=1) == 1.0).all()


@pytest.mark.parametrize("frame", ["tetrahedron", "hexahedra"])
@pytest.mark.parametrize("order, tol", [(4, 5e-5), (8, 5e-6)])
def test_a_lens_of_the_exact_zero_set_is_found(frame, order, tol):
    """The area of the exact sphere in the cell, against Gauss-Bonnet; the interpolant's
    boxes alone lose 4e-4 of it in the tetrahedron's frame."""
    phi, exact, J, det = sphere_on(LENS_CELL, LENS_CENTRE)
    assert classify_p2_tets(phi, exact)[0] == 0
    rules = p2_tet_cut_rules(
        phi, order, frame=frame, jacobian=lambda rows, X: np.broadcast_to(J, (len(rows), 3, 3)),
        exact=exact,
    )  # fmt: skip
    area = rules.interface.weights.sum() * det
    reference = sphere_area_in_polytope(LENS_CENTRE, RADIUS, tet_planes(LENS_CELL))
    assert abs(area / reference - 1.0) <= tol
    volume = (rules.minus.weights.sum() + rules.plus.weights.sum()) * det
    assert volume == pytest.approx(det / 6.0, rel=1e-13)


def test_a_cell_certified_by_the_interpolant_alone_is_opened():
    """A sphere (R = 0.2) whose cap of depth 0.05 crosses a face of the unit reference
    tetrahedron, every P2 node outside it: the interpolant's Bernstein coefficients on
    the cell are all positive, the margin's are not, and the rules find the cap (area
    2 pi R d, against Gauss-Bonnet)."""
    cell = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
    inradius, radius, depth = (2.0 - np.sqrt(2.0)) / 2.0, 0.2, 0.05
    centre = np.array([inradius, inradius, -radius + depth])
    J = np.eye(3)

    def exact(rows, X):
        return np.linalg.norm(X - centre, axis=1) - radius

    phi = exact(np.zeros(10, int), p2_nodes())[None]
    assert classify_p2_tets(phi)[0] == 1
    assert classify_p2_tets(phi, exact)[0] == 0
    rules = p2_tet_cut_rules(
        phi, 4, jacobian=lambda rows, X: np.broadcast_to(J, (len(rows), 3, 3)), exact=exact
    )
    reference = sphere_area_in_polytope(centre, radius, tet_planes(cell))
    assert reference == pytest.approx(2.0 * np.pi * radius * depth, rel=1e-12)
    assert rules.interface.weights.sum() == pytest.approx(reference, rel=2e-3)


def test_boxes_whose_raised_rules_still_move_are_subdivided():
    """A cell of the same mesh (centre 13 of 16 of the bench) where the rules of a box
    converge slowly with the points per interval (a branch point of the roots near it):
    its area at order 4 is within 1e-7 of the exact one; with the raised orders alone it
    erred by 7.2e-6."""
    cell = np.array(
        [[0.65625, 0.28125, 0.625], [0.65625, 0.28125, 0.65625], [0.65625, 0.3125, 0.65625]]
        + [[0.6875, 0.3125, 0.65625]]
    )
    centre = np.array([0.5111810998971584, 0.5178603072103051, 0.5100584184711232])
    phi, exact, J, det = sphere_on(cell, centre)
    rules = p2_tet_cut_rules(
        phi, 4, jacobian=lambda rows, X: np.broadcast_to(J, (len(rows), 3, 3)), exact=exact
    )
    reference = sphere_area_in_polytope(centre, RADIUS, tet_planes(cell))
    assert abs(rules.interface.weights.sum() * det / reference - 1.0) <= 1e-7
