"""Reference-cell data, sign topology and side polygons for cutting cells.

Helper of :mod:`xfem_contact.cut` (pure numpy and Basix, no DOLFINx). Cells are
Basix reference cells; the level set of each cell is given by its nodal values
``phi`` of shape ``(ncells, ndofs)`` in Basix Lagrange (``gll_warped``) order.

The cell boundary is walked as a counter-clockwise *loop* of vertices; loop
edge ``j`` runs from loop vertex ``j`` to loop vertex ``j + 1`` (cyclically). On
a loop edge the interpolant is a polynomial ``g(t) = A t^2 + B t + C`` of the
edge parameter ``t`` in ``[0, 1]`` (``A = 0`` for degree 1).

Tolerance policy (shared with :mod:`xfem_contact.cut`): ``phi < 0`` is side -1
and ``phi >= 0`` is side +1, decided by exact comparisons of floating-point
values. Two exceptions keep exact zeros from creating spurious topology:

* a vertex with ``phi == 0`` belongs to side -1 *for the topology of its cell*
  when the interpolant turns negative right next to it along an edge whose
  other end is on side +1 (the interface passes through the vertex and leaves
  along that edge); otherwise it stays on side +1;
* a dip of an edge polynomial to the other side by at most ``64 eps`` times
  the largest nodal magnitude of the cell counts as tangency, not as a double
  crossing (the same bound applies to the interior sample check).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import basix
import numpy as np
import numpy.typing as npt

_REMEDY = "refine the mesh near the interface"
_TANGENCY = 64.0 * np.finfo(np.float64).eps
_LATTICE = 8  # interior sample lattice: (_LATTICE + 1) points per direction


@dataclass(frozen=True)
class CellData:
    """Reference-cell data needed to cut cells of one type and level-set degree.

    Attributes:
        cell_type: ``"triangle"`` or ``"quadrilateral"``.
        degree: Degree of the level-set interpolant (1 or 2).
        element: The Basix Lagrange element of the level set.
        loop: Vertex numbers in counter-clockwise order, shape ``(nv,)``.
        loop_coords: Their reference coordinates, shape ``(nv, 2)``.
        loop_mid: Dof number of the mid-node of loop edge ``j``, shape ``(nv,)``
            (``-1`` for degree 1).
        face_normals: Outward normals ``n`` of the cell's half-planes
            ``n . X <= c``, shape ``(nv, 2)``.
        face_offsets: The matching ``c``, shape ``(nv,)``.
        lattice_basis: Basis values at the interior check lattice,
            shape ``(npoints, ndofs)``.
    """

    cell_type: str
    degree: int
    element: basix.finite_element.FiniteElement
    loop: npt.NDArray[np.int64]
    loop_coords: npt.NDArray[np.float64]
    loop_mid: npt.NDArray[np.int64]
    face_normals: npt.NDArray[np.float64]
    face_offsets: npt.NDArray[np.float64]
    lattice_basis: npt.NDArray[np.float64]

    @property
    def nv(self) -> int:
        """Number of vertices."""
        return int(self.loop.size)

    @property
    def ndofs(self) -> int:
        """Number of level-set dofs per cell."""
        return int(self.element.dim)


@functools.cache
def cell_data(cell_type: str, degree: int) -> CellData:
    """The :class:`CellData` of ``cell_type`` (``"triangle"`` or ``"quadrilateral"``)
    and level-set degree 1 or 2."""
    loops = {"triangle": [0, 1, 2], "quadrilateral": [0, 1, 3, 2]}
    if cell_type not in loops:
        raise ValueError(f"cell_type must be 'triangle' or 'quadrilateral', got {cell_type!r}")
    if degree not in (1, 2):
        raise ValueError(f"level-set degree must be 1 or 2, got {degree!r}")
    ctype = basix.CellType[cell_type]
    element = basix.create_element(
        basix.ElementFamily.P, ctype, degree, basix.LagrangeVariant.gll_warped
    )
    loop = np.array(loops[cell_type], dtype=np.int64)
    coords = basix.geometry(ctype)[loop]
    edges = [sorted(e) for e in basix.topology(ctype)[1]]
    loop_mid = np.full(loop.size, -1, dtype=np.int64)
    if degree == 2:
        for j in range(loop.size):
            e = edges.index(sorted((int(loop[j]), int(loop[(j + 1) % loop.size]))))
            loop_mid[j] = element.entity_dofs[1][e][0]
    # Counter-clockwise loop: the outward normal of edge P->Q is (dy, -dx).
    d = np.roll(coords, -1, axis=0) - coords
    normals = np.stack([d[:, 1], -d[:, 0]], axis=1)
    offsets = np.einsum("ij,ij->i", normals, coords)
    n = _LATTICE
    i, j = np.meshgrid(np.arange(n + 1), np.arange(n + 1), indexing="ij")
    keep = (i + j <= n) if cell_type == "triangle" else np.ones_like(i, dtype=bool)
    lattice = np.stack([i[keep], j[keep]], axis=1) / n
    basis = element.tabulate(0, lattice)[0, :, :, 0]
    return CellData(cell_type, degree, element, loop, coords, loop_mid, normals, offsets, basis)


def check_values(data: CellData, phi: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """``phi`` as a float64 array of shape ``(ncells, ndofs)``; raises on bad shape or
    non-finite values (naming the first offending cell)."""
    phi = np.asarray(phi, dtype=np.float64)
    if phi.ndim != 2 or phi.shape[1] != data.ndofs:
        raise ValueError(
            f"phi must have shape (ncells, {data.ndofs}) for a degree-{data.degree} "
            f"{data.cell_type}, got {phi.shape}"
        )
    bad = np.flatnonzero(~np.isfinite(phi).all(axis=1))
    if bad.size:
        raise ValueError(
            f"level-set nodal values of cell {bad[0]} are not finite ({phi[bad[0]].tolist()}); "
            f"{bad.size} cell(s) affected: check the level-set function"
        )
    return phi


def edge_coefficients(
    a: np.ndarray, b: np.ndarray, m: np.ndarray | None
) -> tuple[np.ndarray, np.ndarray]:
    """Coefficients ``A, B`` of ``g(t) = A t^2 + B t + a`` with ``g(0) = a``,
    ``g(1) = b`` and, for degree 2, ``g(1/2) = m`` (``m is None``: linear)."""
    if m is None:
        return np.zeros_like(a), b - a
    return 2.0 * a + 2.0 * b - 4.0 * m, 4.0 * m - 3.0 * a - b


def _loop_edges(data: CellData, phi: np.ndarray) -> tuple[np.ndarray, ...]:
    """Start values, end values, ``A`` and ``B`` of every loop edge, each ``(ncells, nv)``."""
    start = phi[:, data.loop]
    end = np.roll(start, -1, axis=1)
    mid = phi[:, data.loop_mid] if data.degree == 2 else None
    A, B = edge_coefficients(start, end, mid)
    return start, end, A, B


def describe_cells(cells: np.ndarray) -> str:
    """``"cell(s) [i, j, ...] (n in all)"`` for error messages."""
    shown = ", ".join(str(c) for c in cells[:10])
    return f"cell(s) [{shown}{', ...' if cells.size > 10 else ''}] ({cells.size} in all)"


def topology(data: CellData, phi: np.ndarray) -> npt.NDArray[np.bool_]:
    """Side of every vertex for the cut topology (``True``: side -1), in loop order.

    Args:
        data: Reference-cell data.
        phi: Checked nodal values, shape ``(ncells, ndofs)``.

    Returns:
        Boolean array ``(ncells, nv)``; a cell is cut iff its row is mixed.

    Raises:
        ValueError: For cells whose interpolant crosses one edge twice, whose
            boundary has more than two crossings (e.g. a saddle), or which are
            uncut at the boundary but change sign inside (a closed interface
            piece). The message names the cells and the remedy.
    """
    start, end, A, B = _loop_edges(data, phi)
    neg = start < 0
    # Zero vertices that the interface leaves along an edge towards side +1.
    out_neg = (B < 0) | ((B == 0) & (A < 0))  # g < 0 just after t = 0
    slope_end = 2.0 * A + B  # g'(1); going backwards from t = 1 the slope is -g'(1)
    in_neg = (slope_end > 0) | ((slope_end == 0) & (A < 0))  # g < 0 just before t = 1
    trig = (start == 0) & (((end >= 0) & out_neg) | (np.roll((start >= 0) & in_neg, 1, axis=1)))
    neg = neg | trig
    neg_end = np.roll(neg, -1, axis=1)
    tol = _TANGENCY * np.abs(phi).max(axis=1, keepdims=True)
    with np.errstate(divide="ignore", invalid="ignore"):
        tstar = -B / (2.0 * A)
        gstar = start + 0.5 * B * tstar  # g(t*) = C - B^2 / (4A)
    inside = (tstar > 0) & (tstar < 1)
    dip = inside & np.where(neg, (A < 0) & (gstar > tol), (A > 0) & (gstar < -tol))
    double = np.flatnonzero((dip & (neg == neg_end)).any(axis=1))
    if double.size:
        raise ValueError(
            f"the interpolated level set crosses an edge twice in {describe_cells(double)} "
            f"(two interface pieces, or a cap on one edge: unsupported); {_REMEDY}"
        )
    changes = (neg != neg_end).sum(axis=1)
    many = np.flatnonzero(changes > 2)
    if many.size:
        raise ValueError(
            "more than two interface crossings on the boundary (saddle) of "
            f"{describe_cells(many)}; {_REMEDY}"
        )
    if data.degree == 2:
        _check_interior(data, phi, neg, changes == 0, tol[:, 0])
    return neg


def _check_interior(
    data: CellData, phi: np.ndarray, neg: np.ndarray, uncut: np.ndarray, tol: np.ndarray
) -> None:
    """Raise if a cell uncut at its boundary changes sign at the interior lattice."""
    rows = np.flatnonzero(uncut)
    bad: list[np.ndarray] = []
    chunk = 65536
    for k in range(0, rows.size, chunk):  # bounded memory, vectorised within a chunk
        r = rows[k : k + chunk]
        values = phi[r] @ data.lattice_basis.T
        minus = neg[r, 0]
        wrong = np.where(minus, values.max(axis=1) > tol[r], values.min(axis=1) < -tol[r])
        bad.append(r[wrong])
    found = np.concatenate(bad) if bad else np.zeros(0, dtype=np.int64)
    if found.size:
        raise ValueError(
            f"the interpolated level set changes sign inside {describe_cells(found)} without "
            f"crossing its boundary (a closed interface piece); {_REMEDY}"
        )


def side_polygon(code: int, nv: int, side: int) -> list[int]:
    """Counter-clockwise polygon of one side of a cut cell as indices into the
    point table ``[loop vertices (nv), c_pm, c_mp]``.

    ``c_pm`` is the crossing on the loop edge going from side +1 to side -1 and
    ``c_mp`` the one going from -1 to +1. The side -1 polygon is
    ``[c_pm, negative vertices..., c_mp]`` and the side +1 polygon
    ``[c_mp, positive vertices..., c_pm]``; in both the interface closes the
    polygon from its last to its first point.

    Args:
        code: Sign pattern, bit ``j`` set iff loop vertex ``j`` is on side -1.
        nv: Number of vertices.
        side: -1 or +1.
    """
    neg = [(code >> j) & 1 == 1 for j in range(nv)]
    i_pm = next(j for j in range(nv) if not neg[j] and neg[(j + 1) % nv])
    i_mp = next(j for j in range(nv) if neg[j] and not neg[(j + 1) % nv])
    first, last, wanted = (i_pm, i_mp, True) if side == -1 else (i_mp, i_pm, False)
    inner, j = [], (first + 1) % nv
    while True:
        assert neg[j] == wanted
        inner.append(j)
        if j == last:
            break
        j = (j + 1) % nv
    start, stop = (nv, nv + 1) if side == -1 else (nv + 1, nv)
    return [start, *inner, stop]
