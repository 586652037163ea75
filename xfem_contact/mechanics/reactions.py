"""Reaction forces of supports, resultants of interface tractions, and the global balance.

Computed the standard way from the residual vector ``b = F(w; v_i)`` assembled without
Dirichlet lifting (every row, the laws' two-cell terms of large sliding included): the
force a support exerts on the body is ``R_c = sum_i b_i e_c(i)`` over its Dirichlet dofs
``i``, ``e_c`` the unit vector of component ``c`` on both sides' displacement fields
(the action of the residual on a function equal to ``e_c`` on the part's Dirichlet dofs,
zero elsewhere). The resultant of an interface is the force its traction exerts on side
-1, ``-F_law(w; (e_c, 0))`` (the multiplier is the traction ``sigma n`` on side -1). The
applied loads are ``L(e_c)`` (tractions, pressures, body forces). A tangential spring
support acts as a reaction too: ``-F_spring(w; e_c)``. SI units: forces per unit
thickness (N/m), 2-vectors.

A Dirichlet dof on several boundary parts (a corner) counts for the first part named;
Dirichlet dofs on no part named (fixed points) count under ``"points"``, so the
reactions of all parts add up to the total.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

import dolfinx.fem
import dolfinx.fem.petsc
import numpy as np
import ufl
from mpi4py import MPI
from petsc4py import PETSc

from xfem_contact.fem.forms import form
from xfem_contact.fem.subspaces import collapse

#: A boundary part for :func:`reactions`: local facet indices or a locator ``x -> bool``
Part = np.ndarray | Callable[[np.ndarray], np.ndarray]


# -- accessors of the problem (one place to follow its API) ---------------------------
def dirichlet_conditions(problem) -> list:
    """The problem's Dirichlet conditions."""
    return list(problem.loads.bcs)


def _load_form(problem) -> ufl.Form:
    """The loads' terms ``L(v)`` (tractions, pressures, body forces)."""
    return problem.loads.linear_form()


def _springs(problem):
    """The springs' residual terms (UFL, linear in the test of ``W``), or None."""
    return problem.loads.spring_terms(ufl.split(problem.w), problem.space.test())


def named_parts(problem) -> dict[str, Part]:
    """The problem's named boundary parts: those its Dirichlet conditions name first (in
    the order added), then the others, ``boundary`` (the whole) last."""
    parts = dict(problem.loads.parts)
    named = [
        item.part
        for item in problem.loads.items
        if item.part in parts and getattr(item, "functions", None) is not None
    ]
    order = [*dict.fromkeys(named), *(k for k in parts if k != "boundary"), "boundary"]
    return {k: parts[k] for k in dict.fromkeys(order) if k in parts}


# -- vectors --------------------------------------------------------------------------
def _vector(problem, ufl_form) -> PETSc.Vec:
    """``ufl_form`` (linear in the test of ``W``) assembled, ghosts added to owners."""
    b = dolfinx.fem.petsc.assemble_vector(form(ufl_form))
    b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    return b


def residual_vector(problem) -> PETSc.Vec:
    """``F(w; v_i)`` of the problem's current ``w`` for every dof ``i`` of ``W``, without
    Dirichlet lifting and with no row set (owned entries valid). Collective."""
    if problem.linear:  # A w - L with the forms of the solve (no new compile)
        A = dolfinx.fem.petsc.assemble_matrix(form(problem.bilinear_form()))
        A.assemble()
        b = _vector(problem, _load_form(problem))
        b.scale(-1.0)
        A.multAdd(problem.w.x.petsc_vec, b, b)
        A.destroy()
        return b
    b = _vector(problem, problem.residual())
    for coupling in (getattr(problem, "couplings", None) or {}).values():
        coupling.add_residual(problem.w, b)
    return b


def unit_vectors(problem) -> list[np.ndarray]:
    """``e_x``, ``e_y`` as local arrays of ``W`` (1 on the component of both sides'
    displacement fields, 0 elsewhere; owned and ghost dofs)."""
    W = problem.space.W
    size = W.dofmap.index_map.size_local + W.dofmap.index_map.num_ghosts
    units = [np.zeros(size * W.dofmap.index_map_bs) for _ in range(2)]
    for field in (0, 1):
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


def _part_dofs(problem, part: Part) -> np.ndarray:
    """Local dofs of ``W`` (both displacement fields) on a boundary part."""
    fdim = problem.mesh.topology.dim - 1
    dofs = []
    for field in (0, 1):
        sub = problem.space.W.sub(field)
        V, _ = collapse(sub)
        if callable(part):
            dofs.append(dolfinx.fem.locate_dofs_geometrical((sub, V), part)[0])
        else:
            facets = np.asarray(part, dtype=np.int32)
            dofs.append(dolfinx.fem.locate_dofs_topological((sub, V), fdim, facets)[0])
    return np.concatenate(dofs)


