"""Rigid modes that no Dirichlet condition or interface law removes, found before solving.

A problem is singular when a body can move rigidly with nothing resisting it: the
solve fails (Newton iterates until SNES gives up) or, worse, returns a solution
with an arbitrary rigid motion in it.
:func:`check_rigid_modes` finds those motions from the data that decide them,
without assembling anything:

- the *bodies*: the connected parts of the sides' fields (field 1 on side +1, field 0
  on side -1, joined through the dofs their cells share and, beside a crack, through
  the ties of the two sides' dofs where the crack does not cut the body: around its
  tips and along its extension), each with its rigid modes (translations x, y and the
  rotation about its centroid). The two sides of a crack ending inside the body are
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

import dataclasses
import logging
import warnings

import basix
import dolfinx.la
import numpy as np
from mpi4py import MPI

from xfem_contact.fem.evaluation import interface_points

logger = logging.getLogger(__name__)

#: What a closed interface of each kind transmits (the reason in the messages)
_KIND_TEXT = {
    "none": "transmits nothing",
    "normal": "transmits no tangential traction",
    "full": "ties the two sides",
}


@dataclasses.dataclass
class _Body:
    """A connected part of the sides' fields: its owned active dofs per component."""

    name: str
    dofs: list[np.ndarray]  # per component: owned local dofs of W
    coords: list[np.ndarray]  # their coordinates, (n, 2)
    alone: list[np.ndarray]  # per component: whether no other side's field is active there
    centre: np.ndarray
    radius: float  # radius of gyration of its area (m)

    def modes(self, x: np.ndarray, component: int) -> np.ndarray:
        """Component ``component`` of the 3 scaled modes at points ``x``, shape (n, 3)."""
        d = (x - self.centre) / self.radius
        z = np.zeros((x.shape[0], 3))
        z[:, component] = 1.0
        z[:, 2] = -d[:, 1] if component == 0 else d[:, 0]
        return z


@dataclasses.dataclass
class FreeBody:
    """A body with rigid modes nothing constrains.

    Attributes:
        body: e.g. ``"side -1 (inside interface 'inclusion')"``.
        modes: e.g. ``["translation x", "rotation about (0.5, 0.5)"]``.
        reasons: Why nothing holds them (Dirichlet data, interface laws).
        remedies: ``(point, component)`` of point constraints that remove them
            (``problem.loads.add_point_displacement(point, 0.0, component)``).
        spin_only: The only free mode is a rotation that a frictionless interface of
            the body leaves (a spin its geometry does not lock), not a missing support.
    """

    body: str
    modes: list[str]
    reasons: list[str]
    remedies: list[tuple[list[float], int]]
    spin_only: bool = False

    def message(self) -> str:
        one = len(self.modes) == 1
        fixes = ", ".join(
            f"loads.add_point_displacement([{_num(p[0], 6)}, {_num(p[1], 6)}], 0.0, {c})"
            for p, c in self.remedies
        )
        return (
            f"{self.body}: {' and '.join(self.modes)} {'is' if one else 'are'} not constrained "
            f"({'; '.join(self.reasons)}); fix {'it' if one else 'them'} with {fixes}"
        )


def _num(value: float, digits: int) -> str:
    """``value`` to ``digits`` significant digits, round-off (below 1e-9) shown as 0."""
    return f"{(0.0 if abs(value) < 1e-9 else float(value)):.{digits}g}"


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
    Q = _dirichlet_gram(problem, bodies)
    held = [np.trace(Q[3 * b : 3 * b + 3, 3 * b : 3 * b + 3]) >= tol for b in range(nb)]
    kinds = {name: law.transmits for name, law in problem.laws.items()}
    bounding: list[set[str]] = [set() for _ in bodies]  # the interfaces along each body
    for name, kind in kinds.items():
        gram, touched = _interface_gram(problem, bodies, pieces, name, kind)
        Q += gram
        for b in touched:
            bounding[b].add(name)
    values, vectors = np.linalg.eigh(0.5 * (Q + Q.T))
    null = vectors[:, values < tol]  # the free combinations, orthonormal columns
    found = []
    for b, body in enumerate(bodies):
        motion = null[3 * b : 3 * b + 3]
        U, s, _ = np.linalg.svd(motion, full_matrices=False)
        S = U[:, s > 0.1]  # the body's motions in free modes, (3, r) in (ax, ay, theta)
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
            if np.linalg.norm(null[3 * o : 3 * o + 3] @ (motion.T @ S)) > 0.1
        ]
        if others:
            reasons.append("it moves together with " + ", ".join(others))
        free = _describe(problem, body, S, reasons)
        free.spin_only = (
            len(free.modes) == 1
            and free.modes[0].startswith("rotation")
            and any(kinds[n] == "normal" for n in names)
        )
        found.append(free)
        # the remedies fix every free mode that moves this body: the later bodies are
        # left with the modes that do not
        null = null @ _null_space(motion)
    return found


