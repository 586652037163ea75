"""The scale of the cut credited through the ghost penalty
(``stabilization_length="patch"``) keeps the displacement block coercive: ``s
int_Gamma_T |t(u)|^2 ds`` summed over the cut cells is at most ``gamma`` times the bulk
energy plus the ghost penalty, so no displacement mode is negative for ``gamma < 1``
(the docs' stability page derives it). On the circle where the cell's scale has 2
negative modes (P2 triangles, n = 16): none at ``gamma = 0.5`` (beta 0.298) or 0.99
(0.394); at ``gamma = 1.5``, past the bound, 4.
"""

import xfem_contact  # noqa: F401  (before dolfinx)

# isort: split
import dolfinx.mesh
import numpy as np
import pytest
from mpi4py import MPI

from xfem_contact.fem.cutmesh import CutMesh
from xfem_contact.io.meshes import ghosted_partitioner
from xfem_contact.mechanics.inf_sup import InfSup, inf_sup_constant
from xfem_contact.mechanics.laws import Bonded
from xfem_contact.mechanics.materials import Material
from xfem_contact.mechanics.problem import Problem

#: The floor of a stable pair's beta (the stability page's bound)
FLOOR = 0.2
#: A circle on which the cell's scale is indefinite (P2 triangles, n = 16)
CIRCLE = (0.5897298894274488, 0.4623662904020971, 0.21349896734588636)


def circle_inf_sup(
    gamma: float | None, cell: str = "triangle", n: int = 16, comm=MPI.COMM_WORLD
) -> InfSup:
    cx, cy, r = CIRCLE
    mesh = dolfinx.mesh.create_unit_square(
        comm, n, n, dolfinx.mesh.CellType[cell], partitioner=ghosted_partitioner()
    )
    cut = CutMesh(mesh, lambda x: np.hypot(x[0] - cx, x[1] - cy) - r, degree=2)
    law = Bonded(lbb="stabilized", stabilization_length="patch", multiplier_stabilization=gamma)
    return inf_sup_constant(Problem(cut, 2, Material(100e6, 0.3), law))


@pytest.mark.parametrize("cell", ["triangle", "quadrilateral"])
@pytest.mark.parametrize("gamma", [None, 0.99])
def test_the_patch_length_keeps_the_displacement_block_coercive(cell, gamma):
    """No negative mode; beta above the floor on triangles (0.298, 0.394). Q2-Q1's
    beta, 0.190 at the default weight, is under it, as with the cut's own lengths
    (0.162 .. 0.166 on 50 circles a mesh; the stability page)."""
    result = circle_inf_sup(gamma, cell)
    assert result.negative_displacement_modes == 0, result
    assert result.beta > (FLOOR if cell == "triangle" else 0.0), result


def test_past_the_bound_the_block_is_indefinite():
    """The bound is close to sharp here: ``gamma = 1.5`` leaves negative modes."""
    assert circle_inf_sup(1.5).negative_displacement_modes > 0


@pytest.mark.mpi
def test_the_patch_length_is_the_same_on_one_and_two_ranks():
    """The neighbours' masses and lengths reach the ghost cells."""
    beta = circle_inf_sup(None, n=8).beta
    beta_self = circle_inf_sup(None, n=8, comm=MPI.COMM_SELF).beta
    assert abs(beta - beta_self) <= 1e-8 * beta_self


def test_lowering_the_credited_ghost_penalty_is_refused():
    """The patch lengths credit the ghost penalty of the cut: a lower weight would void
    the bound; a higher one keeps it."""
    mesh = dolfinx.mesh.create_unit_square(MPI.COMM_WORLD, 4, 4)
    cut = CutMesh(mesh, lambda x: np.hypot(x[0] - 0.5, x[1] - 0.5) - 0.3, degree=2)
    law = Bonded(lbb="stabilized", stabilization_length="patch")
    problem = Problem(cut, 1, Material(100e6, 0.3), law)
    problem.ghost_penalty = 0.05
    with pytest.raises(ValueError, match="ghost_penalty 0.001 is below 0.01"):
        problem.ghost_penalty = 0.001


def test_lowering_the_credited_higher_derivatives_factor_is_refused():
    """The patch lengths credit the ghost penalty's second-derivative jumps too."""
    mesh = dolfinx.mesh.create_unit_square(MPI.COMM_WORLD, 4, 4)
    cut = CutMesh(mesh, lambda x: np.hypot(x[0] - 0.5, x[1] - 0.5) - 0.3, degree=2)
    law = Bonded(lbb="stabilized", stabilization_length="patch")
    problem = Problem(cut, 2, Material(100e6, 0.3), law, ghost_penalty_higher=0.01)
    problem.ghost_penalty_higher = 0.1
    with pytest.raises(ValueError, match="ghost_penalty_higher 0.001 is below 0.01"):
        problem.ghost_penalty_higher = 0.001
