"""3D validation cases with exact solutions: a unit cube cut by an inclined plane with an
open interface (the analogue of paper case 1) and a sphere in a unit cube under triaxial
compression (the analogue of case 2). Shared by the tests and the benchmarks (SI
units, tension positive)."""

from __future__ import annotations

import dolfinx.mesh
import numpy as np
import ufl
from mpi4py import MPI

from xfem_contact.cases.body_fitted import mesh_geo
from xfem_contact.cases.paper import integrate
from xfem_contact.fem.cutmesh import CutMesh
from xfem_contact.fem.evaluation import interface_points, rule_cells
from xfem_contact.mechanics.materials import Material
from xfem_contact.mechanics.presets import ContactProblem, ElasticityProblem

#: The inclined plane ``a.x = d`` (``a`` a unit vector): off every mesh vertex of the
#: unit cubes ``n = 1 .. 8``
PLANE_NORMAL = np.array([0.3, 0.5, 0.8]) / np.linalg.norm([0.3, 0.5, 0.8])
PLANE_OFFSET = float(PLANE_NORMAL @ np.full(3, 0.5)) + 0.013
#: The uniform stress factors ``S_s`` of ``sigma_s = (a.x - d) S_s`` on each side (Pa/m)
PLANE_STRESS = {
    -1: np.array([[2.0, 0.5, -0.3], [0.5, -1.0, 0.2], [-0.3, 0.2, 1.5]]),
    1: np.array([[-1.0, 0.3, 0.4], [0.3, 2.0, -0.6], [0.4, -0.6, 0.5]]),
}
#: The opening of side +1 along ``a`` (m), much larger than the elastic jump
PLANE_OPENING = 1e-2
#: The material of the 3D cases
SOLID = Material(100.0, 0.3)

#: Sphere case: centre (m), radius (m), principal stresses (Pa) along x, y, z
SPHERE_CENTRE, SPHERE_RADIUS = (0.5, 0.5, 0.5), 0.2
TRIAXIAL = (-1.0, -2.0, -3.0)

#: The unit cube for gmsh (OpenCASCADE) with a geometry point embedded at the centre of
#: each face (mesh nodes for the point constraints of :func:`uniform_stress_problem`);
#: the boundary parts ``left``/``right`` (x = 0, 1), ``bottom``/``top`` (y),
#: ``back``/``front`` (z), the cells ``cube``; format with the cell size ``h`` (m)
UNIT_CUBE_GEO = """SetFactory("OpenCASCADE");
lc = {h};
Box(1) = {{0, 0, 0, 1, 1, 1}};
Point(101) = {{0, 0.5, 0.5, lc}}; Point(102) = {{1, 0.5, 0.5, lc}};
Point(103) = {{0.5, 0, 0.5, lc}}; Point(104) = {{0.5, 1, 0.5, lc}};
Point(105) = {{0.5, 0.5, 0, lc}}; Point(106) = {{0.5, 0.5, 1, lc}};
Point{{101}} In Surface{{1}}; Point{{102}} In Surface{{2}}; Point{{103}} In Surface{{3}};
Point{{104}} In Surface{{4}}; Point{{105}} In Surface{{5}}; Point{{106}} In Surface{{6}};
MeshSize{{PointsOf{{Volume{{1}};}}}} = lc;
Physical Surface("left", 1) = {{1}}; Physical Surface("right", 2) = {{2}};
Physical Surface("bottom", 3) = {{3}}; Physical Surface("top", 4) = {{4}};
Physical Surface("back", 5) = {{5}}; Physical Surface("front", 6) = {{6}};
Physical Volume("cube", 7) = {{1}};
"""


def _strain_factor(side: int, material: Material) -> np.ndarray:
    """``M_s``: the strain ``(a.x - d) M_s`` of the stress ``(a.x - d) S_s`` (1/m)."""
    S, mu, lmbda = PLANE_STRESS[side], material.mu, material.lmbda
    return (S - lmbda / (2 * mu + 3 * lmbda) * np.trace(S) * np.eye(3)) / (2 * mu)


