"""Reference-cell data, sign topology and side polygons for cutting cells.

Base of :mod:`xfem_contact.geometry.cut` and its helper modules, importing none of
them (pure numpy and Basix, no DOLFINx). Cells are Basix reference cells; the
level set of each cell is given by its nodal values ``phi`` of shape
``(ncells, ndofs)`` in Basix Lagrange (``gll_warped``) order.

The cell boundary is walked as a counter-clockwise *loop* of vertices; loop
edge ``j`` runs from loop vertex ``j`` to loop vertex ``j + 1`` (cyclically). On
a loop edge the interpolant is a polynomial ``g(t) = A t^2 + B t + C`` of the
edge parameter ``t`` in ``[0, 1]`` (``A = 0`` for degree 1).

Tolerance policy (shared with :mod:`xfem_contact.geometry.cut`): ``phi < 0`` is side -1
and ``phi >= 0`` is side +1, decided by exact comparisons of floating-point
values. Two exceptions keep exact zeros from creating spurious topology:

* a vertex with ``phi == 0`` belongs to side -1 *for the topology of its cell*
  when the interpolant turns negative right next to it along an edge whose
  other end is on side +1 (the interface passes through the vertex and leaves
  along that edge); otherwise it stays on side +1;
* a dip of an edge polynomial to the other side by at most ``64 eps`` times
  the largest nodal magnitude of the cell counts as tangency, not as a double
  crossing (the same bound applies to the interior sample check).

:func:`topology` also flags the cells whose zero line one SEG3 cannot represent
(:data:`TWICE`, :data:`MANY`, :data:`INTERIOR`, :data:`CORNER`). Cells with
only :data:`CORNER` lie wholly on side -1 with the interface along their zero
edges (:func:`zero_edges`); the others are cut after subdividing them into
sub-cells (:mod:`xfem_contact.geometry.cut_children`), on which the level set is again a
degree-1 or 2 Lagrange interpolant (:func:`lagrange_basis` evaluates it at
their nodes). :func:`side_polygon` lists the two sides of a simply cut cell.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import basix
import numpy as np
import numpy.typing as npt

TANGENCY = 64.0 * np.finfo(np.float64).eps
"""Dips within ``TANGENCY * max|phi|`` of zero (per cell) are tangency, not crossings."""
_LATTICE = 8  # interior sample lattice: (_LATTICE + 1) points per direction

# Cuts that one SEG3 cannot represent (bit flags in the ``kind`` of :func:`topology`).
TWICE = 1
"""An edge crossed twice (a cap on one edge, or two interface pieces through it)."""
MANY = 2
"""More than two boundary crossings (several pieces, e.g. at a saddle)."""
INTERIOR = 4
"""A sign change inside but none on the boundary (a closed interface piece)."""
CORNER = 8
"""The interpolant vanishes on two (or more) whole edges of a cut cell and is
positive at no vertex, e.g. at a corner of a mesh-aligned polygonal interface
or where two branches cross."""
KIND_NAMES = {
    TWICE: "crosses an edge twice",
    MANY: "crosses the boundary more than twice",
    INTERIOR: "changes sign inside without crossing the boundary",
    CORNER: "vanishes along two edges",
}


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
        lattice: Interior check lattice, shape ``(npoints, 2)``.
        lattice_basis: Basis values at the lattice, shape ``(npoints, ndofs)``.
        vertices: Vertex coordinates in Basix order, shape ``(nv, 2)``.
        node_weights: Coordinates of the level-set nodes as exact affine (or
            bilinear) combinations of the vertices, shape ``(ndofs, nv)``.
    """

    cell_type: str
    degree: int
    element: basix.finite_element.FiniteElement
    loop: npt.NDArray[np.int64]
    loop_coords: npt.NDArray[np.float64]
    loop_mid: npt.NDArray[np.int64]
    face_normals: npt.NDArray[np.float64]
    face_offsets: npt.NDArray[np.float64]
    lattice: npt.NDArray[np.float64]
    lattice_basis: npt.NDArray[np.float64]
    vertices: npt.NDArray[np.float64]
    node_weights: npt.NDArray[np.float64]

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
    vertices = basix.geometry(ctype)
    coords = vertices[loop]
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
    weights = lagrange_basis(cell_type, 1, element.points)  # exact multiples of 1/4
    return CellData(
        cell_type,
        degree,
        element,
        loop,
        coords,
        loop_mid,
        normals,
        offsets,
        lattice,
        basis,
        vertices,
        weights,
    )


