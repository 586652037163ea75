"""Rigid modes that no Dirichlet condition or interface law removes, found before solving.

A problem is singular when a body can move rigidly with nothing resisting it: the
solve fails (Newton iterates until SNES gives up) or, worse, returns a solution
with an arbitrary rigid motion in it.
:func:`check_rigid_modes` finds those motions from the data that decide them,
without assembling anything:

- the *bodies*: the connected parts of the sides' fields (field 1 on side +1, field 0
  on side -1, joined through the dofs their cells share and, beside a crack, through
  the ties of the two sides' dofs where the crack does not cut the body: around its
  tips and along its extension), each with its rigid modes (:func:`rigid_motions` about
  its centroid: translations x, y and the rotation in 2D; translations x, y, z and the
  rotations about the three axes in 3D). The two sides of a crack ending inside the body are
  thus one body; a line that cuts the body in two leaves two;
- the *Dirichlet conditions* (``problem.loads.bcs``): the values of each mode at the
  prescribed active dofs of its body;
- the *interface laws* (a crack's lips too), by what they transmit once closed:
  ``free`` nothing; ``frictionless`` (and ``coulomb`` with ``mu = 0``) the normal
  jump only; ``bonded``, ``sticking``, ``coulomb`` (``mu > 0``) and any other law
  the whole jump: the jump of the bodies' modes at the interface rule points, with
  the normal the laws use.

A combination of modes is free when its mean-square constraint is below ``tol``:
each prescribed dof weighs one, each interface its mean over arc length, and a
rotation is scaled by the body's radius of gyration so that every mode moves the
body by about one. The question is geometric and answered alike for any mesh and
cut: a straight frictionless interface leaves the sliding along it free, an ellipse
nothing, a frictionless circle the spin of the inner body. The discrete normal
(that of the interpolated level set) makes that spin stiff to round-off of the
geometry only, weakly and the less the finer the mesh (figures: the docs' mechanics
page). The bulk adds no constraint (a rigid mode has no strain and no
ghost-penalty jump), nor do the multiplier stabilisations (nor any traction).
Contact laws are judged closed: an interface that opens under the load may still
leave a body free, which only the solve can tell.
"""

from __future__ import annotations

import logging
import warnings

import basix
import dolfinx.la
import numpy as np
from mpi4py import MPI

from xfem_contact.fem.evaluation import interface_points
from xfem_contact.mechanics.rigid_mode_names import (
    FreeBody,
    describe,
    describe_3d,
    null_space,
    short_number,
)
from xfem_contact.mechanics.rigid_motions import Body, modes_per_body

logger = logging.getLogger(__name__)

#: What a closed interface of each kind transmits (the reason in the messages)
_KIND_TEXT = {
    "none": "transmits nothing",
    "normal": "transmits no tangential traction",
    "full": "ties the two sides",
}


class RigidModeWarning(UserWarning):
    """A body may spin freely (a frictionless circular interface): fine without torque."""


def check_support(problem) -> None:
    """Act on the free rigid modes of ``problem``'s bodies: a body without support is
    an error naming the modes and the constraints that remove them; a spin only a
    frictionless interface leaves free is a :class:`RigidModeWarning` (and a warning
    record on this module's logger, on rank 0): a point constraint for it would carry a
    spurious reaction and spoil the pressure (docs' mechanics page). Collective.

    Raises:
        ValueError: a body has free rigid modes beyond such a spin.
    """
    free = free_bodies(problem)
    if errors := [body.message() for body in free if not body.spin_only]:
        raise ValueError("Free rigid modes: " + " | ".join(errors))
    for body in free:
        message = f"{body.message()} if the loads carry a torque"
        warnings.warn(message, RigidModeWarning, stacklevel=4)  # the caller of solve()
        if problem.mesh.comm.rank == 0:
            logger.warning(message)


