"""The mechanics in 3D: the material's modes, rigid motions, the friction disc, plain 3D
elasticity against an exact field, and the cut 3D cases (a cube cut by an inclined
plane with an open interface; a sphere under triaxial compression)."""

import dolfinx.fem
import dolfinx.fem.petsc
import dolfinx.mesh
import numpy as np
import pytest
import ufl
from mpi4py import MPI
from parallel import all_ranks_against_one

from xfem_contact.cases.solid import (
    SOLID,
    SPHERE_CENTRE,
    SPHERE_RADIUS,
    TRIAXIAL,
    patch_residual,
    plane_errors,
    plane_problem,
    sphere_errors,
    sphere_problem,
)
from xfem_contact.fem.cutmesh import CutMesh
from xfem_contact.fem.forms import form
from xfem_contact.mechanics.fieldsplit_data import rigid_modes
from xfem_contact.mechanics.laws.base import NUMPY_OPS, UFL_OPS, project_on_disc
from xfem_contact.mechanics.materials import Material, Moduli
from xfem_contact.mechanics.plain import PlainElasticityProblem
from xfem_contact.mechanics.presets import ElasticityProblem
from xfem_contact.mechanics.reactions import balance
from xfem_contact.mechanics.rigid_modes import (
    RigidModeWarning,
    check_rigid_modes,
    check_support,
    free_bodies,
)
from xfem_contact.mechanics.rigid_motions import rigid_motions
from xfem_contact.mechanics.stress import StressFields
from xfem_contact.solvers.options import applied_options, preset


def cube(n=2, cell="tetrahedron"):
    return dolfinx.mesh.create_unit_cube(MPI.COMM_WORLD, n, n, n, dolfinx.mesh.CellType[cell])


def square(n=2):
    return dolfinx.mesh.create_unit_square(MPI.COMM_WORLD, n, n)


@pytest.fixture(scope="module")
def solved_sphere():
    """``solved_sphere(degree, law)``: the triaxial sphere (n = 4) solved once per module;
    the tests that take it only read it."""
    problems = {}

    def get(degree: int, law: str):
        if (degree, law) not in problems:
            problem = sphere_problem(4, degree, law)
            problem.solve()
            problems[degree, law] = problem
        return problems[degree, law]

    return get


def sphere_cut(mesh):
    c, R = SPHERE_CENTRE, SPHERE_RADIUS
    return CutMesh(
        mesh,
        lambda x: np.sqrt((x[0] - c[0]) ** 2 + (x[1] - c[1]) ** 2 + (x[2] - c[2]) ** 2) - R,
        degree=2,
    )


# -- the material's modes ------------------------------------------------------------------
def test_material_modes_follow_the_mesh():
    assert Moduli(Material(1.0, 0.3), cube()).plane == "3d"
    assert Moduli(Material(1.0, 0.3), square()).plane == "strain"
    assert Moduli(Material(1.0, 0.3, "stress"), square()).plane == "stress"
    assert Moduli(Material(1.0, 0.3), cube()).material == Material(1.0, 0.3, "3d")
    # 3D and plane strain share Lame's parameters; plane stress reduces lambda
    assert Material(1.0, 0.3, "3d").lmbda == Material(1.0, 0.3, "strain").lmbda
    assert Material(1.0, 0.3, "stress").lmbda < Material(1.0, 0.3).lmbda


@pytest.mark.parametrize(
    "plane, mesh, words",
    [
        ("strain", cube, "plane='strain' does not exist on a 3D mesh; choices there: ('3d',)"),
        ("stress", cube, "plane='stress' does not exist on a 3D mesh"),
        ("3d", square, "plane='3d' does not exist on a 2D mesh; choices there: ('strain', "),
    ],
)
def test_material_mode_of_another_dimension_is_refused(plane, mesh, words):
    with pytest.raises(ValueError) as error:
        Moduli(Material(1.0, 0.3, plane), mesh())
    assert words in str(error.value) and "\n" not in str(error.value)


