"""Free rigid modes found before solving: bodies no Dirichlet condition or interface
law holds, by name, with their modes and the point constraints that remove them."""

import dolfinx.mesh
import numpy as np
import pytest
from mpi4py import MPI

from xfem_contact.cases.paper import inclusion_problem
from xfem_contact.fem.cutmesh import CutMesh
from xfem_contact.mechanics.materials import Material
from xfem_contact.mechanics.problem import Problem
from xfem_contact.mechanics.rigid_modes import check_rigid_modes, free_bodies

INSIDE = "side -1 (inside interface 'interface')"
OUTSIDE = "side +1 (outside interface 'interface')"
#: The point constraints of paper case 2 (inclusion_problem): u_x at two points, u_y at one
PAPER_POINTS = [([0.5, 0.0], 0), ([0.5, 1.0], 0), ([0.0, 0.5], 1)]


def on_boundary(x):
    return np.isclose(x[0], 0) | np.isclose(x[0], 1) | np.isclose(x[1], 0) | np.isclose(x[1], 1)


def case2(law, points=PAPER_POINTS, outer_fixed=False, **options):
    """Paper case 2 with the given point constraints only (or the outer boundary fixed)."""
    options = {k: v for k, v in options.items() if v is not None}
    problem = inclusion_problem(10, 2, law, **options)
    problem.loads.bcs.clear()
    for point, component in points:
        problem.loads.add_point_displacement(point, 0.0, component)
    if outer_fixed:
        problem.loads.add_displacement(on_boundary, 0.0)
    return problem


def check(problem) -> list[str]:
    """check_rigid_modes, with the same answer on every process."""
    messages = check_rigid_modes(problem)
    assert problem.mesh.comm.allgather(messages) == [messages] * problem.mesh.comm.size
    return messages


def fixed_by_the_remedies(problem) -> bool:
    """Whether the point constraints the check proposes leave nothing free."""
    for body in free_bodies(problem):
        for point, component in body.remedies:
            problem.loads.add_point_displacement(point, 0.0, component)
    return check(problem) == []


@pytest.mark.mpi
@pytest.mark.parametrize("law", ["sticking", "coulomb", "bonded"])
def test_case2_with_its_point_constraints_is_held(law):
    options = {"friction": 1.0} if law == "coulomb" else {}
    assert check(inclusion_problem(10, 2, law, **options)) == []


@pytest.mark.mpi
def test_without_point_constraints_the_plate_and_inclusion_are_free():
    (message,) = check(case2("sticking", points=[]))
    assert message.startswith(
        f"{OUTSIDE}: translations x, y and rotation about (0.5, 0.5) are not constrained "
        "(no Dirichlet condition; interface 'interface' is sticking: it ties the two sides; "
        f"it moves together with {INSIDE}); fix them with loads.add_point_displacement("
    )
    assert fixed_by_the_remedies(case2("sticking", points=[]))


@pytest.mark.mpi
@pytest.mark.parametrize(
    "dropped, mode",
    [(1, "rotation about (0, 0)"), (2, "translation y"), (0, "rotation about (0, 1)")],
    ids=["no second u_x", "no u_y", "no first u_x"],
)
def test_one_point_constraint_less_frees_one_mode(dropped, mode):
    points = [p for i, p in enumerate(PAPER_POINTS) if i != dropped]
    (message,) = check(case2("sticking", points=points))
    assert message.startswith(f"{OUTSIDE}: {mode} is not constrained (Dirichlet conditions")
    assert fixed_by_the_remedies(case2("sticking", points=points))


@pytest.mark.mpi
@pytest.mark.parametrize("points, outer_fixed", [([], True), (PAPER_POINTS, False)])
def test_a_frictionless_circle_leaves_the_inclusion_free_to_spin(points, outer_fixed):
    """Only the spin: the normal contact holds the inclusion's translations."""
    (message,) = check(case2("frictionless", points, outer_fixed))
    assert message.startswith(
        f"{INSIDE}: rotation about (0.5, 0.5) is not constrained (no Dirichlet condition; "
        "interface 'interface' is frictionless: it transmits no tangential traction); "
        "fix it with loads.add_point_displacement("
    )
    assert fixed_by_the_remedies(case2("frictionless", points, outer_fixed))


