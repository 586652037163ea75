"""A crack in a cut mesh: the cut by its normal level set where its tangential one is negative.

A crack is the zero line of ``phi`` where ``psi < 0``
(:mod:`xfem_contact.geometry.crack`). :class:`~xfem_contact.fem.cutmesh.CutMesh` cuts
the mesh by ``phi`` as for an interface; :func:`crack_rules` then keeps the interface
rules of the cells the crack crosses (its *lips*), empties those of the cells cut by
``phi`` only ahead of a tip (the crack's extension: no discontinuity there; their side
rules stay, the displacement is continuous across), and gives each tip cell the fan
rules of :mod:`xfem_contact.quadrature.tip_rules`: graded Duffy rules on both sides
(the tip's ``1/r`` energy density) and a graded rule on the lip piece up to the tip.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
from mpi4py import MPI

from xfem_contact.geometry.crack import CROSSED, NONE, TIP, classify_crack
from xfem_contact.geometry.crack_tip_cell import cut_tip_cells
from xfem_contact.geometry.crack_union import CrackUnion
from xfem_contact.geometry.cut import CutGeometry
from xfem_contact.geometry.levelset import CellMaps, LevelSet
from xfem_contact.quadrature.rules import RuleSet
from xfem_contact.quadrature.tip_rules import near_tip_side_rules, tip_lip_rule, tip_side_rules

__all__ = ["Crack", "crack_rules"]


@dataclass(frozen=True)
class Crack:
    """The crack of a cut mesh on its current cut.

    Attributes:
        tangent: The tangential level set ``psi`` (``psi < 0`` on the crack).
        kind: Kind of every (owned) cut cell, :data:`~xfem_contact.geometry.crack.NONE`
            (cut by ``phi`` ahead of a tip), ``CROSSED`` or ``TIP``, ``(ncut,)``.
        tips: Physical positions (m) of the tips of all processes, ``(ntips, gdim)``,
            in the order of their tip cells' global indices; the same on every process.
        directions: Unit direction of the crack ahead of each tip, ``grad psi / |grad
            psi|`` there, ``(ntips, gdim)``; the same on every process.
        upper_sides: Per tip, the side (+1: ``phi >= 0``, or -1) on the left of its
            direction: the upper lip (``theta = pi``) of the tip's frame, ``(ntips,)``.
        tip_names: Per tip, the name of its crack (one of the cut's ``interface_names``;
            set by the cut, empty until then).
        union: Several cracks cut as one (their names, zones, gap, closed interfaces:
            :class:`~xfem_contact.geometry.crack_union.CrackUnion`); ``None`` for a
            crack given by one pair of level sets.
    """

    tangent: LevelSet
    kind: npt.NDArray[np.int8]
    tips: npt.NDArray[np.float64]
    directions: npt.NDArray[np.float64]
    upper_sides: npt.NDArray[np.int64]
    tip_names: tuple[str, ...] = ()
    union: CrackUnion | None = None

    def cells(self, kind: int, cut_cells: npt.NDArray[np.int32]) -> npt.NDArray[np.int32]:
        """Local indices of the owned cut cells of ``kind``."""
        return cut_cells[self.kind == kind]


def crack_rules(
    cut_cells: npt.NDArray[np.int32],
    rules: dict[str, RuleSet],
    maps: CellMaps,
    tangent: LevelSet,
    geometry: CutGeometry,
    tip_points: int,
) -> tuple[dict[str, RuleSet], Crack]:
    """The side and interface rules of a crack from those of the cut by ``phi``.

    Args:
        cut_cells: Local indices of the owned cells ``phi`` cuts, ``(ncut,)``.
        rules: ``{"minus": side -1, "plus": side +1, "interface": ...}`` of the cut by
            ``phi`` (one rule per cut cell).
        maps: The cell maps and ``phi`` of the cut.
        tangent: ``psi``, interpolated in the degree of ``phi``.
        geometry: The sub-triangulation of the cut cells by ``phi``.
        tip_points: Gauss points per direction of the Duffy rules of a tip cell's fan
            triangles (and along its lip piece), and of the other cut cells with a
            node within one cell diameter of a tip (see
            :func:`~xfem_contact.quadrature.tip_rules.near_tip_side_rules`).

    Returns:
        The new rules (same keys and rows) and the :class:`Crack`. Collective.

    Raises:
        ValueError: the degenerate positions refused by
            :func:`~xfem_contact.geometry.crack.classify_crack` (a crack ending twice in
            a cell, ...), naming the case.
    """
    mesh, degree = maps.mesh, tangent.degree
    cell_name = mesh.topology.cell_name()
    phi = maps.nodal_values(cut_cells)
    psi_maps = CellMaps(mesh, tangent)
    psi = psi_maps.nodal_values(cut_cells)
    cells = classify_crack(cell_name, degree, phi, psi)
    rows = cells.tip_cells
    new = dict(rules)
    new["interface"] = rules["interface"].select(cells.kind == CROSSED)
    if rows.size:
        tip_cut = cut_tip_cells(cell_name, degree, phi[rows], psi[rows], cells.tip)

        def jacobian(r, X):
            return maps.jacobian(cut_cells[rows[r]], X)

        def grad_phi(r, X):
            return maps.grad_ref(cut_cells[rows[r]], X)

        lips = tip_lip_rule(tip_cut, tip_points, jacobian, grad_phi)
        new["interface"] = new["interface"].replace(rows, lips)
        for key, side in (("minus", -1), ("plus", 1)):
            new[key] = rules[key].replace(rows, tip_side_rules(tip_cut, side, tip_points))
    gdim = mesh.geometry.dim
    tip_cells = cut_cells[rows]
    local = np.zeros((rows.size, 2 * gdim + 1))
    if rows.size:
        J_T = np.transpose(maps.jacobian(tip_cells, cells.tip), (0, 2, 1))
        grad = np.linalg.solve(J_T, psi_maps.grad_ref(tip_cells, cells.tip)[..., None])[..., 0]
        normal = np.linalg.solve(J_T, maps.grad_ref(tip_cells, cells.tip)[..., None])[..., 0]
        local[:, :gdim] = maps.push_forward(tip_cells, cells.tip)
        local[:, gdim : 2 * gdim] = grad / np.linalg.norm(grad, axis=1)[:, None]
        left = -grad[:, 1] * normal[:, 0] + grad[:, 0] * normal[:, 1]  # rot90(d) . grad phi
        local[:, -1] = np.where(left >= 0, 1, -1)
    imap = mesh.topology.index_map(mesh.topology.dim)
    gathered = mesh.comm.allgather((imap.local_to_global(tip_cells.astype(np.int32)), local))
    keys = np.concatenate([k for k, _ in gathered])
    tips = np.concatenate([t for _, t in gathered]).reshape(-1, 2 * gdim + 1)
    tips = tips[np.argsort(keys, kind="stable")]
    if mesh.comm.allreduce(int((cells.kind != NONE).sum()), op=MPI.SUM) == 0:
        raise ValueError(
            "The crack never enters the mesh: psi >= 0 all along the zero line of phi "
            "(the crack is phi = 0 where psi < 0)"
        )
    near = _near_tip_rows(maps, cut_cells, cells.kind, tips[:, :gdim])
    if near.size:

        def distance(r, X):
            x = maps.push_forward(cut_cells[r], X)
            return np.linalg.norm(x[:, None, :] - tips[None, :, :gdim], axis=2).min(axis=1)

        for key, side in (("minus", -1), ("plus", 1)):
            near_rules = near_tip_side_rules(geometry, side, near, distance, tip_points)
            new[key] = new[key].replace(near, near_rules)
    upper = tips[:, -1].astype(np.int64)
    return new, Crack(tangent, cells.kind, tips[:, :gdim], tips[:, gdim : 2 * gdim], upper)


def _near_tip_rows(
    maps: CellMaps, cut_cells: npt.NDArray[np.int32], kind: npt.NDArray[np.int8], tips: np.ndarray
) -> npt.NDArray[np.int64]:
    """Rows of the cut cells, tip cells excepted, with a geometry node within their own
    diameter of a tip (``tips`` (m), ``(ntips, gdim)``). Not collective."""
    if not len(tips) or not cut_cells.size:
        return np.zeros(0, dtype=np.int64)
    mesh = maps.mesh
    gdim = mesh.geometry.dim
    nodes = mesh.geometry.x[mesh.geometry.dofmap[cut_cells]][..., :gdim]  # (ncut, k, gdim)
    diameter = np.linalg.norm(nodes[:, :, None] - nodes[:, None, :], axis=-1).max(axis=(1, 2))
    to_tip = np.linalg.norm(nodes[:, :, None] - tips[None, None], axis=-1).min(axis=(1, 2))
    return np.flatnonzero((to_tip <= diameter) & (kind != TIP)).astype(np.int64)
