"""Cracks and interfaces on meshes whose nodes lie on the level sets' zeros.

The crack's line ``y = -2 x`` passes through nodes of the structured meshes of
``[-1, 1]^2`` (``h = 1/4``): where it leaves the top face (the crack's mouth), inside,
and where its extension (``psi > 0``) leaves the bottom face. Every boundary part of
both sides, the areas and the lips are measured against the exact lengths; the level
sets are exact zeros at those nodes (``2 x + y`` in dyadic arithmetic).
"""

import math

import dolfinx.fem
import dolfinx.mesh
import numpy as np
import pytest
from conftest import CELLS
from mpi4py import MPI

import xfem_contact
from xfem_contact.fem.cutmesh import CutMesh
from xfem_contact.fem.enrichment import EnrichedSpace

ROOT5 = math.sqrt(5.0)
#: Tip positions along the line: ``x - 2 y = c`` at the tip (a cell's inside, a node
#: (the origin), the middle of the horizontal edge at y = -1/4); None: an interface
TIPS = {"cell": 0.3, "node": 0.0, "edge": 0.625}
#: Exact side lengths of each face of [-1, 1]^2 cut by y = -2 x: (side -1, side +1)
FACES = {
    "bottom": (lambda x: np.isclose(x[1], -1.0), (1.5, 0.5)),
    "top": (lambda x: np.isclose(x[1], 1.0), (0.5, 1.5)),
    "left": (lambda x: np.isclose(x[0], -1.0), (2.0, 0.0)),
    "right": (lambda x: np.isclose(x[0], 1.0), (0.0, 2.0)),
}


def _phi(x):
    return (2.0 * x[0] + x[1]) / ROOT5


def _psi(c):
    return lambda x: (x[0] - 2.0 * x[1] - c) / ROOT5


def _mesh(cell, comm=MPI.COMM_WORLD, n=8):
    corners = [np.array([-1.0, -1.0]), np.array([1.0, 1.0])]
    return dolfinx.mesh.create_rectangle(comm, corners, [n, n], CELLS[cell])


def _integrate(expr_measure):
    form = xfem_contact.form(expr_measure)
    return form.mesh.comm.allreduce(dolfinx.fem.assemble_scalar(form), op=MPI.SUM)


def _measures(cut):
    """Lengths of every face's part on each side, both areas and the interface length."""
    mesh = cut.mesh
    one = dolfinx.fem.Constant(mesh, 1.0)
    out = {}
    for name, (where, _) in FACES.items():
        facets = dolfinx.mesh.locate_entities_boundary(mesh, mesh.topology.dim - 1, where)
        for side in (-1, 1):
            out[name, side] = _integrate(one * cut.ds(side, facets))
    for side in (-1, 1):
        out["area", side] = _integrate(one * cut.dx(side))
    out["interface"] = _integrate(one * cut.dGamma)
    return out


def _exact(tip):
    """The exact values of :func:`_measures`: the lips run from the mouth (-1/2, 1),
    where ``x - 2 y = -5/2``, to the tip; an interface all along the line."""
    exact = {
        (name, side): lengths[k]
        for name, (_, lengths) in FACES.items()
        for k, side in enumerate((-1, 1))
    }
    exact["area", -1] = exact["area", 1] = 2.0
    exact["interface"] = ROOT5 if tip is None else (2.5 + TIPS[tip]) / ROOT5
    return exact


def _cut(cell, degree, tip, comm=MPI.COMM_WORLD):
    mesh = _mesh(cell, comm)
    tangent = None if tip is None else _psi(TIPS[tip])
    return CutMesh(mesh, _phi, degree=degree, tangent=tangent)


@pytest.mark.parametrize("tip", [None, "cell"])
@pytest.mark.parametrize("degree", [1, 2])
def test_measures_with_nodes_on_the_line(cell, degree, tip):
    """Crack (tip inside a cell) or interface through nodes: every face's part on
    each side, the areas and the lips (or interface) exact; each facet counted once
    (a P2 crack's mouth at a node measured the top face's side +1 as 2.5 m, not 1.5 m:
    fallback fans of a sliver side folded, their pieces counted without orientation)."""
    measured = _measures(_cut(cell, degree, tip))
    for key, value in _exact(tip).items():
        assert measured[key] == pytest.approx(value, abs=1e-12), key


@pytest.mark.mpi
@pytest.mark.parametrize("degree", [1, 2])
def test_measures_with_nodes_on_the_line_parallel(cell, degree):
    """The same measures on all ranks as on one (each rank's own serial copy) and exact."""
    serial = _measures(_cut(cell, degree, "cell", MPI.COMM_SELF))
    parallel = _measures(_cut(cell, degree, "cell"))
    for key, value in _exact("cell").items():
        assert parallel[key] == pytest.approx(serial[key], abs=1e-13), key
        assert parallel[key] == pytest.approx(value, abs=1e-12), key


@pytest.mark.parametrize("degree", [1, 2])
def test_circle_through_boundary_nodes(cell, degree):
    """An interface leaving the boundary at nodes (a circle about a corner through
    (0, -1) and (-1, 0)): each face split exactly, each facet once."""
    mesh = _mesh(cell)
    cut = CutMesh(mesh, lambda x: (x[0] + 1) ** 2 + (x[1] + 1) ** 2 - 1.0, degree=degree)
    one = dolfinx.fem.Constant(mesh, 1.0)
    for name, inside in (("bottom", 1.0), ("left", 1.0), ("top", 0.0), ("right", 0.0)):
        facets = dolfinx.mesh.locate_entities_boundary(mesh, 1, FACES[name][0])
        assert _integrate(one * cut.ds(-1, facets)) == pytest.approx(inside, abs=1e-12)
        assert _integrate(one * cut.ds(1, facets)) == pytest.approx(2.0 - inside, abs=1e-12)


@pytest.mark.parametrize("degree", [1, 2])
def test_active_dofs_with_empty_sides(cell, degree):
    """Cut cells with no rule point on one side (a node on the line, the others on one
    side) get side fractions, not an IndexError (add.reduceat past the last point)."""
    cut = _cut(cell, degree, "cell")
    counts = [np.diff(cut.side_rules(s).offsets) for s in (-1, 1)]
    assert any((c == 0).any() for c in counts)  # the case is present
    space = EnrichedSpace(cut, degree, min_support_fraction=1e-12)
    assert space.dof_counts().enriched > 0
