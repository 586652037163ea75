"""Bounded conditioning of the crack-tip enrichment: a change of unknowns ``x = R Z y``.

Geometric tip enrichment (every node within ``r_e`` of a tip carries the four branch
functions ``N_i F_k``) makes the reduced stiffness nearly singular: far from the tip
``F_k`` is smooth on a node's support, so ``N_i F_k`` is close to the polynomials there
(P1: ``N_i F_k(x_i)`` and a linear part; P2: ``N_i`` times the Taylor polynomial of
degree one of ``F_k`` is quadratic, in the P2 space whole). With the Jacobi scaling of
:mod:`xfem_contact.solvers.scaling` alone the condition number grew like ``h^-6`` at
fixed ``r_e``. Two changes of basis of the same space bound it (Béchet, Minnebo, Moës
and Burgardt, IJNME 64, 2005, whose local preconditioning is step 2):

1. ``T``: every branch unknown's function becomes ``N_i F_k - I_h(N_i F_k)``, its
   interpolant on the standard (displacement) nodes inside ``supp N_i`` subtracted
   (P1: the node itself, the shifted enrichment; P2: the node and the mid-edge nodes of
   its edges; per side ``s`` with ``F_k`` of that side, at a node whose two sides share
   one unknown with ``F_k`` of the side it lies on). The subtracted part lies in the
   standard space: same span, same sparsity.
2. ``S``: per node carrying branch unknowns, the block of ``T^T J T`` on all the
   node's unknowns (both sides' displacements and the branch ones) is made the
   identity, ``S_b = D_b Q |Lambda|^-1/2`` with ``D_b J_b D_b = Q Lambda Q^T``
   (symmetrised; eigenvalues floored at ``1e-14`` of the largest, none dropped); every
   other unknown keeps the scaling ``D`` of :mod:`xfem_contact.solvers.scaling`.

With gathered tip dofs (:mod:`~xfem_contact.fem.tip_dofs`: one column per tip, branch
function and component, shared by the zone's vertices) ``T`` subtracts from each such
column the interpolant of ``R F_k`` on every standard node of the zone, and ``S`` is
the scaling ``D`` alone (a column in every vertex's block would couple them all).

``Z = T S`` is fixed (made from the first Jacobian); the solvers factor ``Z^T J_r Z``.
Any invertible ``Z`` gives the same solution in exact arithmetic. Measured
(``bench/crack_convergence.py --parts conditioning``): see ``docs/crack_enrichment.md``.
"""

from __future__ import annotations

import functools
from collections.abc import Callable

import basix
import basix.ufl
import dolfinx.fem
import numpy as np
from petsc4py import PETSc

from xfem_contact.fem.branch import side_of, side_values
from xfem_contact.fem.enrichment import EnrichedSpace
from xfem_contact.solvers.scaling import saddle_point_scaling
from xfem_contact.solvers.symmetry import TOLERANCE, mark_symmetric, symmetry_gap

REFINEMENTS = 1
#: Eigenvalues of a node's scaled block below this fraction of its largest are raised
#: to it (kept: the space is never changed)
FLOOR = 1e-14


def tip_transform(
    space: EnrichedSpace, off: bool = False
) -> Callable[[PETSc.Mat, PETSc.Mat], PETSc.Mat] | None:
    """The solvers' ``transform(R, J)`` for ``space``: :func:`tip_scaling` with a crack's
    tip enrichment; None without a crack, or when ``off``. Not collective."""
    if off or space.branch_field is None:
        return None
    return functools.partial(tip_scaling, space)