def test_plane_mode_refused_by_a_3d_problem():
    with pytest.raises(ValueError, match="plane='stress' does not exist on a 3D mesh"):
        ElasticityProblem(sphere_cut(cube()), 1, Material(1.0, 0.3, "stress"), "bonded")


def test_unknown_mode_is_refused():
    choices = r"plane must be one of \(None, 'strain', 'stress', '3d'\)"
    with pytest.raises(ValueError, match=choices):
        Material(1.0, 0.3, "axisymmetric")


# -- rigid motions ---------------------------------------------------------------------------
def elasticity_matrix(V, material):
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    a = ufl.inner(Moduli(material, V.mesh).stress(u), ufl.sym(ufl.grad(v))) * ufl.dx
    A = dolfinx.fem.petsc.assemble_matrix(dolfinx.fem.form(a))
    A.assemble()
    return A


def test_six_rigid_motions_in_3d_are_killed_by_elasticity():
    """Serial check on a P2 box: the six motions are independent, Hooke's 3D matrix
    maps each to zero, and a strained field (not rigid) is not."""
    mesh = dolfinx.mesh.create_unit_cube(MPI.COMM_SELF, 2, 2, 2)
    V = dolfinx.fem.functionspace(mesh, ("Lagrange", 2, (3,)))
    x = V.tabulate_dof_coordinates()
    Z = rigid_motions(x)  # (nodes, 3, 6)
    assert Z.shape == (x.shape[0], 3, 6)
    modes = Z.reshape(-1, 6)  # a node's components together, as V's dofs
    assert np.linalg.matrix_rank(modes) == 6
    A = elasticity_matrix(V, SOLID)
    scale = A.norm() * np.linalg.norm(modes, axis=0).max()
    vec, y = A.createVecRight(), A.createVecLeft()
    for k in range(6):
        vec.array[:] = modes[:, k]
        A.mult(vec, y)
        assert np.abs(y.array).max() < 1e-12 * scale, k
    stretch = np.zeros_like(x)
    stretch[:, 0] = x[:, 0] * x[:, 1]
    vec.array[:] = stretch.ravel()
    A.mult(vec, y)
    assert np.abs(y.array).max() > 1e-5 * scale
    # 2D: the three of the plane, as the 2D near null space always had
    assert rigid_motions(x[:, :2]).shape == (x.shape[0], 2, 3)


def test_near_null_space_of_each_side_in_3d():
    """The iterative preset's near null space: six motions per side field, each killed
    by the cut problem's Jacobian (both sides, ghost penalty; free interface)."""
    problem = plane_problem(2, 1)
    W = problem.space.W
    J = ufl.derivative(problem.residual(problem.w), problem.w)
    A = dolfinx.fem.petsc.assemble_matrix(form(J))
    A.assemble()
    vec, y = A.createVecRight(), A.createVecLeft()
    n = W.dofmap.index_map.size_local * W.dofmap.index_map_bs
    count = 0
    for mode in rigid_modes(problem.space):
        vec.array[:] = mode.x.array[:n]
        A.mult(vec, y)
        size = problem.mesh.comm.allreduce(np.abs(y.array).max(initial=0.0), op=MPI.MAX)
        assert size < 1e-10 * A.norm(), count
        count += 1
    assert count == 12


def test_rigid_mode_check_in_3d():
    assert check_rigid_modes(sphere_problem(4, 1, "bonded")) == []
    assert check_rigid_modes(plane_problem(2, 1)) == []
    unsupported = ElasticityProblem(sphere_cut(cube(4)), 1, SOLID, "bonded")
    unsupported.loads.add_pressure("boundary", 1.0)
    (message,) = check_rigid_modes(unsupported)
    assert "translations x, y, z" in message and message.count("rotation about") == 3
    assert message.count("loads.add_point_displacement([") == 6
    with pytest.raises(ValueError, match=r"point must be 3 finite numbers \[x, y, z\]"):
        unsupported.loads.add_point_displacement([0.5, 0.5], 0.0, 0)
    with pytest.raises(ValueError, match="add_rotation turns a part in the plane"):
        unsupported.loads.add_rotation("boundary", angle=0.1)


