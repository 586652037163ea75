"""Several disjoint cracks in one cut (xfem_contact.geometry.crack_union): the cut of each
crack as if alone, its tips named, the mechanics of two cracks (mirror symmetry, the
interaction of two collinear cracks, a bonded crack that is no crack) and the refusals.
"""

import xfem_contact  # noqa: F401  (before dolfinx)

# isort: split
import math

import dolfinx.fem
import dolfinx.mesh
import numpy as np
import pytest
import ufl
from mpi4py import MPI

from xfem_contact.cases.cracks import MATERIAL
from xfem_contact.fem.cutmesh import CutMesh
from xfem_contact.fem.forms import form
from xfem_contact.geometry.crack import TIP
from xfem_contact.geometry.crack_paths import arc, polyline
from xfem_contact.mechanics.fracture import TipIntegrals
from xfem_contact.mechanics.fracture.growth import grow
from xfem_contact.mechanics.materials import Material
from xfem_contact.mechanics.problem import Problem

COMM = MPI.COMM_WORLD


def total(expr) -> float:
    return COMM.allreduce(dolfinx.fem.assemble_scalar(form(expr)), op=MPI.SUM)


def square(n: int, half: float = 2.0, diagonal=dolfinx.mesh.DiagonalType.right):
    corners = [[-half, -half], [half, half]]
    cell = dolfinx.mesh.CellType.triangle
    return dolfinx.mesh.create_rectangle(COMM, corners, [n, n], cell, diagonal=diagonal)


STRAIGHT = polyline([(-1.01, -0.73), (0.61, -0.41)])
CURVED = arc((0.013, 0.021), 1.3, [math.radians(40), math.radians(150)])


@pytest.fixture(scope="module")
def mesh():
    return square(24)


@pytest.mark.mpi
def test_each_crack_is_cut_as_if_alone(mesh):
    """A straight and a curved crack: each crack's lips as long as in a cut by it alone
    (the straight one exactly), the areas exact, the four tips where the paths end,
    named by their crack."""
    (pa, sa), (pb, sb) = STRAIGHT.levelsets(), CURVED.levelsets()
    cut = CutMesh(mesh, {"a": pa, "b": pb}, 2, tangent={"a": sa, "b": sb})
    assert cut.interface_names == ("a", "b")
    a, b = (total(1 * cut.interface_measure(name)) for name in "ab")
    assert a == pytest.approx(STRAIGHT.length, abs=1e-12)
    alone = CutMesh(mesh, pb, 2, tangent=sb)
    assert b == pytest.approx(total(1 * alone.dGamma), abs=1e-12)  # 6.8e-5 from the arc's
    assert b == pytest.approx(CURVED.length, rel=1e-4)
    assert total(1 * cut.dGamma) == pytest.approx(a + b, abs=1e-12)
    assert total(1 * cut.dx(-1)) + total(1 * cut.dx(1)) == pytest.approx(16.0, abs=1e-11)
    kinds = COMM.allreduce(np.bincount(cut.crack.kind, minlength=3), op=MPI.SUM)
    assert kinds[TIP] == 4
    found = list(zip(cut.crack.tips, cut.crack.tip_names, strict=True))
    assert len(found) == 4
    for name, points in (("a", STRAIGHT.ends), ("b", alone.crack.tips)):
        for point in points:  # the arc's tips as found alone (its ends within 1e-4)
            (match,) = [n for t, n in found if np.allclose(t, point, atol=1e-12)]
            assert match == name
    assert np.allclose(
        sorted(map(tuple, alone.crack.tips)), sorted(map(tuple, CURVED.ends)), atol=1e-4
    )
    # the lip measure of one crack holds none of the other's lips
    below = ufl.conditional(ufl.lt(ufl.SpatialCoordinate(mesh)[1], 0.0), 1.0, 0.0)
    assert total(below * cut.interface_measure("a")) == pytest.approx(a, abs=1e-12)
    assert total(below * cut.interface_measure("b")) == 0.0  # crack b lies above y = 0.8