def tip_scaling(space: EnrichedSpace, R: PETSc.Mat, J: PETSc.Mat) -> PETSc.Mat:
    """The change of unknowns ``Z`` (``x = R Z y``) of the module docstring. Collective.

    Args:
        space: The enriched space, with a crack (``space.branch_field`` set).
        R: Its prolongation (full x reduced).
        J: The unscaled reduced Jacobian ``R^T J R`` (not modified).

    Returns:
        ``Z``, square, laid out as ``J``'s columns; the caller destroys it.
    """
    columns = reduced_columns(space, R)
    T = shift_matrix(space, R, columns)
    JT = J.ptap(T)
    gathered = space.tip_dofs == "gathered"  # a tip's column is in every zone node's block
    S = node_block_scaling(JT, [] if gathered else node_blocks(space, R, columns))
    Z = T.matMult(S)
    for obj in (T, JT, S):
        obj.destroy()
    return Z


def scaled(J: PETSc.Mat, Z: PETSc.Mat, out: PETSc.Mat | None = None) -> PETSc.Mat:
    """``Z^T J Z`` (into ``out`` when given: the same pattern), made exactly symmetric
    when ``J`` is (to :data:`~xfem_contact.solvers.symmetry.TOLERANCE`): the products'
    round-off differs between ``(i, j)`` and ``(j, i)`` by more than the symmetric
    factorisation's check allows on fine meshes. Collective."""
    P = J.ptap(Z) if out is None else J.ptap(Z, result=out)
    if _symmetric(J):
        Pt = P.transpose(PETSc.Mat())  # a new matrix (None: in place)
        P.axpy(1.0, Pt)
        P.scale(0.5)
        Pt.destroy()
    return P


def _symmetric(A: PETSc.Mat) -> bool:
    """Whether ``A`` is symmetric to ``TOLERANCE`` (:func:`symmetry_gap`). Collective."""
    gap, scale = symmetry_gap(A)
    return gap <= TOLERANCE * scale


def refined(ksp: PETSc.KSP, Z: PETSc.Mat, A: PETSc.Mat, b: PETSc.Vec, y_s: PETSc.Vec):
    """``y = Z y_s`` for ``ksp`` solving ``Z^T A Z y_s = Z^T b``, refined against
    ``A y = b`` itself (:func:`refine`). Destroys ``A``, ``b`` and ``y_s``; returns ``y``.
    Collective."""
    y, t = A.createVecRight(), y_s.duplicate()
    Z.mult(y_s, y)

    def solve(r: PETSc.Vec, c: PETSc.Vec) -> None:
        Z.multTranspose(r, t)
        ksp.solve(t, y_s)
        Z.mult(y_s, c)

    refine(solve, A, b, y)
    for obj in (A, b, y_s, t):
        obj.destroy()
    return y


def refine(
    solve: Callable[[PETSc.Vec, PETSc.Vec], None], A: PETSc.Mat, b: PETSc.Vec, y: PETSc.Vec
) -> None:
    """Iterative refinement of ``y`` against ``A y = b``, in place: up to
    :data:`REFINEMENTS` steps ``y += solve(b - A y)``, each kept only if it lowers
    ``|b - A y|``: a factorisation too inexact for the system's conditioning (a small
    cut) makes the steps diverge, and the first solution is then the best. Collective."""
    r, c, trial = y.duplicate(), y.duplicate(), y.duplicate()
    A.mult(y, r)
    r.aypx(-1.0, b)
    norm = r.norm()
    for _ in range(REFINEMENTS):
        solve(r, c)
        y.copy(trial)
        trial.axpy(1.0, c)
        A.mult(trial, r)
        r.aypx(-1.0, b)
        if not r.norm() < norm:
            break
        norm = r.norm()
        trial.copy(y)
    for v in (r, c, trial):
        v.destroy()


def reduced_columns(space: EnrichedSpace, R: PETSc.Mat) -> np.ndarray:
    """The global reduced column of each local (owned and ghost) dof of ``W`` that is
    one (an identity or tied column of ``R``), else -1 (an inactive dof, or a combination
    of columns: a multiplier prolongation's or an aggregated dof). Collective (ghost
    update)."""
    indptr, cols, _ = R.getValuesCSR()
    n_owned = indptr.size - 1
    has = np.diff(indptr) == 1
    column = np.full(n_owned, -1.0)
    column[has] = cols[indptr[:-1][has]]
    carrier = dolfinx.fem.Function(space.W)
    carrier.x.array[:] = -1.0
    carrier.x.array[:n_owned] = column
    carrier.x.scatter_forward()
    return np.rint(carrier.x.array).astype(np.int64)