def check_rigid_modes(problem, tol: float = 1e-3) -> list[str]:
    """Messages naming each body with free rigid modes, the modes, why, and the
    point constraints that remove them; empty when every body is held. Collective
    (the same list on every process). See the module docstring for the method."""
    return [body.message() for body in free_bodies(problem, tol)]


def free_bodies(problem, tol: float = 1e-3) -> list[FreeBody]:
    """The bodies with free rigid modes (:class:`FreeBody`), collective."""
    bodies, pieces = _bodies(problem)
    nb = len(bodies)
    m = modes_per_body(problem.mesh.geometry.dim)
    Q = _dirichlet_gram(problem, bodies)
    held = [np.trace(Q[m * b : m * b + m, m * b : m * b + m]) >= tol for b in range(nb)]
    kinds = {name: law.transmits for name, law in problem.laws.items()}
    bounding: list[set[str]] = [set() for _ in bodies]  # the interfaces along each body
    for name, kind in kinds.items():
        gram, touched = _interface_gram(problem, bodies, pieces, name, kind, m)
        Q += gram
        for b in touched:
            bounding[b].add(name)
    values, vectors = np.linalg.eigh(0.5 * (Q + Q.T))
    null = vectors[:, values < tol]  # the free combinations, orthonormal columns
    found = []
    for b, body in enumerate(bodies):
        motion = null[m * b : m * b + m]
        U, s, _ = np.linalg.svd(motion, full_matrices=False)
        S = U[:, s > 0.1]  # the body's motions in free modes, (m, r) in (a, theta)
        if S.shape[1] == 0:
            continue
        names = [name for name in kinds if name in bounding[b]]
        reasons = ["Dirichlet conditions hold it in part" if held[b] else "no Dirichlet condition"]
        reasons += [
            f"interface {n!r} is {problem.laws[n].name}: it {_KIND_TEXT[kinds[n]]}" for n in names
        ]
        others = [
            bodies[o].name
            for o in range(b + 1, nb)
            if np.linalg.norm(null[m * o : m * o + m] @ (motion.T @ S)) > 0.1
        ]
        if others:
            reasons.append("it moves together with " + ", ".join(others))
        name_motions = describe if problem.mesh.geometry.dim == 2 else describe_3d
        free = name_motions(problem, body, S, reasons)
        free.spin_only = all(mode.startswith("rotation") for mode in free.modes) and any(
            kinds[n] == "normal" for n in names
        )
        found.append(free)
        # the remedies fix every free mode that moves this body: the later bodies are
        # left with the modes that do not
        null = null @ null_space(motion)
    return found