def test_functions_as_level_sets(mesh):
    """Level sets given as Functions: the same straight lips, the same tips."""
    V = dolfinx.fem.functionspace(mesh, ("Lagrange", 2))
    fields = {}
    for name, path in (("a", STRAIGHT), ("b", polyline([(0.31, 0.83), (1.41, 1.21)]))):
        for which, f in zip(("phi", "psi"), path.levelsets(), strict=True):
            fields[which, name] = dolfinx.fem.Function(V)
            fields[which, name].interpolate(f)
    cut = CutMesh(
        mesh,
        {n: fields["phi", n] for n in "ab"},
        2,
        tangent={n: fields["psi", n] for n in "ab"},
    )
    length_b = math.dist((0.31, 0.83), (1.41, 1.21))
    assert total(1 * cut.interface_measure("a")) == pytest.approx(STRAIGHT.length, abs=1e-12)
    assert total(1 * cut.interface_measure("b")) == pytest.approx(length_b, abs=1e-12)
    expected = sorted(map(tuple, [*STRAIGHT.ends, (0.31, 0.83), (1.41, 1.21)]))
    assert np.allclose(sorted(map(tuple, cut.crack.tips)), expected, atol=1e-12)


def test_update_moves_the_cracks(mesh):
    cracks = {"a": STRAIGHT, "b": polyline([(0.31, 0.83), (1.41, 1.21)])}
    cut = CutMesh(
        mesh,
        {n: p.levelsets()[0] for n, p in cracks.items()},
        2,
        tangent={n: p.levelsets()[1] for n, p in cracks.items()},
    )
    moved = {n: polyline(p.ends + [0.043, 0.029]) for n, p in cracks.items()}
    cut.update(
        {n: p.levelsets()[0] for n, p in moved.items()},
        {n: p.levelsets()[1] for n, p in moved.items()},
    )
    expected = sorted(map(tuple, np.concatenate([p.ends for p in moved.values()])))
    assert np.allclose(sorted(map(tuple, cut.crack.tips)), expected, atol=1e-12)
    with pytest.raises(ValueError, match=r"^levelset: update\(\) needs the cracks \['a', 'b'\]"):
        cut.update({"a": STRAIGHT.levelsets()[0]}, {"a": STRAIGHT.levelsets()[1]})


def test_crossing_and_near_cracks_are_refused(mesh):
    """Crossing cracks, cracks a cell apart, and a crack with no psi: a ValueError
    naming the argument and the cracks."""
    pa, sa = STRAIGHT.levelsets()
    crossing = polyline([(-0.5, -1.5), (0.0, 0.5)]).levelsets()
    with pytest.raises(ValueError, match=r"^levelset: cracks 'a' and 'c' come within 0\.0"):
        CutMesh(mesh, {"a": pa, "c": crossing[0]}, 2, tangent={"a": sa, "c": crossing[1]})
    near = polyline([(-1.01, -0.53), (0.61, -0.21)]).levelsets()  # 0.2 m: one cell
    with pytest.raises(ValueError, match="touching or crossing cracks are not handled"):
        CutMesh(mesh, {"a": pa, "c": near[0]}, 2, tangent={"a": sa, "c": near[1]})
    circle = lambda x: np.hypot(x[0] - 1.0, x[1] - 1.0) - 0.3  # noqa: E731
    with pytest.raises(ValueError, match=r"^tangent: several cracks take a mapping"):
        CutMesh(mesh, {"a": pa, "inclusion": circle}, 2, tangent={"a": sa})
    around = lambda x: np.hypot(x[0] + 0.2, x[1] + 0.6) - 1.5  # noqa: E731
    with pytest.raises(ValueError, match=r"^levelset: crack 'a' enters the inside of interf"):
        CutMesh(mesh, {"a": pa, "inclusion": around}, 2, tangent={"a": sa, "inclusion": None})


# -- mechanics: two collinear cracks of half length A centred at (+-XC, Y0) ---------------
A, XC, Y0, W = 0.4, 1.0, 0.0271, 2.0