def plane_exact(side: int, ops=np, material: Material = SOLID):
    """The exact displacement (m) of ``side`` of the plane case,
    ``u = (a.x - d) M x - (x.M x) a / 2`` (its strain is ``(a.x - d) M``, its stress
    ``(a.x - d) S_s``), side +1 moved by ``PLANE_OPENING a``: a callable of points ``x``
    (numpy ``(3, n)`` giving ``(3, n)``, or with ``ops=ufl`` the spatial coordinate
    giving a UFL vector)."""
    M, a, d = _strain_factor(side, material), PLANE_NORMAL, PLANE_OFFSET
    shift = PLANE_OPENING * a if side == 1 else np.zeros(3)

    def u(x):
        x = [x[k] for k in range(3)]
        phi = sum(a[k] * x[k] for k in range(3)) - d
        Mx = [sum(M[i, k] * x[k] for k in range(3)) for i in range(3)]
        xMx = sum(x[i] * Mx[i] for i in range(3))
        values = [phi * Mx[i] - 0.5 * xMx * a[i] + shift[i] for i in range(3)]
        return ops.as_vector(values) if ops is not np else np.array(values)

    return u


def plane_problem(
    n: int,
    degree: int,
    cell: str = "tetrahedron",
    comm: MPI.Comm = MPI.COMM_WORLD,
    quadrature_degree: int | None = None,
) -> ElasticityProblem:
    """The unit cube (``n`` cells per edge) cut by the plane ``a.x = d``, free (open)
    interface, each side loaded by the body force ``-div sigma_s = -S_s a`` and held on
    the whole boundary by its exact displacement (:func:`plane_exact`): the solution is
    quadratic on each side, the interface traction-free and open (its gap
    ``PLANE_OPENING`` plus the elastic jump, > 0). ``quadrature_degree``: the cut
    rules' (:class:`~xfem_contact.fem.cutmesh.CutMesh`'s default when None)."""
    mesh = dolfinx.mesh.create_unit_cube(comm, n, n, n, dolfinx.mesh.CellType[cell])
    a, d = PLANE_NORMAL, PLANE_OFFSET
    cut = CutMesh(
        mesh,
        lambda x: a[0] * x[0] + a[1] * x[1] + a[2] * x[2] - d,
        degree=1,
        quadrature_degree=quadrature_degree,
    )
    problem = ElasticityProblem(cut, degree, SOLID, "free")
    problem.loads.add_displacement("boundary", {s: plane_exact(s) for s in (-1, 1)})
    for side in (-1, 1):
        problem.loads.add_body_force(tuple(-PLANE_STRESS[side] @ a), side=side)
    return problem


def plane_errors(problem: ElasticityProblem) -> dict[int, float]:
    """Relative L2 error of each side's displacement on its own part of the cube, against
    :func:`plane_exact` (UFL, exact). Collective."""
    errors = {}
    fields = problem.space.split(problem.w)
    x = ufl.SpatialCoordinate(problem.mesh)
    for side, u_h in ((-1, fields[0]), (1, fields[1])):
        exact = plane_exact(side, ufl)(x)
        dx, e = problem.cut.dx(side), u_h - exact
        ratio = integrate(ufl.dot(e, e) * dx) / integrate(ufl.dot(exact, exact) * dx)
        errors[side] = float(np.sqrt(ratio))
    return errors


def _sphere_levelset(levelset: str, R: float = SPHERE_RADIUS):
    """The level set (numpy callable of ``x`` ``(3, n)``) named ``levelset`` (see
    :func:`sphere_problem`) of the sphere about ``SPHERE_CENTRE`` of radius ``R`` (m)."""
    c = np.asarray(SPHERE_CENTRE)
    shapes = {
        "distance": lambda x: np.sqrt(((x.T - c) ** 2).sum(axis=1)) - R,
        "quadric": lambda x: (((x.T - c) ** 2).sum(axis=1) - R**2) / (2 * R),
    }
    if levelset not in shapes:
        raise ValueError(f"levelset must be one of {sorted(shapes)}, got {levelset!r}")
    return shapes[levelset]


