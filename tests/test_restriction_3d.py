"""The vital-vertex restriction (``lbb="restriction"``) on tetrahedra and hexahedra: each
cut edge's vital vertex is its end nearer the interface
(``xfem_contact.mechanics.lbb_space.VITAL_RULE``).

Measured (sphere R = 0.2 about the centre of the unit cube, ``python bench/inf_sup.py
--solid``): P1-P1 tetrahedra, beta at n = 8, 12, 16, 20: 0.231, 0.222, 0.208, 0.205
with the restriction, 0.082 (n = 4), 0.015 (n = 8) without LBB treatment. The sticking
sphere's pressure error (P1, quadric level set) at n = 4, 6, 8: 0.478, 0.167, 0.0495
(the greedy covering, switched on here, gives 0.10 at n = 8 with P2).
"""

import xfem_contact  # noqa: F401  (before dolfinx)

# isort: split
import dolfinx.mesh
import numpy as np
import pytest
from mpi4py import MPI
from parallel import all_ranks_against_one
from test_multiplier_degree import assert_p2_restriction_is_p1s
from test_scenes_3d import solved, sphere_scene

from xfem_contact.cases.solid import TRIAXIAL, sphere_errors, sphere_problem, unstructured_cube
from xfem_contact.fem.cutmesh import CutMesh
from xfem_contact.mechanics import lbb_space
from xfem_contact.mechanics.inf_sup import inf_sup_constant
from xfem_contact.mechanics.laws import Bonded
from xfem_contact.mechanics.materials import Material
from xfem_contact.mechanics.problem import Problem
from xfem_contact.scenes.scene import load_scene

#: beta of the restricted P1-P1 pair on tetrahedra stays above this at n = 4 and 8;
#: without LBB treatment it is below (0.082 and 0.015: the guard's failure, checked on the
#: same sphere and meshes by tests/stability/test_inf_sup.py)
FLOOR = 0.15


def sphere_beta(n: int, lbb: str, cell: str = "tetrahedron", degree: int = 1) -> float:
    mesh = dolfinx.mesh.create_unit_cube(MPI.COMM_WORLD, n, n, n, dolfinx.mesh.CellType[cell])
    cut = CutMesh(mesh, lambda x: np.sqrt(((x.T - 0.5) ** 2).sum(axis=1)) - 0.2, degree=2)
    problem = Problem(cut, degree, Material(100e6, 0.3), Bonded(lbb=lbb))
    return inf_sup_constant(problem).beta


def test_the_restriction_keeps_the_constant_above_the_floor():
    values = [sphere_beta(n, "restriction") for n in (4, 8)]
    assert min(values) > FLOOR, values


def test_the_restriction_on_unstructured_tetrahedra():
    """gmsh's unstructured tetrahedra (h = 0.2, 0.15: 705 and 1488 cells), P1-P1, the
    exact sphere: the restricted pair's constant above the floor (0.381, 0.361), the pair
    without LBB treatment below (0.026, 0.019: its guard switched off)."""
    for h in (0.2, 0.15):
        mesh = unstructured_cube(h)
        beta = {
            lbb: inf_sup_constant(
                sphere_problem(None, 1, "bonded", mesh=mesh, levelset="quadric", lbb=lbb)
            ).beta
            for lbb in ("restriction", "none")
        }
        assert beta["restriction"] > FLOOR > beta["none"], (h, beta)


def test_the_unstructured_cube_holds_the_point_constraints():
    """Every face centre of :func:`unstructured_cube` is a mesh node (the uniform-stress
    cases hold their rigid modes there), and a bad size is refused in one line."""
    mesh = unstructured_cube(0.3)
    x = mesh.geometry.x
    centres = [
        c
        for k in range(3)
        for c in (np.eye(3)[k] * v + 0.5 * (1 - np.eye(3)[k]) for v in (0.0, 1.0))
    ]
    found = [
        MPI.COMM_WORLD.allreduce(bool(np.isclose(x, c).all(axis=1).any()), MPI.LOR) for c in centres
    ]
    assert all(found), found
    with pytest.raises(ValueError, match="h must be a cell size"):
        unstructured_cube(0.0)
    with pytest.raises(ValueError, match="give n"):
        sphere_problem(4, 1, "sticking", mesh=mesh)


