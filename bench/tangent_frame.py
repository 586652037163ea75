"""The 3D contact multiplier, Cartesian (the package's) or in a tangent frame
``t1 = e x n / |e x n|``, ``t2 = n x t1`` (``e`` a fixed axis): the sticking sphere of
:func:`xfem_contact.cases.solid.sphere_problem` (P2 tets), its pressure and tangential
errors and the RMS of ``lambda - sigma n`` near the frame's poles (``|n.e| > 0.95``).

The frame variant is made here by swapping the law's tangential parts (the context's
``tangential``, ``tangent_vector``, ``tangential_at`` and the contact law's
``multipliers``) for this process only: an experiment, not an option of the package.

Run (serial): ``python bench/tangent_frame.py cartesian|frame N [ex,ey,ez]``.
"""

import sys

import xfem_contact  # noqa: F401  (before dolfinx with the PyPI wheel)

# isort: split
import numpy as np
import ufl

from xfem_contact.cases.solid import SPHERE_CENTRE, TRIAXIAL, sphere_problem
from xfem_contact.fem.evaluation import interface_points, rule_cells
from xfem_contact.mechanics.laws import base, contact

variant, n = sys.argv[1], int(sys.argv[2])
e_axis = (
    np.array([0.0, 0.0, 1.0])
    if len(sys.argv) < 4
    else np.array([float(v) for v in sys.argv[3].split(",")])
)
e_axis /= np.linalg.norm(e_axis)


def frame_ufl(n):
    e = ufl.as_vector(e_axis.tolist())
    c = ufl.cross(e, n)
    t1 = c / ufl.sqrt(ufl.dot(c, c))
    t2 = ufl.cross(n, t1)
    return t1, t2


def frame_np(n):
    c = np.cross(e_axis, n)
    t1 = c / np.linalg.norm(c, axis=1)[:, None]
    return t1, np.cross(n, t1)


if variant == "frame":

    def tangential(self, v):
        t1, t2 = frame_ufl(self.normal)
        return ufl.as_vector([ufl.dot(v, t1), ufl.dot(v, t2)])

    def tangent_vector(self, a):
        t1, t2 = frame_ufl(self.normal)
        return a[0] * t1 + a[1] * t2

    def tangential_at(self, v):
        t1, t2 = frame_np(self.normal_at())
        return np.c_[np.sum(v * t1, 1), np.sum(v * t2, 1)]

    def multipliers(self, ctx, u):
        lam = u.multiplier
        return lam[0], ufl.as_vector([lam[1], lam[2]])

    base.InterfaceContext.tangential = tangential
    base.InterfaceContext.tangent_vector = tangent_vector
    base.InterfaceContext.tangential_at = tangential_at
    contact.ContactLaw.multipliers = multipliers

p = sphere_problem(n, 2, "sticking")
p.solve()
ctx = p.contexts[next(iter(p.laws))]
rules = ctx.rules
J = p.cut.maps.jacobian(rule_cells(p.cut, rules), rules.points)
dA = rules.weights * np.abs(np.linalg.det(J))
arm = interface_points(p.cut, rules) - np.asarray(SPHERE_CENTRE)
nx = arm / np.linalg.norm(arm, axis=1)[:, None]
trac = nx @ np.diag(TRIAXIAL)
p_ex = np.sum(trac * nx, 1)
t_ex = trac - p_ex[:, None] * nx
lam = ctx.values_at(p.w, ctx.field)
if variant == "frame":
    nh = ctx.normal_at()
    t1, t2 = frame_np(nh)
    lam = lam[:, :1] * nh + lam[:, 1:2] * t1 + lam[:, 2:3] * t2
ln = np.sum(lam * nx, 1)
lt = lam - ln[:, None] * nx
e_n = np.sqrt(np.sum((ln - p_ex) ** 2 * dA) / np.sum(p_ex**2 * dA))
e_t = np.sqrt(np.sum(np.sum((lt - t_ex) ** 2, 1) * dA) / np.sum(np.sum(t_ex**2, 1) * dA))
near = np.abs(np.sum(nx * e_axis, 1)) > 0.95  # near the frame's poles
local = np.sqrt(np.sum(np.sum((lam - trac) ** 2, 1)[near] * dA[near]) / np.sum(dA[near]))
print(
    f"{variant} n={n} axis={e_axis.round(3).tolist()}: pressure {e_n:.3e}, tangential {e_t:.3e}, "
    f"rms |lambda - sigma n| near the poles {local:.3e} Pa"
)
