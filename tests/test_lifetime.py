"""A solved problem is freed as soon as it is dropped, without the cyclic garbage
collector: its meshes hold MPI communicators, and MPICH has about 2000 of them, so a
reference cycle (the Newton solver holding a bound method of its problem, a large-
sliding coupling holding the context that caches it) made an MPI test suite or a
parameter sweep abort with "Too many communicators" after about 120 problems."""

import xfem_contact  # noqa: F401  (before dolfinx)

# isort: split
import gc
import weakref

import pytest

from xfem_contact.cases.paper import inclusion_problem
from xfem_contact.cases.rotation import rotating_annulus_problem

BUILDERS = {
    "small sliding": lambda: inclusion_problem(4, 2, "sticking"),
    "large sliding": lambda: rotating_annulus_problem(4, 2, 0.2),
}


@pytest.mark.mpi
@pytest.mark.parametrize("kind", list(BUILDERS))
def test_a_dropped_problem_frees_its_mesh_at_once(kind):
    problem = BUILDERS[kind]()
    problem.solve()
    mesh = weakref.ref(problem.mesh)
    gc.collect()
    gc.disable()
    try:
        del problem
        assert mesh() is None, "a reference cycle keeps the problem (and its MPI communicators)"
    finally:
        gc.enable()
