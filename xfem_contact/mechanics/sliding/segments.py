"""Segment-to-segment integration: slave pieces broken where their feet cross master-piece ends.

A slave piece is a SEG3 of a cut cell on the slave side, ``X(t)``, ``t in [0, 1]``, in
the cell's reference coordinates; deformed, ``x_s(t) = F_c(X(t)) + u_s(X(t))``. The
foot of ``x_s(t)`` on the master lip passes from one master piece to the next where it
reaches a piece end ``x_e`` (tangent ``t_e``): ``h(t) = (x_s(t) - x_e) . t_e = 0``.
There the master field's derivative jumps (C0 between cells), so a Gauss rule across
such a point integrates a kink. :func:`break_pieces` finds these *breakpoints* (Newton on
``t``) for
both ends of every master piece that the feet of the slave piece's ends and of its
rule points (or of :data:`SAMPLES`) reach (the ends of an unreached piece lying
between two reached ones are theirs too; two unreached pieces in a row would be
missed) and cuts each slave piece there into sub-segments. Each sub-segment gets its
own Gauss rule (:meth:`SlavePieces.rule`, weights scaled by its length) and one master
piece, that of its midpoint's foot (past a crossing into a piece, that piece; between
the two crossings of one corner of the lip, the previous sub-segment's), on which all
its points are projected. Geometry only, no physics; local (each process breaks its
own slave pieces against the whole lip). SI units (m).
"""

from __future__ import annotations

import typing

import basix
import numpy as np
import numpy.typing as npt

from xfem_contact._deprecation import renamed
from xfem_contact.fem.evaluation import cell_dofs, lagrange_element
from xfem_contact.geometry.cut_topology import seg3_basis
from xfem_contact.mechanics.sliding.element import node_slots
from xfem_contact.mechanics.sliding.lips import along
from xfem_contact.mechanics.sliding.projection import closest_points

#: Parameters of a slave piece whose feet choose the candidate master pieces
SAMPLES = np.linspace(0.0, 1.0, 5)
#: Sub-segments shorter than this (in ``t``) are dropped (two roots at one point)
MIN_LENGTH = 1e-12
#: Crossings this close (in ``t``) to an end of the slave piece are not breakpoints:
#: aligned pieces (a slave node over a master node) would otherwise get slivers of
#: round-off length paired with either neighbour in turn, a new Jacobian pattern at
#: every iterate; the kink left inside the piece's rule costs ``TOUCH^2`` of its
#: integrand's derivative jump
TOUCH = 1e-8
#: Sub-segments shorter than this (in ``t``; between the two crossings of one master
#: corner) get one point: the midpoint rule's error, ``SHORT^3 / 24`` of the piece's
#: integrand scale, is below round-off of the Newton residual
SHORT = 1e-4


class Segments(typing.NamedTuple):
    """Sub-segments ``[t0, t1]`` of slave pieces and the master piece of each.

    Attributes:
        piece: Slave piece of each sub-segment, ``(k,)``.
        t0, t1: Its parameter interval on the piece, ``(k,)``.
        master: Master piece (index into the lip) of its points, ``(k,)``; -1: none
            within the search radius (unpaired).
        start_master, start_end: Where ``t0`` is a breakpoint (the previous
            sub-segment on the same piece ends there): the master piece and its end
            (0.0 or 1.0) whose crossing it is, ``(k,)``; -1 where ``t0`` is fixed.
    """

    piece: npt.NDArray[np.int64]
    t0: npt.NDArray[np.float64]
    t1: npt.NDArray[np.float64]
    master: npt.NDArray[np.int64]
    start_master: npt.NDArray[np.int64]
    start_end: npt.NDArray[np.float64]


