"""Reaction forces of supports, resultants of interface tractions, and the global balance.

Computed the standard way from the residual vector ``b = F(w; v_i)`` assembled without
Dirichlet lifting (every row, the laws' two-cell terms of large sliding included): the
force a support exerts on the body is ``R_c = sum_i b_i e_c(i)`` over its Dirichlet dofs
``i``, ``e_c`` the unit vector of component ``c`` on both sides' displacement fields
(the action of the residual on a function equal to ``e_c`` on the part's Dirichlet dofs,
zero elsewhere). The resultant of an interface is the force its traction exerts on side
-1, ``-F_law(w; (e_c, 0))`` (the multiplier is the traction ``sigma n`` on side -1). The
applied loads are ``L(e_c)`` (tractions, pressures, body forces). A tangential spring
acts as a reaction too: ``-F_spring(w; e_c)``. SI units: forces per unit
thickness (N/m), 2-vectors.

Reactions are grouped by the load that prescribes the displacement (by its part's name,
or its kind, e.g. ``point displacement``); a dof two loads hold (a corner held by two
parts in the same component) counts for the first, so the reactions add up to the total.
"""

from __future__ import annotations

import dolfinx.fem
import dolfinx.fem.petsc
import numpy as np
import ufl
from mpi4py import MPI
from petsc4py import PETSc

from xfem_contact.fem.forms import form


# -- accessors of the problem (one place to follow its API) ---------------------------
def _load_form(problem) -> ufl.Form:
    """The loads' terms ``L(v)`` (tractions, pressures, body forces)."""
    return problem.loads.linear_form()


def _springs(problem, w: dolfinx.fem.Function):
    """The springs' residual terms at the state ``w`` (UFL, linear in the test of ``W``),
    or None."""
    return problem.loads.spring_terms(problem.space.split(w), problem.space.test())


def _functions(load) -> list:
    """The Dirichlet functions of a load (none for tractions, pressures, springs)."""
    return getattr(load, "functions", None) or []


def supports(problem) -> dict[str, list]:
    """The Dirichlet conditions grouped by what they hold: the boundary part's name for a
    prescribed displacement or rotation given by name, else the load's kind (e.g.
    ``point displacement``), in the order added."""
    groups: dict[str, list] = {}
    for bc in problem.loads.bcs:
        value = bc.g
        item = next(
            (i for i in problem.loads.items if any(value is f._cpp_object for f in _functions(i))),
            None,
        )
        name = "other" if item is None else (item.part or item.kind)
        groups.setdefault(name, []).append(bc)
    return groups


# -- vectors --------------------------------------------------------------------------
def _vector(problem, ufl_form) -> PETSc.Vec:
    """``ufl_form`` (linear in the test of ``W``) assembled, ghosts added to owners."""
    b = dolfinx.fem.petsc.assemble_vector(form(ufl_form))
    b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    return b


def residual_vector(problem, w: dolfinx.fem.Function) -> PETSc.Vec:
    """``F(w; v_i)`` at the state ``w`` (a function on the problem's space, e.g. its
    solution ``problem.w``) for every dof ``i`` of ``W``, without Dirichlet lifting and
    with no row set (owned entries valid). Collective."""
    if problem.linear:  # A w - L with the forms of the solve (no new compile)
        A = dolfinx.fem.petsc.assemble_matrix(form(problem.bilinear_form()))
        A.assemble()
        b = _vector(problem, _load_form(problem))
        b.scale(-1.0)
        A.multAdd(w.x.petsc_vec, b, b)
        A.destroy()
        return b
    b = _vector(problem, problem.residual(w))
    for coupling in problem.couplings.values():
        coupling.add_residual(w, b)
    return b


def unit_vectors(problem) -> list[np.ndarray]:
    """``e_x``, ``e_y`` as local arrays of ``W`` (1 on the component of both sides'
    displacement fields, 0 elsewhere; owned and ghost dofs)."""
    W = problem.space.W
    size = W.dofmap.index_map.size_local + W.dofmap.index_map.num_ghosts
    units = [np.zeros(size * W.dofmap.index_map_bs) for _ in range(2)]
    for field in getattr(problem.space, "fields", (0, 1)):
        _, parent = problem.space.field_space(field)
        for c, e in enumerate(units):
            e[parent[c::2]] = 1.0
    return units


def _owned(problem) -> int:
    imap = problem.space.W.dofmap.index_map
    return imap.size_local * problem.space.W.dofmap.index_map_bs


