"""The inverse estimate of a side's stress on its interface piece, per cut cell.

For a displacement of degree ``k`` the strains of a cut cell's side ``T_s`` lie in a
polynomial space ``S`` (reference coordinates): ``P_(k-1)`` on simplices, ``Q_k``
without its top monomial on quadrilaterals and hexahedra (the span of the partial
derivatives of ``Q_k``). The *trace length* of the side is

    l_s = min over p in S of  int_(T_s) p^2 dx / int_(Gamma_T) p^2 ds   (m),

so that ``int_(Gamma_T) p^2 ds <= int_(T_s) p^2 dx / l_s`` for every ``p`` in ``S``: the
least eigenvalue of the pencil of the two mass matrices, from the cut's rules. For
``k = 1`` on simplices it is ``|T_s| / |Gamma_T|`` exactly; it tends to 0 with the side's
share of the cell. Exact on affine cells; on others (whose strains are not polynomials
in reference coordinates) an estimate.
"""

from __future__ import annotations

import itertools
import math
import typing

import basix
import dolfinx.la
import dolfinx.mesh
import numpy as np
import numpy.typing as npt

from xfem_contact.fem.cut_state import SIDE_MINUS, SIDE_PLUS

if typing.TYPE_CHECKING:
    from xfem_contact.fem.cutmesh import CutMesh
    from xfem_contact.quadrature.rules import RuleSet

#: Cell kinds whose strain space is ``P_(k-1)`` (else ``Q_k`` without its top monomial)
SIMPLICES = ("triangle", "tetrahedron")
#: Eigenvalues of a side's mass matrix below this share of its largest are raised to
#: it (a degenerate side: a tiny trace length, never a division by zero)
REGULARIZATION = 1e-10
#: Points per chunk of the per-cell mass matrices (bounds the memory of the monomials'
#: values: ``POINTS`` times the number of distinct products of two monomials of ``S``)
POINTS = 20_000
#: A cut cell borrows from a cut facet neighbour whose own trace length is more than
#: this many times its own (:func:`patch_trace_lengths`)
BORROW_RATIO = 2.0


def strain_exponents(cell_name: str, degree: int, tdim: int) -> npt.NDArray[np.int64]:
    """Exponents of the monomials spanning the strains of a displacement of ``degree``
    on ``cell_name`` cells, shape ``(dim S, tdim)``."""
    if degree < 1:
        raise ValueError(f"degree must be at least 1, got {degree!r}")
    powers = np.array(list(itertools.product(range(degree + 1), repeat=tdim)), dtype=np.int64)
    if cell_name in SIMPLICES:
        return powers[powers.sum(axis=1) <= degree - 1]
    return powers[(powers <= degree - 1).any(axis=1)]