def sphere_problem(
    n: int | None,
    degree: int,
    law: str,
    cell: str = "tetrahedron",
    comm: MPI.Comm = MPI.COMM_WORLD,
    stress: tuple[float, float, float] = TRIAXIAL,
    levelset: str = "distance",
    **options,
) -> ElasticityProblem:
    """A sphere (``SPHERE_RADIUS``) in the unit cube: :func:`uniform_stress_problem`
    (``n`` None with its ``mesh`` option) with ``levelset``: ``"distance"`` (the signed
    distance, whose P2 interpolant's zero set is a sphere to O(h^3)) or ``"quadric"``
    (``(|x - c|^2 - R^2) / (2 R)``, which P2 represents exactly: the exact sphere and
    normal)."""
    return uniform_stress_problem(
        n, degree, law, _sphere_levelset(levelset), cell, comm, stress, **options
    )


def unstructured_cube(h: float, comm: MPI.Comm = MPI.COMM_WORLD) -> dolfinx.mesh.Mesh:
    """The unit cube meshed by gmsh into unstructured tetrahedra of size ``h`` (m), with a
    node at the centre of each face (:data:`UNIT_CUBE_GEO`). Collective."""
    if not (np.isfinite(h) and 0.0 < h <= 1.0):
        raise ValueError(f"h must be a cell size in (0, 1] m, got {h!r}")
    return mesh_geo(UNIT_CUBE_GEO.format(h=h), 1, "tetrahedron", comm).mesh


def uniform_stress_problem(
    n: int | None,
    degree: int,
    law: str,
    levelset,
    cell: str = "tetrahedron",
    comm: MPI.Comm = MPI.COMM_WORLD,
    stress: tuple[float, float, float] = TRIAXIAL,
    mesh: dolfinx.mesh.Mesh | None = None,
    quadrature_degree: int | None = None,
    **options,
) -> ElasticityProblem:
    """An inclusion (``levelset < 0``: a numpy callable of ``x`` ``(3, n)``, a closed
    surface inside the cube) in the unit cube (``n`` cells per edge, even; or ``mesh``, a
    mesh of the unit cube with a node at the centre of each face, e.g.
    :func:`unstructured_cube`, with ``n`` None), one material
    on both sides, pressures ``-stress`` (Pa) on the three pairs of faces and the six
    rigid modes held by point constraints the exact field satisfies (``u_i = 0`` where
    ``x_i = 1/2``): the exact stress is ``diag(stress)`` everywhere, the exact contact
    traction ``sigma n``. ``law``: ``bonded``, ``sticking`` (a contact law stays closed:
    every ``n.sigma.n < 0``), ...; ``quadrature_degree``: the cut rules'
    (:class:`~xfem_contact.fem.cutmesh.CutMesh`'s default when None); ``options`` go to
    the problem."""
    if (n is None) == (mesh is None):
        raise ValueError(f"give n (cells per edge) or mesh, not both nor neither; got n={n!r}")
    if mesh is None:
        if n % 2:
            raise ValueError(f"n must be even (the point constraints are mesh nodes), got {n}")
        mesh = dolfinx.mesh.create_unit_cube(comm, n, n, n, dolfinx.mesh.CellType[cell])
    cut = CutMesh(mesh, levelset, degree=2, quadrature_degree=quadrature_degree)
    cls = ContactProblem if law in ContactProblem.LAWS else ElasticityProblem
    problem = cls(cut, degree, SOLID, law, **options)
    problem.stress = tuple(stress)
    for k, s in enumerate(stress):
        faces = lambda x, k=k: np.isclose(x[k], 0.0) | np.isclose(x[k], 1.0)  # noqa: E731
        problem.loads.add_pressure(faces, -s)
    held = [
        ((0.5, 0.0, 0.5), 0),
        ((0.5, 1.0, 0.5), 0),
        ((0.5, 0.5, 0.0), 0),
        ((0.5, 0.5, 1.0), 0),
        ((0.0, 0.5, 0.5), 1),
        ((0.5, 0.5, 0.0), 1),
        ((0.0, 0.5, 0.5), 2),
    ]
    for point, component in held:
        problem.loads.add_point_displacement(list(point), 0.0, component)
    return problem