def _describe(problem, body: _Body, S: np.ndarray, reasons: list[str]) -> FreeBody:
    """Names of the free motions ``S`` of ``body`` and point constraints removing them."""
    theta = S[2]
    turns = np.linalg.norm(theta) > 0.1
    # translations: the motions without rotation
    T = S @ _null_space(theta[None, :]) if turns else S
    modes, remedies = [], []
    pivot = body.centre
    if T.shape[1] == 2:
        modes.append("translations x, y")
        q = _node(problem, body, 0, body.centre, farthest=False)
        remedies += [(q, 0), (q, 1)]
        pivot = np.asarray(q)
    elif T.shape[1] == 1:
        d = T[:2, 0] / np.linalg.norm(T[:2, 0])
        c = int(np.argmax(np.abs(d)))
        modes.append(
            ("translation x", "translation y")[c]
            if abs(d[c]) > 0.999
            else f"translation along ({_num(d[0], 3)}, {_num(d[1], 3)})"
        )
        remedies.append((_node(problem, body, c, body.centre, farthest=False), c))
    if turns:
        v = S @ theta / np.linalg.norm(theta)  # the free motion turning most
        a, th = v[:2], v[2]
        centre = body.centre
        if T.shape[1] < 2:
            centre = body.centre + body.radius / th * np.array([-a[1], a[0]])
        modes.append(f"rotation about ({_num(centre[0], 3)}, {_num(centre[1], 3)})")
        if T.shape[1] < 2:
            pivot = centre
        q = _node(problem, body, None, pivot, farthest=True)
        arm = np.asarray(q) - pivot
        remedies.append((q, int(np.argmax(np.abs([arm[1], arm[0]])))))
    return FreeBody(body.name, modes, reasons, remedies)


def _null_space(A: np.ndarray) -> np.ndarray:
    _, s, Vt = np.linalg.svd(A)
    rank = int(np.sum(s > 0.1))
    return Vt[rank:].T


def _node(problem, body: _Body, component, point, farthest: bool) -> list[float]:
    """The node of ``body`` farthest from (or nearest to) ``point``, preferring nodes no
    other side's field uses (a point constraint fixes both sides' fields). Collective."""
    c = 0 if component is None else component
    x = body.coords[c]
    comm = problem.mesh.comm
    prefer = comm.allreduce(int(body.alone[c].sum()), op=MPI.SUM) > 0
    if prefer:
        x = x[body.alone[c]]
    best = None
    if x.shape[0]:
        dist = np.linalg.norm(x - point, axis=1)
        i = int(np.argmax(dist) if farthest else np.argmin(dist))
        best = (float(dist[i]) if farthest else -float(dist[i]), *x[i].tolist())
    candidates = [b for b in comm.allgather(best) if b is not None]
    return list(max(candidates)[1:])


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


def _bodies(problem) -> tuple[list[_Body], dict[int, np.ndarray]]:
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
    nodes = {}  # field -> (parent dof of each component of each node, node coordinates)
    for field in (0, 1):
        V, parent = space.field_space(field)
        nodes[field] = ([parent[c :: V.dofmap.bs] for c in range(2)], V.tabulate_dof_coordinates())
    where = "interface " + repr(names[0]) if len(names) == 1 else "the interfaces"
    found = []
    for p in range(nparts):
        dofs, coords, alone = [], [], []
        for c in (0, 1):  # components x, y
            parents = [nodes[f][0][c] for f in (0, 1)]
            keep = [(parent < nowned) & (part[parent] == p) for parent in parents]
            dofs.append(np.concatenate([parents[f][keep[f]] for f in (0, 1)]))
            coords.append(np.concatenate([nodes[f][1][keep[f], :2] for f in (0, 1)]))
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
        body = _Body(label, dofs, coords, alone, centre, radius)
        found.append(((not holds[p, 1], first, p), body))
    found.sort(key=lambda item: item[0])  # side +1's first, then by interface
    bodies = [body for _, body in found]
    for label in {body.name for body in bodies}:
        twins = [body for body in bodies if body.name == label]
        for body in twins if len(twins) > 1 else []:
            body.name += f", the part about ({_num(body.centre[0], 3)}, {_num(body.centre[1], 3)})"
    of_part = np.full(nparts + 1, -1)  # the body of each part, -1 (index -1 too): none
    of_part[[key[2] for key, _ in found]] = np.arange(len(found))
    return bodies, {f: of_part[pieces[f]] for f in (0, 1)}