# -- Coulomb's disc -----------------------------------------------------------------------------
def test_disc_projection_pointwise():
    rng = np.random.default_rng(0)
    trial = rng.normal(size=(400, 3))
    bound = np.abs(rng.normal(size=400))
    bound[:20], trial[:10] = 0.0, 0.0  # no contact; and no slip either for ten of them
    P = project_on_disc(trial, bound, NUMPY_OPS)
    size = np.linalg.norm(trial, axis=1)
    inside = size <= bound
    assert inside.sum() > 50 and (~inside).sum() > 50
    assert np.array_equal(P[inside], trial[inside])  # unchanged
    outside = ~inside
    assert np.allclose(np.linalg.norm(P[outside], axis=1), bound[outside], rtol=1e-14, atol=0)
    cosine = np.sum(P[outside] * trial[outside], axis=1)
    assert np.allclose(cosine, bound[outside] * size[outside], rtol=1e-14, atol=0)
    assert np.all(np.isfinite(P)) and np.all(P[:10] == 0.0)
    # gdim 2: a scalar along t, the clamp; the radial formula on one component is the
    # same value to the last bit
    t = rng.normal(size=400) * 2.0
    clamp = project_on_disc(t, bound, NUMPY_OPS)
    assert np.array_equal(clamp, np.maximum(-bound, np.minimum(bound, t)))
    assert np.array_equal(project_on_disc(t[:, None], bound, NUMPY_OPS)[:, 0], clamp)


def test_disc_projection_in_ufl_on_a_3d_mesh():
    """The UFL projection evaluated in a 3D kernel equals numpy's at the same points,
    and its derivative is finite where the trial and the bound vanish."""
    mesh = cube(2)
    x = ufl.SpatialCoordinate(mesh)
    trial = ufl.as_vector([x[0] - 0.5, 2.0 * (x[1] - 0.25), x[2] - x[0]])
    bound = 0.5 * x[1]  # zero on y = 0
    P = project_on_disc(trial, bound, UFL_OPS)
    points = np.array([[0.1, 0.2, 0.3], [0.25, 0.25, 0.25], [0.6, 0.1, 0.1], [0.0, 0.0, 0.0]])
    cells = np.arange(mesh.topology.index_map(3).size_local, dtype=np.int32)
    values = dolfinx.fem.Expression(P, points).eval(mesh, cells).reshape(cells.size, -1, 3)
    X = dolfinx.fem.Expression(x, points).eval(mesh, cells).reshape(-1, 3)
    T = np.c_[X[:, 0] - 0.5, 2.0 * (X[:, 1] - 0.25), X[:, 2] - X[:, 0]]
    expected = project_on_disc(T, 0.5 * X[:, 1], NUMPY_OPS)
    assert np.allclose(values.reshape(-1, 3), expected, rtol=1e-13, atol=1e-15)
    # the derivative where trial = 0 and bound = 0 (a point out of contact that never
    # slipped): finite (at the first vertex of cell 0)
    origin = np.zeros((1, 3))
    X0 = dolfinx.fem.Expression(x, origin).eval(mesh, cells[:1]).ravel()
    t = ufl.variable(x - ufl.as_vector(X0.tolist()))
    dP = ufl.diff(project_on_disc(t, x[1] - X0[1], UFL_OPS), t)
    jac = dolfinx.fem.Expression(dP, origin).eval(mesh, cells[:1])
    assert np.all(np.isfinite(jac))