def sphere_errors(problem) -> tuple[float, float]:
    """Relative L2 errors on the sphere of :func:`sphere_problem`'s solved ``problem`` of
    the normal and the tangential traction of the multiplier (``lambda_n`` against
    ``n.sigma.n``, the tangential part against
    ``(I - n n) sigma n``; the Cartesian multiplier of ``bonded`` and of the 3D contact
    laws split on the exact sphere's ``n``), summed by the interface rule at its points
    (numpy). ``frictionless`` gives ``nan`` for the tangential one. Collective."""
    return traction_errors(problem, lambda n: n @ np.diag(problem.stress))


def uniform_stress_state(problem, w: dolfinx.fem.Function) -> None:
    """Write into ``w`` (a Function on ``problem.space.W``) the exact solution of
    :func:`sphere_problem`'s ``problem`` interpolated: on both sides the linear
    displacement ``eps (x - 1/2)`` (m) of the uniform stress (``eps`` its strain in
    ``SOLID``: it meets the point constraints), and the Cartesian multiplier
    ``sigma (x - c) / R`` (Pa), the traction ``sigma n`` on the exact sphere and linear.
    With the quadric level set and degree 2 (or a multiplier of degree 1 or 2) every
    field lies in its discrete space. Local (no communication but the ghost update)."""
    stress = np.diag(problem.stress)
    E, nu = SOLID.E, SOLID.nu
    strain = ((1.0 + nu) * stress - nu * np.trace(stress) * np.eye(3)) / E
    centre = np.asarray(SPHERE_CENTRE)[:, None]
    fields = {0: lambda x: strain @ (x - 0.5), 1: lambda x: strain @ (x - 0.5)}
    for field, _, _ in problem.space.multiplier_fields:
        fields[field] = lambda x: stress @ (x - centre) / SPHERE_RADIUS
    for field, exact in fields.items():
        V, parent = problem.space.field_space(field)
        if V.value_size != 3:
            raise ValueError(
                f"uniform_stress_state: field {field} has {V.value_size} components; valid: "
                "the 3 of a displacement or of a Cartesian multiplier (not frictionless)"
            )
        values = dolfinx.fem.Function(V)
        values.interpolate(exact)
        w.x.array[parent] = values.x.array
    w.x.scatter_forward()


def patch_residual(problem) -> float:
    """The patch test of a solved :func:`sphere_problem` with a contact law: the norm of
    the scaled reduced residual ``|D R^T F|`` at its exact solution
    (:func:`uniform_stress_state`) over that at zero (the loads'). Consistent rules give
    0; the cut rules' error leaves its trace. ``problem.w`` is restored; ``nan`` for a
    linear law (``bonded``: no Newton solver) and a scalar multiplier (``frictionless``).
    Collective."""
    newton = problem.newton
    if newton is None or any(c != 3 for _, c, _ in problem.space.multiplier_fields):
        return float("nan")
    solution = problem.w.x.array.copy()
    uniform_stress_state(problem, problem.w)
    exact = newton.residual_of_w()
    problem.w.x.array[:] = 0.0
    zero = newton.residual_of_w()
    problem.w.x.array[:] = solution
    newton.residual_of_w()  # its iterate back at the solution
    return exact / zero


def sphere_normals(points: np.ndarray) -> np.ndarray:
    """The unit normals ``(p, 3)`` at ``points`` ``(p, 3)`` (m) of the spheres about
    ``SPHERE_CENTRE``."""
    arm = points - np.asarray(SPHERE_CENTRE)
    return arm / np.linalg.norm(arm, axis=1)[:, None]


def interface_rule(problem, normals=sphere_normals) -> tuple:
    """``(ctx, n, dA)`` of the one interface of a problem: its context, the exact unit
    normal ``(p, 3)`` (``normals`` of the points: by default a sphere's about
    ``SPHERE_CENTRE``) and the area (m^2) ``(p,)`` of each of this process's interface
    rule points. Local."""
    (name,) = problem.laws
    ctx = problem.contexts[name]
    cut, rules = problem.cut, ctx.rules
    J = cut.maps.jacobian(rule_cells(cut, rules), rules.points)
    dA = rules.weights * np.abs(np.linalg.det(J))
    return ctx, normals(interface_points(cut, rules)), dA


