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
import typing

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
    cells = cut.cut_cells

    cell_name = cut.mesh.topology.cell_name()
    if cut.maps.coordinate_element.degree == 1 and cell_name in SIMPLICES:
        # affine cells: one Jacobian a cell
        origin = np.zeros((cells.size, cut.mesh.topology.dim))
        per_cell = np.abs(np.linalg.det(cut.maps.jacobian(cells, origin)))

        def det(rules: RuleSet) -> npt.NDArray[np.float64]:
            return per_cell[rules.point_rows]

    else:

        def det(rules: RuleSet) -> npt.NDArray[np.float64]:
            J = cut.maps.jacobian(cells[rules.point_rows], rules.points)
            return np.abs(np.linalg.det(J))

    interface_det = det(interface)
    out = {}
    for s, slot in ((-1, SIDE_MINUS), (1, SIDE_PLUS)):
        side = cut.rules[slot]
        lengths = trace_lengths(cell_name, degree, side, det(side), interface, interface_det)
        out[s] = np.where(np.isfinite(lengths), lengths, 0.0)
    return out