# -- plain 3D elasticity -------------------------------------------------------------------
def test_plain_3d_elasticity_is_exact_for_a_linear_field():
    """Hooke's 3D law: P1 tets reproduce ``u = G x`` (G not symmetric) to round-off;
    the stress and von Mises fields are those of ``sym(G)`` with 3D Lame parameters."""
    G = np.array([[1.0, 0.2, -0.3], [0.4, -0.5, 0.1], [0.0, 0.3, 0.7]]) * 1e-3
    problem = PlainElasticityProblem(cube(2), 1, Material(200.0, 0.3))
    problem.loads.add_displacement("boundary", lambda x: G @ x)
    problem.solve()
    u = problem.w
    exact = G @ u.function_space.tabulate_dof_coordinates().T
    n = u.function_space.dofmap.index_map.size_local
    assert np.abs(u.x.array.reshape(-1, 3)[:n] - exact.T[:n]).max() < 1e-14
    fields = StressFields([("", problem.material, u)])
    E, nu = 200.0, 0.3
    lmbda, mu = E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))
    eps = 0.5 * (G + G.T)
    sigma = 2 * mu * eps + lmbda * np.trace(eps) * np.eye(3)
    s = sigma - np.trace(sigma) / 3 * np.eye(3)
    assert np.allclose(fields.stress[0].x.array.reshape(-1, 3, 3), sigma, rtol=0, atol=1e-12)
    assert np.allclose(fields.von_mises[0].x.array, np.sqrt(1.5 * np.sum(s * s)), atol=1e-12)


# -- the cut cases -------------------------------------------------------------------------
@pytest.mark.parametrize("cell, n, quadrature", [("tetrahedron", 3, None), ("hexahedron", 2, 8)])
def test_inclined_plane_open_interface_is_exact(cell, n, quadrature):
    """Paper case 1 in 3D: a quadratic field per side, traction-free open interface.
    P2 tets to 6e-15; Q2 hexes to 1e-14 with rules of degree 8, the least with the 5
    Gauss points per interval the cut Q2 stiffness needs (the default 6 and 7 take 4:
    7e-10)."""
    problem = plane_problem(n, 2, cell, quadrature_degree=quadrature)
    problem.solve()
    errors = plane_errors(problem)
    print(f"\ninclined plane {cell} Q2/P2 n={n}: relative L2 errors {errors}")
    assert max(errors.values()) < 1e-10


def test_inclined_plane_degree_one_is_not_exact():
    """The same case with P1 tets: the quadratic field is not in the space."""
    problem = plane_problem(2, 1)
    problem.solve()
    assert min(plane_errors(problem).values()) > 1e-3


def test_sticking_sphere_with_the_quadric_is_a_patch_test():
    """The quadric level set interpolated in P2 is the sphere itself: the exact solution
    (linear displacement, Cartesian multiplier ``sigma (x - c) / R``) lies in the
    discrete space, so what is left is the cut rules' inconsistency. P1 tets, n = 4:
    the exact solution's residual 6.5e-8 of the loads', the pressure error 1.2e-7
    (Saye's boxes with shallow slopes not subdivided: 8.1e-6 and 1.4e-5; rules of
    ``order`` points everywhere: 1.1e-6 and 2.2e-6)."""
    problem = sphere_problem(4, 1, "sticking", levelset="quadric")
    problem.solve()
    e_n, e_t = sphere_errors(problem)
    residual = patch_residual(problem)
    print(f"\nquadric sticking sphere P1 n=4: residual {residual:.2e}, pressure {e_n:.2e}")
    assert residual < 3e-7 and e_n < 1e-6 and e_t < 2e-6
    assert patch_residual(problem) == pytest.approx(residual, rel=1e-6)  # w restored


