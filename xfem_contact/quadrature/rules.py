"""Per-cell quadrature rules on cut cells from a :class:`~xfem_contact.geometry.cut.CutGeometry`.

Pure numpy and Basix. Points are in the parent cell's (dimensionless)
reference coordinates. Weights are in the parent *reference* measure: FFCx
multiplies every weight by ``|det J|`` of the parent map, so a side rule sums
to the reference area of that side and an interface rule stores
``ds / |det J|`` (``ds`` physical arc length) so that FFCx's factor turns it
into arc length.

Accuracy: a side rule of degree ``q`` maps Basix's triangle rule through
each curved P2 sub-triangle, whose map is quadratic with a quadratic
Jacobian determinant; it integrates polynomials of degree ``p`` exactly when
``2 p + 2 <= q`` (``p <= q`` on sub-triangles with straight edges). On a
curved SEG3 the length element ``|dX/ds|`` is the square root of a
polynomial, so the interface rule is not exact even for constants; it
converges fast as its degree grows (exact on straight pieces).
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass

import basix
import numpy as np
import numpy.typing as npt

from xfem_contact.geometry.cut import CutGeometry
from xfem_contact.geometry.cut_topology import seg3_basis

__all__ = ["RuleSet", "curve_rules", "interface_rule", "side_rules", "triangle_rules"]


@dataclass(frozen=True)
class RuleSet:
    """Quadrature rules of a set of cut cells, stored back to back.

    Attributes:
        points: Reference points, shape ``(N, 2)``.
        weights: Weights in the parent reference measure, shape ``(N,)``.
        offsets: Rule ``k`` is rows ``offsets[k]:offsets[k + 1]``, shape
            ``(ncut + 1,)``, int64. Empty rules have equal offsets.
        normals: Physical unit normals, shape ``(N, gdim)``, pointing from side
            -1 to side +1 (interface rules only, else ``None``).
    """

    points: npt.NDArray[np.float64]
    weights: npt.NDArray[np.float64]
    offsets: npt.NDArray[np.int64]
    normals: npt.NDArray[np.float64] | None = None

    @property
    def point_rows(self) -> npt.NDArray[np.int64]:
        """Rule (cut-cell row) of every point, shape ``(N,)``."""
        return np.repeat(np.arange(self.offsets.size - 1), np.diff(self.offsets))

    @property
    def num_rules(self) -> int:
        """Number of rules (cut cells)."""
        return int(self.offsets.size - 1)

    def sums(self, values: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """Per rule, the sum of ``values`` ``(N,)`` over its points, shape ``(num_rules,)``
        (0 for an empty rule, wherever it lies)."""
        values = np.asarray(values, dtype=np.float64)
        if values.shape != self.weights.shape:
            raise ValueError(f"values must have shape {self.weights.shape}, got {values.shape}")
        return np.bincount(self.point_rows, weights=values, minlength=self.num_rules)

    def select(self, keep: npt.NDArray[np.bool_]) -> RuleSet:
        """The same rules with those of the rows not in ``keep`` emptied.

        Args:
            keep: Per rule (cut-cell row), shape ``(num_rules,)``.

        Returns:
            A :class:`RuleSet` with the same number of rules (rows keep their
            meaning), holding only the points of the kept rules.
        """
        keep = np.asarray(keep, dtype=bool)
        if keep.shape != (self.num_rules,):
            raise ValueError(f"keep must have shape ({self.num_rules},), got {keep.shape}")
        points = keep[self.point_rows]
        counts = np.where(keep, np.diff(self.offsets), 0)
        return RuleSet(
            self.points[points],
            self.weights[points],
            _offsets(counts),
            None if self.normals is None else self.normals[points],
        )

    def replace(self, rows: npt.NDArray[np.int64], other: RuleSet) -> RuleSet:
        """The same rules with rule ``rows[k]`` replaced by rule ``k`` of ``other``.

        Args:
            rows: Distinct rule rows, shape ``(other.num_rules,)``.
            other: The new rules (normals if and only if this set has normals).

        Returns:
            A :class:`RuleSet` with the same number of rules.
        """
        rows = np.asarray(rows, dtype=np.int64)
        if rows.shape != (other.num_rules,) or np.unique(rows).size != rows.size:
            raise ValueError(f"rows must be {other.num_rules} distinct rule rows, got {rows}")
        if (self.normals is None) != (other.normals is None):
            raise ValueError("replace: both rule sets need normals, or neither")
        starts, counts = self.offsets[:-1].copy(), np.diff(self.offsets)
        starts[rows] = self.points.shape[0] + other.offsets[:-1]  # into the concatenation
        counts[rows] = np.diff(other.offsets)
        take = np.repeat(starts - np.cumsum(counts) + counts, counts) + np.arange(counts.sum())
        points = np.concatenate([self.points, other.points])[take]
        weights = np.concatenate([self.weights, other.weights])[take]
        normals = None
        if self.normals is not None:
            normals = np.concatenate([self.normals, other.normals])[take]
        return RuleSet(points, weights, _offsets(counts), normals)


@functools.cache
def _p2_triangle() -> basix.finite_element.FiniteElement:
    return basix.create_element(
        basix.ElementFamily.P, basix.CellType.triangle, 2, basix.LagrangeVariant.gll_warped
    )


def _offsets(counts: np.ndarray) -> np.ndarray:
    return np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)


def side_rules(geom: CutGeometry, side: int, degree: int, ncut: int) -> RuleSet:
    """Rules of one side of every cut cell through its curved P2 sub-triangles.

    ``X = sum_i N_i(xi) X_i`` and ``w = w_hat det(dX/dxi)`` for each point
    ``(xi, w_hat)`` of ``basix.make_quadrature(triangle, degree)``. Sub-triangles
    are counter-clockwise and unfolded (``det > 0``), so this is
    ``w_hat |det dX/dxi|``, except on the rare least-folded fallback of
    :mod:`xfem_contact.geometry.cut_subcells`, where the signed determinant keeps the
    rule exact (folds cancel) and weights in the fold are negative.

    Args:
        geom: Sub-triangulation of the cut cells.
        side: -1 or +1.
        degree: Polynomial degree of the triangle rule.
        ncut: Number of cut cells (rules), ``geom.num_cells``.

    Returns:
        A :class:`RuleSet` (no normals); cells without sub-triangles on this
        side get empty rules.
    """
    if side not in (-1, 1):
        raise ValueError(f"side must be -1 or +1, got {side!r}")
    _check_ncut(geom, ncut)
    tri, cell = (
        (geom.tri_minus, geom.tri_minus_cell) if side == -1 else (geom.tri_plus, geom.tri_plus_cell)
    )
    order = np.argsort(cell, kind="stable")
    xi, w_hat = basix.make_quadrature(basix.CellType.triangle, degree)
    return triangle_rules(tri[order], cell[order], ncut, xi, w_hat)


def triangle_rules(
    tri: np.ndarray, cell: np.ndarray, ncut: int, xi: np.ndarray, w_hat: np.ndarray
) -> RuleSet:
    """Rules of cells through their curved P2 sub-triangles and a reference-triangle rule.

    Args:
        tri: P2 sub-triangles ``(m, 6, 2)`` (Basix node order), sorted by cell.
        cell: Cell row of each, shape ``(m,)``, sorted.
        ncut: Number of cells (rules).
        xi: Points of the rule on the reference triangle, shape ``(nq, 2)``.
        w_hat: Its weights, shape ``(nq,)``.

    Returns:
        A :class:`RuleSet` (no normals): ``X = sum_i N_i(xi) X_i``, ``w = w_hat det(dX/dxi)``.
    """
    tab = _p2_triangle().tabulate(1, xi)[:, :, :, 0]  # (3, nq, 6)
    X = np.einsum("qi,tid->tqd", tab[0], tri)
    J = np.einsum("kqi,tid->tqdk", tab[1:], tri)  # dX_d / dxi_k
    det = J[..., 0, 0] * J[..., 1, 1] - J[..., 0, 1] * J[..., 1, 0]
    weights = w_hat * det
    counts = np.bincount(cell, minlength=ncut) * xi.shape[0]
    return RuleSet(X.reshape(-1, 2), weights.reshape(-1), _offsets(counts))


def _check_ncut(geom: CutGeometry, ncut: int) -> None:
    """Raise unless ``ncut`` is the geometry's number of cut cells."""
    if ncut != geom.num_cells:
        raise ValueError(
            f"ncut = {ncut} but the geometry has {geom.num_cells} cut cells; "
            "pass the number of rows given to cut.subtriangulate"
        )