# -- public ---------------------------------------------------------------------------
def reactions(
    problem, parts: Mapping[str, Part] | None = None, b: np.ndarray | None = None
) -> dict:
    """Force (N/m, ``(2,)``) of the supports of each boundary part on the body.

    Args:
        problem: A solved problem (its ``w``).
        parts: Name to part, in order of precedence (default: :func:`named_parts`);
            parts with no Dirichlet dof are left out.
        b: The residual vector's local array (:func:`residual_vector`), if at hand.

    Returns:
        ``{name: array([R_x, R_y])}``, and ``"points"`` for Dirichlet dofs on no part.
        Collective.
    """
    if b is None:
        vec = residual_vector(problem)
        b = vec.array_r.copy()
        vec.destroy()
    n = _owned(problem)
    b = np.concatenate([b[:n], np.zeros(len(unit_vectors(problem)[0]) - n)])
    constrained = np.zeros(b.size, dtype=bool)
    for bc in dirichlet_conditions(problem):
        constrained[bc.dof_indices()[0]] = True
    comm, out = problem.mesh.comm, {}
    for name, part in (named_parts(problem) if parts is None else parts).items():
        mine = np.zeros(b.size, dtype=bool)
        mine[_part_dofs(problem, part)] = True
        mine &= constrained
        constrained &= ~mine
        if comm.allreduce(int(mine[:n].sum()), op=MPI.SUM):
            out[name] = _force(problem, b, mine)
    if comm.allreduce(int(constrained[:n].sum()), op=MPI.SUM):
        out["points"] = _force(problem, b, constrained)
    return out


def applied_loads(problem) -> np.ndarray:
    """The resultant (N/m, ``(2,)``) of the tractions, pressures and body forces at the
    current load factor, ``L(e_c)``. Collective."""
    vec = _vector(problem, _load_form(problem))
    force = _force(problem, vec.array_r)
    vec.destroy()
    return force


def interface_resultants(problem) -> dict[str, np.ndarray]:
    """Per interface, the resultant (N/m, ``(2,)``) of its traction on side -1 (the force
    side +1 exerts on side -1 across it; zero for a free interface). Collective."""
    out = {}
    v = problem.space.test()
    for name, law in problem.laws.items():
        ctx = problem.contexts[name]
        term = law.residual(ctx, ctx.fields(ufl.split(problem.w)), ctx.fields(v))
        b = None if term is None else _vector(problem, term)
        coupling = (getattr(problem, "couplings", None) or {}).get(name)
        if coupling is not None:
            if b is None:
                b = dolfinx.fem.petsc.create_vector(problem.space.W)
                b.zeroEntries()
            coupling.add_residual(problem.w, b)
        if b is None:
            out[name] = np.zeros(2)
            continue
        minus = np.zeros(unit_vectors(problem)[0].size, dtype=bool)
        minus[problem.space.field_space(0)[1]] = True
        out[name] = -_force(problem, b.array_r, minus)
        b.destroy()
    return out


def spring_reactions(problem) -> np.ndarray | None:
    """The force (N/m, ``(2,)``) of the tangential spring supports on the body, or None
    without springs. Collective."""
    terms = _springs(problem)
    if terms is None:
        return None
    vec = _vector(problem, terms)
    force = -_force(problem, vec.array_r)
    vec.destroy()
    return force


def balance(problem, parts: Mapping[str, Part] | None = None) -> dict:
    """Reactions per part, the applied loads, interface resultants and the global
    balance ``sum(reactions) + loads`` (N/m) with its size relative to the largest force.
    Collective."""
    vec = residual_vector(problem)
    supports = reactions(problem, parts, vec.array_r.copy())
    vec.destroy()
    springs = spring_reactions(problem)
    if springs is not None:
        supports["tangential_supports"] = springs
    loads = applied_loads(problem)
    total = sum(supports.values(), np.zeros(2)) + loads
    scale = max([np.abs(loads).max(), *(np.abs(r).max() for r in supports.values()), 0.0])
    return {
        "reactions": {k: r.tolist() for k, r in supports.items()},
        "applied_loads": loads.tolist(),
        "interface_resultants": {k: r.tolist() for k, r in interface_resultants(problem).items()},
        "balance": total.tolist(),
        "balance_relative": float(np.abs(total).max() / scale) if scale > 0 else 0.0,
    }
