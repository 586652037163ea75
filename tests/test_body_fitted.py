"""The body-fitted baselines of the accuracy-vs-time bench: gmsh meshes following the
interface, shared nodes (bonded) or duplicated lines tied by Nitsche's method.

For the paper's case 2 (closed, sticking) the Nitsche tie of the two meshes has the
bonded body's solution: the pressure errors agree to 1e-8 relative (measured 1.5e-13)
and converge (P2: 2.8e-4 at h = 0.1, 5.2e-5 at 0.05). Case 3 at alpha = 0 with a
frictionless (normal) tie: 2.2e-3 at h = 2 m, 7.4e-4 at 1 m."""

import xfem_contact  # noqa: F401  (before dolfinx)

# isort: split
import pytest

from xfem_contact.cases.body_fitted import fitted_annulus, fitted_inclusion
from xfem_contact.cases.fitted_nitsche import nitsche_annulus, nitsche_inclusion


@pytest.mark.mpi
def test_nitsche_tie_of_duplicated_lines_is_the_bonded_solution():
    tied = nitsche_inclusion(0.1, 2)
    shared = fitted_inclusion(0.1, 2)
    assert tied["error"] < 1e-3
    assert abs(tied["error"] / shared["error"] - 1.0) < 1e-8
    assert tied["dofs"] > shared["dofs"]  # the interface nodes are there twice


@pytest.mark.mpi
def test_frictionless_nitsche_annulus_converges():
    coarse, fine = nitsche_annulus(2.0, 2)["error"], nitsche_annulus(1.0, 2)["error"]
    assert fine < coarse / 2.5 and fine < 1e-3
    assert abs(fitted_annulus(1.0, 2)["error"] / fine - 1.0) < 0.2  # the bonded route
