"""The foundation of trust: the standard rule fed through the runtime path
reproduces stock DOLFINx/FFCx assembly to round-off."""

import basix
import dolfinx.fem
import numpy as np
import pytest
import ufl
from conftest import CELLS_3D, unit_cube, unit_square
from dolfinx.fem import assemble_matrix, assemble_scalar, assemble_vector

import xfem_contact

DEGREE = 4


def standard_rules(mesh):
    """Every owned cell gets basix's default rule of degree DEGREE."""
    ncell = mesh.topology.index_map(mesh.topology.dim).size_local
    X, W = basix.make_quadrature(mesh.basix_cell(), DEGREE)
    return xfem_contact.CellRules(
        mesh,
        np.arange(ncell),
        np.tile(X, (ncell, 1)),
        np.tile(W, ncell),
        np.arange(ncell + 1) * W.size,
    )


def forms(mesh):
    """(name, UFL integrand) pairs: bilinear, linear, functional; one nonlinear
    residual with its Jacobian."""
    gdim = mesh.geometry.dim
    V = dolfinx.fem.functionspace(mesh, ("Lagrange", 2, (gdim,)))
    S = dolfinx.fem.functionspace(mesh, ("Lagrange", 2))
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    p, q = ufl.TrialFunction(S), ufl.TestFunction(S)
    f = dolfinx.fem.Function(S)
    f.interpolate(lambda x: 1.0 + x[0] ** 2 + np.sin(x[1]))
    w = dolfinx.fem.Function(V)
    w.interpolate(
        lambda x: np.stack([0.1 * x[0] * x[1], 0.2 * np.cos(x[0]), 0.3 * x[2] * x[0]][:gdim])
    )
    eps = ufl.sym(ufl.grad(u))
    residual = ufl.inner((1 + ufl.inner(w, w)) * ufl.grad(w), ufl.grad(v)) + f * ufl.inner(w, v)
    return {
        "scalar mass": p * q,
        "scalar stiffness with coefficient": f * ufl.inner(ufl.grad(p), ufl.grad(q)),
        "vector elasticity": 2.0 * ufl.inner(eps, ufl.sym(ufl.grad(v))) + ufl.div(u) * ufl.div(v),
        "nonlinear residual": residual,
        "jacobian": ufl.derivative(residual, w, u),
        "functional": f * ufl.inner(w, w) * ufl.det(ufl.grad(ufl.SpatialCoordinate(mesh))),
    }


def assemble(form):
    rank = len(form.function_spaces)
    if rank == 2:
        A = assemble_matrix(form)
        A.scatter_reverse()
        return A.to_dense()
    if rank == 1:
        b = assemble_vector(form)
        b.scatter_reverse(dolfinx.la.InsertMode.add)
        dofmap = form.function_spaces[0].dofmap
        return b.array[: dofmap.index_map.size_local * dofmap.index_map_bs]
    return form.mesh.comm.allreduce(assemble_scalar(form))


@pytest.mark.mpi
@pytest.mark.parametrize("distorted", [False, True], ids=["affine", "distorted"])
def test_standard_rule_through_runtime_path(cell, distorted):
    check_identity(unit_square(4, cell, distorted))


@pytest.mark.mpi
@pytest.mark.parametrize("distorted", [False, True], ids=["affine", "distorted"])
@pytest.mark.parametrize("cell3d", list(CELLS_3D))
def test_standard_rule_through_runtime_path_3d(cell3d, distorted):
    """The same on tetrahedra and hexahedra (3D placeholder points)."""
    check_identity(unit_cube(2, cell3d, distorted))


def check_identity(mesh):
    """Every form of :func:`forms` through the runtime path equals stock FFCx."""
    rules = standard_rules(mesh)
    dx_std = ufl.dx(domain=mesh, metadata={"quadrature_degree": DEGREE})
    for name, integrand in forms(mesh).items():
        reference = assemble(dolfinx.fem.form(integrand * dx_std))
        runtime = assemble(xfem_contact.form(integrand * rules.measure()))
        scale = np.max(np.abs(reference))
        assert scale > 0, name
        assert np.max(np.abs(runtime - reference)) <= 1e-13 * scale, name


def test_missing_rule_data_gives_nan_not_zero():
    """A runtime kernel on a cell whose marker has no registry writes NaN."""
    mesh = unit_square(2, "quadrilateral")
    rules = standard_rules(mesh)
    form = xfem_contact.form(1.0 * rules.measure())
    rules.marker.x.array[:] = 0.0  # wipe the rule index and the registry address
    assert np.isnan(assemble_scalar(form))


def test_bad_rules_raise():
    mesh = unit_square(2, "triangle")
    with pytest.raises(ValueError, match="offsets"):
        xfem_contact.CellRules(mesh, [0], np.zeros((3, 2)), np.ones(3), [0, 2])
    with pytest.raises(ValueError, match="finite"):
        xfem_contact.CellRules(mesh, [0], np.full((1, 2), np.nan), np.ones(1), [0, 1])
    with pytest.raises(ValueError, match="owned cells"):
        xfem_contact.CellRules(mesh, [10**6], np.zeros((1, 2)), np.ones(1), [0, 1])