def CIRCLE(x):
    """An inclusion of radius 0.5 m left of the crack at XC (1.3 m between them)."""
    return np.hypot(x[0] + 1.2013, x[1] - 0.0187) - 0.5


RINGS = [(0.15, 0.35)]


def plate(centres, law="free", tip_radius=0.25, n=32, inclusion=None):
    """The plate of half width W (crossed triangles: mirror symmetric about x = 0) with
    horizontal cracks at ``centres``, pulled by 1 Pa on top and bottom; solved. With an
    ``inclusion`` material: the circle :data:`CIRCLE` of it, named ``inc``."""
    mesh = square(n, W, dolfinx.mesh.DiagonalType.crossed)
    phi = {f"c{i}": (lambda x: x[1] - Y0) for i, _ in enumerate(centres)}
    psi = {f"c{i}": (lambda x, c=c: np.abs(x[0] - c) - A) for i, c in enumerate(centres)}
    materials = MATERIAL
    if inclusion is not None:
        phi["inc"], psi["inc"] = CIRCLE, None
        materials = {-1: {**dict.fromkeys(psi, MATERIAL), "inc": inclusion}, 1: MATERIAL}
    cut = CutMesh(mesh, phi, 2, tangent=psi)
    problem = Problem(cut, 2, materials, law, tip_radius=tip_radius)
    problem.loads.add_traction(lambda x: np.isclose(x[1], W), (0.0, 1.0))
    problem.loads.add_traction(lambda x: np.isclose(x[1], -W), (0.0, -1.0))
    for component in (0, 1):
        problem.loads.add_point_displacement((-W, -W), 0.0, component)
    problem.loads.add_point_displacement((W, -W), 0.0, 1)
    problem.solve()
    return problem


def K_by_tip(problem) -> dict:
    """``{(round(x, 6), crack name): (K_I, K_II) / sqrt(pi A)}`` on the ring."""
    crack = problem.cut.crack
    results = TipIntegrals(problem, RINGS).evaluate()
    scale = math.sqrt(math.pi * A)
    return {
        (round(float(tip[0]), 6), name): (r[0].K_I / scale, r[0].K_II / scale)
        for tip, name, r in zip(crack.tips, crack.tip_names, results, strict=True)
    }


def collinear_interaction(b: float, c: float) -> tuple[float, float]:
    """K_I of the inner (``|x| = b``) and outer (``|x| = c``) tips of two collinear
    cracks ``b < |x| < c`` in an infinite plate under remote tension, over that of one
    crack of the same length (Tada, Paris & Irwin, with the complete elliptic integrals
    of ``m = 1 - b^2/c^2``)."""
    t = np.linspace(0.0, math.pi / 2, 200001)
    m = 1 - b * b / (c * c)
    K = np.trapezoid(1 / np.sqrt(1 - m * np.sin(t) ** 2), t)
    E = np.trapezoid(np.sqrt(1 - m * np.sin(t) ** 2), t)
    lam2 = c * c * E / K
    a = (c - b) / 2
    inner = math.sqrt(math.pi / b) * (lam2 - b * b) / math.sqrt(c * c - b * b)
    outer = math.sqrt(math.pi / c) * (c * c - lam2) / math.sqrt(c * c - b * b)
    return inner / math.sqrt(math.pi * a), outer / math.sqrt(math.pi * a)


@pytest.fixture(scope="module")
def single():
    return K_by_tip(plate([XC]))


@pytest.fixture(scope="module")
def two():
    return plate([-XC, XC])


