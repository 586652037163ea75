"""A cut is a value: ``CutMesh`` is built by its constructor, each ``update`` installs the
next frozen :class:`~xfem_contact.fem.cut_state.CutState`, and a problem attached to an
older state refuses to solve; a cut by cracks has one crack type."""

import xfem_contact  # noqa: F401

# isort: split
import ast
import dataclasses
import pathlib

import dolfinx.fem
import dolfinx.mesh
import numpy as np
import pytest
from mpi4py import MPI

from xfem_contact.cases.paper import INCLUSION_CENTRE, inclusion_problem
from xfem_contact.fem.cut_state import CutState
from xfem_contact.fem.cutmesh import CutMesh
from xfem_contact.geometry.crack_paths import arc, polyline
from xfem_contact.mechanics import fracture

PACKAGE = pathlib.Path(xfem_contact.__file__).parent
#: The modules that build a cut and attach a problem to it
ATTACHING = ("fem/cutmesh.py", "fem/cut_state.py", "mechanics/problem.py")


def self_probes(source: str, filename: str) -> list[str]:
    """Places in ``source`` that probe an object's own attributes: ``hasattr(self, ...)``
    or ``getattr(self, ...)``."""
    return [
        f"{filename}:{node.lineno}: {ast.unparse(node)}"
        for node in ast.walk(ast.parse(source, filename))
        if isinstance(node, ast.Call)
        and isinstance(node.func, ast.Name)
        and node.func.id in ("hasattr", "getattr")
        and node.args
        and isinstance(node.args[0], ast.Name)
        and node.args[0].id == "self"
    ]


def circle(radius: float):
    cx, cy = INCLUSION_CENTRE
    return lambda x: np.hypot(x[0] - cx, x[1] - cy) - radius


@pytest.fixture
def cut():
    mesh = dolfinx.mesh.create_unit_square(MPI.COMM_WORLD, 8, 8)
    return CutMesh(mesh, circle(0.2))


def test_no_module_probes_its_own_attributes():
    found = [p for name in ATTACHING for p in self_probes((PACKAGE / name).read_text(), name)]
    assert not found, "build attributes in the constructor:\n" + "\n".join(found)


@pytest.mark.parametrize(
    "source, count",
    [
        ("known = getattr(self, 'interface_names', None)", 1),
        ("if hasattr(self, 'side_indicator'): pass", 1),
        ("f = getattr(law, 'friction', None)", 0),
        ("s = self.state", 0),
    ],
)
def test_the_probe_check_finds_probes(source, count):
    assert len(self_probes(source, "x.py")) == count


@pytest.mark.mpi
def test_the_state_is_frozen(cut):
    state = cut.state
    assert isinstance(state, CutState) and state.revision == 0
    with pytest.raises(dataclasses.FrozenInstanceError):
        state.revision = 1
    with pytest.raises(TypeError):
        state.rules[1] = state.rules[2]
    with pytest.raises(ValueError, match="read-only"):
        state.cell_sides[0] = 1
    with pytest.raises(AttributeError):
        cut.revision = 3


@pytest.mark.mpi
def test_update_installs_the_next_state_and_keeps_the_old_one(cut):
    old = cut.state
    cells, sides, rules = old.cut_cells.copy(), old.cell_sides.copy(), old.rules
    new = cut.update(circle(0.3))
    assert new is cut.state and new is not old
    assert (new.revision, old.revision, cut.revision) == (1, 0, 1)
    np.testing.assert_array_equal(old.cut_cells, cells)
    np.testing.assert_array_equal(old.cell_sides, sides)
    assert old.rules is rules and new.rules is not rules
    assert cut.cut_cells is new.cut_cells and cut.geometry is new.geometry
    assert cut.interface_names == old.interface_names
    # the same level-set Function (compiled forms keep their signature), the new values
    assert new.levelset.function is old.levelset.function
    inside = cut.mesh.comm.allreduce(int(np.sum(new.cell_sides == -1)), op=MPI.SUM)
    assert inside > cut.mesh.comm.allreduce(int(np.sum(sides == -1)), op=MPI.SUM)


@pytest.mark.mpi
def test_a_problem_on_an_older_state_refuses_to_solve():
    problem = inclusion_problem(4, 1, "bonded")
    attached = problem.cut_state
    assert attached is problem.cut.state
    problem.cut.update(circle(0.25))
    assert problem.cut_state is attached  # the problem's own, now stale
    with pytest.raises(ValueError, match=r"cut revision 0, now 1\).*update_interface"):
        problem.solve()
    problem.update_interface(circle(0.22))
    assert problem.cut_state is problem.cut.state and problem.cut_state.revision == 2
    assert problem.solve().converged


@pytest.mark.mpi
def test_cracks_have_one_type():
    mesh = dolfinx.mesh.create_rectangle(MPI.COMM_WORLD, [[-2, -2], [2, 2]], [24, 24])
    paths = {
        "a": polyline([(-1.01, -0.73), (0.61, -0.41)]),
        "b": arc((0.01, 0.02), 1.3, [0.7, 2.6]),
    }
    phi = {name: path.levelsets()[0] for name, path in paths.items()}
    psi = {name: path.levelsets()[1] for name, path in paths.items()}
    cut = CutMesh(mesh, phi, degree=2, tangent=psi)
    union = cut.crack.union
    assert union.names == ("a", "b") and union.pair == ("a", "b") and union.gap > 0
    assert set(cut.crack.tip_names) == {"a", "b"}
    with pytest.warns(DeprecationWarning, match="crack.union"):
        assert cut.cracks is union
    single = CutMesh(mesh, phi["a"], degree=2, tangent=psi["a"])
    assert single.crack.union is None and single.crack.tips.shape == (2, 2)


def test_one_crack_path():
    assert fracture.GrowthPath.__name__ == "GrowthPath"
    with pytest.warns(DeprecationWarning, match="GrowthPath"):
        assert fracture.CrackPath is fracture.GrowthPath


def test_exact_zero_set_in_2d():
    """In 2D a callable is cut on its exact zero set by default (interface nodes on it);
    ``exact_zero_set=False`` cuts it as its interpolant, as a Function is cut."""
    mesh = dolfinx.mesh.create_unit_square(MPI.COMM_WORLD, 6, 6)
    circle = lambda x: np.hypot(x[0] - 0.5, x[1] - 0.5) - 0.3  # noqa: E731
    phi = dolfinx.fem.Function(dolfinx.fem.functionspace(mesh, ("Lagrange", 2)))
    phi.interpolate(circle)

    def length(cut):
        form = xfem_contact.form(1.0 * cut.dGamma)
        return mesh.comm.allreduce(dolfinx.fem.assemble_scalar(form))

    exact = 2 * np.pi * 0.3
    default, interpolant, function = (
        length(CutMesh(mesh, levelset, degree=2, exact_zero_set=flag))
        for levelset, flag in ((circle, None), (circle, False), (phi, None))
    )
    print(default - exact, interpolant - exact, function - exact)
    assert abs(interpolant - function) <= 1e-12 * exact
    assert abs(default - exact) < abs(function - exact) / 4, (default, function, exact)
