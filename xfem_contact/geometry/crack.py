"""Cracks as two level sets: cell classification, tip positions and the tip's polar coordinates.

Pure numpy and Basix, no DOLFINx. A crack is the zero line of a *normal* level set
``phi`` where a *tangential* level set ``psi`` is negative (Code_Aster's ``LN``/``LT``,
GetFEM's two level sets); its tip is where ``phi = psi = 0``. Both are Lagrange
interpolants (degree 1 or 2, Basix ``gll_warped`` node order) of nodal values
``(ncells, ndofs)`` on the same cells, as in :mod:`xfem_contact.geometry.cut`. All
positions are reference coordinates of the parent cell.

Each cell is of one kind (:data:`KIND_NAMES`): :data:`NONE` (``phi`` keeps its sign,
or ``psi >= 0`` along the whole zero line of ``phi`` in the cell), :data:`CROSSED`
(``psi < 0`` along all of it: the crack crosses the cell and is cut as a closed
interface by :func:`xfem_contact.geometry.cut.subtriangulate`; a crack that meets the
domain boundary ends in such cells) or :data:`TIP` (``psi`` changes sign once along
it: the tip is inside; cut by :mod:`xfem_contact.geometry.crack_tip_cell`).

Tolerance policy: ``psi`` is sampled at :data:`SAMPLES` points of the SEG3 of the
``phi`` cut; the tip is the Newton solution of ``(phi, psi) = 0`` started from the
sampled sign change, converged to ``16 eps``. Where ``|psi| <= tip_tol * (max psi -
min psi)`` at an end of the SEG3, the tip is that end, on the cell's boundary (a node
or an edge): the cell the crack comes from (``psi < 0`` along the rest of its SEG3) is
the tip cell, the one it goes on into is of the extension (:data:`NONE`), and a cell
``phi`` touches at that node only is :data:`NONE`. A crack along a mesh edge (``phi``
vanishing on it) is cut as an interface along the edge: by the cell on its side -1,
the other side's cell is uncut; a tip on such an edge is inside the SEG3 of that cell.
Refused with a ``ValueError`` naming the case and the cell: ``psi`` changing sign more
than once in a cell, or vanishing at both ends of a crack piece (*crack ends twice*), a
tip in a cell that ``phi`` does not cut simply, a tip Newton finds outside its cell,
and level sets tangent at the tip.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from xfem_contact.geometry.cut_simple import cut_simple, interpolant
from xfem_contact.geometry.cut_topology import (
    CellData,
    cell_data,
    check_values,
    describe_cells,
    describe_kinds,
    interior_values,
    seg3_basis,
    topology,
)

__all__ = ["NONE", "CROSSED", "TIP", "KIND_NAMES", "CrackCells", "classify_crack", "polar"]

NONE, CROSSED, TIP = 0, 1, 2
KIND_NAMES = {NONE: "none", CROSSED: "crossed", TIP: "tip"}
"""Name of each cell kind."""
SAMPLES = 17
"""Points of the ``phi`` cut at which ``psi`` is sampled."""
_EPS = np.finfo(np.float64).eps


@dataclass(frozen=True)
class CrackCells:
    """Kinds of cells for one crack and the tip of each tip cell.

    Attributes:
        kind: :data:`NONE`, :data:`CROSSED` or :data:`TIP` per cell, ``int8`` ``(ncells,)``.
        tip_cells: Rows of the tip cells, ``(ntip,)``, sorted.
        tip: Reference position of the tip in each, ``(ntip, 2)``.
    """

    kind: npt.NDArray[np.int8]
    tip_cells: npt.NDArray[np.int64]
    tip: npt.NDArray[np.float64]

    def cells(self, kind: int) -> npt.NDArray[np.int64]:
        """Rows of the cells of ``kind`` (:data:`NONE`, :data:`CROSSED`, :data:`TIP`)."""
        if kind not in KIND_NAMES:
            raise ValueError(f"kind must be one of {sorted(KIND_NAMES)}, got {kind!r}")
        return np.flatnonzero(self.kind == kind)

    def physical_tips(
        self, push_forward: Callable[[np.ndarray, np.ndarray], np.ndarray]
    ) -> npt.NDArray[np.float64]:
        """Physical tip positions ``(ntip, gdim)`` (m) through ``push_forward(rows (m,),
        X (m, 2)) -> (m, gdim)``, the parent maps of the cells (rows of ``phi``)."""
        return np.asarray(push_forward(self.tip_cells, self.tip), dtype=np.float64)


def classify_crack(
    cell_type: str,
    degree: int,
    phi: npt.ArrayLike,
    psi: npt.ArrayLike,
    tip_tol: float = 1e-9,
) -> CrackCells:
    """Kind of every cell for the crack ``phi = 0, psi < 0`` and its tips.

    Args:
        cell_type: ``"triangle"`` or ``"quadrilateral"``.
        degree: Level-set degree, 1 or 2 (both level sets).
        phi: Normal level set, nodal values ``(ncells, ndofs)``.
        psi: Tangential level set, nodal values ``(ncells, ndofs)``.
        tip_tol: ``|psi|`` (relative to its range in the cell) below which an end of
            the ``phi`` cut is the tip, on the cell's boundary; and the distance
            (reference units) by which a Newton tip may lie outside its cell.

    Returns:
        The :class:`CrackCells`.

    Raises:
        ValueError: Bad shapes or values, and the degenerate positions of the module
            docstring (the message names the case and the cells).
    """
    data = cell_data(cell_type, degree)
    phi, psi = check_values(data, phi), check_values(data, psi)
    if phi.shape != psi.shape:
        raise ValueError(f"psi must have the shape of phi {phi.shape}, got {psi.shape}")
    if not tip_tol > 0:
        raise ValueError(f"tip_tol must be positive, got {tip_tol!r}")
    scale = np.ptp(psi, axis=1)
    neg, flags = topology(data, phi)
    mixed = neg.any(axis=1) & ~neg.all(axis=1)
    kind = np.full(phi.shape[0], NONE, dtype=np.int8)
    _classify_special(data, phi, psi, flags, kind)
    simple = np.flatnonzero((flags == 0) & mixed)
    seg = cut_simple(data, phi[simple], neg[simple], None, 1e-15)[4]
    s = np.linspace(0.0, 1.0, SAMPLES)
    X = np.einsum("qk,ckd->cqd", seg3_basis(s)[0], seg)
    values = _values(data, psi[simple], X)
    # A tip on the cell's boundary (on a node or an edge) ends the zero line: psi = 0 there
    ends = np.abs(values[:, [0, -1]]) <= tip_tol * scale[simple, None]
    values[:, [0, -1]] = np.where(ends, 0.0, values[:, [0, -1]])
    point = np.hypot(*(seg[:, 1] - seg[:, 0]).T) == 0  # phi touches the cell at a node
    values[point & ends.any(axis=1)] = 0.0  # ... where the tip is: no crack in the cell
    below = values < 0
    changes, first, second = _sign_changes(values)
    if np.any(changes > 1):
        raise ValueError(
            f"the crack ends twice in {describe_cells(simple[changes > 1])}: psi changes sign "
            "more than once along phi = 0 (a crack shorter than a cell); refine the mesh"
        )
    crack_side = below.any(axis=1) & (changes == 0)  # psi <= 0 all along
    at_end = crack_side & ends.any(axis=1) & ~point  # the crack ends on the cell's boundary
    if np.any(at_end & ends.all(axis=1)):
        raise ValueError(
            f"the crack ends twice in {describe_cells(simple[at_end & ends.all(axis=1)])}: "
            "psi vanishes at both ends of phi = 0 (a crack of one cell); refine the mesh"
        )
    kind[simple] = np.where((changes == 1) | at_end, TIP, np.where(crack_side, CROSSED, NONE))
    tips = np.flatnonzero(changes == 1)
    i, j = first[tips], second[tips]
    v0, v1 = values[tips, i], values[tips, j]
    t = v0 / (v0 - v1)
    start = (1 - t)[:, None] * X[tips, i] + t[:, None] * X[tips, j]
    tip = _newton_tip(data, phi[simple[tips]], psi[simple[tips]], start, simple[tips])
    _refuse_outside(data, simple[tips], tip, tip_tol)
    boundary = np.flatnonzero(at_end)
    rows = np.concatenate([simple[tips], simple[boundary]])
    tip = np.concatenate([tip, seg[boundary, np.where(ends[boundary, 0], 0, 1)]])
    order = np.argsort(rows)
    return CrackCells(kind, rows[order], tip[order])


def _sign_changes(values: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per row of ``values`` ``(n, q)``: how often the sign changes between its nonzero
    samples (exact zeros, a tip on the cell's boundary, are skipped), and the columns
    ``(i, j)`` of the two nonzero samples the first change lies between; each ``(n,)``."""
    n = values.shape[0]
    count, i, j = (np.zeros(n, dtype=np.int64) for _ in range(3))
    last = np.full(n, -1)  # the column of the last nonzero sample, -1: none yet
    signs = np.sign(values)
    for column in range(values.shape[1]):
        here = signs[:, column] != 0
        change = here & (last >= 0)
        change &= signs[:, column] != signs[np.arange(n), np.maximum(last, 0)]
        first = change & (count == 0)
        i, j = np.where(first, last, i), np.where(first, column, j)
        count += change
        last = np.where(here, column, last)
    return count, i, j


