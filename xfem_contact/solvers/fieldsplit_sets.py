"""The index sets, near null space and interpolation a fieldsplit preconditioner of the
Newton steps reads (:class:`~xfem_contact.solvers.newton.ReducedNewton`): PETSc's
``fieldsplit`` or the band multigrid of
:class:`~xfem_contact.solvers.band_multigrid.BandMultigrid`, in the reduced, scaled
unknowns ``y`` (``x = R D y``)."""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np
from petsc4py import PETSc

from xfem_contact.solvers.scaling import gather


def fieldsplit_sets(
    pc: PETSc.PC,
    R: PETSc.Mat,
    D: PETSc.Vec,
    w,
    chosen,
    fieldsplit_dofs: dict,
    near_nullspace: Iterable,
    interpolation=None,
) -> list:
    """Give a fieldsplit preconditioner its index sets ``"u"`` and ``"lambda"`` (and
    ``"u"`` its near null space), or a Python one with a ``configure`` method
    (:class:`~xfem_contact.solvers.band_multigrid.BandMultigrid`) the sets ``"u"``
    and ``"band"``, the near null space (its vectors then the context's) and the
    ``interpolation`` in the reduced unknowns. Other preconditioners get nothing.
    Collective.

    Args:
        pc: The Newton steps' preconditioner (its type already set from the options).
        R: The scaled prolongation ``R D``, global shape ``(dim W, n_reduced)``.
        D: The scaling of the reduced unknowns.
        w: The unknown on ``W`` (for its local sizes).
        chosen: The dof selection of a selecting ``R``
            (:func:`~xfem_contact.solvers.assembly.selection`), or ``None``.
        fieldsplit_dofs: Fieldsplit name to the local dofs of ``W`` it holds, as for
            :class:`~xfem_contact.solvers.newton.ReducedNewton`.
        near_nullspace: Functions on ``W`` (any iterable) for the near null space of
            fieldsplit ``"u"``.
        interpolation: ``(rows, cols, weights)`` on local dofs of ``W``, or ``None``.

    Returns:
        The PETSc objects made here, for the caller to destroy.
    """
    kind = pc.getType()
    if kind not in (PETSc.PC.Type.FIELDSPLIT, PETSc.PC.Type.PYTHON) or not fieldsplit_dofs:
        return []
    comm = R.getComm()
    first = R.getOwnershipRangeColumn()[0]
    n_owned = w.x.index_map.size_local * w.x.block_size
    marker, reduced = R.createVecLeft(), R.createVecRight()
    indptr, columns, _ = R.getValuesCSR()
    single = np.diff(indptr) == 1  # a dof that is one reduced unknown (scaled)
    column = np.full(n_owned, -1, dtype=np.int64)
    column[single] = columns[indptr[:-1][single]]
    objects, sets = [], []
    for name, dofs in fieldsplit_dofs.items():
        dofs = np.asarray(dofs)
        if dofs.ndim == 2:  # blocks (a node's components), kept in order and together
            blocks = dofs[np.all(dofs < n_owned, axis=1)]
            blocks = column[blocks][np.all(column[blocks] >= 0, axis=1)]
            index = PETSc.IS().createGeneral(blocks.ravel().astype(PETSc.IntType), comm=comm)
            index.setBlockSize(dofs.shape[1])
        else:  # any reduced unknown touching the dofs
            marker.set(0.0)
            marker.getArray()[dofs[dofs < n_owned]] = 1.0
            R.multTranspose(marker, reduced)
            local = np.flatnonzero(reduced.getArray(readonly=True) > 0.0)
            index = PETSc.IS().createGeneral((first + local).astype(PETSc.IntType), comm=comm)
        sets.append((name, index))
        objects.append(index)
    if kind == PETSc.PC.Type.FIELDSPLIT:
        pc.setFieldSplitIS(*[(name, index) for name, index in sets if name != "band"])
    index, vectors = dict(sets).get("u"), []
    if index is not None and near_nullspace:
        squared = D.copy()
        squared.pointwiseMult(D, D)
        vectors = []
        local = index.getIndices() - first  # owned: a local slice (no scatter, no copy of R)
        for mode in near_nullspace:  # z = D^-1 R^T x, x = R D z on the active dofs
            R.multTranspose(mode.x.petsc_vec, reduced)
            reduced.pointwiseDivide(reduced, squared)
            part = PETSc.Vec().createMPI((local.size, PETSc.DECIDE), comm=comm)
            part.setArray(reduced.getArray(readonly=True)[local])
            vectors.append(part)
        vectors = _orthonormalise(vectors)
        squared.destroy()
        if kind == PETSc.PC.Type.FIELDSPLIT:
            space = PETSc.NullSpace().create(vectors=vectors, comm=comm)
            index.compose("nearnullspace", space)
            objects += [space, *vectors]
    marker.destroy()
    reduced.destroy()
    context = pc.getPythonContext() if kind == PETSc.PC.Type.PYTHON else None
    if hasattr(context, "configure"):
        reduced_interpolation = _reduced(interpolation, chosen, D)
        context.configure(dict(sets)["u"], dict(sets)["band"], vectors, reduced_interpolation)
    elif kind == PETSc.PC.Type.PYTHON:
        for vector in vectors:
            vector.destroy()
    return objects


def _reduced(interpolation, chosen, D):
    """``(rows, cols, weights)`` on local dofs of ``W`` in the reduced, scaled
    unknowns (``y = D^-1 x``: ``w D_col / D_row``); ``None`` without a selecting
    ``R`` (a multiplier prolongation). Collective."""
    if interpolation is None or chosen is None:
        return None
    rows, cols, weights = interpolation
    rows, cols = chosen.columns[rows], chosen.columns[cols]
    scale = gather(D, cols) / gather(D, rows)
    return rows, cols, weights * scale


def _orthonormalise(vectors: list[PETSc.Vec]) -> list[PETSc.Vec]:
    """Modified Gram-Schmidt (a near null space must be orthonormal): the orthonormal
    vectors kept, the ones that vanish on the fieldsplit (e.g. the rigid modes of a body
    that lies in the interface layer) destroyed. Collective."""
    kept = []
    for v in vectors:
        size = v.norm()
        for u in kept:
            v.axpy(-v.dot(u), u)
        norm = v.norm()
        if norm > 1e-10 * size:
            v.scale(1.0 / norm)
            kept.append(v)
        else:
            v.destroy()
    return kept