def _unit(v: np.ndarray) -> np.ndarray:
    norm = np.linalg.norm(v, axis=-1, keepdims=True)
    return np.divide(v, norm, out=np.zeros_like(v), where=norm > 0)


def interface_rule(
    geom: CutGeometry,
    degree: int,
    ncut: int,
    jacobian: Callable[[np.ndarray, np.ndarray], np.ndarray],
    grad_phi_ref: Callable[[np.ndarray, np.ndarray], np.ndarray],
) -> RuleSet:
    """Gauss-Legendre rules on the SEG3 interface pieces, with physical normals.

    The rule of a cut cell concatenates those of its pieces (several in a
    subdivided cell).

    A point ``s`` (weight ``w_hat``) of ``basix.make_quadrature(interval, degree)``
    maps to ``X(s)`` through the SEG3 nodes ``a, mid, b`` at ``s = 0, 1/2, 1``.
    With the parent Jacobian ``J = dx/dX`` the physical tangent is
    ``t = J dX/ds`` and the stored weight ``w_hat |t| / vol(J)``, where
    ``vol(J) = sqrt(det(J^T J))`` (``|det J|`` when ``gdim = 2``). The normal is
    the curve's unit normal ``J (J^T J)^{-1} n_ref`` (``n_ref`` the reference
    normal of the SEG3, i.e. the tangent ``t`` rotated by 90 degrees when
    ``gdim = 2``), oriented so that it has a non-negative component along the
    physical level-set gradient ``J (J^T J)^{-1} grad_ref(phi)``. Zero-length
    pieces (the interface touches the cell at one point) contribute no points;
    a cell without other pieces gets an empty rule.

    Args:
        geom: Sub-triangulation of the cut cells.
        degree: Polynomial degree of the interval rule.
        ncut: Number of cut cells, ``geom.num_cells``.
        jacobian: ``(rows (m,), X (m, 2)) -> (m, gdim, 2)``: the parent map's
            Jacobian at reference points of cut cells ``rows``.
        grad_phi_ref: ``(rows (m,), X (m, 2)) -> (m, 2)``: reference gradient of
            the level set, used only for the orientation of the normal.

    Returns:
        A :class:`RuleSet` with normals of shape ``(N, gdim)``.
    """
    _check_ncut(geom, ncut)
    seg = geom.seg
    pieces = np.flatnonzero(~(seg[:, 0] == seg[:, 1]).all(axis=1))
    pieces = pieces[np.argsort(geom.seg_cell[pieces], kind="stable")]
    cells = geom.seg_cell[pieces]
    s, w_hat = basix.make_quadrature(basix.CellType.interval, degree)
    nq = s.shape[0]
    N, dN = seg3_basis(s[:, 0])
    X = np.einsum("qk,ckd->cqd", N, seg[pieces]).reshape(-1, 2)
    dX = np.einsum("qk,ckd->cqd", dN, seg[pieces]).reshape(-1, 2)
    w = np.tile(w_hat, pieces.size)
    return curve_rules(X, dX, w, np.repeat(cells, nq), ncut, jacobian, grad_phi_ref)