class SlavePieces:
    """The SEG3 pieces of one interface in this process's slave cells.

    Args:
        cut: The cut mesh.
        V: The slave displacement space (``W.sub(field)``).
        rows: Cut-cell rows whose pieces carry the interface's rule.
        degree: Degree of the Gauss-Legendre rule of each (sub-)segment (the cut's
            quadrature degree: unbroken, the rule is the cut's interface rule).

    Attributes:
        seg: Piece nodes (a, b, mid) in reference coordinates, ``(P, 3, 2)``.
        cells: Local cell of each piece, ``(P,)``.
        dofs: Local dofs of the slave field on it, ``(P, 2 nnodes)`` (node by node).
        nodes: The cell's geometry nodes (m), ``(P, ngeom, 2)``.

    Pieces are in the order of the cut's interface rule (by cut cell, stable).
    Construction is local.
    """

    def __init__(self, cut, V, rows: np.ndarray, degree: int):
        geometry = cut.geometry
        seg = geometry.seg
        pieces = np.flatnonzero(~np.all(seg[:, 0] == seg[:, 1], axis=1))
        pieces = pieces[np.isin(geometry.seg_cell[pieces], rows)]
        pieces = pieces[np.argsort(geometry.seg_cell[pieces], kind="stable")]
        self.seg = seg[pieces]
        self.cells = cut.cut_cells[geometry.seg_cell[pieces]]
        dofs = cell_dofs(V, self.cells)
        self.dofs = dofs.reshape(self.cells.size, dofs.shape[1] * dofs.shape[2])
        self.nodes = cut.maps.cell_nodes(self.cells)[:, :, :2]
        self.maps = cut.maps
        self.element = lagrange_element(V)
        s, w = basix.make_quadrature(basix.CellType.interval, degree)
        self.gauss = (s[:, 0], w)

    @property
    def size(self) -> int:
        return self.seg.shape[0]

    def curve(self, values: np.ndarray, pieces: np.ndarray, t: np.ndarray):
        """``(x_s, dx_s/dt)`` (m), each ``(m, 2)``, of ``pieces`` ``(m,)`` at ``t``
        ``(m,)`` for the dof values ``values`` (a Function's array on ``W``)."""
        seg = self.seg[pieces]
        psi, dpsi, _ = along(self.maps.coordinate_element, seg, t)
        phi, dphi, _ = along(self.element, seg, t)
        u = values[self.dofs[pieces]].reshape(pieces.size, phi.shape[1], 2)
        nodes = self.nodes[pieces]
        x = np.einsum("mi,mid->md", psi, nodes) + np.einsum("mi,mid->md", phi, u)
        dx = np.einsum("mi,mid->md", dpsi, nodes) + np.einsum("mi,mid->md", dphi, u)
        return x, dx

    def at(self, pieces: np.ndarray, t: np.ndarray):
        """``(X (m, 2), speed (m,))``: the reference point of ``pieces`` at ``t``
        (cell reference coordinates) and its undeformed arc length per unit ``t`` (m)."""
        N, dN = seg3_basis(t)
        seg = self.seg[pieces]
        X = np.einsum("mk,mkd->md", N, seg)
        dX = np.einsum("mk,mkd->md", dN, seg)
        J = self.maps.jacobian(self.cells[pieces], X)[:, :2, :]
        return X, np.linalg.norm(np.einsum("mdk,mk->md", J, dX), axis=1)

    def parameters(self, segments: Segments):
        """The sub-segments' Gauss points on their pieces: ``(segment (m,) index into
        segments, t (m,), weights (m,) in t)``. Sub-segments shorter than
        :data:`SHORT` get the midpoint rule."""
        s, w_hat = self.gauss
        length = segments.t1 - segments.t0
        short = length < SHORT
        full = np.flatnonzero(~short)
        segment = np.concatenate([np.repeat(full, s.size), np.flatnonzero(short)])
        t = np.concatenate(
            [
                (segments.t0[full, None] + length[full, None] * s[None]).ravel(),
                segments.t0[short] + 0.5 * length[short],
            ]
        )
        w = np.concatenate([(length[full, None] * w_hat[None]).ravel(), length[short]])
        return segment, t, w

    def rule(self, segments: Segments):
        """Gauss points of the sub-segments (see :meth:`parameters`): ``(segment (m,),
        X (m, 2) reference coordinates in the piece's cell, weights (m,) reference arc
        length (m))``."""
        segment, t, w = self.parameters(segments)
        X, speed = self.at(segments.piece[segment], t)
        return segment, X, w * speed

    def whole(self) -> Segments:
        """Every piece unbroken, without master pieces (the cut's own rule)."""
        P = self.size
        none = np.full(P, -1)
        return Segments(np.arange(P), np.zeros(P), np.ones(P), none, none, np.zeros(P))