def test_the_sticking_sphere_pressure_with_the_restriction():
    """P1 tetrahedra, n = 8, the quadric level set (the exact sphere): the exact field is
    linear, so the error is the multiplier space's (0.0495; stabilised 0.0088 with P2)."""
    problem = sphere_problem(8, 1, "sticking", levelset="quadric", lbb="restriction")
    problem.solve()
    e_n, _ = sphere_errors(problem)
    assert e_n < 0.06, e_n


@pytest.mark.parametrize("cell", ["tetrahedron", "hexahedron"])
def test_the_restricted_p2_space_is_the_restricted_p1_space(cell):
    """P2 multipliers with the restriction: every node off the vertices tied to the mean
    of its entity's vertices (edges; a hexahedron's faces and centre too), so the same
    unknowns and the same multiplier as P1 to round-off."""
    assert_p2_restriction_is_p1s(
        lambda degree: sphere_problem(
            4, 1, "sticking", cell, levelset="quadric", lbb="restriction", multiplier_degree=degree
        )
    )


def test_the_scene_option_in_3d():
    """``lbb = "restriction"`` in a 3D scene: the restricted multiplier space, the
    sticking sphere's pressure (P2, n = 4; the exact sphere)."""
    data = sphere_scene()
    data["interfaces"][0]["lbb"] = "restriction"
    problem = solved(load_scene(data))
    assert problem.law(None).lbb == "restriction"
    R = problem.prolongation()
    full = problem.space.W.dofmap.index_map.size_global * problem.space.W.dofmap.index_map_bs
    assert R.getSize()[1] < full
    R.destroy()
    problem.stress = TRIAXIAL
    e_n, _ = sphere_errors(problem)
    assert e_n < 0.5, e_n


def test_tetrahedra_take_the_nearer_end(monkeypatch):
    """The nearer-end rule is the one in use on tetrahedra: switched off (the greedy
    covering of quadrilaterals) the space has fewer unknowns."""
    problem = sphere_problem(6, 1, "sticking", levelset="quadric", lbb="restriction")
    R = problem.prolongation()
    nearer = R.getSize()[1]
    R.destroy()
    monkeypatch.setitem(lbb_space.VITAL_RULE, "tetrahedron", ("covering", "covering"))
    problem = sphere_problem(6, 1, "sticking", levelset="quadric", lbb="restriction")
    R = problem.prolongation()
    assert R.getSize()[1] < nearer
    R.destroy()


@pytest.mark.mpi
@pytest.mark.parallel
def test_the_restricted_sphere_on_unstructured_tetrahedra_parallel_equals_serial():
    """The sticking sphere with the restriction on gmsh's cube (P1, h = 0.2; gmsh meshes
    on one rank, the mesh is the same): its fields gathered by position, 2 ranks = 1."""

    def build(comm):
        mesh = unstructured_cube(0.2, comm)
        problem = sphere_problem(None, 1, "sticking", comm=comm, mesh=mesh, lbb="restriction")
        return problem

    for name, difference in all_ranks_against_one(build).items():
        assert difference < 1e-10, (name, difference)


@pytest.mark.mpi
@pytest.mark.parallel
def test_the_restricted_sphere_parallel_equals_serial():
    """The sticking sphere with the restriction (P1, n = 6): its fields gathered by
    position, 2 ranks = 1 rank."""
    for name, difference in all_ranks_against_one(
        lambda comm: sphere_problem(6, 1, "sticking", comm=comm, lbb="restriction")
    ).items():
        assert difference < 1e-10, (name, difference)