def _cell_type(space: EnrichedSpace) -> str:
    return space.cut.mesh.topology.cell_name()


def _hats_at_nodes(space: EnrichedSpace) -> np.ndarray:
    """``N_k(x_m)``: the P1 hats (columns, the branch field's) at the displacement
    element's nodes (rows), on the reference cell."""
    cell, degree = _cell_type(space), space.degree
    points = basix.ufl.element("Lagrange", cell, degree).basix_element.points
    hat = basix.ufl.element("Lagrange", cell, 1).basix_element
    return hat.tabulate(0, points)[0, :, :, 0]


def _branch_at_nodes(space: EnrichedSpace) -> tuple[dict[int, np.ndarray], np.ndarray]:
    """Per side, the functions of the branch dofs at the nodes of field 0's own space,
    shape ``(4, nodes)`` (the branch functions times the space's ramp where it has one,
    minus its interpolants where it has them), and the side each node lies on (by the
    sign of ``phi``, :func:`~xfem_contact.fem.branch.side_of`)."""
    V = space.field_space(0)[0]
    bs = V.dofmap.index_map_bs
    S, dofs = V.sub(0).collapse()
    nodes = np.asarray(dofs).ravel() // bs
    values = []
    ramp = space.ramp
    functions = [space.cut.levelset.function, space.cut.crack.tangent.function]
    for g in functions + ([] if ramp is None else [ramp]):
        f = dolfinx.fem.Function(S)
        f.interpolate(g)
        at = np.empty(nodes.size)
        at[nodes] = f.x.array[: nodes.size]
        values.append(at)
    phi, psi = values[:2]
    ramp = values[2] if len(values) > 2 else 1.0
    F = side_values(phi, psi, ramp, space.round_off)
    if space.interpolants is not None:
        for s, functions in space.interpolants.items():
            for k, g in enumerate(functions):
                f = dolfinx.fem.Function(S)
                f.interpolate(g)
                F[s][k, nodes] -= f.x.array[: nodes.size]
    return F, side_of(phi, space.round_off)


def shift_matrix(space: EnrichedSpace, R: PETSc.Mat, columns: np.ndarray) -> PETSc.Mat:
    """``T = I + C``: each branch column minus the interpolant of its function on the
    standard nodes inside its support (step 1 of the module docstring; a column shared
    by several nodes' branch dofs, gathered, minus the sum of theirs). Collective."""
    gdim = space.cut.mesh.geometry.dim
    (Vb, pb), (V0, p0), (V1, p1) = (space.field_space(f) for f in (space.branch_field, 0, 1))
    hats = _hats_at_nodes(space)
    M, K = np.nonzero(np.abs(hats) > 1e-12)  # (displacement node, vertex) pairs in a cell
    H = hats[M, K]
    F, side_of = _branch_at_nodes(space)
    bcells, cells0, cells1 = Vb.dofmap.list, V0.dofmap.list, V1.dofmap.list
    rows, cols, vals, dofs = [], [], [], []
    for comp in range(gdim):
        minus = columns[p0[cells0[:, M] * gdim + comp]]  # (cells, pairs)
        plus = columns[p1[cells1[:, M] * gdim + comp]]
        node = cells0[:, M]
        tied = minus == plus
        for j in range(4):
            dof = pb[bcells[:, K] * 4 * gdim + gdim * j + comp]
            e = columns[dof]
            for col, s in ((minus, -1), (plus, 1)):
                Fs = np.where(
                    tied, np.where(side_of[node] > 0, F[1][j, node], F[-1][j, node]), F[s][j, node]
                )
                keep = (e >= 0) & (col >= 0) & ~((s == 1) & tied)
                rows.append(col[keep])
                cols.append(e[keep])
                vals.append(-(H[None, :] * Fs)[keep])
                dofs.append(dof[keep])
    first, last = R.getOwnershipRangeColumn()
    rows, cols, vals, dofs = (np.concatenate(a) for a in (rows, cols, vals, dofs))
    owned = (rows >= first) & (rows < last)
    rows, cols, vals, dofs = rows[owned], cols[owned], vals[owned], dofs[owned]
    # the same (row, branch dof) from each cell sharing it: kept once; then the branch
    # dofs sharing a column summed
    _, once = np.unique(np.stack([rows, dofs]), axis=1, return_index=True)
    keys, inverse = np.unique(np.stack([rows[once], cols[once]]), axis=1, return_inverse=True)
    vals = np.bincount(inverse.ravel(), weights=vals[once], minlength=keys.shape[1])
    n = last - first
    rows = np.concatenate([np.arange(first, last), keys[0]])
    cols = np.concatenate([np.arange(first, last), keys[1]])
    vals = np.concatenate([np.ones(n), vals])
    return _csr(R.getComm(), n, rows - first, cols, vals)


