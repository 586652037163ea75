"""The Griffith crack: Westergaard's exact stresses and displacements of a straight crack of
length ``2a`` in an infinite plate under a uniform remote stress (numpy and UFL).

Imposing its tractions ``sigma n`` on the boundary of a finite plate containing the same
crack makes the plate's size add no error to the stress intensity factors
``K_I = S22 sqrt(pi a)`` and ``K_II = S12 sqrt(pi a)`` (``S`` the remote stress in the
crack's frame; the same at both tips in their own frames).

The crack frame has its origin at the crack's centre, ``x`` along the crack and ``y``
turned by +90 degrees; with ``z = x + i y`` and the branch of ``sqrt(z^2 - a^2) =
sqrt(z - a) sqrt(z + a)`` cut on the crack only, ``Z = z / sqrt(z^2 - a^2)``::

    s_xx = S22 (Re Z - y Im Z') + S12 (2 Im Z + y Re Z') + S11 - S22
    s_yy = S22 (Re Z + y Im Z') - S12 y Re Z'
    s_xy = -S22 y Re Z' + S12 (Re Z - y Im Z')
    2 mu u_x = S22 ((k - 1)/2 Re W - y Im Z) + S12 ((k + 1)/2 Im W + y Re Z) + 2 mu e_xx x
    2 mu u_y = S22 ((k + 1)/2 Im W - y Re Z) - S12 ((k - 1)/2 Re W + y Im Z) + 2 mu e_yy y

with ``W = sqrt(z^2 - a^2)``, ``k`` Kolosov's constant and ``e`` the strain of the uniform
stress ``(S11 - S22) e_x e_x`` (rigid motions are not fixed: the centre does not move and
does not rotate). Everything is written in real arithmetic (``atan2`` for the arguments),
so the same code gives numpy values and UFL expressions of ``ufl.SpatialCoordinate``.
"""

from __future__ import annotations

import dataclasses
import math
import typing

import numpy as np

from xfem_contact.mechanics.fracture.williams import (
    NUMPY,
    Ops,
    TipFrame,
    kolosov,
    local_coordinates,
    tip_frame,
    to_global_tensor,
    to_global_vector,
)


def _potentials(x, y, a, ops: Ops, side: int) -> dict[str, typing.Any]:
    """Real and imaginary parts of ``Z``, ``Z'`` and ``W`` for unit load (see the module);
    ``side`` +-1 takes the arguments' limits from above or below (points on the faces)."""
    if side not in (-1, 0, 1):
        raise ValueError(f"side must be -1, 0 or 1, got {side!r}")
    dx1, dx2 = x - a, x + a
    rho = ops.sqrt(ops.sqrt(dx1 * dx1 + y * y) * ops.sqrt(dx2 * dx2 + y * y))
    args = (ops.atan2(y, dx1), ops.atan2(y, dx2))
    if side:
        args = tuple(side * abs(t) for t in args)
    phi = (args[0] + args[1]) / 2
    c, s = ops.cos(phi), ops.sin(phi)
    return {
        "ReZ": (x * c + y * s) / rho,
        "ImZ": (y * c - x * s) / rho,
        "ReZp": -(a * a) / rho**3 * ops.cos(3 * phi),
        "ImZp": (a * a) / rho**3 * ops.sin(3 * phi),
        "ReW": rho * c,
        "ImW": rho * s,
    }


