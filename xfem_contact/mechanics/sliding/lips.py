"""The master lip of an interface, on every process: curved pieces mapped by a field.

A piece is a SEG3 of a cut cell in that cell's reference coordinates
(:class:`~xfem_contact.geometry.cut.CutGeometry`); its deformed position is
``x(s) = F_c(X(s)) + u_m(X(s))``, ``s in [0, 1]``, with ``F_c`` the cell map and
``u_m`` the master side's displacement. The pieces of all processes are gathered once
(reference data, dof numbers) and their dof values at every :meth:`MasterLip.refresh`,
so the closest-point search sees the whole lip whatever the partition (a master point
may slide onto another process's cells during the solve). SI units (m).
"""

from __future__ import annotations

import typing

import numpy as np
import numpy.typing as npt

from xfem_contact.fem.evaluation import cell_dofs, lagrange_element
from xfem_contact.geometry.cut_topology import seg3_basis

#: Second derivatives of the SEG3 shape functions (a, b, mid), constant
_SEG3_SECOND = np.array([4.0, 4.0, -8.0])


class CurvePoint(typing.NamedTuple):
    """The deformed master curve at parameters ``s`` of pieces, ``m`` points.

    Attributes:
        x: Position (m), ``(m, 2)``.
        t: ``dx/ds`` (m), ``(m, 2)``.
        t2: ``d^2x/ds^2`` (m), ``(m, 2)``.
        phi: The master displacement basis at the point, ``(m, nnodes)``.
        dphi: Its ``d/ds``, ``(m, nnodes)``.
        ddphi: Its ``d^2/ds^2``, ``(m, nnodes)``.
        geometry: The undeformed curve ``(X, X', X'')``, each ``(m, 2)`` (m).
    """

    x: npt.NDArray[np.float64]
    t: npt.NDArray[np.float64]
    t2: npt.NDArray[np.float64]
    phi: npt.NDArray[np.float64]
    dphi: npt.NDArray[np.float64]
    ddphi: npt.NDArray[np.float64] | None = None
    geometry: tuple | None = None


def along(element, seg: np.ndarray, s: np.ndarray, order: int = 2) -> tuple[np.ndarray, ...]:
    """A cell basis and its ``s``-derivatives along SEG3 pieces.

    Args:
        element: Scalar Basix element of the cell.
        seg: Piece nodes (a, b, mid) in reference coordinates, ``(m, 3, 2)``.
        s: Piece parameter of each point, ``(m,)``.
        order: Highest derivative (2 or 3).

    Returns:
        ``(phi, dphi, ddphi[, dddphi])``, each ``(m, ndofs)``.
    """
    N, dN = seg3_basis(s)
    X = np.einsum("mk,mkd->md", N, seg)
    x, y = np.einsum("mk,mkd->dm", dN, seg)[:, :, None]  # X'(s), components (m, 1)
    xx, yy = np.einsum("k,mkd->dm", _SEG3_SECOND, seg)[:, :, None]  # X''(s); X''' = 0
    tab = element.tabulate(order, X)[..., 0]  # 1, x, y, xx, xy, yy[, xxx, xxy, xyy, yyy]
    dphi = tab[1] * x + tab[2] * y
    ddphi = tab[3] * x * x + 2.0 * tab[4] * x * y + tab[5] * y * y + tab[1] * xx + tab[2] * yy
    if order == 2:
        return tab[0], dphi, ddphi
    dddphi = (
        tab[6] * x**3
        + 3.0 * tab[7] * x * x * y
        + 3.0 * tab[8] * x * y * y
        + tab[9] * y**3
        + 3.0 * (tab[3] * xx * x + tab[4] * (xx * y + yy * x) + tab[5] * yy * y)
    )
    return tab[0], dphi, ddphi, dddphi