def _csr(comm, n: int, rows: np.ndarray, cols: np.ndarray, vals: np.ndarray) -> PETSc.Mat:
    """A square AIJ matrix of ``n`` local rows from (local row, global column, value)
    triples; a repeated pair keeps its first value."""
    order = np.lexsort((cols, rows))
    rows, cols, vals = rows[order], cols[order], vals[order]
    first = np.ones(rows.size, dtype=bool)
    first[1:] = (np.diff(rows) != 0) | (np.diff(cols) != 0)
    rows, cols, vals = rows[first], cols[first], vals[first]
    indptr = np.searchsorted(rows, np.arange(n + 1)).astype(PETSc.IntType)
    A = PETSc.Mat().createAIJ(((n, PETSc.DETERMINE), (n, PETSc.DETERMINE)), comm=comm)
    A.setPreallocationCSR((indptr, cols.astype(PETSc.IntType), vals))
    A.assemble()
    return A


def node_blocks(space: EnrichedSpace, R: PETSc.Mat, columns: np.ndarray) -> list[np.ndarray]:
    """Per node (vertex) carrying branch unknowns owned here: the local reduced columns
    of all its unknowns (both sides' displacements at the vertex and the branch ones).
    A vertex's dofs of every field belong to one process. Not collective."""
    first, last = R.getOwnershipRangeColumn()
    gdim = space.cut.mesh.geometry.dim
    (Vb, pb), (V0, p0), (V1, p1) = (space.field_space(f) for f in (space.branch_field, 0, 1))
    nv = Vb.dofmap.list.shape[1]  # the vertex nodes come first in each cell
    nodes = Vb.dofmap.index_map.size_local + Vb.dofmap.index_map.num_ghosts
    sides = []
    for V, parent in ((V0, p0), (V1, p1)):
        vertex = np.zeros(nodes, dtype=np.int64)  # field V's node at each branch node
        vertex[Vb.dofmap.list.ravel()] = V.dofmap.list[:, :nv].ravel()
        sides.append(columns[parent.reshape(-1, gdim)[vertex]])
    branch = columns[pb].reshape(-1, 4 * gdim)
    out = []
    for node in np.flatnonzero((branch >= 0).any(axis=1)):
        parts = [sides[0][node], sides[1][node], branch[node]]
        every = np.unique(np.concatenate(parts))
        every = every[every >= 0]
        if np.any((every < first) | (every >= last)):
            continue  # a ghost vertex: its owner makes the block
        out.append(every - first)
    return out