def _values(data: CellData, values: np.ndarray, X: np.ndarray) -> np.ndarray:
    """Interpolant of ``values`` ``(n, ndofs)`` at points ``X`` ``(n, q, 2)`` of each row."""
    n, q = X.shape[:2]
    return interpolant(data, np.repeat(values, q, axis=0), X.reshape(-1, 2))[0].reshape(n, q)


def _classify_special(
    data: CellData, phi: np.ndarray, psi: np.ndarray, flags: np.ndarray, kind: np.ndarray
) -> None:
    """Kinds of the cells ``phi`` does not cut simply (``flags != 0``): crossed when
    ``psi < 0`` at every node and lattice point, none when ``> 0``; else refused."""
    rows = np.flatnonzero(flags != 0)
    if rows.size == 0:
        return
    inner = interior_values(data, psi, rows)
    low = np.minimum(psi[rows].min(axis=1), inner.min(axis=1))
    high = np.maximum(psi[rows].max(axis=1), inner.max(axis=1))
    kind[rows[high < 0]] = CROSSED
    bad = (low <= 0) & (high >= 0)
    if bad.any():
        raise ValueError(
            f"a crack tip lies in {describe_cells(rows[bad])}, where the normal level set "
            f"{describe_kinds(flags[rows[bad]])}; refine the mesh near the tip"
        )