def _roots(pieces: SlavePieces, values, lip, slave, master, x0, x1, iterations=30):
    """Parameters ``t in (0, 1)`` where the foot of slave piece ``slave[i]`` crosses an
    end of master piece ``master[i]``: ``(slave piece, t, master piece, end,
    entering)``, each ``(k,)``; ``entering``: past ``t`` the foot is on that piece."""
    slave, master = np.repeat(slave, 2), np.repeat(master, 2)
    ends = np.tile([0.0, 1.0], master.size // 2)
    end = lip.curve(master, ends)
    x0, x1 = np.repeat(x0, 2, axis=0), np.repeat(x1, 2, axis=0)
    h0 = np.sum((x0 - end.x) * end.t, axis=1)
    h1 = np.sum((x1 - end.x) * end.t, axis=1)
    crossing = h0 * h1 < 0.0
    slave, x_e, t_e = slave[crossing], end.x[crossing], end.t[crossing]
    master, ends = master[crossing], ends[crossing]
    t = h0[crossing] / (h0[crossing] - h1[crossing])  # the chord's root
    for _ in range(iterations):
        if t.size == 0:
            break
        x, dx = pieces.curve(values, slave, t)
        h = np.sum((x - x_e) * t_e, axis=1)
        dh = np.sum(dx * t_e, axis=1)
        step = np.where(dh != 0.0, h / np.where(dh != 0.0, dh, 1.0), 0.0)
        t = np.clip(t - step, 0.0, 1.0)
        if np.all(np.abs(step) < 1e-14):
            break
    inner = (t > TOUCH) & (t < 1.0 - TOUCH)
    slave, t, master, ends, x_e, t_e = (a[inner] for a in (slave, t, master, ends, x_e, t_e))
    _, dx = pieces.curve(values, slave, t)
    entering = (ends == 0.0) == (np.sum(dx * t_e, axis=1) > 0.0)
    return slave, t, master, ends, entering


def break_pieces(
    pieces: SlavePieces, values: np.ndarray, lip, radius: float, feet=None
) -> Segments:
    """Break the slave pieces at their breakpoints, the crossings of master-piece ends
    (see the module).

    Args:
        pieces: The slave pieces.
        values: Dof values of the state (a Function's array on ``W``).
        lip: The :class:`~xfem_contact.mechanics.sliding.lips.MasterLip`, refreshed at
            the same state.
        radius: Search radius (m) of the pairing.
        feet: Master pieces (-1: none) already found for points of each slave piece,
            ``(P, k)`` (the interface rule's): they replace the inner samples.

    Returns:
        The :class:`Segments`, piece by piece, ``t`` increasing. Local.
    """
    P = pieces.size
    if P == 0:
        return pieces.whole()
    samples = SAMPLES if feet is None else SAMPLES[[0, -1]]
    S = samples.size
    rows = np.repeat(np.arange(P), S)
    x, _ = pieces.curve(values, rows, np.tile(samples, P))
    found = closest_points(lip, x, radius).piece.reshape(P, S)
    if feet is not None:
        found = np.concatenate([found, feet], axis=1)
    x = x.reshape(P, S, 2)
    rows = np.repeat(np.arange(P), found.shape[1])
    pairs = np.unique(np.column_stack([rows, found.ravel()])[found.ravel() >= 0], axis=0)
    ends = x[pairs[:, 0], 0], x[pairs[:, 0], -1]
    roots = _roots(pieces, values, lip, pairs[:, 0], pairs[:, 1], *ends)
    fixed = np.full(P, -1)
    piece = np.concatenate([np.arange(P), np.arange(P), roots[0]])
    t = np.concatenate([np.zeros(P), np.ones(P), roots[1]])
    source = np.concatenate([fixed, fixed, roots[2]])
    end = np.concatenate([np.zeros(2 * P), roots[3]])
    entering = np.concatenate([np.zeros(2 * P, dtype=bool), roots[4]])
    order = np.lexsort((t, piece))
    piece, t, source, end = piece[order], t[order], source[order], end[order]
    keep = (piece[1:] == piece[:-1]) & (t[1:] - t[:-1] > MIN_LENGTH)
    piece, t0, t1 = piece[:-1][keep], t[:-1][keep], t[1:][keep]
    source, end, entering = source[:-1][keep], end[:-1][keep], entering[order][:-1][keep]
    # a breakpoint ends the previous sub-segment of its piece (else it is not one)
    after = np.r_[False, piece[1:] == piece[:-1]] & np.r_[False, t0[1:] == t1[:-1]]
    source = np.where(after, source, -1)
    mid, _ = pieces.curve(values, piece, 0.5 * (t0 + t1))
    # the midpoints' candidates: the master pieces of their slave piece's pairs
    rank = np.arange(pairs.shape[0]) - np.searchsorted(pairs[:, 0], pairs[:, 0])
    given = np.full((P, rank.max(initial=0) + 1), -1)
    given[pairs[:, 0], rank] = pairs[:, 1]
    feet = closest_points(lip, mid, radius, given=given[piece])
    master = feet.piece
    # a foot at a piece end (the sub-segment between the two crossings of a convex
    # corner) is a tie between the two pieces: take a neighbour's master instead
    corner = (feet.s == 0.0) | (feet.s == 1.0)
    before = np.r_[False, piece[1:] == piece[:-1]]
    later = np.r_[piece[1:] == piece[:-1], False]
    master = np.where(corner & before, np.roll(master, 1), master)
    master = np.where(corner & ~before & later, np.roll(master, -1), master)
    # past a crossing into a piece the foot is on it (no tie near a concave corner)
    master = np.where(entering & (source >= 0) & (master >= 0), source, master)
    # between the two crossings of one corner: the previous sub-segment's master
    # (its foot stays on that piece or its end; whichever way the corner turns)
    short = (t1 - t0 < SHORT) & (master >= 0)
    master = np.where(short & before, np.roll(master, 1), master)
    return Segments(piece, t0, t1, master, source, end)


def breakpoint_gradient(pieces: SlavePieces, values: np.ndarray, lip, segments: Segments):
    """How the breakpoints move with the dofs: ``(k, grad)``, ``k`` the sub-segments
    that start at a breakpoint ``(b,)`` and ``grad`` ``(b, 2 nn_s + 2 nn_m)`` the
    derivative of that point's ``t`` in the slave piece's displacement dofs and in
    those of the master piece whose end it crosses (node by node), from ``h(t) = 0``:
    ``dt = -(dh/dz) / (dh/dt)``. Local."""
    k = np.flatnonzero(segments.start_master >= 0)
    piece, t = segments.piece[k], segments.t0[k]
    end = lip.curve(segments.start_master[k], segments.start_end[k])
    x, dx = pieces.curve(values, piece, t)
    phi_s = along(pieces.element, pieces.seg[piece], t)[0]
    dh = np.concatenate(
        [node_slots(phi_s, end.t), node_slots(end.dphi, x - end.x) - node_slots(end.phi, end.t)],
        axis=1,
    )
    dh_dt = np.sum(dx * end.t, axis=1)
    return k, -dh / np.where(dh_dt != 0.0, dh_dt, np.inf)[:, None]


__getattr__ = renamed(
    __name__, {"split": "break_pieces", "split_gradient": "breakpoint_gradient"}, globals()
)
