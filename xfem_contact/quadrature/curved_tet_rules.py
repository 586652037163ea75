"""Rules of tetrahedra cut by P2 level sets (curved interfaces): Saye's rules on the four
hexahedra of each tetrahedron, pure numpy and Basix.

The reference tetrahedron is subdivided into four hexahedra, one per vertex ``i``, with corners
``i``, the midpoints of its three edges, the centroids of its three faces and the
centroid of the tetrahedron. Each is the image of the unit cube by a trilinear map ``M``
with a positive Jacobian determinant (a polynomial bounded away from zero). A P2
polynomial composed with ``M`` has degree at most 2 in each cube coordinate: a Q2
polynomial, obtained exactly by interpolating the composition at the 27 Q2 nodes.
Saye's rules of those polynomials (:func:`~xfem_contact.quadrature.saye.saye_points`)
map back through ``M``: volume weights times ``det dM``, interface area vectors by
Nanson's formula ``cof(dM) a``. Nothing is triangulated along the interface, so
nothing can tangle, and all weights are positive. The rules are not exact for planes
(the composed level set is not planar: along a height line its root is a rational
function of the outer coordinates) but converge as Saye's rules do as ``order`` grows or
as the boxes shrink (``min_depth`` forced subdivisions). Their relative error on a cell depends
only on where the interface crosses the reference cell, not on the cell's size.

A tetrahedron is classified first by its own Bernstein coefficients (the four
hexahedra's are convex combinations of them), then, if still open, by the hexahedra's.
Cells are processed in batches, one Saye call per hexahedron index and batch.

Tolerance policy and refusals are Saye's (:mod:`xfem_contact.quadrature.saye`): side -1 is
``phi < 0``, side +1 ``phi >= 0``; a zero set with a singular point is refused naming the
tetrahedron.
"""

from __future__ import annotations

import functools

import basix
import numpy as np
import numpy.typing as npt

from xfem_contact.geometry.cut_topology import nodal_values
from xfem_contact.geometry.exact_lines import ExactLevelSet
from xfem_contact.geometry.exact_margin import exact_margin
from xfem_contact.geometry.simplex_bernstein import lattice_indices, lattice_to_bernstein
from xfem_contact.geometry.tensor_levelset import coefficients, derivative, gradient
from xfem_contact.quadrature.rules import RuleSet
from xfem_contact.quadrature.saye import (
    MAX_DEPTH,
    CutRules,
    certified_boxes,
    certified_sides,
    saye_points,
)
from xfem_contact.quadrature.surface_rules import Jacobian, surface_rules
from xfem_contact.quadrature.tet_saye import truncated_saye_points

__all__ = [
    "FRAMES",
    "HEXAHEDRA",
    "RAISE_POWER",
    "RAISE_TOLERANCE",
    "RESOLVED",
    "classify_p2_tets",
    "hexahedron_map",
    "p2_tet_cut_rules",
    "raise_tolerances",
]


def _subdivision() -> np.ndarray:
    """Corners ``(4, 8, 3)`` of the four hexahedra of the reference tetrahedron, in Basix
    hexahedron vertex order."""
    V = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
    hexes = []
    for i in range(4):
        a, b, c = (j for j in range(4) if j != i)
        if i % 2:  # keep every map orientation-preserving
            b, c = c, b
        mid = {j: 0.5 * (V[i] + V[j]) for j in (a, b, c)}
        face = {(j, k): (V[i] + V[j] + V[k]) / 3.0 for j, k in ((a, b), (a, c), (b, c))}
        hexes.append(
            [V[i], mid[a], mid[b], face[a, b], mid[c], face[a, c], face[b, c], V.mean(axis=0)]
        )
    return np.array(hexes)


HEXAHEDRA = _subdivision()
"""Corners of the four hexahedra of the reference tetrahedron, shape ``(4, 8, 3)``."""


def _trilinear() -> np.ndarray:
    """Monomial coefficients ``(4, 8, 3)`` of the four hexahedron maps: row ``a + 2 b + 4 c``
    of ``u^a v^b w^c``."""
    P = np.transpose(HEXAHEDRA.reshape(4, 2, 2, 2, 3), (0, 3, 2, 1, 4))  # [k, u, v, w]
    D = np.array([[1.0, 0.0], [-1.0, 1.0]])  # (1 - t, t) -> (1, t)
    M = np.einsum("ai,bj,cl,kijlx->kcbax", D, D, D, P)  # [k, c, b, a]: w slowest
    return M.reshape(4, 8, 3)