@pytest.mark.mpi
@pytest.mark.parametrize("law, friction", [("sticking", None), ("coulomb", 0.3), ("bonded", None)])
def test_laws_that_tie_the_sides_hold_the_inclusion(law, friction):
    assert check(case2(law, [], outer_fixed=True, friction=friction)) == []


def test_coulomb_without_friction_is_frictionless():
    (message,) = check(case2("coulomb", [], outer_fixed=True, friction=0.0))
    assert message.startswith(f"{INSIDE}: rotation about (0.5, 0.5) is not constrained")


def test_a_free_interface_leaves_the_inclusion_free():
    (message,) = check(case2("free", [], outer_fixed=True))
    assert message.startswith(
        f"{INSIDE}: translations x, y and rotation about (0.5, 0.5) are not constrained "
        "(no Dirichlet condition; interface 'interface' is free: it transmits nothing)"
    )
    assert fixed_by_the_remedies(case2("free", [], outer_fixed=True))


@pytest.mark.mpi
def test_an_elliptic_frictionless_inclusion_is_locked_by_its_shape():
    problem = Problem(
        CutMesh(
            dolfinx.mesh.create_unit_square(MPI.COMM_WORLD, 12, 12),
            lambda x: np.hypot((x[0] - 0.5) / 0.3, (x[1] - 0.5) / 0.2) - 1.0,
        ),
        2,
        Material(1e6, 0.3),
        "frictionless",
    )
    problem.loads.add_displacement(on_boundary, 0.0)
    assert check(problem) == []


def test_a_spin_left_by_a_frictionless_interface_is_told_from_a_missing_support():
    (spin,) = free_bodies(case2("frictionless", [], outer_fixed=True))
    (support,) = free_bodies(case2("sticking", [PAPER_POINTS[0], PAPER_POINTS[2]]))
    (free,) = free_bodies(case2("free", [], outer_fixed=True))
    assert spin.spin_only and spin.modes == ["rotation about (0.5, 0.5)"]
    assert not support.spin_only and support.modes == ["rotation about (0, 0)"]
    assert not free.spin_only


def straight(law):
    """Two blocks on y = 1 (not a mesh line): the lower one clamped at y = 0."""
    mesh = dolfinx.mesh.create_rectangle(
        MPI.COMM_WORLD, [[0.0, 0.0], [2.0, 2.0]], [8, 7], dolfinx.mesh.CellType.quadrilateral
    )
    cut = CutMesh(mesh, lambda x: x[1] - 1.0, degree=1)
    problem = Problem(cut, 1, Material(1e6, 0.3), law)
    problem.loads.add_displacement(lambda x: np.isclose(x[1], 0.0), 0.0)
    return problem


@pytest.mark.mpi
def test_a_straight_frictionless_interface_lets_the_upper_block_slide():
    """The same question on another geometry: the normal contact holds the upper block's
    lift and rotation, not its sliding."""
    (message,) = check(straight("frictionless"))
    assert message.startswith(
        "side +1 (outside interface 'interface'): translation x is not constrained "
        "(no Dirichlet condition; interface 'interface' is frictionless"
    )
    assert check(straight("sticking")) == []
    assert fixed_by_the_remedies(straight("frictionless"))


