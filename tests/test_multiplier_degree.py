"""The multiplier degree (``multiplier_degree``): P2-P2 against P2-P1 on paper case 2
(sticking inclusion, uniform stress: the exact contact pressure ``n.sigma.n`` is on the
circle the trace of a quadratic polynomial), the restricted P2 space, and the refusals.

Measured (quadrilaterals, the circle held exactly by the quadric level set, stabilised;
pressure error at n = 8, 16): P2-P1 5.41e-3, 1.27e-3 (rate 2.1); P2-P2 6.56e-5,
5.16e-6 (rate 3.7).
"""

import xfem_contact  # noqa: F401  (before dolfinx)

# isort: split
import math

import dolfinx.mesh
import numpy as np
import pytest
from mpi4py import MPI

from xfem_contact.cases.paper import inclusion_errors, inclusion_problem
from xfem_contact.fem.cutmesh import CutMesh
from xfem_contact.mechanics.laws import Bonded
from xfem_contact.mechanics.materials import Material
from xfem_contact.mechanics.problem import Problem


def pressure_errors(multiplier_degree: int, sizes=(8, 16), **options) -> list[float]:
    out = []
    for n in sizes:
        problem = inclusion_problem(
            n, 2, "sticking", levelset="quadric", multiplier_degree=multiplier_degree, **options
        )
        problem.solve()
        out.append(inclusion_errors(problem, problem.w).pressure)
    return out


def rate(errors: list[float]) -> float:
    return math.log(errors[0] / errors[1]) / math.log(2.0)


def test_p2_multipliers_converge_a_degree_faster_than_p1():
    """The stabilised P2-P2 pressure converges at rate >= 3, P2-P1 at about 2."""
    p1, p2 = pressure_errors(1), pressure_errors(2)
    assert rate(p2) > 3.0 and rate(p1) < 2.5, (p1, p2)
    assert p2[1] < 0.01 * p1[1], (p1, p2)


def test_the_restricted_p2_space_is_the_restricted_p1_space():
    """With ``lbb="restriction"`` every P2 node off the vertices is tied to the mean of
    its edge's ends: the same multiplier, the same solution as P2-P1 to round-off."""
    assert_p2_restriction_is_p1s(
        lambda degree: inclusion_problem(
            8, 2, "sticking", "triangle", lbb="restriction", multiplier_degree=degree
        )
    )


def assert_p2_restriction_is_p1s(make) -> None:
    """``make(multiplier_degree)`` -> an interface problem with the restriction: solved with
    P1 and with P2 multipliers, the reduced unknowns are as many and the multipliers at
    the interface's rule points agree to 1e-9 of their largest value."""
    results, unknowns = [], []
    for degree in (1, 2):
        problem = make(degree)
        problem.solve()
        ctx = problem.contexts["interface"]
        results.append(ctx.values_at(problem.w, ctx.field))
        R = problem.prolongation()
        unknowns.append(R.getSize()[1])
        R.destroy()
    assert unknowns[0] == unknowns[1]
    scale = np.abs(results[0]).max()
    assert np.abs(results[1] - results[0]).max() < 1e-9 * scale


@pytest.mark.parametrize("bad", [3, 0, True, 2.0])
def test_a_bad_degree_is_refused_in_one_line(bad):
    with pytest.raises(ValueError, match=r"multiplier_degree must be one of \(1, 2\), got"):
        Bonded(multiplier_degree=bad)


def test_p2_multipliers_on_tetrahedra_with_the_stabilisation():
    """3D: the stabilised P2 multiplier is built on tetrahedra (solved by
    ``bench/sphere_triaxial.py --multiplier-degree 2``; the restricted one:
    tests/test_restriction_3d.py)."""
    mesh = dolfinx.mesh.create_unit_cube(MPI.COMM_WORLD, 3, 3, 3)
    cut = CutMesh(mesh, lambda x: np.sqrt(((x.T - 0.5) ** 2).sum(axis=1)) - 0.3, degree=2)
    problem = Problem(cut, 2, Material(100e6, 0.3), Bonded(multiplier_degree=2))
    assert problem.space.W.sub(2).ufl_element().embedded_superdegree == 2