def _volume_ratio(J: np.ndarray) -> np.ndarray:
    """``|det J|`` of Jacobians ``J``, shape ``(m, d, d)`` -> ``(m,)`` (2 x 2 written out:
    LAPACK's per-matrix call is ten times slower on many small matrices)."""
    if J.shape[1:] == (2, 2):
        return np.abs(J[:, 0, 0] * J[:, 1, 1] - J[:, 0, 1] * J[:, 1, 0])
    return np.abs(np.linalg.det(J))


def _centroid(cut, cells: dict[int, np.ndarray]) -> tuple[np.ndarray, float]:
    """Centroid (m) and radius of gyration (m) of the part of ``cells[f]`` on the side of
    field ``f`` (0: side -1, 1: side +1): uncut cells by a degree-2 rule, cut cells by
    the side's rules. Collective."""
    maps, comm = cut.maps, cut.mesh.comm
    X, W = basix.make_quadrature(cut.mesh.basix_cell(), 2)
    xs, ws = [np.zeros((0, 2))], [np.zeros(0)]
    for field, where in cells.items():
        side = 2 * field - 1
        whole = where[cut.cell_sides[where] == side]
        if whole.size:  # one rule in every uncut cell: the cell maps tabulated once
            J = maps.jacobian_lattice(whole, X)
            ws.append(np.tile(W, whole.size) * _volume_ratio(J))
            xs.append(maps.push_forward_lattice(whole, X)[:, :2])
        rules = cut.side_rules(side)
        mine = np.isin(cut.cut_cells[rules.point_rows], where)
        rows, points = cut.cut_cells[rules.point_rows[mine]].astype(np.int32), rules.points[mine]
        if rows.size:
            ws.append(rules.weights[mine] * _volume_ratio(maps.jacobian(rows, points)))
            xs.append(maps.push_forward(rows, points)[:, :2])
    x, weights = np.concatenate(xs), np.concatenate(ws)
    area = comm.allreduce(float(weights.sum()), op=MPI.SUM)
    centre = comm.allreduce(weights @ x, op=MPI.SUM) / area
    inertia = comm.allreduce(float(weights @ np.sum((x - centre) ** 2, axis=1)), op=MPI.SUM)
    return centre, float(np.sqrt(inertia / area))


def _dirichlet_gram(problem, bodies: list[_Body]) -> np.ndarray:
    """Block-diagonal Gram of each body's modes at its prescribed dofs (global)."""
    W = problem.space.W
    imap = W.dofmap.index_map
    prescribed = np.zeros((imap.size_local + imap.num_ghosts) * W.dofmap.index_map_bs, bool)
    for bc in problem.loads.bcs:
        prescribed[bc.dof_indices()[0]] = True
    G = np.zeros((3 * len(bodies), 3 * len(bodies)))
    for b, body in enumerate(bodies):
        for c in (0, 1):
            z = body.modes(body.coords[c][prescribed[body.dofs[c]]], c)
            G[3 * b : 3 * b + 3, 3 * b : 3 * b + 3] += z.T @ z
    return problem.mesh.comm.allreduce(G, op=MPI.SUM)


def _interface_gram(
    problem, bodies: list[_Body], pieces: dict[int, np.ndarray], name: str, kind: str
) -> tuple[np.ndarray, set[int]]:
    """Gram (global, per unit length) of the jump of the bodies' modes across interface
    ``name`` (at each rule point, from the body of field 0 of its cell to that of field
    1): the whole jump, its normal part or nothing (``kind``); and the bodies along it."""
    cut, comm = problem.cut, problem.mesh.comm
    rules = cut.interface_rules_of(name)
    cells = cut.cut_cells[rules.point_rows]
    minus, plus = pieces[0][cells], pieces[1][cells]
    touched = {int(b) for mine in comm.allgather(np.unique(np.r_[minus, plus])) for b in mine}
    touched.discard(-1)
    nb = len(bodies)
    if kind == "none":
        return np.zeros((3 * nb, 3 * nb)), touched
    x = interface_points(cut, rules)[:, :2]
    n = cut.normal_at(rules)[:, :2]
    J = cut.maps.jacobian(cells, rules.points)
    w = rules.weights * np.abs(np.linalg.det(J))
    jump = np.zeros((x.shape[0], 2, 3 * nb))  # per point, component, coefficient
    for bs, sign in ((minus, -1.0), (plus, 1.0)):
        for b in np.unique(bs[bs >= 0]):
            at = bs == b
            for c in (0, 1):
                jump[at, c, 3 * b : 3 * b + 3] += sign * bodies[b].modes(x[at], c)
    jump[(minus == plus) | (minus < 0) | (plus < 0)] = 0.0  # one body, or a side without
    if kind == "normal":
        jump = np.einsum("pc,pcm->pm", n, jump)[:, None, :]
    G = comm.allreduce(np.einsum("p,pcm,pcl->ml", w, jump, jump), op=MPI.SUM)
    return G / comm.allreduce(float(w.sum()), op=MPI.SUM), touched