@pytest.mark.mpi
def test_each_inclusion_is_a_body():
    """Two inclusions with their own laws in a clamped plate: only the frictionless one
    spins, named by its interface, about its own centre."""
    mesh = dolfinx.mesh.create_unit_square(MPI.COMM_WORLD, 16, 16)
    cut = CutMesh(
        mesh,
        {
            "left": lambda x: np.hypot(x[0] - 0.28, x[1] - 0.5) - 0.12,
            "right": lambda x: np.hypot(x[0] - 0.72, x[1] - 0.5) - 0.12,
        },
    )
    problem = Problem(cut, 2, Material(1e6, 0.3), {"left": "sticking", "right": "frictionless"})
    problem.loads.add_displacement(on_boundary, 0.0)
    (message,) = check(problem)
    assert message.startswith(
        "side -1 (inside interface 'right'): rotation about (0.72, 0.5) is not constrained "
        "(no Dirichlet condition; interface 'right' is frictionless"
    )


# -- what Problem.solve does with them ------------------------------------------------------


def test_solve_refuses_a_body_without_support():
    """Instead of Newton iterates ending in a SNES failure: one error naming the modes."""
    problem = case2("sticking", points=[])
    with pytest.raises(
        ValueError, match="Free rigid modes: .*translations x, y.*add_point_displacement"
    ):
        problem.solve()


def test_solve_warns_of_a_free_spin():
    """A frictionless circle carries no torque: the solve warns, names the point
    constraints that would remove the spin, and goes on."""
    from xfem_contact.mechanics.rigid_modes import RigidModeWarning

    problem = case2("frictionless", outer_fixed=True)
    with pytest.warns(RigidModeWarning, match="rotation.*add_point_displacement"):
        problem.solve()


# -- cracks: the two sides are one body where the crack ends inside it -----------------------


def cracked_plate(half: float, n: int = 64, supports: bool = True) -> Problem:
    """A square plate of half width 2 (P1, n cells a side) with a short inclined crack of
    half length ``half`` about its centre, pulled down by 1 Pa on its top, held by a pin
    at its lower left corner and a roller at its lower right one (statically determinate:
    the roller carries half the load, whatever the crack)."""
    from xfem_contact.geometry.crack_paths import polyline

    mesh = dolfinx.mesh.create_rectangle(MPI.COMM_WORLD, [[-2.0, -2.0], [2.0, 2.0]], [n, n])
    centre, d = np.array([0.0123, 0.0271]), np.array([np.cos(0.3), np.sin(0.3)])
    phi, psi = polyline([centre - half * d, centre + half * d]).levelsets()
    cut = CutMesh(mesh, phi, degree=1, tangent=psi)
    problem = Problem(cut, 1, Material(1.0, 0.3), "free", ghost_penalty=0.0)
    problem.loads.add_traction(lambda x: np.isclose(x[1], 2.0), (0.0, -1.0))
    if supports:
        for point, component in (([-2.0, -2.0], 0), ([-2.0, -2.0], 1), ([2.0, -2.0], 1)):
            problem.loads.add_point_displacement(point, 0.0, component)
    return problem


@pytest.mark.mpi
def test_a_pin_and_a_roller_hold_a_plate_with_a_short_crack():
    """The lips hold nothing (a free crack): the two sides are joined beyond the tips.
    Before, they were two bodies joined along the lips only: the crack being short
    (a / R = 0.05), their relative rotation was judged free and a third support asked
    for."""
    from xfem_contact.mechanics.reactions import balance, residual_vector, unit_vectors

    problem = cracked_plate(0.07)
    assert check(problem) == []
    assert problem.solve().converged
    result = balance(problem, problem.w)
    assert result["balance_relative"] < 1e-10
    assert result["reactions"]["point displacement"] == pytest.approx([0.0, 4.0], abs=1e-9)
    vec = residual_vector(problem, problem.w)
    dofs, owned = problem.loads.bcs[2].dof_indices()  # the roller's
    roller = vec.array_r[dofs[:owned]] @ unit_vectors(problem)[1][dofs[:owned]]
    vec.destroy()
    # half of the 4 N/m on the top, as statics says
    assert problem.mesh.comm.allreduce(roller, op=MPI.SUM) == pytest.approx(2.0, rel=1e-9)


