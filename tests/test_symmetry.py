"""Symmetric Jacobians are factored LDL^T, and only they.

- the laws that declare a symmetric Jacobian (sticking, frictionless, bonded) get
  ``pc_type = "cholesky"`` by default and the solution of the LU, to round-off; each
  of their Jacobians passes the guard (:func:`xfem_contact.solvers.symmetry.mark_symmetric`);
- Coulomb friction keeps the LU; asking it for ``cholesky`` is refused, and the guard
  catches its unsymmetric Jacobian when the problem's check is bypassed;
- the guard passes a symmetric matrix and refuses one with a small unsymmetric part.
"""

import warnings

import numpy as np
import pytest
from mpi4py import MPI
from petsc4py import PETSc

from xfem_contact.cases.paper import inclusion_errors, inclusion_problem
from xfem_contact.solvers.newton import ReducedNewton
from xfem_contact.solvers.symmetry import mark_symmetric


def _solved(law, pc_type, **options):
    problem = inclusion_problem(12, 2, law, "quadrilateral", **options)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # frictionless: the free spin of the inclusion
        problem.petsc_options = {} if pc_type is None else {"pc_type": pc_type}
        problem.solve()
    return problem


@pytest.mark.mpi
@pytest.mark.parametrize("law", ["sticking", "frictionless", "bonded"])
def test_symmetric_laws_factor_ldlt_to_the_lu_solution(law):
    default, lu = _solved(law, None), _solved(law, "lu")
    assert default.symmetric
    if not default.linear:
        assert default.newton.options["pc_type"] == "cholesky"
    scale = np.abs(lu.w.x.array).max()
    assert np.abs(default.w.x.array - lu.w.x.array).max() <= 1e-9 * scale
    if law != "bonded":
        errors = inclusion_errors(default, default.w), inclusion_errors(lu, lu.w)
        assert errors[0].pressure == pytest.approx(errors[1].pressure, rel=1e-8)


@pytest.mark.mpi
def test_coulomb_keeps_lu_and_its_jacobian_fails_the_guard():
    problem = inclusion_problem(12, 2, "coulomb", "quadrilateral", friction=0.3)
    assert not problem.symmetric
    with pytest.raises(ValueError, match="needs a symmetric Jacobian"):
        problem.petsc_options = {"pc_type": "cholesky"}
        problem.solve()
    newton = ReducedNewton(
        problem.residual(problem.w),
        problem.w,
        problem.loads.bcs,
        problem.prolongation(),
        {"pc_type": "cholesky"},
        field_space=problem.space.field_space,
    )
    with pytest.raises(ValueError, match="is not symmetric"):
        newton.solve()
    newton.destroy()


def _matrix(values: np.ndarray) -> PETSc.Mat:
    n = values.shape[0]
    A = PETSc.Mat().createAIJ((n, n), comm=MPI.COMM_SELF)
    A.setUp()
    A.setValues(range(n), range(n), values)
    A.assemble()
    return A


def test_guard_passes_symmetric_and_refuses_a_small_unsymmetric_part():
    rng = np.random.default_rng(0)
    M = rng.standard_normal((30, 30))
    symmetric = _matrix(M + M.T)
    mark_symmetric(symmetric)
    assert symmetric.isSymmetricKnown() == (True, True)
    skew = np.zeros_like(M)
    skew[3, 7], skew[7, 3] = 1e-6, -1e-6  # 1e-6 of entries of size ~1
    unsymmetric = _matrix(M + M.T + skew)
    with pytest.raises(ValueError, match="is not symmetric"):
        mark_symmetric(unsymmetric)
    for A in (symmetric, unsymmetric):
        A.destroy()


def test_each_jacobian_checked_once_and_never_copied_onto_itself(monkeypatch):
    """A direct solve factors the Jacobian itself (no preconditioner copy): the set-up
    Jacobian, which the only Newton step reuses, is checked for symmetry once and not
    copied onto itself (the SNES callback's two matrices are new wrappers of one)."""
    from xfem_contact.solvers import newton

    checked, onto_itself = [], []
    original_copy = PETSc.Mat.copy

    def copy(A, result=None, *args):
        onto_itself.append(result is not None and result.handle == A.handle)
        return original_copy(A, result, *args)

    monkeypatch.setattr(newton, "mark_symmetric", lambda A: checked.append(A) or mark_symmetric(A))
    monkeypatch.setattr(PETSc.Mat, "copy", copy)
    problem = inclusion_problem(8, 2, "sticking")
    report = problem.solve()
    assert problem.solver_options()["pc_type"] == "cholesky" and report.iterations == 1
    assert len(checked) == 1
    assert not any(onto_itself)
