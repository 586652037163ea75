"""A 3D contact case with an exact solution that slips: the unit cube cut by the
inclined plane of :func:`~xfem_contact.cases.solid.plane_problem`, the two sides
pressed together and slipping along the plane (the frictionless solution, linear on
each side). Shared by the tests and the benchmarks (SI units, tension positive)."""

from __future__ import annotations

import dolfinx.mesh
import numpy as np
import ufl
from mpi4py import MPI

from xfem_contact.cases.paper import integrate
from xfem_contact.cases.solid import PLANE_NORMAL, PLANE_OFFSET, SOLID, traction_errors
from xfem_contact.fem.cutmesh import CutMesh
from xfem_contact.mechanics.presets import ContactProblem

#: The sliding plane case: the pressure (Pa) across the plane and the in-plane stress
#: (Pa) along ``SLIDING_DIRECTION`` that side +1 alone carries
SLIDING_PRESSURE, SLIDING_SHEAR = 1.0, 2.0
#: A unit vector in the plane ``a.x = d`` of :data:`PLANE_NORMAL`
SLIDING_DIRECTION = np.cross(PLANE_NORMAL, [0.0, 0.0, 1.0]) / np.linalg.norm(
    np.cross(PLANE_NORMAL, [0.0, 0.0, 1.0])
)


def sliding_stress(side: int) -> np.ndarray:
    """The uniform stress (Pa, 3x3) of ``side`` of :func:`sliding_plane_problem`:
    ``-p a a^T`` on side -1, ``-p a a^T + q b b^T`` on side +1 (``a`` the plane's
    normal, ``b`` :data:`SLIDING_DIRECTION`): the same traction ``-p a`` on the plane
    from both sides, normal to it."""
    a, b = PLANE_NORMAL, SLIDING_DIRECTION
    stress = -SLIDING_PRESSURE * np.outer(a, a)
    return stress + SLIDING_SHEAR * np.outer(b, b) if side == 1 else stress


def sliding_exact(side: int, ops=np):
    """The exact displacement (m) of ``side`` of :func:`sliding_plane_problem`, ``eps_s
    (x - d a)`` (``eps_s`` the strain of :func:`sliding_stress` in ``SOLID``): a
    callable of points ``x`` (numpy ``(3, n)`` giving ``(3, n)``, or with ``ops=ufl``
    the spatial coordinate giving a UFL vector). The jump across the plane is tangential
    (no gap: ``a^T (eps_+ - eps_-) t = 0`` for ``t`` in the plane) and grows along it:
    the sides slip."""
    E, nu, stress = SOLID.E, SOLID.nu, sliding_stress(side)
    strain = ((1.0 + nu) * stress - nu * np.trace(stress) * np.eye(3)) / E
    origin = PLANE_OFFSET * PLANE_NORMAL

    def u(x):
        arm = [x[k] - origin[k] for k in range(3)]
        values = [sum(strain[i, k] * arm[k] for k in range(3)) for i in range(3)]
        return ops.as_vector(values) if ops is not np else np.array(values)

    return u


def sliding_plane_problem(
    n: int,
    degree: int,
    law: str,
    cell: str = "tetrahedron",
    comm: MPI.Comm = MPI.COMM_WORLD,
    **options,
) -> ContactProblem:
    """The unit cube (``n`` cells per edge) cut by the plane ``a.x = d`` of
    :func:`plane_problem`, each side held on the whole boundary by its exact displacement
    (:func:`sliding_exact`): uniform stresses (:func:`sliding_stress`) that press the
    sides together with ``p`` and make them slip along the plane. It is the solution of
    frictionless contact (Coulomb with ``mu = 0``: no tangential traction), linear on
    each side with a constant multiplier, so P1/Q1 hold it; not of sticking nor of
    Coulomb with ``mu > 0``. ``law``: a contact law; ``options`` go to the problem."""
    mesh = dolfinx.mesh.create_unit_cube(comm, n, n, n, dolfinx.mesh.CellType[cell])
    a, d = PLANE_NORMAL, PLANE_OFFSET
    cut = CutMesh(mesh, lambda x: a[0] * x[0] + a[1] * x[1] + a[2] * x[2] - d, degree=1)
    problem = ContactProblem(cut, degree, SOLID, law, **options)
    problem.loads.add_displacement("boundary", {s: sliding_exact(s) for s in (-1, 1)})
    return problem


def sliding_plane_errors(problem) -> dict[str, float]:
    """Relative errors of a solved :func:`sliding_plane_problem`: each side's
    displacement in L2 on its own part of the cube (``"u_minus"``, ``"u_plus"``, UFL)
    and the multiplier's normal and tangential traction against ``-p a``
    (:func:`traction_errors`, ``"pressure"``, ``"tangential"``). Collective."""
    errors = {}
    fields = problem.space.split(problem.w)
    x = ufl.SpatialCoordinate(problem.mesh)
    for side, name, u_h in ((-1, "u_minus", fields[0]), (1, "u_plus", fields[1])):
        exact = sliding_exact(side, ufl)(x)
        dx, e = problem.cut.dx(side), u_h - exact
        ratio = integrate(ufl.dot(e, e) * dx) / integrate(ufl.dot(exact, exact) * dx)
        errors[name] = float(np.sqrt(ratio))
    normals = lambda points: np.tile(PLANE_NORMAL, (len(points), 1))  # noqa: E731
    errors["pressure"], errors["tangential"] = traction_errors(
        problem, lambda n: -SLIDING_PRESSURE * n, normals
    )
    return errors