def node_block_scaling(J: PETSc.Mat, blocks: list[np.ndarray]) -> PETSc.Mat:
    """``S`` (step 2 of the module docstring): ``D`` of the saddle-point scaling, and
    on each block ``D_b Q |Lambda|^-1/2``. Collective."""
    D = saddle_point_scaling(J)
    d = D.getArray(readonly=True).copy()
    D.destroy()
    first, last = J.getOwnershipRange()
    n = last - first
    in_block = np.zeros(n, dtype=bool)
    rows, cols, vals = [], [], []
    for block in blocks:
        g = (block + first).astype(PETSc.IntType)
        B = J.getValues(g, g)
        Bs = d[block][:, None] * (0.5 * (B + B.T)) * d[block][None, :]
        lam, Q = np.linalg.eigh(Bs)
        lam = np.abs(lam)
        lam = np.maximum(lam, FLOOR * lam.max())
        Sb = d[block][:, None] * Q / np.sqrt(lam)[None, :]
        rows.append(np.repeat(block, block.size))
        cols.append(np.tile(g, block.size))
        vals.append(Sb.ravel())
        in_block[block] = True
    alone = np.flatnonzero(~in_block)
    rows.append(alone)
    cols.append(alone + first)
    rows, cols = np.concatenate(rows), np.concatenate(cols).astype(np.int64)
    return _csr(J.getComm(), n, rows, cols, np.concatenate([*vals, d[alone]]))


class TipFactor:
    """The Newton steps' direct solve through ``Z``: a Python PC (petsc4py) on SNES's
    ``D``-scaled Jacobian ``J_D = D J_r D`` giving ``Z_D (Z_D^T J_D Z_D)^-1 Z_D^T r``
    with ``Z_D = D^-1 Z`` (exactly ``J_D^-1 r``), the well-conditioned ``Z^T J_r Z``
    factored by an inner KSP under SNES's options prefix (its ``ksp_type``, ``pc_type``
    and MUMPS options). SNES's unknowns and residual norms stay those of ``D``: in
    ``Z``'s the residual's round-off is amplified where the shifted branch functions are
    small, above ``snes_atol`` (``docs/crack_enrichment.md``). Construction
    (within the options' scope) is collective; it takes over ``Z``.

    Args:
        snes: The Newton solver; its KSP's PC becomes this one.
        Z: The change of unknowns (:func:`tip_scaling`).
        D: SNES's diagonal scaling.
        symmetric: Whether the factorisation is LDL^T (the matrix is then checked).
    """

    def __init__(self, snes: PETSc.SNES, Z: PETSc.Mat, D: PETSc.Vec, symmetric: bool):
        inverse = D.copy()
        inverse.reciprocal()
        Z.diagonalScale(L=inverse)
        inverse.destroy()
        self.Z, self.symmetric, self.J = Z, symmetric, None
        self.ksp = PETSc.KSP().create(Z.getComm())
        self.ksp.setOptionsPrefix(snes.getOptionsPrefix())
        self.ksp.setFromOptions()
        self.r, self.s = Z.createVecs()
        pc = snes.getKSP().getPC()
        pc.setType("python")
        pc.setPythonContext(self)

    def setUp(self, pc: PETSc.PC) -> None:
        """Form and hand over ``Z_D^T J_D Z_D`` (factored at the first solve)."""
        self.J = scaled(pc.getOperators()[1], self.Z, self.J)
        if self.symmetric:
            mark_symmetric(self.J)
        self.ksp.setOperators(self.J)

    def apply(self, pc: PETSc.PC, x: PETSc.Vec, y: PETSc.Vec) -> None:
        self._solve(pc, x, y)
        refine(functools.partial(self._solve, pc), pc.getOperators()[1], x, y)  # against J_D

    def _solve(self, pc: PETSc.PC, x: PETSc.Vec, y: PETSc.Vec) -> None:
        self.Z.multTranspose(x, self.r)
        self.ksp.solve(self.r, self.s)
        if self.ksp.getConvergedReason() < 0:
            pc.setFailedReason(PETSc.PC.FailedReason.FACTOR_OTHER)
        self.Z.mult(self.s, y)

    def destroy(self, pc: PETSc.PC | None = None) -> None:
        """Destroy the PETSc objects made or taken over here (PETSc calls it with the
        PC; again: nothing). Collective."""
        for obj in (self.ksp, self.Z, self.r, self.s, *([self.J] if self.J else [])):
            obj.destroy()