def _components(n: int, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Connected components of the graph of ``n`` nodes and edges ``(a[i], b[i])``: each
    node's label is the smallest node of its component, shape (n,)."""
    label = np.arange(n)
    while True:
        low = np.minimum(label[a], label[b])
        new = label.copy()
        np.minimum.at(new, label[a], low)  # hook the roots onto the smaller label
        np.minimum.at(new, label[b], low)
        while not np.array_equal(new, new[new]):  # then jump to the roots
            new = new[new]
        if np.array_equal(new, label):
            return label
        label = new


def _pieces(problem) -> tuple[dict[int, np.ndarray], np.ndarray]:
    """The connected parts of the sides' fields. Collective.

    Returns:
        ``pieces``: per field (0, 1), the global part of each owned cell, shape
        (num_cells,), -1 where the field has no active dof on the cell (field 0 lives on
        side -1 and cut cells, field 1 on side +1 and cut cells);
        ``part``: the global part of each local dof of ``W`` (-1: none), the parts
        numbered 0, 1, ... alike on every process.
    """
    cut, space = problem.cut, problem.space
    W, comm = space.W, problem.mesh.comm
    imap, bs = W.dofmap.index_map, W.dofmap.index_map_bs
    ndofs = (imap.size_local + imap.num_ghosts) * bs
    sides = cut.cell_sides
    cells = {0: np.flatnonzero(sides <= 0), 1: np.flatnonzero(sides >= 0)}
    active = space.active
    a, b = [space.ties[:, 0]], [space.ties[:, 1]]  # the crack's ties join the two sides
    for field, where in cells.items():
        dofs = W.sub(field).dofmap.list[where]
        on = active[dofs]
        first = dofs[np.arange(dofs.shape[0]), np.argmax(on, axis=1)]
        a.append(dofs[on])
        b.append(np.broadcast_to(first[:, None], dofs.shape)[on])
    a, b = np.concatenate(a), np.concatenate(b)
    local = _components(ndofs, a, b)
    used = np.zeros(ndofs, bool)
    used[a] = used[b] = True
    # the local parts of all processes as nodes of one graph, joined by the dofs they share
    labels = np.unique(local[used])
    counts = comm.allgather(labels.size)
    offset = int(np.sum(counts[: comm.rank]))
    node = np.full(ndofs, -1, dtype=np.int64)
    node[used] = offset + np.searchsorted(labels, local[used])
    shared = dolfinx.la.vector(imap, bs)
    shared.array[imap.size_local * bs :] = 1.0
    shared.scatter_reverse(dolfinx.la.InsertMode.add)
    mine = np.flatnonzero(used & ((shared.array > 0) | (np.arange(ndofs) >= imap.size_local * bs)))
    blocks = imap.local_to_global((mine // bs).astype(np.int32))
    keys = np.concatenate(comm.allgather(blocks * bs + mine % bs))
    nodes = np.concatenate(comm.allgather(node[mine]))
    order = np.argsort(keys, kind="stable")
    keys, nodes = keys[order], nodes[order]
    same = keys[1:] == keys[:-1]
    root = _components(int(np.sum(counts)), nodes[1:][same], nodes[:-1][same])
    _, glob = np.unique(root, return_inverse=True)
    part = np.where(node >= 0, glob[np.maximum(node, 0)], -1)
    pieces = {}
    for field, where in cells.items():
        dofs = W.sub(field).dofmap.list
        pieces[field] = np.full(sides.size, -1, dtype=np.int64)
        on = active[dofs[where]]
        first = dofs[where][np.arange(where.size), np.argmax(on, axis=1)]
        pieces[field][where] = np.where(on.any(axis=1), part[first], -1)
    return pieces, part


def _bodies(problem) -> tuple[list[Body], dict[int, np.ndarray]]:
    """The bodies (the connected parts with active dofs, see :func:`_pieces`), side +1's
    first, and per field the body of each owned cell (-1: none). Collective."""
    cut, space = problem.cut, problem.space
    W, comm = space.W, problem.mesh.comm
    nowned = W.dofmap.index_map.size_local * W.dofmap.index_map_bs
    pieces, part = _pieces(problem)
    names = cut.interface_names
    region = cut.cell_regions()
    owned = np.arange(cut.cell_sides.size, dtype=np.int32)
    regions = np.rint(region.x.array[region.function_space.dofmap.list[owned, 0]]).astype(int)
    nparts = 1 + max(comm.allreduce(int(p.max(initial=-1)), op=MPI.MAX) for p in pieces.values())
    # per part: whether it holds each field, and the interfaces of its side -1 cells
    holds = np.zeros((nparts, 2 + len(names)), bool)
    for field in (0, 1):
        holds[pieces[field][pieces[field] >= 0], field] = True
    inside = pieces[0] >= 0
    holds[pieces[0][inside], 2 + regions[inside]] = True
    holds = comm.allreduce(holds.astype(np.int64), op=MPI.SUM) > 0
    # the other side's dof at the same node and component (the two fields' elements match)
    partner = np.full(space.active.size, -1, dtype=np.int64)
    for f in (0, 1):
        partner[W.sub(f).dofmap.list.ravel()] = W.sub(1 - f).dofmap.list.ravel()
    gdim = problem.mesh.geometry.dim
    nodes = {}  # field -> (parent dof of each component of each node, node coordinates)
    for field in (0, 1):
        V, parent = space.field_space(field)
        parents = [parent[c :: V.dofmap.bs] for c in range(gdim)]
        nodes[field] = (parents, V.tabulate_dof_coordinates())
    where = "interface " + repr(names[0]) if len(names) == 1 else "the interfaces"
    found = []
    for p in range(nparts):
        dofs, coords, alone = [], [], []
        for c in range(gdim):  # components x, y(, z)
            parents = [nodes[f][0][c] for f in (0, 1)]
            keep = [(parent < nowned) & (part[parent] == p) for parent in parents]
            dofs.append(np.concatenate([parents[f][keep[f]] for f in (0, 1)]))
            coords.append(np.concatenate([nodes[f][1][keep[f], :gdim] for f in (0, 1)]))
            alone.append(~space.active[partner[dofs[-1]]])
        if comm.allreduce(coords[0].shape[0], op=MPI.SUM) == 0:
            continue
        around = [names[k] for k in np.flatnonzero(holds[p, 2:])]
        if holds[p, 0] and holds[p, 1]:
            label = f"the body cracked by {', '.join(map(repr, around))}"
        elif holds[p, 1]:
            label = f"side +1 (outside {where})"
        else:
            label = f"side -1 (inside interface {around[0]!r})"
        centre, radius = _centroid(cut, {f: owned[pieces[f] == p] for f in (0, 1)})
        first = int(np.argmax(holds[p, 2:])) if holds[p, 2:].any() else -1
        body = Body(label, dofs, coords, alone, centre, radius)
        found.append(((not holds[p, 1], first, p), body))
    found.sort(key=lambda item: item[0])  # side +1's first, then by interface
    bodies = [body for _, body in found]
    for label in {body.name for body in bodies}:
        twins = [body for body in bodies if body.name == label]
        for body in twins if len(twins) > 1 else []:
            body.name += f", the part about ({', '.join(short_number(v, 3) for v in body.centre)})"
    of_part = np.full(nparts + 1, -1)  # the body of each part, -1 (index -1 too): none
    of_part[[key[2] for key, _ in found]] = np.arange(len(found))
    return bodies, {f: of_part[pieces[f]] for f in (0, 1)}


def _volume_ratio(J: np.ndarray) -> np.ndarray:
    """``|det J|`` of Jacobians ``J``, shape ``(m, d, d)`` -> ``(m,)`` (2 x 2 and 3 x 3
    written out: LAPACK's per-matrix call is ten times slower on many small matrices)."""
    if J.shape[1:] == (2, 2):
        return np.abs(J[:, 0, 0] * J[:, 1, 1] - J[:, 0, 1] * J[:, 1, 0])
    if J.shape[1:] == (3, 3):
        return np.abs(np.einsum("pi,pi->p", J[:, 0], np.cross(J[:, 1], J[:, 2])))
    return np.abs(np.linalg.det(J))


def _centroid(cut, cells: dict[int, np.ndarray]) -> tuple[np.ndarray, float]:
    """Centroid (m) and radius of gyration (m) of the part of ``cells[f]`` on the side of
    field ``f`` (0: side -1, 1: side +1): uncut cells by a degree-2 rule, cut cells by
    the side's rules. Collective."""
    maps, comm = cut.maps, cut.mesh.comm
    X, W = basix.make_quadrature(cut.mesh.basix_cell(), 2)
    gdim = cut.mesh.geometry.dim
    xs, ws = [np.zeros((0, gdim))], [np.zeros(0)]
    for field, where in cells.items():
        side = 2 * field - 1
        whole = where[cut.cell_sides[where] == side]
        if whole.size:  # one rule in every uncut cell: the cell maps tabulated once
            J = maps.jacobian_lattice(whole, X)
            ws.append(np.tile(W, whole.size) * _volume_ratio(J))
            xs.append(maps.push_forward_lattice(whole, X)[:, :gdim])
        rules = cut.side_rules(side)
        mine = np.isin(cut.cut_cells[rules.point_rows], where)
        rows, points = cut.cut_cells[rules.point_rows[mine]].astype(np.int32), rules.points[mine]
        if rows.size:
            ws.append(rules.weights[mine] * _volume_ratio(maps.jacobian(rows, points)))
            xs.append(maps.push_forward(rows, points)[:, :gdim])
    x, weights = np.concatenate(xs), np.concatenate(ws)
    area = comm.allreduce(float(weights.sum()), op=MPI.SUM)
    centre = comm.allreduce(weights @ x, op=MPI.SUM) / area
    inertia = comm.allreduce(float(weights @ np.sum((x - centre) ** 2, axis=1)), op=MPI.SUM)
    return centre, float(np.sqrt(inertia / area))


def _dirichlet_gram(problem, bodies: list[Body]) -> np.ndarray:
    """Block-diagonal Gram of each body's modes at its prescribed dofs (global)."""
    W = problem.space.W
    imap = W.dofmap.index_map
    prescribed = np.zeros((imap.size_local + imap.num_ghosts) * W.dofmap.index_map_bs, bool)
    for bc in problem.loads.bcs:
        prescribed[bc.dof_indices()[0]] = True
    m = modes_per_body(problem.mesh.geometry.dim)
    G = np.zeros((m * len(bodies), m * len(bodies)))
    for b, body in enumerate(bodies):
        for c in range(problem.mesh.geometry.dim):
            z = body.modes(body.coords[c][prescribed[body.dofs[c]]], c)
            G[m * b : m * b + m, m * b : m * b + m] += z.T @ z
    return problem.mesh.comm.allreduce(G, op=MPI.SUM)


def _interface_gram(
    problem, bodies: list[Body], pieces: dict[int, np.ndarray], name: str, kind: str, m: int
) -> tuple[np.ndarray, set[int]]:
    """Gram (global, per unit length or area) of the jump of the bodies' ``m`` modes
    across interface ``name`` (at each rule point, from the body of field 0 of its cell
    to that of field 1): the whole jump, its normal part or nothing (``kind``); and the
    bodies along it."""
    cut, comm = problem.cut, problem.mesh.comm
    rules = cut.interface_rules_of(name)
    cells = cut.cut_cells[rules.point_rows]
    minus, plus = pieces[0][cells], pieces[1][cells]
    touched = {int(b) for mine in comm.allgather(np.unique(np.r_[minus, plus])) for b in mine}
    touched.discard(-1)
    nb = len(bodies)
    if kind == "none":
        return np.zeros((m * nb, m * nb)), touched
    gdim = cut.mesh.geometry.dim
    x = interface_points(cut, rules)[:, :gdim]
    n = cut.normal_at(rules)[:, :gdim]
    J = cut.maps.jacobian(cells, rules.points)
    w = rules.weights * np.abs(np.linalg.det(J))
    jump = np.zeros((x.shape[0], gdim, m * nb))  # per point, component, coefficient
    for bs, sign in ((minus, -1.0), (plus, 1.0)):
        for b in np.unique(bs[bs >= 0]):
            at = bs == b
            for c in range(gdim):
                jump[at, c, m * b : m * b + m] += sign * bodies[b].modes(x[at], c)
    jump[(minus == plus) | (minus < 0) | (plus < 0)] = 0.0  # one body, or a side without
    if kind == "normal":
        jump = np.einsum("pc,pcm->pm", n, jump)[:, None, :]
    G = comm.allreduce(np.einsum("p,pcm,pcl->ml", w, jump, jump), op=MPI.SUM)
    return G / comm.allreduce(float(w.sum()), op=MPI.SUM), touched