@dataclasses.dataclass(frozen=True)
class GriffithCrack:
    """A straight crack ``|x| < a`` on ``y = 0`` of its frame in an infinite plate.

    Args:
        a: Half length (m), > 0.
        remote: Remote stress in the crack frame ``(S11, S22, S12)`` (Pa): ``S11`` along
            the crack, ``S22`` normal to it.
        center: The crack's centre (m).
        direction: The crack's direction (normalised here).
        far_field: False leaves the uniform remote stress out: the plate is then
            unloaded at infinity and the faces carry the traction ``(S12, S22)`` (upper
            face, crack frame) and its opposite (lower face), with the same K.

    The methods take ``side`` as :func:`~.williams.polar`: 0 off the faces, +1 or -1 for
    points on the upper or lower face.
    """

    a: float
    remote: tuple[float, float, float]
    center: tuple[float, float] = (0.0, 0.0)
    direction: tuple[float, float] = (1.0, 0.0)
    far_field: bool = True

    def __post_init__(self):
        if not (isinstance(self.a, int | float) and math.isfinite(self.a) and self.a > 0):
            raise ValueError(f"a (half length, m) must be a positive number, got {self.a!r}")
        if len(self.remote) != 3 or not all(math.isfinite(float(s)) for s in self.remote):
            raise ValueError(
                f"remote must be three finite stresses (S11, S22, S12), got {self.remote!r}"
            )
        frame = tip_frame(self.center, self.direction)
        object.__setattr__(self, "center", tuple(float(v) for v in frame.origin))
        object.__setattr__(self, "direction", tuple(float(v) for v in frame.direction))

    @classmethod
    def uniaxial(cls, a: float, sigma: float, beta: float = math.pi / 2, **kwargs) -> GriffithCrack:
        """Remote uniaxial tension ``sigma`` (Pa) at angle ``beta`` (rad) from the crack:
        ``S = sigma (cos^2 b, sin^2 b, sin b cos b)``; ``beta = pi/2`` loads mode I only."""
        c, s = math.cos(beta), math.sin(beta)
        return cls(a, (sigma * c * c, sigma * s * s, sigma * s * c), **kwargs)

    @classmethod
    def biaxial(cls, a: float, sigma: float, **kwargs) -> GriffithCrack:
        """Remote equal biaxial tension ``sigma`` (Pa): ``S = (sigma, sigma, 0)``."""
        return cls(a, (sigma, sigma, 0.0), **kwargs)

    @property
    def frame(self) -> TipFrame:
        """The crack frame (origin at the centre)."""
        return TipFrame(np.asarray(self.center), np.asarray(self.direction))

    @property
    def tips(self) -> tuple[TipFrame, TipFrame]:
        """The two tips with their outward directions: ``(c + a d, d)`` and ``(c - a d, -d)``."""
        c, d = np.asarray(self.center), np.asarray(self.direction)
        return TipFrame(c + self.a * d, d), TipFrame(c - self.a * d, -d)

    @property
    def stress_intensity_factors(self) -> tuple[float, float]:
        """``(K_I, K_II)`` (Pa m^1/2) at either tip, in the tip's own frame."""
        root = math.sqrt(math.pi * self.a)
        return self.remote[1] * root, self.remote[2] * root

    def remote_stress(self) -> np.ndarray:
        """The remote stress in global components, ``(2, 2)`` (Pa)."""
        S11, S22, S12 = self.remote
        return np.array(to_global_tensor(((S11, S12), (S12, S22)), self.frame))

    def stress_components(self, x, ops: Ops = NUMPY, side: int = 0) -> tuple:
        """Cauchy stress (Pa) in global components, a pair of rows."""
        X, Y = local_coordinates(x, self.frame)
        p = _potentials(X, Y, self.a, ops, side)
        S11, S22, S12 = self.remote
        sxx = S22 * (p["ReZ"] - Y * p["ImZp"]) + S12 * (2 * p["ImZ"] + Y * p["ReZp"]) + (S11 - S22)
        syy = S22 * (p["ReZ"] + Y * p["ImZp"]) - S12 * Y * p["ReZp"]
        sxy = -S22 * Y * p["ReZp"] + S12 * (p["ReZ"] - Y * p["ImZp"])
        if not self.far_field:
            sxx, syy, sxy = sxx - S11, syy - S22, sxy - S12
        return to_global_tensor(((sxx, sxy), (sxy, syy)), self.frame)

    def stress(self, x, ops: Ops = NUMPY, side: int = 0):
        """Cauchy stress (Pa), ``ops.matrix`` (numpy: ``(2, 2, *x[0].shape)``)."""
        return ops.matrix(self.stress_components(x, ops, side))

    def traction(self, x, n, ops: Ops = NUMPY, side: int = 0):
        """Traction ``sigma n`` (Pa) on a surface of unit normal ``n`` (pair or UFL vector)."""
        s = self.stress_components(x, ops, side)
        return ops.vector(tuple(s[i][0] * n[0] + s[i][1] * n[1] for i in range(2)))

    def displacement(self, x, E, nu, plane: str = "strain", ops: Ops = NUMPY, side: int = 0):
        """Displacement (m) for Young's modulus ``E`` (Pa), Poisson's ratio ``nu`` and the
        plane assumption, global components, ``ops.vector``."""
        kappa, two_mu = kolosov(nu, plane), E / (1 + nu)
        X, Y = local_coordinates(x, self.frame)
        p = _potentials(X, Y, self.a, ops, side)
        S11, S22, S12 = self.remote
        # the uniform part beyond the mode I field's biaxial S22 (e = (k+1)/(8 mu) s_xx ...)
        sxx, syy, sxy = (S11 - S22, 0.0, 0.0) if self.far_field else (-S22, -S22, -S12)
        exx = ((kappa + 1) * sxx + (kappa - 3) * syy) / (4 * two_mu)
        eyy = ((kappa + 1) * syy + (kappa - 3) * sxx) / (4 * two_mu)
        ux = (
            (
                S22 * ((kappa - 1) / 2 * p["ReW"] - Y * p["ImZ"])
                + S12 * ((kappa + 1) / 2 * p["ImW"] + Y * p["ReZ"])
            )
            / two_mu
            + exx * X
            + 2 * sxy / two_mu * Y
        )
        uy = (
            S22 * ((kappa + 1) / 2 * p["ImW"] - Y * p["ReZ"])
            - S12 * ((kappa - 1) / 2 * p["ReW"] + Y * p["ImZ"])
        ) / two_mu + eyy * Y
        return ops.vector(to_global_vector((ux, uy), self.frame))