@pytest.mark.parametrize("law, bound", [("sticking", 2.5e-2), ("bonded", 2.5e-2)])
def test_sphere_triaxial_contact_pressure(solved_sphere, law, bound):
    """Uniform stress diag(-1, -2, -3) Pa: the multiplier is ``sigma n`` (P2 tets,
    n = 4: 1.8e-2 sticking; bench/sphere_triaxial.py gives the rates)."""
    problem = solved_sphere(2, law)
    e_n, e_t = sphere_errors(problem)
    print(f"\nsphere triaxial {law} P2 n=4: pressure error {e_n:.3e}, tangential {e_t:.3e}")
    assert e_n < bound and e_t < 0.1
    state = problem.interface_state(problem.w)
    assert np.asarray(state["slip"]).shape[1] == 3
    samples = problem.interface_samples(problem.w)
    assert set("xyz") <= set(samples) and np.shape(samples["lambda_t"])[1] == 3
    # reactions in 3D: the point constraints carry nothing (the exact field meets them),
    # the pressures balance, the interface transmits sigma n (resultant zero on a sphere)
    summary = balance(problem, problem.w)
    assert len(summary["applied_loads"]) == 3 and summary["balance_relative"] < 1e-10
    assert max(np.abs(r).max() for r in summary["reactions"].values()) < 1e-10


def test_sphere_pressure_error_is_the_geometry_s():
    """With the quadric level set, which P2 holds exactly (the exact sphere and normal),
    the sticking sphere's pressure error at n = 4 is 8.2e-4, against 1.8e-2 for the
    interpolated signed distance: the mechanics reads the traction to the accuracy of
    the geometry it is given. A bad level-set name is refused naming the choices."""
    problem = sphere_problem(4, 2, "sticking", levelset="quadric")
    problem.solve()
    e_n, e_t = sphere_errors(problem)
    assert e_n < 2e-3 and e_t < 5e-3, (e_n, e_t)
    with pytest.raises(ValueError, match=r"levelset must be one of \['distance', 'quadric'\]"):
        sphere_problem(4, 2, "sticking", levelset="cube")


def test_sphere_coulomb_with_a_large_friction_sticks(solved_sphere):
    """The friction limit: with mu = 10 the trial tangential tractions lie inside the
    disc everywhere, and Coulomb's solution is the sticking one."""
    sticking = solved_sphere(1, "sticking")
    coulomb = sphere_problem(4, 1, "coulomb", friction=10.0)
    report = coulomb.solve()
    assert report.iterations <= 3
    a, b = (p.interface_state(p.w) for p in (sticking, coulomb))
    assert np.abs(a["lambda_n"] - b["lambda_n"]).max() < 1e-8 * np.abs(TRIAXIAL).max()
    assert np.abs(a["lambda_t"] - b["lambda_t"]).max() < 1e-8 * np.abs(TRIAXIAL).max()
    assert coulomb.laws[next(iter(coulomb.laws))].status(b)["slip"] == 0


def test_sphere_coulomb_partial_slip():
    """Coulomb with mu = 0.1 under the triaxial load: the sphere slips but near the six
    points where the exact tangential traction vanishes (the axes' poles)."""
    problem = sphere_problem(4, 1, "coulomb", friction=0.1)
    report = problem.solve()
    law = problem.laws["interface"]
    counts = law.status(law.state(problem.contexts["interface"], problem.w))
    print(f"\nsphere Coulomb mu=0.1 P1 n=4: {counts}, {report.iterations} Newton iterations")
    assert report.iterations <= 10
    assert counts["stick"] > 0 and counts["slip"] > 10 * counts["stick"]


@pytest.mark.mpi
@pytest.mark.parallel
@pytest.mark.parametrize("law, options", [("sticking", {}), ("coulomb", {"friction": 0.1})])
def test_sphere_parallel_equals_serial(law, options):
    differences = all_ranks_against_one(
        lambda comm: sphere_problem(4, 1, law, comm=comm, **options)
    )
    if MPI.COMM_WORLD.rank == 0:
        print(law, {k: f"{v:.1e}" for k, v in differences.items()})
    assert all(v <= 1e-10 for v in differences.values()), differences