def _newton_tip(
    data: CellData, phi: np.ndarray, psi: np.ndarray, X: np.ndarray, rows: np.ndarray
) -> np.ndarray:
    """Solve ``(phi, psi)(X) = 0`` per row by Newton from ``X`` ``(n, 2)``."""
    X = X.copy()
    for _ in range(50):
        f, gf = interpolant(data, phi, X)
        g, gg = interpolant(data, psi, X)
        det = gf[:, 0] * gg[:, 1] - gf[:, 1] * gg[:, 0]
        size = np.hypot(*gf.T) * np.hypot(*gg.T)
        tangent = np.abs(det) <= 1e-10 * size
        if tangent.any():
            raise ValueError(
                f"phi and psi are tangent at the crack tip in {describe_cells(rows[tangent])}; "
                "psi must cross the crack line"
            )
        step = np.stack([gg[:, 1] * f - gf[:, 1] * g, gf[:, 0] * g - gg[:, 0] * f], axis=1)
        step /= det[:, None]
        X -= step
        if np.all(np.abs(step) <= 16 * _EPS):
            break
    return X


def _refuse_outside(data: CellData, rows: np.ndarray, X: np.ndarray, tol: float) -> None:
    """Refuse tips ``X`` ``(n, 2)`` farther than ``tol`` outside their cells."""
    if rows.size == 0:
        return
    norms = np.hypot(*data.face_normals.T)
    distance = (data.face_offsets - X @ data.face_normals.T) / norms  # (n, nfaces)
    outside = (distance < -tol).any(axis=1)
    if outside.any():
        raise ValueError(
            f"no crack tip found inside {describe_cells(rows[outside])} (Newton on (phi, psi) "
            "= 0 left the cell); the level sets are too curved for the mesh: refine it"
        )


def polar(
    phi: npt.ArrayLike,
    psi: npt.ArrayLike,
    grad_phi: npt.ArrayLike | None = None,
    grad_psi: npt.ArrayLike | None = None,
) -> tuple[np.ndarray, ...]:
    """The tip's local polar coordinates from the level sets, with their gradients.

    ``r = sqrt(phi^2 + psi^2)`` and ``theta = atan2(phi, psi)``: the crack lies
    along ``theta = +-pi`` (``+pi`` on the lip ``phi > 0``, the Williams fields'
    convention), ``theta = 0`` ahead of the tip. Exact for a straight crack with
    signed-distance level sets. ``grad r = (phi grad phi + psi grad psi) / r``,
    ``grad theta = (psi grad phi - phi grad psi) / r^2``.

    Args:
        phi, psi: Level-set values at points, shape ``(m,)`` (m).
        grad_phi, grad_psi: Their gradients ``(m, gdim)`` (any frame; give both or none).

    Returns:
        ``(r, theta)`` of shape ``(m,)``, followed by ``(grad_r, grad_theta)`` of shape
        ``(m, gdim)`` when the gradients are given. At ``r = 0`` the gradients are NaN.
    """
    phi, psi = np.asarray(phi, dtype=np.float64), np.asarray(psi, dtype=np.float64)
    if phi.shape != psi.shape:
        raise ValueError(f"psi must have the shape of phi {phi.shape}, got {psi.shape}")
    r, theta = np.hypot(phi, psi), np.arctan2(phi, psi)
    if grad_phi is None and grad_psi is None:
        return r, theta
    if grad_phi is None or grad_psi is None:
        raise ValueError("grad_phi and grad_psi: give both or none")
    gphi, gpsi = np.asarray(grad_phi, np.float64), np.asarray(grad_psi, np.float64)
    if gphi.shape != gpsi.shape or gphi.shape[:1] != phi.shape:
        raise ValueError(f"grad_phi and grad_psi must have shape ({phi.size}, gdim)")
    with np.errstate(divide="ignore", invalid="ignore"):
        grad_r = (phi[:, None] * gphi + psi[:, None] * gpsi) / r[:, None]
        grad_theta = (psi[:, None] * gphi - phi[:, None] * gpsi) / (r * r)[:, None]
    return r, theta, grad_r, grad_theta
