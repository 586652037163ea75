"""Several disjoint cracks as one pair of level sets, each crack keeping its own in a zone.

A crack is the zero line of ``phi_k`` where ``psi_k < 0`` (:mod:`xfem_contact.geometry.crack`).
For ``K`` cracks, :func:`crack_union` builds one pair ``(phi, psi)`` that the one-crack
machinery (cut, tip cells, Heaviside and tip enrichment) takes as it is. With
``d_k = sqrt(phi_k^2 + max(psi_k, 0)^2)`` (the distance to crack ``k`` for
signed-distance level sets) and ``k(x)`` the nearest crack (smallest ``d_k``)::

    phi = phi_k(x)                               # the nearest crack's
    psi = psi_k(x) where d_k(x) < zone, else +zone   # positive: no crack there

with ``zone = max(gap / 3, gap / 2 - 2 h)``, ``gap`` the smallest distance between two
cracks (the minimum of ``d_a + d_b`` over the mesh's level-set nodes) and ``h`` the
largest cell diameter. So each crack's lips, tips and tip enrichment see its own level
sets within ``zone`` of it; ``phi`` jumps between two cracks only where ``psi > 0`` (cells
cut ahead of a tip, no discontinuity there), and at the edge of a zone, where ``psi``
jumps, ``|phi_k| >= zone - h > 0`` cuts nothing. Cracks closer than :data:`MIN_CELLS`
cells (touching, crossing) are refused, naming them; so are tip enrichments that reach
beyond the zone (:meth:`CrackUnion.check_tip_radius`).

A closed interface among the cracks is given with ``psi = None``: a crack with
``psi = -zone`` in its zone (every cell it cuts is crossed, it has no tip). The cracks
must lie outside it (their body is its outside); several interfaces are checked as by
:func:`~xfem_contact.geometry.levelset.union`.
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Callable, Mapping
from dataclasses import dataclass

import dolfinx.fem
import dolfinx.mesh
import numpy as np
import numpy.typing as npt
from mpi4py import MPI

from xfem_contact.geometry.levelset import LevelSet, interpolate, union

__all__ = ["MIN_CELLS", "CrackUnion", "crack_union", "interpolate_tangent"]

#: Two cracks must be at least this many (largest) cell diameters apart
MIN_CELLS = 4


@dataclass(frozen=True)
class CrackUnion:
    """The cracks of one cut and their union level sets.

    Attributes:
        names: The cracks' names, in the order of the mapping given.
        phi: The union normal level set (a callable when all were, else a Function).
        psi: The union tangential level set (likewise).
        zone: Each crack keeps its own level sets within this distance of it (m);
            ``inf`` for one crack.
        gap: The smallest distance between two cracks (m, ``inf`` for one), between
            ``pair``.
        pair: The names of the two closest cracks (``None`` for one).
        cell_crack: Index (into ``names``) of the nearest crack of every owned cell.
        h: The largest cell diameter of the mesh (m).
    """

    names: tuple[str, ...]
    phi: Callable | dolfinx.fem.Function
    psi: Callable | dolfinx.fem.Function
    zone: float
    gap: float
    pair: tuple[str, str] | None
    cell_crack: npt.NDArray[np.int32]
    h: float
    _distances: npt.NDArray[np.float64]  # (K, local nodes) d_k at the nodes
    _nodes: npt.NDArray[np.float64]  # (local nodes, gdim)
    _comm: MPI.Comm
    #: The closed interfaces among ``names`` (given with ``psi = None``)
    interfaces: tuple[str, ...] = ()

    def nearest(self, points: npt.ArrayLike) -> npt.NDArray[np.int64]:
        """Index of the crack nearest to each point ``(n, gdim)``: the smallest
        ``min_nodes |x - node| + d_k(node)`` over all processes. Collective."""
        points = np.asarray(points, dtype=np.float64).reshape(-1, self._nodes.shape[1])
        far = np.full((len(self.names), len(points)), np.inf)
        if self._nodes.size:
            gaps = np.linalg.norm(points[:, None] - self._nodes[None], axis=2)
            far = np.min(gaps[None] + self._distances[:, None, :], axis=2)
        total = np.empty_like(far)
        self._comm.Allreduce(far, total, op=MPI.MIN)
        return np.argmin(total, axis=0)

    def check_tip_radius(self, tip_radius: float | None) -> None:
        """Refuse a tip enrichment (nodes within ``tip_radius`` of a tip, or the tip
        cells' for ``None``, and the cells around them) that reaches beyond a crack's
        zone: there the level sets are another crack's or none."""
        if len(self.names) < 2:
            return
        radius = self.h if tip_radius is None else float(tip_radius)
        if radius + self.h > self.zone:
            a, b = self.pair
            raise ValueError(
                f"tip_radius = {radius:.4g} m: the tip enrichment of cracks {a!r} and {b!r} "
                f"(tip_radius plus one cell, {radius + self.h:.4g} m) must stay within "
                f"{self.zone:.4g} m of its crack ({self.gap:.4g} m between them): take a "
                "smaller tip_radius, a finer mesh or cracks further apart (their tip zones "
                "must not overlap)"
            )


def interpolate_tangent(
    mesh: dolfinx.mesh.Mesh, tangent, degree: int, into: dolfinx.fem.Function | None = None
) -> LevelSet:
    """A crack's ``psi`` interpolated (:func:`~xfem_contact.geometry.levelset.interpolate`),
    its errors said for a crack. Collective."""
    try:
        return interpolate(mesh, tangent, degree, into=into)
    except ValueError as error:
        if "never crosses zero" in str(error):
            raise ValueError(
                "The crack's tangential level set psi never changes sign on the mesh: "
                "the crack has no tip in the body (psi < 0 everywhere: it cuts the body "
                "in two, give it as an interface) or no part in it (psi >= 0)"
            ) from None
        raise ValueError(f"Crack tangential level set (tangent): {error}") from None


def _of(levelsets: Mapping, names: tuple[str, ...], argument: str) -> list:
    """The level sets of ``names`` from the mapping given as ``argument``."""
    if not isinstance(levelsets, Mapping) or tuple(levelsets) != names:
        got = list(levelsets) if isinstance(levelsets, Mapping) else type(levelsets).__name__
        raise ValueError(
            f"{argument}: several cracks take a mapping {{name: psi}} with the names of "
            f"levelset's, in the same order ({list(names)}; None for a closed interface), "
            f"got {got}"
        )
    return [levelsets[name] for name in names]


def crack_union(
    mesh: dolfinx.mesh.Mesh,
    levelsets: Mapping,
    tangents: Mapping | Callable | dolfinx.fem.Function,
    degree: int,
    known: tuple[str, ...] | None = None,
) -> CrackUnion:
    """The :class:`CrackUnion` of the cracks ``{name: phi}`` and ``{name: psi}``
    (callables or scalar Functions; one crack may give ``psi`` alone). Collective.

    Raises:
        ValueError: naming the argument and the crack: no names, names other than an
            earlier cut's (``known``), a crack whose level sets do not cross the mesh,
            two cracks closer than :data:`MIN_CELLS` cells (touching or crossing).
    """
    names = tuple(levelsets)
    if not names:
        raise ValueError("levelset: give at least one crack {name: phi}")
    if known is not None and names != known:
        raise ValueError(f"levelset: update() needs the cracks {list(known)}, got {list(names)}")
    if len(names) == 1 and not isinstance(tangents, Mapping):
        tangents = {names[0]: tangents}
    phis, psis = _of(levelsets, names, "levelset"), _of(tangents, names, "tangent")
    interfaces = tuple(name for name, psi in zip(names, psis, strict=True) if psi is None)
    if len(interfaces) == len(names):
        raise ValueError("tangent: no crack (every psi is None): cut interfaces without tangent")
    tdim = mesh.topology.dim
    num_cells = mesh.topology.index_map(tdim).size_local
    if len(names) == 1:  # checked by the cut as one crack's
        none = np.zeros((1, 0))
        zeros = np.zeros(num_cells, dtype=np.int32)
        return CrackUnion(
            names, phis[0], psis[0], np.inf, np.inf, None, zeros, 0.0, none, none.T, mesh.comm
        )
    h = mesh.comm.allreduce(
        float(mesh.h(tdim, np.arange(num_cells, dtype=np.int32)).max(initial=0.0)), op=MPI.MAX
    )
    P, S = [], []
    for name, phi, psi in zip(names, phis, psis, strict=True):
        try:
            P.append(interpolate(mesh, phi, degree).function)
        except ValueError as error:
            raise ValueError(f"levelset[{name!r}]: {error}") from None
        try:
            S.append(None if psi is None else interpolate_tangent(mesh, psi, degree).function)
        except ValueError as error:
            raise ValueError(f"tangent[{name!r}]: {error}") from None
    V = P[0].function_space
    phi_n = np.array([f.x.array for f in P])
    pairs = zip(P, S, strict=True)
    psi_n = np.array([-np.ones_like(f.x.array) if g is None else g.x.array for f, g in pairs])
    D = np.hypot(phi_n, np.maximum(psi_n, 0.0))
    nodes = V.tabulate_dof_coordinates()[:, : mesh.geometry.dim]
    if interfaces:
        _check_interfaces(mesh, names, interfaces, phis, phi_n, D, degree, h)
    nearest = np.argmin(D, axis=0)
    at = np.arange(D.shape[1])
    # a cell's crack: that of its node of the smallest union phi, the one of its side -1
    # part (its material: a cell cut between two cracks' zones is -1 on one's side only)
    cells = V.dofmap.list[:num_cells]
    lowest = np.argmin(phi_n[nearest[cells], cells], axis=1)
    cell_crack = nearest[cells[np.arange(num_cells), lowest]].astype(np.int32)
    gap, pair = np.inf, None
    for i, a in enumerate(names):
        for j in range(i + 1, len(names)):
            local = float((D[i] + D[j]).min(initial=np.inf))
            distance = mesh.comm.allreduce(local, op=MPI.MIN)
            if distance < gap:
                gap, pair = distance, (a, names[j])
    if pair is not None and gap < MIN_CELLS * h:
        raise ValueError(
            f"levelset: cracks {pair[0]!r} and {pair[1]!r} come within {gap:.4g} m of each "
            f"other (they must be at least {MIN_CELLS} cells, {MIN_CELLS * h:.4g} m, apart, "
            "and their tip zones must not overlap): touching or crossing cracks are not "
            "handled"
        )
    zone = max(gap / 3.0, gap / 2.0 - 2.0 * h)
    for k, name in enumerate(names):  # a closed interface: psi = -zone around it
        if name in interfaces:
            psi_n[k] = -zone
            psis[k] = functools.partial(_constant, -zone)
    if all(callable(f) and not isinstance(f, dolfinx.fem.Function) for f in phis + psis):
        phi, psi = _union_callables(phis, psis, zone)
    else:
        phi, psi = (dolfinx.fem.Function(V) for _ in range(2))
        phi.x.array[:] = phi_n[nearest, at]
        psi.x.array[:] = np.where(D[nearest, at] < zone, psi_n[nearest, at], zone)
    union = CrackUnion(names, phi, psi, zone, gap, pair, cell_crack, h, D, nodes, mesh.comm)
    return dataclasses.replace(union, interfaces=interfaces)


def _constant(value: float, x: np.ndarray) -> np.ndarray:
    return np.full(x.shape[1], value)


def _check_interfaces(mesh, names, interfaces, phis, phi_n, D, degree, h) -> None:
    """Refuse closed interfaces that overlap or cut common cells (as
    :func:`~xfem_contact.geometry.levelset.union`) and cracks that enter an interface's
    inside (their body is the interfaces' outside). Collective."""
    if len(interfaces) > 1:
        union(mesh, {n: phis[names.index(n)] for n in interfaces}, degree)
    for i, crack in enumerate(names):
        if crack in interfaces:
            continue
        for inside in interfaces:
            local = int(np.count_nonzero((D[i] < h) & (phi_n[names.index(inside)] < 0)))
            if mesh.comm.allreduce(local, op=MPI.SUM):
                raise ValueError(
                    f"levelset: crack {crack!r} enters the inside of interface {inside!r}: "
                    "cracks must lie in the body outside the closed interfaces"
                )


def _union_callables(phis: list, psis: list, zone: float) -> tuple[Callable, Callable]:
    """The union level sets as callables of ``x`` (exact where each crack's are)."""

    def nearest(x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        P = np.array([np.asarray(f(x), dtype=np.float64) for f in phis])
        S = np.array([np.asarray(f(x), dtype=np.float64) for f in psis])
        D = np.hypot(P, np.maximum(S, 0.0))
        k = np.argmin(D, axis=0)
        at = np.arange(P.shape[1])
        return P[k, at], S[k, at], D[k, at]

    def phi(x: np.ndarray) -> np.ndarray:
        return nearest(x)[0]

    def psi(x: np.ndarray) -> np.ndarray:
        _, S, D = nearest(x)
        return np.where(D < zone, S, zone)

    return phi, psi