_MONOMIALS = _trilinear()


def hexahedron_map(U: npt.NDArray[np.float64], k: int) -> tuple[np.ndarray, np.ndarray]:
    """The trilinear map of hexahedron ``k`` at cube points ``U`` ``(N, 3)``: tetrahedron
    points ``(N, 3)`` and Jacobians ``dM/dU`` ``(N, 3, 3)``."""
    X, du, dv, dw = _trilinear_map(U, _MONOMIALS[k])
    return X.T, np.stack([du.T, dv.T, dw.T], axis=2)


def _trilinear_map(U: np.ndarray, c: np.ndarray) -> tuple[np.ndarray, ...]:
    """Values and the three columns ``dM/du, dM/dv, dM/dw`` of the Jacobian, each
    ``(3, N)`` (coordinate first), at ``U`` ``(N, 3)`` of the trilinear map with monomial
    coefficients ``c`` ``(8, 3)``."""
    u, v, w = np.ascontiguousarray(U.T)
    m = np.empty((8, u.size))  # 1, u, v, uv, w, uw, vw, uvw
    m[0], m[1], m[2], m[4] = 1.0, u, v, w
    np.multiply(u, v, out=m[3])
    np.multiply(u, w, out=m[5])
    np.multiply(v, w, out=m[6])
    np.multiply(m[3], w, out=m[7])
    # einsum, not BLAS: a threaded BLAS spends more on these thin products than it saves
    return (
        np.einsum("kd,kn->dn", c, m),
        np.einsum("kd,kn->dn", c[[1, 3, 5, 7]], m[[0, 2, 4, 6]]),
        np.einsum("kd,kn->dn", c[[2, 3, 6, 7]], m[[0, 1, 4, 5]]),
        np.einsum("kd,kn->dn", c[[4, 5, 6, 7]], m[:4]),
    )


@functools.cache
def _to_cubes() -> np.ndarray:
    """Matrix ``(4 * 27, 10)``: P2 tetrahedron nodal values -> values of the compositions
    with the four hexahedron maps at the Q2 nodes of the cube (Basix orders)."""
    q2 = basix.create_element(
        basix.ElementFamily.P, basix.CellType.hexahedron, 2, basix.LagrangeVariant.gll_warped
    )
    p2 = basix.create_element(
        basix.ElementFamily.P, basix.CellType.tetrahedron, 2, basix.LagrangeVariant.gll_warped
    )
    X = np.concatenate([hexahedron_map(q2.points, k)[0] for k in range(4)])
    return p2.tabulate(0, X)[0, :, :, 0]


def _cube_coefficients(phi: npt.ArrayLike) -> np.ndarray:
    phi = nodal_values(phi, 10, "P2 tetrahedron", "tetrahedron")
    # einsum, not BLAS: a cell's values must not depend on the batch it is in
    values = np.einsum("nk,jk->nj", phi, _to_cubes()).reshape(-1, 27)  # row 4 c + k: hexahedron k
    return coefficients(values, 2)


def classify_p2_tets(
    phi: npt.ArrayLike, exact: ExactLevelSet | None = None
) -> npt.NDArray[np.int8]:
    """Side of each tetrahedron certified by its own Bernstein coefficients, else by those
    on its four hexahedra: -1, +1, or 0 (possibly cut).

    Args:
        phi: P2 nodal values, shape ``(ncells, 10)`` (Basix order).
        exact: ``(rows, X) -> (m,)``: the level set that ``phi`` interpolates (see
            :func:`p2_tet_cut_rules`). A cell near its zero set, whose Bernstein
            coefficients' least magnitude is at most their spread (``|phi|`` small against
            ``h |grad phi|``), is certified only with the margin of
            :func:`~xfem_contact.geometry.exact_margin.exact_margin`: coefficients all
            ``< -margin`` or all ``>= margin``, else 0. Farther cells keep the
            interpolant's certificate (there the margin, of order ``h^3``, is below it).
            ``None``: the interpolant's sides.

    Returns:
        ``int8`` array of shape ``(ncells,)``.
    """
    phi = nodal_values(phi, 10, "P2 tetrahedron", "tetrahedron")
    B = phi @ _to_simplex_bernstein().T
    low, high = B.min(axis=1), B.max(axis=1)
    side = np.where(high < 0, -1, np.where(low >= 0, 1, 0)).astype(np.int8)
    rest = np.flatnonzero(side == 0)
    sides = certified_sides(_cube_coefficients(phi[rest])).reshape(-1, 4)
    side[rest] = np.where((sides == -1).all(axis=1), -1, np.where((sides == 1).all(axis=1), 1, 0))
    if exact is not None:  # the tetrahedron's coefficients with the margin decide
        near = np.flatnonzero((side != 0) & (np.minimum(np.abs(low), np.abs(high)) <= high - low))
        margin = exact_margin(phi[near], lambda rows, X: exact(near[rows], X))
        boxes = certified_boxes(B[near], margin, np.arange(near.size))
        side[near[~(boxes["minus"] | boxes["plus"])]] = 0
    return side