def traction_errors(problem, exact, normals=sphere_normals) -> tuple[float, float]:
    """Relative L2 errors of the normal and the tangential traction of the multiplier on
    the interface against ``exact``, a callable of the exact unit normals ``(p, 3)`` at
    the interface rule's points giving the exact traction ``(p, 3)`` (Pa); ``normals``:
    see :func:`interface_rule`; the rest as :func:`sphere_errors`. The tangential error
    is relative to the exact pressure's norm where the exact tangential traction
    vanishes, ``nan`` for ``frictionless``. Collective."""
    ctx, n, dA = interface_rule(problem, normals)
    traction = exact(n)
    p_ex = np.sum(traction * n, axis=1)
    t_ex = traction - p_ex[:, None] * n
    lam = ctx.values_at(problem.w, ctx.field)  # Cartesian (bonded, contact in 3D)
    if lam.shape[1] == 3:
        lam_n = np.sum(lam * n, axis=1)
        lam_t = lam - lam_n[:, None] * n
    else:  # frictionless: lambda_n alone
        lam_n, lam_t = lam[:, 0], None
    comm = problem.mesh.comm

    def total(values) -> float:
        return comm.allreduce(float(np.sum(values * dA)), op=MPI.SUM)

    e_n = np.sqrt(total((lam_n - p_ex) ** 2) / total(p_ex**2))
    e_t = np.nan
    if lam_t is not None:
        misfit, norm = total(np.sum((lam_t - t_ex) ** 2, axis=1)), total(np.sum(t_ex**2, axis=1))
        e_t = np.sqrt(misfit / (norm if norm > 1e-20 * total(p_ex**2) else total(p_ex**2)))
    return float(e_n), float(e_t)


#: Composite sphere: the ball's radius (m, about ``SPHERE_CENTRE``), its material (side
#: -1; the matrix is ``SOLID``) and the strain ``A`` of the matrix's radial field
#: (compression: the interface closed)
COMPOSITE_RADIUS = 0.35
INCLUSION = Material(300.0, 0.2)
COMPOSITE_STRAIN = -1e-2


def composite_sphere_coefficients(
    inside: Material = INCLUSION, outside: Material = SOLID, strain: float = COMPOSITE_STRAIN
) -> tuple[float, float, float]:
    """``(A, B, C)`` of the composite sphere's radial displacement: ``u = C (x - c)`` in
    the ball of radius ``R = COMPOSITE_RADIUS`` (side -1), ``u = (A + B / r^3) (x - c)``
    outside (``A = strain``, B in m^3), continuous with a continuous radial traction at
    ``r = R`` (3D Lame: ``sigma_rr = 3 K C`` inside, ``3 K A - 4 mu B / r^3`` outside, K
    the bulk modulus)."""
    R, A = COMPOSITE_RADIUS, strain
    k_in = inside.lmbda + 2 * inside.mu / 3
    k_out = outside.lmbda + 2 * outside.mu / 3
    B = 3 * (k_out - k_in) * A * R**3 / (3 * k_in + 4 * outside.mu)
    return A, B, A + B / R**3


def composite_sphere_exact(side: int, ops=np, inside: Material = INCLUSION):
    """The exact displacement (m) of ``side`` of :func:`composite_sphere_problem`: a
    callable of points ``x`` (numpy ``(3, n)`` giving ``(3, n)``, or with ``ops=ufl`` the
    spatial coordinate giving a UFL vector; numpy's side +1 is taken at ``r >= R / 2``
    for its nodes near the centre, away from its part of the cube). ``inside``: the
    ball's material."""
    A, B, C = composite_sphere_coefficients(inside)
    c = SPHERE_CENTRE

    def u(x):
        arm = [x[k] - c[k] for k in range(3)]
        if side == -1:
            factor = C
        else:
            r = (arm[0] ** 2 + arm[1] ** 2 + arm[2] ** 2) ** 0.5
            if ops is np:  # finite at the centre: side +1's nodes inside the ball
                r = np.maximum(r, COMPOSITE_RADIUS / 2)
            factor = A + B / r**3
        values = [factor * arm[k] for k in range(3)]
        return ops.as_vector(values) if ops is not np else np.array(values)

    return u