def trace_lengths(
    cell_name: str,
    degree: int,
    side: RuleSet,
    side_det: npt.NDArray[np.float64],
    interface: RuleSet,
    interface_det: npt.NDArray[np.float64],
) -> npt.NDArray[np.float64]:
    """The trace length ``l_s`` (m) of one side of every cut cell (see the module).

    Args:
        cell_name: The cells' kind (``"triangle"``, ``"quadrilateral"``, ...).
        degree: The displacement's degree ``k``.
        side: The side's rules (rows: cut cells; reference points and weights).
        side_det: ``|det J|`` at the side's points, shape ``(npoints,)``.
        interface: The interface rules (the same rows; weights ``ds / |det J|``).
        interface_det: ``|det J|`` at the interface points.

    Returns:
        Per row, shape ``(nrows,)``: ``l_s``; 0 where the side is empty, ``inf``
        where the interface is. Local, pure.
    """
    tdim = side.points.shape[1]
    exponents = strain_exponents(cell_name, degree, tdim)
    nrows = side.num_rules
    w_side = side.weights * side_det
    # monomials about each side's centroid, per axis scaled by its spread
    mass = np.maximum(side.sums(w_side), np.finfo(float).tiny)
    rows = side.point_rows
    centre = np.stack([side.sums(w_side * side.points[:, i]) for i in range(tdim)], 1)
    centre /= mass[:, None]
    spread = np.stack(
        [side.sums(w_side * (side.points[:, i] - centre[rows, i]) ** 2) for i in range(tdim)], 1
    )
    spread = np.sqrt(np.maximum(spread / mass[:, None], 1e-24))

    def masses(rules: RuleSet, weights: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
        r = rules.point_rows
        X = (rules.points - centre[r]) / spread[r]
        return _cell_masses(rules, X, weights, exponents)

    M_side = masses(side, w_side)
    M_gamma = masses(interface, interface.weights * interface_det)
    lengths = np.zeros(nrows)
    present = (side.sums(w_side) > 0) & (interface.sums(interface.weights) > 0)
    Ms, Mg = M_side[present], M_gamma[present]
    d, Q = np.linalg.eigh(Ms)
    d = np.maximum(d, REGULARIZATION * d[:, -1:])
    T = Q / np.sqrt(d)[:, None, :]  # Ms^(-1/2) in its eigenbasis
    largest = np.linalg.eigvalsh(np.swapaxes(T, 1, 2) @ Mg @ T)[:, -1]
    lengths[present] = 1.0 / largest
    lengths[interface.sums(interface.weights) == 0] = np.inf
    return lengths


def _cell_masses(
    rules: RuleSet,
    X: npt.NDArray[np.float64],
    weights: npt.NDArray[np.float64],
    exponents: npt.NDArray[np.int64],
) -> npt.NDArray[np.float64]:
    """Per rule, the mass matrix ``sum_q w_q phi_i(X_q) phi_j(X_q)`` of the monomials
    ``phi_i = X^exponents[i]``, shape ``(nrows, m, m)``, from the moments of the
    distinct products ``X^(e_i + e_j)``, :data:`POINTS` points at a time."""
    m, tdim = exponents.shape
    sums = (exponents[:, None, :] + exponents[None, :, :]).reshape(-1, tdim)
    products, entry = np.unique(sums, axis=0, return_inverse=True)
    moments = np.zeros((rules.num_rules, len(products)))
    rows = rules.point_rows
    top = int(products.max(initial=0))
    for start in range(0, rows.size, POINTS):
        part = slice(start, start + POINTS)
        x, r = X[part].T, rows[part]
        powers = [np.ones_like(x), np.ascontiguousarray(x)]  # x^e, (tdim, npoints)
        for _ in range(2, top + 1):
            powers.append(powers[-1] * powers[1])
        values = np.empty((len(products), x.shape[1]))
        for k, exponent in enumerate(products):
            values[k] = weights[part]
            for axis, e in enumerate(exponent):
                if e:
                    values[k] *= powers[e][axis]
        # the points of a rule are consecutive: sum each run of equal rows
        first = np.flatnonzero(np.r_[True, r[1:] != r[:-1]])
        if first.size:
            moments[r[first]] += np.add.reduceat(values, first, axis=1).T
    return moments[:, entry.ravel()].reshape(-1, m, m)


def side_trace_lengths(cut: CutMesh, name: str | None, degree: int) -> dict[int, np.ndarray]:
    """``{-1: l_-, 1: l_+}`` (m) of the cut cells of interface ``name`` (rows of
    ``cut.cut_cells``; 0 on the cells of other interfaces) for a displacement of
    ``degree`` (see the module). Local."""
    interface = cut.interface_rules_of(name)
    cell_name = cut.mesh.topology.cell_name()
    interface_det = _rule_dets(cut, interface)
    out = {}
    for s, slot in ((-1, SIDE_MINUS), (1, SIDE_PLUS)):
        side = cut.rules[slot]
        dets = _rule_dets(cut, side)
        lengths = trace_lengths(cell_name, degree, side, dets, interface, interface_det)
        out[s] = np.where(np.isfinite(lengths), lengths, 0.0)
    return out


def patch_trace_lengths(
    cut: CutMesh,
    name: str | None,
    degree: int,
    ghost: dict[int, float],
    h: npt.NDArray[np.float64],
    higher: float = 1.0,
) -> dict[int, np.ndarray]:
    """``{-1: l_-, 1: l_+}`` (m) of the cut cells of interface ``name`` (rows of
    ``cut.cut_cells``, 0 on other interfaces' cells), each side's trace length
    credited with its facet neighbours' control through the ghost penalty (the
    docs' stability page derives the bound):

        int_(Gamma_T) p^2 ds <= (kappa_T int_(T_s) p^2 dx + sum_K [theta int_(K_s) q_K^2 dx
                                 + eta sum_(j<k) c_j h^(2j+1) int_F |grad^j (p - q_K)|^2]) / l_s

    for ``p`` in the strain space ``S`` on ``T`` and any ``q_K`` in ``S`` on ``K``. A
    cut cell ``T`` borrows from a facet neighbour ``K`` that is not cut (entirely on
    side ``s``) or whose own trace length is more than :data:`BORROW_RATIO` times
    ``T``'s; a lender keeps the share ``kappa_K = 1 - theta b_K`` of its own side
    (``b_K`` its borrowers, ``theta = 1 / (2 n_f)``, ``n_f`` a cell's facets).

    Args:
        cut: The cut mesh (affine cells: simplices of degree-1 geometry, or
            axis-aligned quadrilaterals and hexahedra; elsewhere no borrowing).
        name: The interface (None: all).
        degree: The displacement's degree ``k``.
        ghost: Per side, ``eta_s = g 2 mu_s / (2 mu_s + d lambda_s)`` (``g`` the ghost
            penalty's weight; 0 without it).
        h: Cell diameters of the ghost penalty's ``h`` (m), per local cell (ghosts
            included).
        higher: ``c_j`` for ``j >= 1`` (``c_0 = 1``): the ghost penalty's factor of
            the jumps of second and higher derivatives of the displacement.

    Collective (the neighbours' masses are scattered to the ghost cells).
    """
    mesh = cut.mesh
    tdim = mesh.topology.dim
    cell_name = mesh.topology.cell_name()
    exponents = strain_exponents(cell_name, degree, tdim)
    m = exponents.shape[0]
    own = side_trace_lengths(cut, name, degree)
    cells = cut.cut_cells
    interface = cut.interface_rules_of(name)
    carries = interface.sums(interface.weights) > 0
    imap = mesh.topology.index_map(tdim)
    nlocal = imap.size_local + imap.num_ghosts
    centres = _cell_centres(mesh, nlocal)
    affine = _affine_cells(cut, nlocal)

    # the sides' masses of the cut cells in their own bases, and their own lengths
    bs = 2 * m * m + 2
    shared = dolfinx.la.vector(imap, bs)
    data = shared.array.reshape(-1, bs)
    for k, (s, slot) in enumerate(((-1, SIDE_MINUS), (1, SIDE_PLUS))):
        M = _own_basis_masses(cut, cut.rules[slot], centres, h, exponents)
        data[cells[carries], k * m * m : (k + 1) * m * m] = M[carries].reshape(-1, m * m)
        data[cells[carries], 2 * m * m + k] = own[s][carries]
    shared.scatter_forward()
    M_gamma = _own_basis_masses(cut, interface, centres, h, exponents)

    side_of = cut.side_indicator().x.array
    mesh.topology.create_connectivity(tdim, tdim - 1)
    mesh.topology.create_connectivity(tdim - 1, tdim)
    c2f = mesh.topology.connectivity(tdim, tdim - 1)
    f2c = mesh.topology.connectivity(tdim - 1, tdim)
    theta = 1.0 / (2 * c2f.links(0).size)
    # the facet neighbours of the carrying cut cells (both affine)
    pairs = []  # (row, T, F, K)
    for row in np.flatnonzero(carries):
        T = cells[row]
        for F in c2f.links(T) if affine[T] else ():
            link = f2c.links(F)
            K = link[0] if link[-1] == T else link[-1]
            if link.size == 2 and affine[K]:
                pairs.append((row, T, F, K))
    uncut = np.unique([K for *_, K in pairs if side_of[K] != 0]).astype(np.int32)
    masses = _full_cell_masses(cut, degree, uncut, centres, h, exponents)
    full = dict(zip(uncut, masses, strict=True))
    facet_rule = _facet_rule(mesh, degree)
    jumps, bases = {}, {}  # per (T, F) and (T, K), shared by the sides

    out = {s: own[s].copy() for s in (-1, 1)}
    for k, s in enumerate((-1, 1)):
        length = data[:, 2 * m * m + k]
        A = {row: data[cells[row], k * m * m : (k + 1) * m * m].reshape(m, m) for row, *_ in pairs}
        lent = dict.fromkeys(A, False)
        borrowers = dict.fromkeys(A, 0)
        for row, T, F, K in pairs:
            if length[T] <= 0:
                continue
            if side_of[K] == s:
                M_K = full[K]
            elif length[K] > BORROW_RATIO * length[T]:
                M_K = data[K, k * m * m : (k + 1) * m * m].reshape(m, m)
            else:
                borrowers[row] += 0 < length[K] and BORROW_RATIO * length[K] < length[T]
                continue
            if (T, K) not in bases:
                bases[T, K] = _basis_change(exponents, centres, h, T, K)
                h_facet = 0.5 * (h[T] + h[K])  # the ghost penalty's avg(h)
                jumps[T, F] = _jump_mass(
                    mesh, F, facet_rule, degree, exponents, centres[T], h[T], h_facet, higher
                )
            M_K = bases[T, K].T @ M_K @ bases[T, K]
            G = ghost[s] * jumps[T, F]
            # min over q_K of theta |q_K|^2_(K_s) + |p - q_K|^2_G: a Schur complement
            A[row] = (
                A[row] + G - G @ np.linalg.pinv(theta * M_K + G, rcond=1e-13, hermitian=True) @ G
            )
            lent[row] = True
        for row in A:
            if length[cells[row]] <= 0 or not (lent[row] or borrowers[row]):
                continue
            # A[row] holds the own mass once: the borrowers' shares come off it
            M_own = data[cells[row], k * m * m : (k + 1) * m * m].reshape(m, m)
            matrix = A[row] - theta * borrowers[row] * M_own
            out[s][row] = _least_ratio(matrix, M_gamma[row])
    return out


def _cell_centres(mesh: dolfinx.mesh.Mesh, nlocal: int) -> npt.NDArray[np.float64]:
    """The mean of each local cell's vertices, shape ``(nlocal, tdim)``."""
    tdim = mesh.topology.dim
    nodes = dolfinx.mesh.entities_to_geometry(mesh, tdim, np.arange(nlocal, dtype=np.int32))
    return mesh.geometry.x[nodes].mean(axis=1)[:, :tdim]


def _abs_det(cut: CutMesh, cells: npt.NDArray[np.int32], X: npt.NDArray[np.float64]):
    return np.abs(np.linalg.det(cut.maps.jacobian(cells, X)))


def _affine_cells(cut: CutMesh, nlocal: int) -> npt.NDArray[np.bool_]:
    """Whether each local cell's map is affine and maps the strain space of the
    reference cell onto the same monomials of the physical coordinates: every simplex
    of degree-1 geometry; a quadrilateral or hexahedron whose Jacobian is one diagonal
    matrix up to a permutation of
    its columns (an axis-aligned box)."""
    mesh = cut.mesh
    if mesh.topology.cell_name() in SIMPLICES and cut.maps.coordinate_element.degree == 1:
        return np.ones(nlocal, dtype=bool)
    tdim = mesh.topology.dim
    X = basix.geometry(cut.maps.coordinate_element.cell_type)
    cells = np.repeat(np.arange(nlocal, dtype=np.int32), X.shape[0])
    J = cut.maps.jacobian(cells, np.tile(X, (nlocal, 1)))[:, :tdim, :tdim]
    J = J.reshape(nlocal, -1, tdim, tdim)
    scale = np.abs(J).max(axis=(1, 2, 3))
    constant = np.abs(J - J[:, :1]).max(axis=(1, 2, 3)) <= 1e-10 * scale
    nonzero = np.abs(J[:, 0]) > 1e-10 * scale[:, None, None]
    one_a_row = (nonzero.sum(axis=1) == 1).all(axis=1) & (nonzero.sum(axis=2) == 1).all(axis=1)
    return constant & one_a_row


def _monomials(exponents, Y, derivative=None, h=1.0):
    """Values of ``phi_e(Y) = Y^e`` (or of their derivative ``d^alpha / dx^alpha`` for
    ``x = h Y``), shape ``(m, npoints)``."""
    m, tdim = exponents.shape
    alpha = np.zeros(tdim, dtype=np.int64) if derivative is None else derivative
    top = int(exponents.max(initial=0))
    out = np.ones((m, Y.shape[0]))
    for axis in range(tdim):
        powers = np.cumprod(np.vstack([np.ones(Y.shape[0]), np.tile(Y[:, axis], (top, 1))]), 0)
        e, a = exponents[:, axis], int(alpha[axis])
        factor = np.ones(m)
        for i in range(a):  # the falling factorial e (e - 1) ... (e - a + 1)
            factor *= e - i
        out *= (factor / h**a)[:, None] * powers[np.maximum(e - a, 0)]
    return out


def _basis_change(exponents, centres, h, T, K) -> npt.NDArray[np.float64]:
    """``B^T`` with ``phi^T = B phi^K`` (the monomials about ``T``'s centre and scale
    in those about ``K``'s): a mass matrix ``M`` in ``K``'s basis is ``B M B^T`` in
    ``T``'s."""
    m, tdim = exponents.shape
    rng = np.random.default_rng(0)
    x = centres[K] + h[K] * rng.uniform(-1.0, 1.0, (4 * m, tdim))
    phi_T = _monomials(exponents, (x - centres[T]) / h[T])
    phi_K = _monomials(exponents, (x - centres[K]) / h[K])
    return np.linalg.lstsq(phi_K.T, phi_T.T, rcond=None)[0]


def _rule_dets(cut: CutMesh, rules: RuleSet) -> npt.NDArray[np.float64]:
    """``|det J|`` at the points of ``rules`` (rows of ``cut.cut_cells``); one Jacobian a
    cell on affine simplices."""
    cells = cut.cut_cells
    if cut.maps.coordinate_element.degree == 1 and cut.mesh.topology.cell_name() in SIMPLICES:
        origin = np.zeros((cells.size, cut.mesh.topology.dim))
        return np.abs(np.linalg.det(cut.maps.jacobian(cells, origin)))[rules.point_rows]
    return _abs_det(cut, cells[rules.point_rows], rules.points)


def _own_basis_masses(cut: CutMesh, rules: RuleSet, centres, h, exponents) -> np.ndarray:
    """Per rule (rows of ``cut.cut_cells``) the mass matrix of the monomials about its
    cell's centre scaled by its ``h``, shape ``(nrows, m, m)``."""
    tdim = exponents.shape[1]
    cells = cut.cut_cells[rules.point_rows]
    x = cut.maps.push_forward(cells, rules.points)[:, :tdim]
    weights = rules.weights * _rule_dets(cut, rules)
    return _cell_masses(rules, (x - centres[cells]) / h[cells, None], weights, exponents)


def _full_cell_masses(cut: CutMesh, degree: int, cells, centres, h, exponents) -> np.ndarray:
    """The mass matrices of the monomials about each of ``cells``' centres over the
    whole cell, shape ``(len(cells), m, m)``."""
    mesh = cut.mesh
    tdim = mesh.topology.dim
    cell = getattr(basix.CellType, mesh.topology.cell_type.name)
    X, w = basix.make_quadrature(cell, 2 * degree * tdim)
    out = np.empty((len(cells), exponents.shape[0], exponents.shape[0]))
    chunk = max(1, POINTS // X.shape[0])
    for start in range(0, len(cells), chunk):
        part = cells[start : start + chunk]
        x = cut.maps.push_forward_lattice(part, X)[:, :tdim].reshape(len(part), -1, tdim)
        J = cut.maps.jacobian_lattice(part, X)[:, :tdim, :tdim]
        dx = (w * np.abs(np.linalg.det(J)).reshape(len(part), -1)).ravel()
        Y = ((x - centres[part, None]) / h[part, None, None]).reshape(-1, tdim)
        phi = _monomials(exponents, Y).reshape(exponents.shape[0], len(part), -1)
        weighted = phi * dx.reshape(len(part), -1)[None]
        out[start : start + len(part)] = np.einsum("icq,jcq->cij", weighted, phi)
    return out


def _facet_rule(mesh: dolfinx.mesh.Mesh, degree: int):
    """A Gauss rule on the reference facet exact for the products of the strain
    monomials' derivatives restricted to a facet."""
    tdim = mesh.topology.dim
    cell = getattr(basix.CellType, mesh.topology.cell_type.name)
    facet = basix.cell.sub_entity_type(cell, tdim - 1, 0)
    return basix.make_quadrature(facet, 2 * degree * (tdim - 1))


def _jump_mass(
    mesh, F, rule, degree, exponents, centre, h_cell, h_facet, higher=1.0
) -> npt.NDArray[np.float64]:
    """``sum_(j<k) c_j h_facet^(2j+1) int_F grad^j phi . grad^j phi^T ds`` for the
    monomials about ``centre`` scaled by ``h_cell`` (``k`` the displacement's
    ``degree``: the ghost penalty jumps ``grad^(j+1) u``; ``c_0 = 1``, ``c_j =
    higher`` for ``j >= 1``), shape ``(m, m)``."""
    tdim = mesh.topology.dim
    X, w = rule
    nodes = dolfinx.mesh.entities_to_geometry(mesh, tdim - 1, np.array([F], dtype=np.int32))[0]
    v = mesh.geometry.x[nodes][:, :tdim]
    axes = np.stack([v[1] - v[0]] + ([v[2] - v[0]] if tdim == 3 else []), 1)  # (tdim, tdim-1)
    measure = np.sqrt(np.linalg.det(axes.T @ axes))
    Y = (v[0] + X @ axes.T - centre) / h_cell
    m = exponents.shape[0]
    G = np.zeros((m, m))
    for j in range(degree):
        for alpha in itertools.product(range(j + 1), repeat=tdim):
            alpha = np.array(alpha)
            if alpha.sum() != j:
                continue
            # |grad^j q|^2 = sum over |alpha| = j of j! / alpha! (d^alpha q)^2
            multiplicity = math.factorial(j) / np.prod([math.factorial(a) for a in alpha])
            d = _monomials(exponents, Y, alpha, h_cell)
            weight = 1.0 if j == 0 else higher
            G += weight * h_facet ** (2 * j + 1) * multiplicity * (d * (w * measure)) @ d.T
    return G


def _least_ratio(A: npt.NDArray[np.float64], B: npt.NDArray[np.float64]) -> float:
    """``min_p p^T A p / p^T B p`` (``A`` positive definite up to :data:`REGULARIZATION`)."""
    d, Q = np.linalg.eigh(A)
    d = np.maximum(d, REGULARIZATION * d[-1])
    T = Q / np.sqrt(d)[None, :]
    return float(1.0 / np.linalg.eigvalsh(T.T @ B @ T)[-1])