@functools.cache
def _to_simplex_bernstein() -> np.ndarray:
    """Matrix ``(10, 10)``: P2 nodal values (Basix ``gll_warped`` order) -> Bernstein
    coefficients on the tetrahedron, coefficient ``k`` that of node ``k``'s multi-index
    (a vertex's is its value, an edge's ``2 phi_mid - (phi_a + phi_b) / 2``)."""
    p2 = basix.create_element(
        basix.ElementFamily.P, basix.CellType.tetrahedron, 2, basix.LagrangeVariant.gll_warped
    )
    order = {a[1:]: i for i, a in enumerate(lattice_indices(2))}
    perm = [order[tuple(int(v) for v in np.rint(2 * x))] for x in p2.points]
    return lattice_to_bernstein(2)[np.ix_(perm, perm)]


RAISE_TOLERANCE = 1e-6
"""Default ``raise_tolerance`` of :func:`p2_tet_cut_rules`: the tolerance of coarse cells
(reference units; see :func:`raise_tolerances`)."""

RAISE_POWER = 3
"""Power of the cell's resolution ``theta = h kappa`` in :func:`raise_tolerances`: the
rules' change that a cell allows falls as ``h^3``, the order of a P2 interpolant's
distance to the surface (``h^(k + 1)``)."""

RESOLVED = 0.5
"""Resolution ``theta = h kappa`` below which :func:`raise_tolerances` falls: cells of
``theta >= RESOLVED`` keep ``raise_tolerance``."""

ROUND_OFF = 1e-13
"""Least tolerance of :func:`raise_tolerances` (reference units): nearly planar cells,
whose rules change by round-off only, keep ``order`` points."""