def curve_rules(
    X: np.ndarray,
    dX: np.ndarray,
    w: np.ndarray,
    rows: np.ndarray,
    ncut: int,
    jacobian: Callable[[np.ndarray, np.ndarray], np.ndarray],
    grad_phi_ref: Callable[[np.ndarray, np.ndarray], np.ndarray],
) -> RuleSet:
    """Rules on curves given by points, tangents and parameter weights (see :func:`interface_rule`).

    Args:
        X: Reference points ``(N, 2)``, sorted by ``rows``.
        dX: Reference tangents ``dX/ds`` there, ``(N, 2)``; side -1 lies on their left.
        w: Weights in the curve parameter ``s``, ``(N,)``.
        rows: Cell row of each point, ``(N,)``, sorted.
        ncut: Number of cells (rules).
        jacobian, grad_phi_ref: As for :func:`interface_rule`.

    Returns:
        A :class:`RuleSet` with weights ``w |J dX/ds| / vol(J)`` and normals ``(N, gdim)``.
    """
    J = np.asarray(jacobian(rows, X), dtype=np.float64)
    if J.ndim != 3 or J.shape[0] != rows.size or J.shape[2] != 2:
        raise ValueError(f"jacobian must return shape ({rows.size}, gdim, 2), got {J.shape}")
    G = np.einsum("mdi,mdj->mij", J, J)
    detG = G[:, 0, 0] * G[:, 1, 1] - G[:, 0, 1] * G[:, 1, 0]
    Ginv = np.stack([[G[:, 1, 1], -G[:, 0, 1]], [-G[:, 1, 0], G[:, 0, 0]]]).transpose(2, 0, 1)
    Ginv = Ginv / detG[:, None, None]
    t = np.einsum("mdi,mi->md", J, dX)
    weights = w * np.linalg.norm(t, axis=1) / np.sqrt(detG)
    n_ref = np.stack([dX[:, 1], -dX[:, 0]], axis=1)  # towards side +1 (see CutGeometry.seg)
    normal = _unit(np.einsum("mdi,mij,mj->md", J, Ginv, n_ref))
    grad = np.asarray(grad_phi_ref(rows, X), dtype=np.float64)
    grad_x = np.einsum("mdi,mij,mj->md", J, Ginv, grad)
    normal = np.where(((normal * grad_x).sum(axis=1) < 0)[:, None], -normal, normal)
    return RuleSet(X, weights, _offsets(np.bincount(rows, minlength=ncut)), normal)
