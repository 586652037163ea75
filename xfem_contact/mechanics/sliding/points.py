"""Slave integration points: positions, bases and dofs at reference points of slave cells.

The points of the hybrid elements are the interface rule's, or (segment-to-segment)
those of the sub-segment rules of :mod:`~xfem_contact.mechanics.sliding.segments`,
new at every iterate; :class:`PointMaker` tabulates what the element needs at any of
them. Local. SI units (m).
"""

from __future__ import annotations

import typing

import numpy as np

from xfem_contact.fem.evaluation import cell_dofs, lagrange_element


class SlavePoints(typing.NamedTuple):
    """Slave integration points (``m``) and what the element needs of them.

    Attributes:
        x_ref: Reference (undeformed) positions (m), ``(m, 2)``.
        phi_s: Slave displacement basis, ``(m, nnodes)``.
        lam_basis: Multiplier basis, ``(m, nl)``.
        weights: Reference arc-length weights (m), ``(m,)``.
        h: Size of each point's cell (m), ``(m,)``.
        cells: Local cell of each point, ``(m,)``.
        slave_dofs: Local slave-field dofs of the cell, ``(m, 2 nnodes)`` (node by node).
        lam_dofs: Local multiplier dofs of the cell, ``(m, nl)``.
    """

    x_ref: np.ndarray
    phi_s: np.ndarray
    lam_basis: np.ndarray
    weights: np.ndarray
    h: np.ndarray
    cells: np.ndarray
    slave_dofs: np.ndarray
    lam_dofs: np.ndarray


class PointMaker:
    """Makes :class:`SlavePoints` of one interface.

    Args:
        maps: The cut's cell maps.
        V_s: The slave displacement space (``W.sub(field)``).
        V_l: The multiplier space.
        cell_size: Cell diameters (m), a DG0 Function.
    """

    def __init__(self, maps, V_s, V_l, cell_size):
        self.maps, self.spaces, self.cell_size = maps, (V_s, V_l), cell_size
        self.elements = (lagrange_element(V_s), lagrange_element(V_l))

    def __call__(self, cells: np.ndarray, X: np.ndarray, weights: np.ndarray) -> SlavePoints:
        """The points at reference coordinates ``X`` ``(m, 2)`` of local ``cells``
        ``(m,)``, with ``weights`` (m) ``(m,)``."""
        (V_s, V_l), (e_s, e_l), h = self.spaces, self.elements, self.cell_size
        return SlavePoints(
            self.maps.push_forward(cells, X),
            e_s.tabulate(0, X)[0, :, :, 0],
            e_l.tabulate(0, X)[0, :, :, 0],
            weights,
            h.x.array[h.function_space.dofmap.list[cells, 0]],
            cells,
            _flat(cell_dofs(V_s, cells)),
            _flat(cell_dofs(V_l, cells)),
        )


def positions(w, points: SlavePoints) -> np.ndarray:
    """Deformed positions (m) of slave points at ``w`` (a Function on ``W``), ``(m, 2)``."""
    m, n = points.slave_dofs.shape
    u_s = w.x.array[points.slave_dofs].reshape(m, n // 2, 2)
    return points.x_ref + np.einsum("mi,mid->md", points.phi_s, u_s)


def _flat(dofs: np.ndarray) -> np.ndarray:
    """``(m, nodes, components)`` dofs as ``(m, nodes x components)``, node by node
    (explicit sizes: a process may hold no point of the interface)."""
    return dofs.reshape(dofs.shape[0], dofs.shape[1] * dofs.shape[2])