def test_sphere_frictionless_hydrostatic():
    """Frictionless contact in 3D: under hydrostatic pressure 1 Pa the contact pressure
    is uniform."""
    problem = sphere_problem(4, 2, "frictionless", stress=(-1.0, -1.0, -1.0))
    problem.solve()
    e_n, _ = sphere_errors(problem)
    print(f"\nsphere hydrostatic frictionless P2 n=4: pressure error {e_n:.3e}")
    assert e_n < 1e-2


def test_sphere_spins_under_frictionless_contact_are_a_warning():
    """A frictionless sphere leaves three spins free (n = 8: the discrete sphere locks
    them less than the check's tolerance): a warning naming the three rotations, not an
    error (the 2D rule, one spin, generalised)."""
    problem = sphere_problem(8, 1, "frictionless", stress=(-1.0, -1.0, -1.0))
    (body,) = free_bodies(problem)
    assert body.spin_only and [m.split(" (")[0] for m in body.modes] == ["rotation about"] * 3
    # the remedies hold the three rotations: their velocity rows are independent
    c = np.asarray(SPHERE_CENTRE)
    rows = [[np.cross(w, np.asarray(q) - c)[k] for w in np.eye(3)] for q, k in body.remedies]
    assert len(rows) == 3 and np.linalg.matrix_rank(np.array(rows), tol=1e-3) == 3
    with pytest.warns(RigidModeWarning, match="rotation about .* rotation about .* rotation"):
        check_support(problem)


@pytest.mark.parametrize(
    ("given", "krylov", "coarse"),
    [({}, "fgmres", "gmres"), ({"ksp_type": "gmres"}, "gmres", "richardson")],
)
def test_iterative_preset_in_3d_gives_the_direct_answer(solved_sphere, given, krylov, coarse):
    """The iterative preset (FGMRES, band multigrid with GAMG on six rigid modes per
    side) on the sticking sphere: the direct solver's fields. FGMRES lets the coarse
    level be solved to a relative tolerance (GMRES + GAMG); under GMRES, which needs a
    fixed preconditioner, it is three Richardson iterations of GAMG. The Jacobian and the
    coarse level are stored in 3 x 3 node blocks (GAMG aggregates nodes), the band
    factored LDL^T (the Jacobian is symmetric) and solved by its factors."""
    direct = solved_sphere(2, "sticking")
    iterative = sphere_problem(4, 2, "sticking")
    iterative.petsc_options = preset("iterative") | given
    iterative.solve()
    scale = np.abs(direct.w.x.array).max()
    assert np.abs(iterative.w.x.array - direct.w.x.array).max() < 1e-8 * scale
    newton = iterative.newton
    pc = newton.snes.getKSP().getPC()
    context = pc.getPythonContext()
    assert not context._built  # the blocks released after the Krylov solve
    with applied_options(newton._prefix, newton.options):  # as in a Newton step's set-up
        context.setUp(pc)
    assert newton.snes.getKSP().getType() == krylov
    solve = context.ksp_u.getPC().getMGCoarseSolve()
    assert solve.getType() == coarse
    assert newton.J_r.getType().endswith("baij")
    assert newton.J_r.getBlockSize() == context.A_c.getBlockSize() == 3
    assert context.ksp_band is None  # factored LDL^T: solved by its factors, J_bb released


@pytest.mark.mpi
@pytest.mark.parallel
@pytest.mark.parametrize("degree", [1, 2])
def test_sphere_iterative_parallel_equals_serial(degree):
    """The iterative preset on 1 and 2 ranks: the same fields (gathered by position)."""

    def build(comm):
        problem = sphere_problem(6, degree, "sticking", comm=comm)
        problem.petsc_options = preset("iterative")
        return problem

    differences = all_ranks_against_one(build)
    assert all(v <= 1e-10 for v in differences.values()), differences