def global_dofs(W, local: np.ndarray) -> np.ndarray:
    """Global (unrolled) indices in ``W``'s PETSc vector of local dof indices."""
    bs = W.dofmap.index_map_bs
    blocks = W.dofmap.index_map.local_to_global(local.ravel() // bs)
    return (blocks * bs + local.ravel() % bs).reshape(local.shape)


class MasterLip:
    """The pieces of one interface on the master side, gathered on every process.

    Args:
        cut: The cut mesh.
        W: The problem's mixed space.
        field: The master displacement's field (0: side -1, 1: side +1).
        rows: Cut-cell rows whose pieces form the lip (this process's).
        columns: Reduced column of every local dof of ``W`` (-1: not an unknown of
            the Jacobian: inactive or Dirichlet), ``(num_local_dofs,)``.

    The attributes are global: identical on all processes, pieces rank by rank.

    Attributes:
        seg: Piece nodes in their cell's reference coordinates, ``(P, 3, 2)``.
        nodes: The cell's geometry nodes (m), ``(P, ngeom, 2)``.
        dofs: Global dofs of ``W`` of the master field on the cell, ``(P, 2 nnodes)``
            (node by node, components inner).
        columns: Their reduced columns (-1: none), same shape.
        cells: Global cell index of each piece, ``(P,)``.
        owners: The process that owns each piece's cell, ``(P,)``.
        orientation: +1 or -1 per piece: ``orientation * (-t_y, t_x)`` points out
            of the master side (into the slave side), ``(P,)``.

    Construction is collective.
    """

    def __init__(self, cut, W, field: int, rows: np.ndarray, columns: np.ndarray):
        comm = cut.mesh.comm
        geometry = cut.geometry
        keep = np.isin(geometry.seg_cell, rows)
        keep &= ~np.all(geometry.seg[:, 0] == geometry.seg[:, 1], axis=1)
        seg = geometry.seg[keep]
        cells = cut.cut_cells[geometry.seg_cell[keep]]
        self._W, self._field = W, field
        V = W.sub(field)
        self.element = lagrange_element(V)
        self.coordinate_element = cut.maps.coordinate_element
        dofs = cell_dofs(V, cells)  # explicit sizes: a process may hold no piece
        local_dofs = dofs.reshape(cells.size, dofs.shape[1] * dofs.shape[2])
        self._local_dofs = local_dofs
        orientation = self._orientation(cut, cells, seg, field)
        tdim = cut.mesh.topology.dim
        global_cells = cut.mesh.topology.index_map(tdim).local_to_global(cells)

        def gather(a: np.ndarray) -> np.ndarray:
            return np.concatenate(comm.allgather(a))

        self.seg = gather(seg)
        self.nodes = gather(cut.maps.cell_nodes(cells)[:, :, :2])
        self.dofs = gather(global_dofs(W, local_dofs))
        self.columns = gather(columns[local_dofs])
        self.cells = gather(global_cells)
        self.orientation = gather(orientation)
        self.owners = gather(np.full(cells.size, comm.rank, dtype=np.int32))
        self.values = np.zeros(self.dofs.shape)
        #: What is derived from the values, until the next :meth:`refresh`
        self.cache: dict = {}
        self._comm = comm

    @property
    def size(self) -> int:
        """Number of pieces (all processes)."""
        return self.seg.shape[0]

    @staticmethod
    def _orientation(cut, cells, seg, field) -> np.ndarray:
        """+1 where ``(-t_y, t_x)`` at a piece's middle points out of the master side."""
        if cells.size == 0:
            return np.zeros(0)
        mid = seg[:, 2]
        _, dN = seg3_basis(np.full(cells.size, 0.5))
        dX = np.einsum("mk,mkd->md", dN, seg)
        J = cut.maps.jacobian(cells, mid)[:, :2, :]
        t = np.einsum("mdi,mi->md", J, dX)
        left = np.column_stack([-t[:, 1], t[:, 0]])
        grad_ref = cut.maps.grad_ref(cells, mid)[:, :, None]
        grad = np.linalg.solve(np.transpose(J, (0, 2, 1)), grad_ref)[:, :, 0]
        # the master side's outward normal points against grad phi for side +1
        master_sign = 1.0 if field == 1 else -1.0
        return np.where(np.sum(left * grad, axis=1) * master_sign < 0.0, 1.0, -1.0)

    def gather(self, w) -> np.ndarray:
        """The master field's dof values of ``w`` on every piece, ``(P, 2 nnodes)``.
        Collective."""
        local = w.x.array[self._local_dofs]
        return np.concatenate(self._comm.allgather(local)).reshape(self.dofs.shape)

    def refresh(self, w) -> None:
        """Gather the master field's dof values of ``w`` (a Function on ``W``) for
        :meth:`curve`. Collective."""
        values = self.gather(w)
        if not np.array_equal(values, self.values):
            self.values, self.cache = values, {}

    def third_derivatives(self, pieces: np.ndarray, s: np.ndarray):
        """``(X''', phi''')`` along the pieces: the undeformed curve's, ``(m, 2)``, and
        the displacement basis's, ``(m, nnodes)`` (what a first-order expansion of
        ``x''`` in ``s`` needs). Local."""
        seg = self.seg[pieces]
        dddpsi = along(self.coordinate_element, seg, s, order=3)[3]
        dddphi = along(self.element, seg, s, order=3)[3]
        return np.einsum("mi,mid->md", dddpsi, self.nodes[pieces]), dddphi

    def curve(self, pieces: np.ndarray, s: np.ndarray) -> CurvePoint:
        """The deformed curve of ``pieces`` ``(m,)`` at parameters ``s`` ``(m,)``
        (for the values of the last :meth:`refresh`). Local."""
        seg = self.seg[pieces]
        psi, dpsi, ddpsi = along(self.coordinate_element, seg, s)
        phi, dphi, ddphi = along(self.element, seg, s)
        nodes = self.nodes[pieces]
        u = self.values[pieces].reshape(pieces.size, self.values.shape[1] // 2, 2)
        X = tuple(np.einsum("mi,mid->md", b, nodes) for b in (psi, dpsi, ddpsi))
        x = X[0] + np.einsum("mi,mid->md", phi, u)
        t = X[1] + np.einsum("mi,mid->md", dphi, u)
        t2 = X[2] + np.einsum("mi,mid->md", ddphi, u)
        return CurvePoint(x, t, t2, phi, dphi, ddphi, X)