def raise_tolerances(
    C: np.ndarray, J: np.ndarray | None, raise_tolerance: float
) -> npt.NDArray[np.float64]:
    """The change of a box's rules (interface area, side -1 volume; reference units)
    between ``order - 1`` and ``order`` points above which it gets ``2 order`` points, per
    cell: ``raise_tolerance min(1, theta / RESOLVED)^RAISE_POWER``, at least
    :data:`ROUND_OFF`.

    ``theta = h |D^2 phi| / |grad phi|`` at the cell's centroid (physical derivatives,
    Frobenius and Euclidean norms; ``h`` the longest edge) is the cell's size against its
    zero set's radius of curvature, of the order of ``h kappa``. A box's reference area
    and volume are fractions of the cell's, so the rules' error that a tolerance lets
    through is a share of each cell's area and volume, and summed over the cut cells a
    share of the surface's:
    a fixed tolerance bounds the relative error of the whole surface by a constant, which
    stops its convergence (the rules' floor), while ``theta^3`` makes the bound fall as
    ``h^3`` (the rules kept, of ``order`` points, err by less than the change from
    ``order - 1`` that it bounds). Cells of ``theta >= RESOLVED`` (coarse against the
    surface) keep ``raise_tolerance``.

    Args:
        C: Monomial coefficients ``(ncells, 3, 3, 3)`` in the reference tetrahedron.
        J: Affine Jacobians ``(ncells, 3, 3)`` of the cells (at their centroids), or
            ``None`` (reference cells).
        raise_tolerance: The tolerance of cells of ``theta >= RESOLVED``, ``>= 0``.

    Returns:
        Shape ``(ncells,)``.
    """
    n = C.shape[0]
    centroid = np.full((n, 3), 0.25)
    slope = gradient(C, centroid)
    hessian = np.stack(
        [gradient(derivative(C, a), centroid) for a in range(3)], axis=1
    )  # [n, a, b]
    if J is None:
        J = np.broadcast_to(np.eye(3), (n, 3, 3))
    inverse = np.linalg.inv(J)
    slope = np.einsum("nji,nj->ni", inverse, slope)  # J^-T grad
    hessian = np.einsum("nki,nkl,nlj->nij", inverse, hessian, inverse)
    edges = np.concatenate([J, J[:, :, [1, 2, 2]] - J[:, :, [0, 0, 1]]], axis=2)
    h = np.linalg.norm(edges, axis=1).max(axis=1)
    curved = h * np.linalg.norm(hessian, axis=(1, 2))
    length = np.linalg.norm(slope, axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        scale = np.where(curved < RESOLVED * length, curved / (RESOLVED * length), 1.0)
    return np.maximum(raise_tolerance * scale**RAISE_POWER, ROUND_OFF)


FRAMES = ("tetrahedron", "hexahedra")
"""Where :func:`p2_tet_cut_rules` runs Saye's algorithm: on boxes of the reference
tetrahedron itself (:mod:`~xfem_contact.quadrature.tet_saye`), or on the four hexahedra."""


def p2_tet_cut_rules(
    phi: npt.ArrayLike,
    order: int = 4,
    *,
    max_depth: int = MAX_DEPTH,
    min_depth: int = 0,
    frame: str = "tetrahedron",
    raise_tolerance: float | None = RAISE_TOLERANCE,
    jacobian: Jacobian | None = None,
    exact: ExactLevelSet | None = None,
) -> CutRules:
    """Rules of both sides and of the interface of tetrahedra with P2 level sets.

    Args:
        phi: P2 nodal values, shape ``(ncells, 10)`` (Basix ``gll_warped`` order).
        order: Gauss-Legendre points per interval of Saye's rules.
        max_depth: Box subdivision levels.
        min_depth: Levels of forced subdivisions of the boxes the interface may cross (0 ..
            ``max_depth``); each level lowers the rules' error on a cell and multiplies
            the points of the cut boxes by about four.
        frame: ``"tetrahedron"``: Saye's rules on truncated boxes of the reference
            tetrahedron (exact for planes), a cell left unresolved at ``max_depth`` going
            to the hexahedra; ``"hexahedra"``: on the four hexahedra of every cell.
        raise_tolerance: In the tetrahedron's frame, a cut box whose rules with
            ``order - 1`` points per interval differ from ``order``'s by more than its
            tolerance (interface area or side -1 volume, reference units) gets ``2
            order`` points
            (:func:`~xfem_contact.quadrature.tet_saye.truncated_saye_points`); ``None``:
            ``order`` everywhere. Not used on the hexahedra. The tolerance is this on
            every cell when the rules follow ``phi``'s zero set, and each cell's
            :func:`raise_tolerances` of this on an ``exact`` one: there the rules are
            the only approximation of the surface, so their error must fall with ``h``;
            an interpolant's zero set is itself ``O(h^3)`` from the surface it samples,
            and the rules' floor under the fixed tolerance lies below that on the meshes
            measured (docs' 3D geometry page).
        jacobian: ``(rows, X) -> (m, 3, 3)`` parent Jacobians for the interface rule
            (and, at the centroids, for :func:`raise_tolerances`); ``None``: reference
            cells.
        exact: ``(rows, X) -> (m,)``: the level set that ``phi`` interpolates, at points
            ``X`` ``(m, 3)`` of the reference tetrahedron of cells ``rows``; the rules
            then follow its zero set (as
            :func:`~xfem_contact.quadrature.saye.hex_cut_rules`'s) in either frame, and
            a box lies on one side only when ``phi``'s Bernstein coefficients there keep
            their sign with the margin of
            :func:`~xfem_contact.geometry.exact_margin.exact_margin` (a thin lens of the
            exact zero set that the interpolant misses is found); ``None``: ``phi``'s.

    Returns:
        A :class:`~xfem_contact.quadrature.saye.CutRules`: points in the reference
        tetrahedron, weights in its measure (all positive).

    Raises:
        ValueError: Bad shape or values, or a singular point of the zero set (naming
            the tetrahedron).
    """
    if frame not in FRAMES:
        raise ValueError(f"frame must be one of {FRAMES}, got {frame!r}")
    if raise_tolerance is not None and not raise_tolerance >= 0:
        raise ValueError(f"raise_tolerance must be >= 0 or None, got {raise_tolerance!r}")
    phi = nodal_values(phi, 10, "P2 tetrahedron", "tetrahedron")
    ncells = phi.shape[0]
    merged = {
        "minus": _Buffer([(3,), ()], [np.float64] * 2),
        "plus": _Buffer([(3,), ()], [np.float64] * 2),
        "interface": _Buffer([(), (3,), (), (3,)], [np.int64] + [np.float64] * 3),
    }
    counts: dict[str, list[np.ndarray]] = {"minus": [], "plus": []}
    reduced = []
    for start in range(0, ncells, _CHUNK):
        chunk = phi[start : start + _CHUNK]
        found: dict[str, list[tuple[np.ndarray, ...]]] = {side: [] for side in merged}
        size = chunk.shape[0]
        rest = np.arange(size)
        on_chunk = None if exact is None else _from_row(exact, start)
        margin = None if exact is None else exact_margin(chunk, on_chunk)
        if frame == "tetrahedron":
            C = _tet_coefficients(chunk)
            tolerance = raise_tolerance
            if raise_tolerance is not None and exact is not None:
                J = None
                if jacobian is not None:
                    J = jacobian(np.arange(start, start + size), np.full((size, 3), 0.25))
                tolerance = raise_tolerances(C, J, raise_tolerance)
            points, rest = truncated_saye_points(
                C,
                order,
                max_depth=max_depth,
                min_depth=min_depth,
                raise_tolerance=tolerance,
                exact=on_chunk,
                margin=margin,
            )
            reduced.append(points.reduced + start)
            if rest.size == 0:  # points sorted by row, vectors as (N, 3): nothing to merge
                for side in merged:
                    rows, *columns = getattr(points, side)
                    _append(merged, counts, side, rows + start, columns, start, size, ncells)
                continue
            for side in merged:
                rows, X, *columns = getattr(points, side)
                found[side].append((rows + start, X.T, *(c.T for c in columns)))
        C = _cube_coefficients(chunk[rest])
        C = C.reshape(rest.size, 4, *C.shape[1:])
        for k in range(4):  # hexahedron k of every cell: one map, no scatter
            points = saye_points(
                np.ascontiguousarray(C[:, k]),
                order,
                max_depth=max_depth,
                min_depth=min_depth,
                kind="tetrahedron",
                first=start,
                names=rest,
                exact=None if exact is None else _on_cube(exact, k, start),
                margin=None if margin is None else margin[rest],
            )
            for side in ("minus", "plus"):
                rows, U, w = getattr(points, side)
                X, c0, c1, c2 = _trilinear_map(U, _MONOMIALS[k])
                found[side].append((rest[rows] + start, X, w * (c0 * _cross(c1, c2)).sum(axis=0)))
            rows, U, w, area = points.interface
            X, c0, c1, c2 = _trilinear_map(U, _MONOMIALS[k])
            a0, a1, a2 = area.T
            area = _cross(c1, c2) * a0 + _cross(c2, c0) * a1 + _cross(c0, c1) * a2  # cof(dM) a
            found["interface"].append((rest[rows] + start, X, w, area))
            reduced.append(rest[points.reduced] + start)
        for side, parts in found.items():
            rows, *columns = _merged(parts)
            _append(merged, counts, side, rows, columns, start, size, ncells)
    sides = []
    for side in ("minus", "plus"):
        X, w = merged[side].arrays()
        offsets = np.concatenate([[0], *counts[side]]).cumsum().astype(np.int64)
        sides.append(RuleSet(X, w, offsets))
    rows, X, w, area = merged["interface"].arrays()
    interface = surface_rules(X, area, w, rows, ncells, jacobian)
    return CutRules(*sides, interface, np.unique(np.concatenate([*reduced, rows[:0]])))


@functools.cache
def _to_tet_monomials() -> np.ndarray:
    """Matrix ``(27, 10)``: P2 tetrahedron nodal values -> monomial coefficients ``(3, 3, 3)``
    of the same polynomial in the reference coordinates (flattened)."""
    q2 = basix.create_element(
        basix.ElementFamily.P, basix.CellType.hexahedron, 2, basix.LagrangeVariant.gll_warped
    )
    p2 = basix.create_element(
        basix.ElementFamily.P, basix.CellType.tetrahedron, 2, basix.LagrangeVariant.gll_warped
    )
    values = p2.tabulate(0, q2.points)[0, :, :, 0]  # (27, 10): the P2 basis at the Q2 nodes
    return coefficients(values.T, 2).reshape(10, 27).T


def _tet_coefficients(phi: np.ndarray) -> np.ndarray:
    """Monomial coefficients ``(n, 3, 3, 3)`` of P2 nodal values ``phi`` ``(n, 10)`` (einsum,
    not BLAS: a cell's coefficients must not depend on the batch it is in)."""
    return np.einsum("nk,jk->nj", phi, _to_tet_monomials()).reshape(-1, 3, 3, 3)


_CHUNK = 2048
"""Cells per batch of :func:`p2_tet_cut_rules`: small batches keep the temporaries small
enough for the allocator to reuse (fresh large arrays cost page faults)."""


def _append(merged, counts, side, rows, columns, start, size, ncells) -> None:
    """Append the points of ``side`` of the batch of ``size`` cells from row ``start``
    (sorted by ``rows``, vectors ``(N, 3)``) to the buffers ``merged``."""
    if side == "interface":
        columns = [rows, *columns]
    else:  # keep counts, not rows: offsets need no more
        counts[side].append(np.bincount(rows - start, minlength=size))
    merged[side].append(columns, batches=-(-ncells // _CHUNK))


class _Buffer:
    """Columns of points appended batch by batch into arrays that grow by doubling; pages
    beyond the points written are never touched (no copy of every batch at the end)."""

    def __init__(self, shapes: list[tuple[int, ...]], dtypes: list[type]):
        self.columns = [
            np.empty((0, *shape), dtype) for shape, dtype in zip(shapes, dtypes, strict=True)
        ]
        self.size = 0

    def append(self, columns: list[np.ndarray], batches: int) -> None:
        """Append ``columns`` (same lengths); ``batches``: the number of batches, to size
        the arrays at the first append."""
        n = columns[0].shape[0]
        if self.size + n > self.columns[0].shape[0]:
            capacity = max(2 * (self.size + n), 2 * n * batches)
            grown = [np.empty((capacity, *c.shape[1:]), c.dtype) for c in self.columns]
            for new, old in zip(grown, self.columns, strict=True):
                new[: self.size] = old[: self.size]
            self.columns = grown
        for target, column in zip(self.columns, columns, strict=True):
            target[self.size : self.size + n] = column
        self.size += n

    def arrays(self) -> list[np.ndarray]:
        return [c[: self.size] for c in self.columns]


def _from_row(exact: ExactLevelSet, start: int) -> ExactLevelSet:
    """``exact`` (of tetrahedron rows) for the rows of the batch from ``start``."""
    return lambda rows, X: exact(rows + start, X)


def _on_cube(exact: ExactLevelSet, k: int, start: int) -> ExactLevelSet:
    """``exact`` (of tetrahedron rows and points) on the cube of hexahedron ``k`` for the
    rows of the batch from ``start``."""

    def phi(rows: np.ndarray, U: np.ndarray) -> np.ndarray:
        return exact(rows + start, _trilinear_map(U, _MONOMIALS[k])[0].T)

    return phi


def _merged(parts: list[tuple[np.ndarray, ...]]) -> list[np.ndarray]:
    """Points of the four hexahedra ``(rows, X (3, N), w[, area (3, N)])`` of a batch in
    one list sorted by cell (stable: hexahedron 0 first), vectors as ``(N, 3)``."""
    rows = np.concatenate([p[0] for p in parts])
    order = np.argsort(rows, kind="stable")
    merged = [rows[order]]
    for column in range(1, len(parts[0])):
        values = np.concatenate([p[column] for p in parts], axis=-1)
        merged.append(np.take(values.T, order, axis=0))
    return merged


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cross products of vectors stored coordinate first, ``(3, N)``."""
    return np.stack(
        [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
    )