def lagrange_basis(cell_type: str, degree: int, X: np.ndarray) -> npt.NDArray[np.float64]:
    """Basix's degree-1 or 2 Lagrange basis (equispaced, node order of Basix) at
    points ``X`` ``(m, 2)``, shape ``(m, ndofs)``, in closed form: exactly 0 or 1
    at the nodes, so values at nodes shared with a parent cell are reproduced
    bitwise (Basix's tabulation differs by rounding)."""
    x, y = X[:, 0], X[:, 1]
    if cell_type == "triangle":
        lam = [1.0 - x - y, x, y]
        if degree == 1:
            return np.stack(lam, axis=1)
        return np.stack(
            [l * (2.0 * l - 1.0) for l in lam]  # noqa: E741
            + [4.0 * lam[i] * lam[j] for i, j in ((1, 2), (0, 2), (0, 1))],
            axis=1,
        )
    if degree == 1:
        lx, ly = [1.0 - x, x], [1.0 - y, y]
        return np.stack([lx[0] * ly[0], lx[1] * ly[0], lx[0] * ly[1], lx[1] * ly[1]], axis=1)
    # 1D nodes 0, 1, 1/2; tensor order: vertices, edges (0,1), (0,2), (1,3), (2,3), interior
    lx = [2.0 * (x - 0.5) * (x - 1.0), 2.0 * x * (x - 0.5), 4.0 * x * (1.0 - x)]
    ly = [2.0 * (y - 0.5) * (y - 1.0), 2.0 * y * (y - 0.5), 4.0 * y * (1.0 - y)]
    order = [(0, 0), (1, 0), (0, 1), (1, 1), (2, 0), (0, 2), (1, 2), (2, 1), (2, 2)]
    return np.stack([lx[i] * ly[j] for i, j in order], axis=1)


def seg3_basis(s: np.ndarray) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """SEG3 shape functions and their derivatives at ``s`` ``(nq,)`` in ``[0, 1]``,
    node order (a, b, mid) (Basix interval order); each of shape ``(nq, 3)``."""
    N = np.stack([2 * (s - 0.5) * (s - 1), 2 * s * (s - 0.5), 4 * s * (1 - s)], axis=1)
    dN = np.stack([4 * s - 3, 4 * s - 1, 4 - 8 * s], axis=1)
    return N, dN


def nodal_values(phi: npt.ArrayLike, ndofs: int, element: str, cell: str = "cell"):
    """``phi`` as a float64 array of shape ``(ncells, ndofs)``; raises on a bad shape
    (naming the ``element``, e.g. ``"P1 tetrahedron"``) or non-finite values (naming the
    first offending ``cell`` by its row). Any cell kind and degree."""
    phi = np.asarray(phi, dtype=np.float64)
    if phi.ndim != 2 or phi.shape[1] != ndofs:
        raise ValueError(f"phi must have shape (ncells, {ndofs}) for a {element}, got {phi.shape}")
    bad = np.flatnonzero(~np.isfinite(phi).all(axis=1))
    if bad.size:
        raise ValueError(
            f"level-set nodal values of {cell} {bad[0]} are not finite ({phi[bad[0]].tolist()}); "
            f"{bad.size} cell(s) affected: check the level-set function"
        )
    return phi