def _force(problem, b: np.ndarray, mask: np.ndarray | None = None) -> np.ndarray:
    """``(sum_i b_i e_x(i), sum_i b_i e_y(i))`` over the owned dofs in ``mask``. Collective."""
    n = _owned(problem)
    keep = slice(None) if mask is None else mask[:n]
    local = np.array([np.sum((b[:n] * e[:n])[keep]) for e in unit_vectors(problem)])
    return problem.mesh.comm.allreduce(local, op=MPI.SUM)


# -- public ---------------------------------------------------------------------------
def reactions(
    problem, w: dolfinx.fem.Function, b: np.ndarray | None = None
) -> dict[str, np.ndarray]:
    """Force (N/m, ``(2,)``) of each support (:func:`supports`) on the body at a state.

    Args:
        problem: A problem (its loads at their current time).
        w: The state, a function on the problem's space (e.g. ``problem.w``).
        b: The residual vector's owned entries at ``w`` (:func:`residual_vector`), if
            at hand.

    Returns:
        ``{name: array([R_x, R_y])}``. Collective.
    """
    if b is None:
        vec = residual_vector(problem, w)
        b = vec.array_r.copy()
        vec.destroy()
    n = _owned(problem)
    b = np.concatenate([b[:n], np.zeros(unit_vectors(problem)[0].size - n)])
    taken = np.zeros(b.size, dtype=bool)
    out = {}
    for name, bcs in supports(problem).items():
        mine = np.zeros(b.size, dtype=bool)
        for bc in bcs:
            mine[bc.dof_indices()[0]] = True
        mine &= ~taken  # a dof held twice counts once, for the first
        taken |= mine
        out[name] = _force(problem, b, mine)
    return out


def applied_loads(problem) -> tuple[np.ndarray, float]:
    """The resultant (N/m, ``(2,)``) of the tractions, pressures and body forces at the
    current time, ``L(e_c)``, and their total size ``max_c sum_i |L_i e_c(i)|`` (N/m: the
    scale of a balance of self-equilibrated loads); they do not depend on the state.
    Collective."""
    vec = _vector(problem, _load_form(problem))
    L = vec.array_r.copy()
    vec.destroy()
    return _force(problem, L), float(_force(problem, np.abs(L)).max())


def interface_resultants(problem, w: dolfinx.fem.Function) -> dict[str, np.ndarray]:
    """Per interface, the resultant (N/m, ``(2,)``) of its traction on side -1 at the
    state ``w`` (the force side +1 exerts on side -1 across it; zero for a free
    interface). Collective."""
    out = {}
    v = problem.space.test()
    for name, law in problem.laws.items():
        ctx = problem.contexts[name]
        term = law.residual(ctx, ctx.fields(problem.space.split(w)), ctx.fields(v))
        b = None if term is None else _vector(problem, term)
        coupling = problem.couplings.get(name)
        if coupling is not None:
            if b is None:
                b = dolfinx.fem.petsc.create_vector(problem.space.W)
                b.zeroEntries()
            coupling.add_residual(w, b)
        if b is None:
            out[name] = np.zeros(2)
            continue
        minus = np.zeros(unit_vectors(problem)[0].size, dtype=bool)
        minus[problem.space.field_space(0)[1]] = True
        out[name] = -_force(problem, b.array_r, minus)
        b.destroy()
    return out


def spring_reactions(problem, w: dolfinx.fem.Function) -> np.ndarray | None:
    """The force (N/m, ``(2,)``) of the tangential springs on the body at the
    state ``w``, or None without springs. Collective."""
    terms = _springs(problem, w)
    if terms is None:
        return None
    vec = _vector(problem, terms)
    force = -_force(problem, vec.array_r)
    vec.destroy()
    return force


def balance(problem, w: dolfinx.fem.Function) -> dict:
    """Reactions per support, the applied loads, interface resultants and the global
    balance ``sum(reactions) + loads`` (N/m) at the state ``w`` (e.g. ``problem.w``),
    with its size relative to the largest reaction or the total size of the loads
    (:func:`applied_loads`). Collective."""
    vec = residual_vector(problem, w)
    held = reactions(problem, w, vec.array_r.copy())
    vec.destroy()
    springs = spring_reactions(problem, w)
    if springs is not None:
        held["tangential_springs"] = springs
    loads, size = applied_loads(problem)
    total = sum(held.values(), np.zeros(2)) + loads
    scale = max([size, *(np.abs(r).max() for r in held.values()), 0.0])
    return {
        "reactions": {k: r.tolist() for k, r in held.items()},
        "applied_loads": loads.tolist(),
        "interface_resultants": {
            k: r.tolist() for k, r in interface_resultants(problem, w).items()
        },
        "balance": total.tolist(),
        "balance_relative": float(np.abs(total).max() / scale) if scale > 0 else 0.0,
    }