def composite_sphere_pressure(inside: Material = INCLUSION) -> float:
    """The exact (uniform) normal traction ``n.sigma.n = 3 K C`` (Pa) on the sphere of
    :func:`composite_sphere_problem` with the ball's material ``inside`` (negative:
    compression)."""
    _, _, C = composite_sphere_coefficients(inside)
    return 3 * (inside.lmbda + 2 * inside.mu / 3) * C


def composite_sphere_problem(
    n: int,
    degree: int,
    law: str = "bonded",
    cell: str = "tetrahedron",
    comm: MPI.Comm = MPI.COMM_WORLD,
    levelset: str = "quadric",
    inside: Material = INCLUSION,
    **options,
) -> ElasticityProblem:
    """A ball (``COMPOSITE_RADIUS``, material ``inside``) in the unit cube (``n`` cells
    per edge, matrix ``SOLID``) under hydrostatic compression, the whole cube boundary
    held by the exact composite-sphere displacement (:func:`composite_sphere_exact`).
    ``law``: ``bonded``, or a contact law (``frictionless``, ``sticking``, ``coulomb``):
    the exact field is radial, closed and free of tangential traction, so it is the
    contact solution too (uniform pressure :func:`composite_sphere_pressure`: the
    concentric spheres); with a contact law the ball's three spins are held at the nodes
    ``c + e_x / n`` (``u_y = u_z = 0``) and ``c + e_y / n`` (``u_z = 0``), which the
    exact field meets (``n`` even). ``levelset`` as :func:`sphere_problem`'s; ``options``
    go to the problem."""
    contact = law in ContactProblem.LAWS
    if contact and n % 2:
        raise ValueError(f"n must be even with a contact law (the spins' nodes), got {n}")
    mesh = dolfinx.mesh.create_unit_cube(comm, n, n, n, dolfinx.mesh.CellType[cell])
    cut = CutMesh(mesh, _sphere_levelset(levelset, COMPOSITE_RADIUS), degree=2)
    cls = ContactProblem if contact else ElasticityProblem
    problem = cls(cut, degree, {-1: inside, 1: SOLID}, law, **options)
    problem.inside = inside
    exact = composite_sphere_exact(1, inside=inside)
    problem.loads.add_displacement("boundary", {s: exact for s in (-1, 1)})
    if contact:
        hold_spins(problem, 1.0 / n)
    return problem


def hold_spins(problem, offset: float) -> None:
    """Hold the three spins of a ball about ``SPHERE_CENTRE`` by point constraints at
    the mesh nodes ``c + offset e_x`` (``u_y = u_z = 0``) and ``c + offset e_y``
    (``u_z = 0``, m), on both sides' fields: a radial field meets them, and so does a
    field symmetric about the planes through ``c``."""
    c = np.asarray(SPHERE_CENTRE)
    for axis, components in ((0, (1, 2)), (1, (2,))):
        for k in components:
            point = c + offset * np.eye(3)[axis]
            problem.loads.add_point_displacement(point.tolist(), 0.0, k)


def composite_sphere_errors(problem: ElasticityProblem) -> dict[int, float]:
    """Relative L2 error of each side's displacement on its own part of the cube against
    :func:`composite_sphere_exact` (UFL, by the cut rules). Collective."""
    errors = {}
    fields = problem.space.split(problem.w)
    x = ufl.SpatialCoordinate(problem.mesh)
    for side, u_h in ((-1, fields[0]), (1, fields[1])):
        exact = composite_sphere_exact(side, ufl, problem.inside)(x)
        dx, e = problem.cut.dx(side), u_h - exact
        ratio = integrate(ufl.dot(e, e) * dx) / integrate(ufl.dot(exact, exact) * dx)
        errors[side] = float(np.sqrt(ratio))
    return errors


def composite_sphere_traction_errors(problem) -> tuple[float, float]:
    """:func:`traction_errors` against the composite sphere's uniform pressure (the
    tangential error relative to the pressure: its exact value is zero). Collective."""
    return traction_errors(problem, lambda n: composite_sphere_pressure(problem.inside) * n)