def check_values(data: CellData, phi: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """``phi`` as a float64 array of shape ``(ncells, ndofs)`` of ``data``'s cells
    (:func:`nodal_values`)."""
    return nodal_values(phi, data.ndofs, f"degree-{data.degree} {data.cell_type}")


def edge_coefficients(
    a: np.ndarray, b: np.ndarray, m: np.ndarray | None
) -> tuple[np.ndarray, np.ndarray]:
    """Coefficients ``A, B`` of ``g(t) = A t^2 + B t + a`` with ``g(0) = a``,
    ``g(1) = b`` and, for degree 2, ``g(1/2) = m`` (``m is None``: linear)."""
    if m is None:
        return np.zeros_like(a), b - a
    return 2.0 * a + 2.0 * b - 4.0 * m, 4.0 * m - 3.0 * a - b


def loop_edges(data: CellData, phi: np.ndarray) -> tuple[np.ndarray, ...]:
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


def topology(data: CellData, phi: np.ndarray) -> tuple[npt.NDArray[np.bool_], npt.NDArray[np.int8]]:
    """Side of every vertex for the cut topology, and the cuts one SEG3 cannot represent.

    Args:
        data: Reference-cell data.
        phi: Checked nodal values, shape ``(ncells, ndofs)``.

    Returns:
        ``neg``: boolean ``(ncells, nv)``, ``True`` for loop vertices on side -1;
        a cell with ``kind == 0`` is cut iff its row is mixed. ``kind``: ``int8``
        ``(ncells,)``, the bitwise or of :data:`TWICE`, :data:`MANY`,
        :data:`INTERIOR` and :data:`CORNER` (0: uncut, or one simple cut).
        :data:`INTERIOR` is checked for degree 2 only (a bilinear or linear
        interpolant has no closed zero line).
    """
    start, end, A, B = loop_edges(data, phi)
    neg = start < 0
    # Zero vertices that the interface leaves along an edge towards side +1.
    out_neg = (B < 0) | ((B == 0) & (A < 0))  # g < 0 just after t = 0
    slope_end = 2.0 * A + B  # g'(1); going backwards from t = 1 the slope is -g'(1)
    in_neg = (slope_end > 0) | ((slope_end == 0) & (A < 0))  # g < 0 just before t = 1
    trig = (start == 0) & (((end >= 0) & out_neg) | (np.roll((start >= 0) & in_neg, 1, axis=1)))
    neg = neg | trig
    tol = TANGENCY * np.abs(phi).max(axis=1)
    double, _ = double_crossings(start, A, B, neg, tol)
    changes = (neg != np.roll(neg, -1, axis=1)).sum(axis=1)
    mixed = changes > 0
    corner = mixed & (_zero_edges(start, A, B).sum(axis=1) >= 2) & ~(start > 0).any(axis=1)
    kind = (
        np.where(double.any(axis=1), TWICE, 0)
        | np.where(changes > 2, MANY, 0)
        | np.where(corner, CORNER, 0)
    ).astype(np.int8)
    if data.degree == 2:  # uncut at the boundary, or wholly -1 there: a sign change inside?
        rows = np.flatnonzero(~mixed | corner)
        kind[_interior_sign_changes(data, phi, neg, rows, tol)] |= INTERIOR
    return neg, kind


def _zero_edges(start: np.ndarray, A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """Loop edges on which the interpolant vanishes identically, ``(ncells, nv)``."""
    return (start == 0) & (A == 0) & (B == 0)


def zero_edges(data: CellData, phi: np.ndarray) -> npt.NDArray[np.bool_]:
    """Loop edges ``(ncells, nv)`` on which the interpolant of ``phi`` vanishes identically."""
    start, _, A, B = loop_edges(data, phi)
    return _zero_edges(start, A, B)


def double_crossings(
    start: np.ndarray, A: np.ndarray, B: np.ndarray, neg: np.ndarray, tol: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Loop edges whose polynomial dips beyond ``tol`` ``(ncells,)`` to the side
    opposite to both (topological) end signs, ``(ncells, nv)``, and the parameter
    of each edge's extremum ``-B / 2A`` (meaningful where dipping)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        tstar = -B / (2.0 * A)
        gstar = start + 0.5 * B * tstar  # g(t*) = C - B^2 / (4A)
    inside = (tstar > 0) & (tstar < 1)
    tol = tol[:, None]
    dip = inside & np.where(neg, (A < 0) & (gstar > tol), (A > 0) & (gstar < -tol))
    return dip & (neg == np.roll(neg, -1, axis=1)), tstar


def interior_values(data: CellData, phi: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """Interpolant at the interior lattice for cells ``rows``, ``(rows.size, npoints)``."""
    return phi[rows] @ data.lattice_basis.T


def _interior_sign_changes(
    data: CellData, phi: np.ndarray, neg: np.ndarray, rows: np.ndarray, tol: np.ndarray
) -> np.ndarray:
    """The cells among ``rows`` (uncut at the boundary, or with no vertex on side
    +1) whose interpolant takes the other side's sign beyond ``tol`` at an
    interior lattice point."""
    found = [np.zeros(0, dtype=np.int64)]
    chunk = 65536
    for k in range(0, rows.size, chunk):  # bounded memory, vectorised within a chunk
        r = rows[k : k + chunk]
        values = interior_values(data, phi, r)
        minus = neg[r].any(axis=1)
        wrong = np.where(minus, values.max(axis=1) > tol[r], values.min(axis=1) < -tol[r])
        found.append(r[wrong])
    return np.concatenate(found)


def describe_kinds(kind: np.ndarray) -> str:
    """What the flags in ``kind`` say, e.g. ``"crosses an edge twice"`` (for errors)."""
    present = int(np.bitwise_or.reduce(kind, initial=0))
    return " / ".join(text for flag, text in KIND_NAMES.items() if present & flag)


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
