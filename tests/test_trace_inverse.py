"""The trace length of a cut cell's side (:mod:`xfem_contact.fem.trace_inverse`) against
exact constants: ``|T_s| / |Gamma_T|`` for constant strains (P1 displacements), and the
sharp trace inverse constant of linear polynomials on a triangle's edge (Warburton and
Hesthaven 2003: ``int_F p^2 <= (k + 1)(k + d) / d |F| / |T| int_T p^2``, equality for
some ``p``; ``k = 1``, ``d = 2``: 3) for P2 displacements, on a corner cut that leaves a
small triangle similar to the cell."""

import xfem_contact  # noqa: F401  (before dolfinx)

# isort: split
import dolfinx.mesh
import numpy as np
import pytest
from mpi4py import MPI

from xfem_contact.fem.cutmesh import CutMesh
from xfem_contact.fem.trace_inverse import (
    patch_trace_lengths,
    side_trace_lengths,
    strain_exponents,
)

#: The corner cut: the line x + y = T through the cell (0, 0), (1, 0), (0, 1) of a
#: 1 x 1 mesh of two right triangles (the other cell is not cut)
T = 0.05


def corner_cut(cell: str = "triangle") -> CutMesh:
    mesh = dolfinx.mesh.create_unit_square(
        MPI.COMM_SELF, 1, 1, dolfinx.mesh.CellType[cell], diagonal=dolfinx.mesh.DiagonalType.left
    )
    return CutMesh(mesh, lambda x: x[0] + x[1] - T, degree=1)


def test_constant_strains_give_the_side_area_over_the_interface_length():
    cut = corner_cut()
    assert cut.cut_cells.size == 1
    lengths = side_trace_lengths(cut, None, 1)
    gamma = T * np.sqrt(2.0)
    small, large = T**2 / 2, 0.5 - T**2 / 2
    assert lengths[-1][0] == pytest.approx(small / gamma, rel=1e-12)
    assert lengths[1][0] == pytest.approx(large / gamma, rel=1e-12)


def test_linear_strains_give_the_sharp_trace_inverse_constant():
    """The small side is the triangle (0, 0), (T, 0), (0, T) and the interface its
    hypotenuse: ``l_- = |T_-| / (3 |Gamma|)``."""
    lengths = side_trace_lengths(corner_cut(), None, 2)
    assert lengths[-1][0] == pytest.approx(T**2 / 2 / (3 * T * np.sqrt(2.0)), rel=1e-10)


def test_the_trace_length_vanishes_with_the_share_of_the_side():
    """The small side's length scales like ``T`` (its share like ``T^2``), the large
    side's does not."""
    lengths = side_trace_lengths(corner_cut("quadrilateral"), None, 2)
    assert lengths[-1][0] < 0.1 * T and lengths[1][0] > 0.1


@pytest.mark.parametrize(
    ("cell", "degree", "tdim", "size"),
    [
        ("triangle", 1, 2, 1),
        ("triangle", 2, 2, 3),
        ("tetrahedron", 2, 3, 4),
        ("quadrilateral", 1, 2, 3),
        ("quadrilateral", 2, 2, 8),
        ("hexahedron", 1, 3, 7),
        ("hexahedron", 2, 3, 26),
    ],
)
def test_the_strain_spaces(cell, degree, tdim, size):
    """``P_(k-1)`` on simplices, ``Q_k`` without its top monomial on tensor cells (the
    span of ``Q_k``'s partial derivatives)."""
    exponents = strain_exponents(cell, degree, tdim)
    assert exponents.shape == (size, tdim)


def test_a_degree_below_one_is_refused():
    with pytest.raises(ValueError, match="degree must be at least 1"):
        strain_exponents("triangle", 0, 2)


def test_a_side_borrows_its_uncut_neighbour_through_the_ghost_penalty():
    """Constant strains (P1): the cut cell's side ``+`` borrows the uncut neighbour ``K``
    across the diagonal ``F``: ``l_+ = (|T_+| + theta |K| G / (theta |K| + G)) / |Gamma|``
    with ``G = eta h |F|`` (the jump term of degree 0; ``theta = 1/6``, ``h`` the cells'
    diameter). Side ``-`` has no neighbour on its side: its own length."""
    cut = corner_cut()
    eta, h = 0.3, np.sqrt(2.0)
    ncells = cut.mesh.topology.index_map(2).size_local
    lengths = patch_trace_lengths(cut, None, 1, {-1: eta, 1: eta}, np.full(ncells, h))
    own = side_trace_lengths(cut, None, 1)
    gamma, lent = T * np.sqrt(2.0), 0.5 / 6.0
    G = eta * h * np.sqrt(2.0)
    expected = (0.5 - T**2 / 2 + lent * G / (lent + G)) / gamma
    assert lengths[1][0] == pytest.approx(expected, rel=1e-12)
    assert lengths[-1][0] == pytest.approx(own[-1][0], rel=1e-12)


@pytest.mark.parametrize("cell", ["triangle", "quadrilateral"])
def test_without_the_ghost_penalty_nothing_is_borrowed(cell):
    """``eta = 0``: no credit, and no cell of this single cut cell's mesh lends."""
    cut = corner_cut(cell)
    ncells = cut.mesh.topology.index_map(2).size_local
    lengths = patch_trace_lengths(cut, None, 2, {-1: 0.0, 1: 0.0}, np.ones(ncells))
    own = side_trace_lengths(cut, None, 2)
    for s in (-1, 1):
        assert lengths[s] == pytest.approx(own[s], rel=1e-10)


def test_the_credit_of_the_second_derivative_jumps_follows_their_factor():
    """P2: the strains' gradient jumps (the ghost penalty's second-derivative jumps)
    lend too; with their factor ``higher`` lowered the credited side's length falls, and
    it stays above the credit of the value jumps alone (``higher = 0``)."""
    cut = corner_cut()
    eta = 0.3
    ncells = cut.mesh.topology.index_map(2).size_local
    h = np.full(ncells, np.sqrt(2.0))
    length = {
        higher: patch_trace_lengths(cut, None, 2, {-1: eta, 1: eta}, h, higher)[1][0]
        for higher in (1.0, 0.01, 0.0)
    }
    assert length[1.0] > length[0.01] > length[0.0] > side_trace_lengths(cut, None, 2)[1][0]