@pytest.mark.mpi
def test_two_mirrored_cracks(single, two):
    """Two equal cracks mirrored about the plate's centre line: K_I equal at mirrored
    tips (1e-5 measured), and each tip's K_I over that of the crack alone in the plate
    the interaction of two collinear cracks in an infinite plate (inner tips: 1.0244
    here, 1.0272 in the infinite plate; outer tips 1.0006 and 1.018, the plate's edge
    dominating)."""
    K = K_by_tip(two)
    assert sorted(K) == [(-1.4, "c0"), (-0.6, "c0"), (0.6, "c1"), (1.4, "c1")]
    for x in (0.6, 1.4):
        assert K[-x, "c0"][0] == pytest.approx(K[x, "c1"][0], rel=1e-4)
        assert abs(K[x, "c1"][1]) < 1e-3 * K[x, "c1"][0]
    inner, _ = collinear_interaction(XC - A, XC + A)
    assert K[0.6, "c1"][0] / single[0.6, "c0"][0] == pytest.approx(inner, abs=0.01)
    assert K[0.6, "c1"][0] / single[0.6, "c0"][0] > 1.015  # the cracks interact
    assert K[1.4, "c1"][0] / single[1.4, "c0"][0] == pytest.approx(1.0, abs=0.01)


def test_a_bonded_crack_is_no_crack(single):
    """Crack c1 bonded, c0 free: c0's K_I is that of a crack alone (mirrored), c1's ~0."""
    K = K_by_tip(plate([-XC, XC], law={"c0": "free", "c1": "bonded"}))
    for x in (0.6, 1.4):
        assert K[-x, "c0"][0] == pytest.approx(single[x, "c0"][0], rel=1e-4)
        assert abs(K[x, "c1"][0]) < 5e-3 * single[x, "c0"][0]


def test_tip_zones_rings_and_growth_refused_for_several(two):
    with pytest.raises(ValueError, match=r"^tip_radius = 0\.3 m: the tip enrichment of cracks"):
        plate([-XC, XC], tip_radius=0.3)  # 0.3 + h = 0.425 > 0.4, a third of the gap
    problem = two
    with pytest.raises(ValueError, match=r"^rings: r_sup = 1\.5 m reaches another crack"):
        TipIntegrals(problem, [(0.3, 1.5)])
    with pytest.raises(NotImplementedError, match=r"^problem: grow\(\) moves one crack"):
        grow(problem, polyline([(0.6, Y0), (1.4, Y0)]), 0.1, RINGS)


@pytest.mark.mpi
def test_a_closed_interface_among_cracks(single):
    """A circular inclusion (``psi = None``) bonded next to crack c0: of the body's own
    material it is no inclusion (K as the crack alone, 5e-10 measured), ten times stiffer
    it moves K (by 0.4 and 1.2 %: its material is where it should be, which the cells'
    regions check too)."""
    K = K_by_tip(plate([XC], law={"c0": "free", "inc": "bonded"}, inclusion=MATERIAL))
    for key, (K_I, _) in single.items():
        assert K[key][0] == pytest.approx(K_I, rel=1e-8)
    stiff = Material(10 * MATERIAL.E, MATERIAL.nu, MATERIAL.plane)
    problem = plate([XC], law={"c0": "free", "inc": "bonded"}, inclusion=stiff)
    cut = problem.cut
    assert cut.interface_names == ("c0", "inc") and cut.crack.union.interfaces == ("inc",)
    assert cut.crack.tip_names == ("c0", "c0")
    K = K_by_tip(problem)
    for key, (K_I, _) in single.items():
        assert abs(K[key][0] / K_I - 1) > 3e-3
    owned = np.arange(cut.cell_sides.size, dtype=np.int32)
    x = dolfinx.mesh.compute_midpoints(cut.mesh, 2, owned).T
    regions = cut.cell_regions()
    region = regions.x.array[regions.function_space.dofmap.list[owned, 0]]
    minus = cut.cell_sides == -1
    assert np.array_equal(region[minus] == 1, CIRCLE(x)[minus] < 0)
    # cells cut away from the circle (the crack's, and those between the circle's zone and
    # the crack's where phi changes sign): their side -1 is the body's
    away = (cut.cell_sides == 0) & (np.abs(CIRCLE(x)) > 0.3)
    between = np.count_nonzero(away & (np.abs(x[1] - Y0) > 0.3))  # between the zones
    assert COMM.allreduce(between, op=MPI.SUM) > 0
    assert np.all(region[away] == 0)
    assert total(1 * cut.interface_measure("inc")) == pytest.approx(math.pi, rel=1e-4)