@pytest.mark.mpi
def test_a_cracked_plate_without_support_is_one_free_body():
    """Its three modes, fixed by three point constraints (not one more)."""
    problem = cracked_plate(0.07, supports=False)
    (body,) = free_bodies(problem)
    assert body.message().startswith(
        "the body cracked by 'interface': translations x, y and rotation about (0, 0) are not "
        "constrained (no Dirichlet condition; interface 'interface' is free: it transmits nothing)"
    )
    assert len(body.remedies) == 3
    assert fixed_by_the_remedies(problem)


@pytest.mark.mpi
def test_a_line_cutting_the_body_in_two_leaves_two_bodies():
    """A free line from edge to edge (given as an interface among the cracks) cuts off the
    top of a plate held at its bottom: that part is free, named and fixed by three point
    constraints (the cracks' laws used to be taken as tying every side together)."""
    from xfem_contact.geometry.crack_paths import polyline

    mesh = dolfinx.mesh.create_rectangle(MPI.COMM_WORLD, [[-2.0, -2.0], [2.0, 2.0]], [24, 24])
    phi, psi = polyline([(-0.61, -1.12), (0.43, -0.91)]).levelsets()
    cut = CutMesh(
        mesh, {"a": phi, "b": lambda x: 1.013 - x[1]}, degree=1, tangent={"a": psi, "b": None}
    )
    material = Material(1.0, 0.3)
    materials = {-1: {"a": material, "b": material}, 1: material}
    problem = Problem(cut, 1, materials, {"a": "free", "b": "free"}, ghost_penalty=0.0)
    for point, component in (([-2.0, -2.0], 0), ([-2.0, -2.0], 1), ([2.0, -2.0], 1)):
        problem.loads.add_point_displacement(point, 0.0, component)
    (body,) = free_bodies(problem)
    assert body.message().startswith(
        "side -1 (inside interface 'b'): translations x, y and rotation about (0, 1.51) are not "
        "constrained (no Dirichlet condition; interface 'b' is free: it transmits nothing)"
    )
    assert len(body.remedies) == 3
    assert fixed_by_the_remedies(problem)


@pytest.mark.parametrize("cell", ["quadrilateral", "triangle"])
def test_body_centroid_and_radius_of_gyration_are_exact(cell):
    """The bodies' centroids and radii of gyration (the scale of their rotations): the
    disc of radius r about (0.5, 0.5), r / sqrt(2); the unit square without it,
    sqrt((1/6 - pi r^4 / 2) / (1 - pi r^2)); the cell maps at one rule in every uncut
    cell (tabulated once) equal to the maps at each point."""
    import basix

    from xfem_contact.mechanics.rigid_modes import _centroid

    problem = inclusion_problem(20, 2, "frictionless", cell)
    cut, r = problem.cut, 0.2
    owned = np.arange(cut.cell_sides.size, dtype=np.int32)
    none = np.zeros(0, dtype=np.int32)
    inside = _centroid(cut, {0: owned[cut.cell_sides <= 0], 1: none})
    outside = _centroid(cut, {0: none, 1: owned[cut.cell_sides >= 0]})
    exact = np.sqrt((1 / 6 - np.pi * r**4 / 2) / (1 - np.pi * r**2))
    for (centre, radius), expected in ((inside, r / np.sqrt(2)), (outside, exact)):
        np.testing.assert_allclose(centre, [0.5, 0.5], atol=1e-6)
        assert abs(radius - expected) < 1e-5 * expected  # the P2 level set's circle
    X, _ = basix.make_quadrature(cut.mesh.basix_cell(), 2)
    cells = owned[:50]
    at_points = (np.repeat(cells, X.shape[0]), np.tile(X, (cells.size, 1)))
    np.testing.assert_allclose(
        cut.maps.jacobian_lattice(cells, X), cut.maps.jacobian(*at_points), atol=1e-15
    )
