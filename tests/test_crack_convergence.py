"""K converges monotonically on unstructured meshes with the default tip enrichment radius
and the default rings (lengths of the crack, not of the mesh): the Griffith crack (open),
P1 and P2, on two gmsh meshes of the plate against the exact K; the closed inclined crack
with Coulomb friction (``lbb="restriction"``) with P2. P1's closed crack does not yet:
expected to fail (strict)."""

import xfem_contact  # noqa: F401  (before dolfinx)

# isort: split
import pytest
from mpi4py import MPI

from xfem_contact.cases.cracks import MATERIAL, frictional_crack_case, griffith_case
from xfem_contact.fem.tip_scale import tip_cells_size, tip_lengths
from xfem_contact.io.gmsh import read_gmsh
from xfem_contact.mechanics.fracture import TipIntegrals
from xfem_contact.mechanics.problem import Problem
from xfem_contact.scenes.crack_builder import default_rings

WIDTH = 2.0  # the plate's half width (m); the cracks' half length is 1 m
SQUARE = """
Point(1) = {{-{w}, -{w}, 0}}; Point(2) = {{{w}, -{w}, 0}};
Point(3) = {{{w}, {w}, 0}}; Point(4) = {{-{w}, {w}, 0}};
Line(1) = {{1, 2}}; Line(2) = {{2, 3}}; Line(3) = {{3, 4}}; Line(4) = {{4, 1}};
Curve Loop(1) = {{1, 2, 3, 4}}; Plane Surface(1) = {{1}};
Physical Surface("plate") = {{1}}; Physical Curve("boundary") = {{1, 2, 3, 4}};
"""
#: Cell sizes of the two meshes (m): a / 4 and a / 8
SIZES = (0.25, 0.125)


@pytest.fixture(scope="module")
def geo(tmp_path_factory):
    path = tmp_path_factory.mktemp("plate") / "square.geo"
    path.write_text(SQUARE.format(w=WIDTH))
    return path


def errors(build, geo, degree: int, component: int) -> list[list[float]]:
    """Per mesh, per tip and default ring: the relative error of K (``component`` 0: K_I,
    1: K_II) against the exact one, with the default tip enrichment radius."""
    out = []
    for size in SIZES:
        mesh = read_gmsh(geo, MPI.COMM_WORLD, size=size).mesh
        case = build(degree, mesh)
        case.problem.solve()
        results = TipIntegrals(case.problem, default_rings(case.problem)).evaluate()
        exact = case.K[0][component]
        K = [[(r.K_I, r.K_II)[component] for r in tip] for tip in results]
        out.append([abs(k - exact) / abs(exact) for tip in K for k in tip])
    return out


def griffith(degree, mesh):
    return griffith_case(0, degree, tip_radius="auto", width=WIDTH, mesh=mesh)


def closed(degree, mesh):
    return frictional_crack_case(
        0, degree, friction=0.3, tip_radius="auto", width=WIDTH, lbb="restriction", mesh=mesh
    )


#: P1's closed crack, K_II errors per tip and ring at a/4, a/8, a/16 on these meshes:
#: tip 0 4.2e-3, 9.7e-5, 7.2e-4; tip 1 4.5e-4, 3.2e-3, 1.3e-3: P1's floor of about 1e-3
#: (the normal multiplier's RMS deviation from the exact uniform value stays at 1.2e-2,
#: 1.3e-2, 7.5e-3), crossed with changes of sign
P1_CLOSED = pytest.mark.xfail(
    strict=True, reason="P1's closed crack K is not monotone on unstructured meshes yet"
)


@pytest.mark.parametrize(
    ("build", "component", "degree"),
    [
        (griffith, 0, 1),
        (griffith, 0, 2),
        pytest.param(closed, 1, 1, marks=P1_CLOSED),
        (closed, 1, 2),
    ],
    ids=["open-1", "open-2", "closed-1", "closed-2"],
)
def test_K_converges_monotonically(geo, build, component, degree):
    coarse, fine = errors(build, geo, degree, component)
    for before, after in zip(coarse, fine, strict=True):
        assert after < before, f"P{degree}: K errors {coarse} -> {fine}"


def test_default_tip_radius_is_a_length_of_the_crack():
    """``tip_radius="auto"``: half the tip's crack length (the Griffith crack's half length
    a = 1 m, exact), not a length of the mesh; the tip cells when they are larger; a bad
    word is refused naming the choices."""
    for N in (4, 8):
        cut = griffith_case(N, 1, tip_radius="auto").problem.cut
        assert tip_lengths(cut) == pytest.approx([1.0, 1.0], abs=1e-12)
        problem = Problem(cut, 1, MATERIAL, "free", ghost_penalty=0.0)  # the default
        assert problem.space.tip_radius == pytest.approx(0.5, abs=1e-12)
    coarse = griffith_case(1, 1, tip_radius="auto").problem  # cells of diameter 1.41 m
    assert coarse.space.tip_radius == pytest.approx(tip_cells_size(coarse.cut))
    assert coarse.space.tip_radius > 0.5
    with pytest.raises(ValueError, match="tip_radius must be a length .*'auto' or None"):
        griffith_case(4, 1, tip_radius="big")
