"""Cell aggregation bounds the conditioning by construction.

Measured (case 2, sticking, 8 x 8 Q2 cells, no ghost penalty, the circle's leftmost
point a fraction f of a cell from the mesh line x = 1/4): condition number of the scaled
reduced Jacobian with ``aggregation=0.25`` 1.3e4 at f = 1e-6, 1e-9 and -1e-9 (0.09x the
generic cut's), pressure error 4.35e-3 (4.15e-3 at 1e-9, where the tiny pieces follow
the cells' edges: 2.7e-2 if their multipliers were extended from a root); without
aggregation 7.9e17 at f = 1e-6.
The extension from the root cells reproduces polynomials of the element's degree
exactly (to 1e-12), so aggregation keeps the approximation order.
"""

import xfem_contact  # noqa: F401  (before dolfinx)

# isort: split
import numpy as np
import pytest
from mpi4py import MPI

from xfem_contact.cases.paper import inclusion_errors, inclusion_problem

N = 8
FRACTIONS = [1e-6, 1e-9, -1e-9]
THRESHOLD = 0.25
#: Condition numbers stay within this multiple of the generic cut's
CONDITION_FACTOR = 10.0
#: Errors stay within this multiple of the generic cut's
ERROR_FACTOR = 2.0


def condition(problem) -> float:
    """2-norm condition number (SVD) of the last factored Jacobian (serial)."""
    J = problem.newton.J_r.convert("dense").getDenseArray()
    s = np.linalg.svd(J, compute_uv=False)
    return float(s[0] / s[-1])


def circle(fraction):
    """Case 2's circle with its leftmost point ``fraction`` of a cell left of x = 1/4."""
    radius = 0.25 + fraction / N
    return lambda x: np.hypot(x[0] - 0.5, x[1] - 0.5) - radius


def aggregated_problem(aggregation=THRESHOLD):
    """Case 2 (sticking, Q2, no ghost penalty) at the generic cut."""
    return inclusion_problem(
        N, 2, "sticking", radius=0.25 + 0.5 / N, ghost_penalty=0.0, aggregation=aggregation
    )


@pytest.mark.serial
def test_aggregation_bounds_the_condition_without_ghost_penalty():
    problem = aggregated_problem()
    assert problem.solve().iterations <= 30
    cond0, err0 = condition(problem), inclusion_errors(problem, problem.w).pressure
    for f in FRACTIONS:
        problem.update_interface(circle(f))
        report = problem.solve()
        cond, err = condition(problem), inclusion_errors(problem, problem.w).pressure
        print(f"f {f:+.0e}: condition {cond:.2e} ({cond / cond0:.2f} x), error {err:.2e}")
        assert report.iterations <= 30
        assert cond <= CONDITION_FACTOR * cond0, (f, cond, cond0)
        assert err <= ERROR_FACTOR * err0, (f, err, err0)


def _polynomial_at_dofs(space, polynomial) -> np.ndarray:
    """``polynomial(d)`` (of degree ``d``: vector-valued of x, y) at the node and
    component of every local dof of the displacement and multiplier fields of
    ``space.W``, ``d`` each field's degree (NaN elsewhere)."""
    values = np.full(space.active.size, np.nan)
    fields = [(0, space.degree), (1, space.degree)]
    fields += [(f, space.multiplier_degrees[f]) for f, _, _ in space.multiplier_fields]
    for field, degree in fields:
        V, parent = space.field_space(field)
        x = V.tabulate_dof_coordinates()
        bs = V.dofmap.index_map_bs
        k = np.arange(parent.size)
        p = polynomial(degree)(x[k // bs, 0], x[k // bs, 1])
        values[parent] = p[k % bs, np.arange(k.size)]
    return values


@pytest.mark.mpi
@pytest.mark.parametrize("cell", ["quadrilateral", "triangle"])
@pytest.mark.parametrize("degree", [1, 2])
def test_extension_reproduces_polynomials(cell, degree):
    """Each constrained dof (displacements and the multiplier) is the root's polynomial
    at its node: for a polynomial of the field's degree (complete on triangles,
    parallelogram maps on the quads) the rows reproduce it exactly."""
    problem = inclusion_problem(
        N, degree, "bonded", cell, radius=0.25 + 1e-6 / N, aggregation=THRESHOLD
    )
    space = problem.space
    aggregation = space.aggregation
    comm = problem.mesh.comm
    assert comm.allreduce(aggregation.dofs.size, op=MPI.SUM) > 0

    def polynomial(d):
        def p(x, y):
            linear = [1 + 2 * x - y, 0.5 - x + 4 * y]
            if d == 1:
                return np.stack(linear)
            return np.stack([linear[0] + 3 * x**2 + x * y, linear[1] - 2 * x * y + 4 * y**2])

        return p

    values = _polynomial_at_dofs(space, polynomial)
    imap = space.W.dofmap.index_map
    # the sources' values from their owners
    wanted = np.unique(aggregation.sources)
    owned_values = values[: imap.size_local]
    gathered = comm.allgather((imap.local_range[0], owned_values))
    source_values = np.empty(wanted.size)
    for start, v in gathered:
        here = (wanted >= start) & (wanted < start + v.size)
        source_values[here] = v[wanted[here] - start]
    at_sources = source_values[np.searchsorted(wanted, aggregation.sources)]
    extended = np.bincount(
        aggregation.rows, weights=aggregation.vals * at_sources, minlength=aggregation.dofs.size
    )
    assert np.allclose(extended, values[aggregation.dofs], rtol=0.0, atol=1e-12)


@pytest.mark.mpi
@pytest.mark.parallel
def test_aggregation_is_the_same_on_one_and_two_ranks():
    """The constrained dofs (their count) and the solution's pressure error of case 2
    (Q2, tiny cut, no ghost penalty) agree between one process and all of them."""

    def run(comm):
        problem = inclusion_problem(
            N,
            2,
            "sticking",
            radius=0.25 + 1e-6 / N,
            comm=comm,
            ghost_penalty=0.0,
            aggregation=THRESHOLD,
        )
        problem.solve()
        count = comm.allreduce(problem.space.aggregation.dofs.size, op=MPI.SUM)
        return count, inclusion_errors(problem, problem.w).pressure

    count, error = run(MPI.COMM_WORLD)
    count_self, error_self = run(MPI.COMM_SELF)
    assert count == count_self
    assert abs(error - error_self) <= 1e-8 * error_self


def _bench():
    """``bench/aggregation.py`` (its problems and condition number), imported by path."""
    import importlib.util
    import pathlib

    path = pathlib.Path(__file__).resolve().parents[2] / "bench" / "aggregation.py"
    spec = importlib.util.spec_from_file_location("bench_aggregation", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.serial
def test_a_badly_cut_multiplier_is_aggregated():
    """A bonded circle (Q2, 16 x 16, no ghost penalty) clipping a cell's corner far from
    the multiplier's vertices: without the multiplier's aggregation its vertex
    multiplier made the scaled matrix's smallest eigenvalue (C = cond h^2 = 2.2e4,
    25 times the median of random circles)."""
    import dolfinx.mesh

    bench = _bench()
    n = 16
    mesh = dolfinx.mesh.create_unit_square(MPI.COMM_SELF, n, n, dolfinx.mesh.CellType.quadrilateral)
    generic = bench.bonded_circle(mesh, (0.5, 0.5), 0.2, 2, 0.0, THRESHOLD)
    C0 = bench.scaled_condition(generic) / n**2
    corner = bench.bonded_circle(mesh, (0.6461708, 0.5177562), 0.1690252, 2, 0.0, THRESHOLD)
    C = bench.scaled_condition(corner) / n**2
    print(f"C = cond h^2: {C:.3e}, generic circle {C0:.3e}")
    assert C <= CONDITION_FACTOR * C0, (C, C0)


@pytest.mark.serial
def test_a_prescribed_dof_is_never_a_source():
    """A crack (P1 triangles, 8 x 8, clamped boundary) whose badly cut cells' roots hold
    Dirichlet dofs: a constrained dof reading them would turn their identity rows into
    combinations (C = cond h^2 2.0e5 against 266 without aggregation)."""
    import dolfinx.mesh

    bench = _bench()
    n = 8
    mesh = dolfinx.mesh.create_unit_square(MPI.COMM_SELF, n, n, dolfinx.mesh.CellType.triangle)
    tip, angle = GENERIC_CRACK
    C = {}
    for threshold in (None, THRESHOLD):
        problem = bench.free_crack(mesh, tip, angle, 1, 0.0, threshold)
        C[threshold] = bench.scaled_condition(problem) / n**2
    print(f"C = cond h^2: {C[THRESHOLD]:.3e} with aggregation, {C[None]:.3e} without")
    assert C[THRESHOLD] <= CONDITION_FACTOR * C[None], C


#: A generic crack of the unit square (tip, angle in rad)
GENERIC_CRACK = ((0.36690109962184747, 0.6252202990915117), 1.3661707578174123)


def sliver_and_generic_conditions(cell: str, sliver) -> dict[str, float]:
    """``C = cond h^2`` of the scaled matrix of a free P2 crack on an 8 x 8 unit square of
    ``cell``s with aggregation, for the crack ``sliver`` (tip, angle) and for
    :data:`GENERIC_CRACK` (keys ``"sliver"``, ``"generic"``)."""
    import dolfinx.mesh

    bench = _bench()
    n = 8
    mesh = dolfinx.mesh.create_unit_square(MPI.COMM_SELF, n, n, dolfinx.mesh.CellType[cell])
    C = {}
    for name, (tip, angle) in {"generic": GENERIC_CRACK, "sliver": sliver}.items():
        problem = bench.free_crack(mesh, tip, angle, 2, 0.0, THRESHOLD)
        C[name] = bench.scaled_condition(problem) / n**2
    print(f"C = cond h^2: {C['sliver']:.3e} at the sliver, {C['generic']:.3e} generic")
    return C


@pytest.mark.serial
@pytest.mark.parametrize("cell", ["triangle", "quadrilateral"])
def test_a_sliver_next_to_a_crack_tip_is_aggregated(cell):
    """A crack (P2, 8 x 8, clamped boundary) passing 1e-5 m from a node 1.5 cells behind
    its tip: the slivers of the crossed cells next to the tip cell (cells holding tied
    dofs) left one side's untied dofs with nothing else in their support. With those
    cells badly cut, C = cond h^2 is 36 (triangles) and 1.2e3 (quadrilaterals), against
    3.1e2 and 1.5e4 for a generic crack; when they could not be, 1.9e8 and 1.5e15."""
    C = sliver_and_generic_conditions(
        cell, ((0.4814421159654495, 0.43063914096601846), 1.6732139876157714)
    )
    assert C["sliver"] <= CONDITION_FACTOR * C["generic"], C


@pytest.mark.mpi
def test_a_crack_is_aggregated_the_same_on_one_and_two_ranks():
    """The constrained dofs of the sliver crack above (P2 triangles), each by its field
    and node, and the scaled matrix's size agree between one process and all of them."""
    import dolfinx.mesh

    bench = _bench()
    tip, angle = (0.4814421159654495, 0.43063914096601846), 1.6732139876157714

    def constrained(comm):
        mesh = dolfinx.mesh.create_unit_square(comm, 8, 8, dolfinx.mesh.CellType.triangle)
        space = bench.free_crack(mesh, tip, angle, 2, 0.0, THRESHOLD).space
        rows = []
        for field in (0, 1):
            V, parent = space.field_space(field)
            bs = V.dofmap.index_map_bs
            x = np.repeat(V.tabulate_dof_coordinates()[:, :2], bs, axis=0)
            where = np.flatnonzero(np.isin(parent, space.aggregation.dofs))
            rows += [(field, where[k] % bs, *np.round(x[where[k]], 12)) for k in range(where.size)]
        return sorted(r for part in comm.allgather(rows) for r in part)

    everywhere, alone = constrained(MPI.COMM_WORLD), constrained(MPI.COMM_SELF)
    assert len(alone) > 0
    assert everywhere == alone


def _rigid_motion(x):
    """A small rigid motion (m): zero strain, so free crack lips carry no traction."""
    return np.stack([1e-3 - 2e-3 * x[1], -5e-4 + 2e-3 * x[0]])


#: A crack of the unit square whose badly cut boundary cells' roots hold the clamped
#: edge's Dirichlet dofs (the worst P2 sample of 250 at n = 8: C = 3.1e7 while those
#: dofs stayed unknowns)
BOUNDARY_SLIVER = ((0.6634857837558401, 0.33158051795101273), 1.3866863116139594)


@pytest.mark.mpi
@pytest.mark.parametrize(
    "cell, degree, law", [("triangle", 2, "free"), ("triangle", 2, "frictionless")]
)
def test_aggregation_carries_the_dirichlet_values(cell, degree, law):
    """A dof extended from a root holding Dirichlet dofs takes their prescribed values
    (``x = E g + R y``): a rigid motion prescribed on the boundary of the cracked square
    is the exact solution (linear solve with free lips; Newton with contact), reproduced
    to round-off by both sides' fields, and the Dirichlet values are imposed exactly.
    Without the offset ``E g`` the side fields miss it by 2.5e-4 m."""
    import dolfinx.mesh

    from xfem_contact import Material, Problem
    from xfem_contact.fem.cutmesh import CutMesh
    from xfem_contact.mechanics.solving import prescribed_extension

    bench = _bench()
    comm = MPI.COMM_WORLD
    mesh = dolfinx.mesh.create_unit_square(comm, N, N, dolfinx.mesh.CellType[cell])
    phi, psi = bench.crack_levelsets(*BOUNDARY_SLIVER)
    cut = CutMesh(mesh, phi, degree=degree, tangent=psi)
    problem = Problem(cut, degree, Material(100e6, 0.3), law, ghost_penalty=0.0, aggregation=0.25)
    boundary = lambda x: (  # noqa: E731
        np.isclose(x[0], 0.0)
        | np.isclose(x[0], 1.0)
        | np.isclose(x[1], 0.0)
        | np.isclose(x[1], 1.0)
    )
    problem.loads.add_displacement(boundary, {-1: _rigid_motion, 1: _rigid_motion})
    E = prescribed_extension(problem)
    assert E is not None and E.norm() > 1.0  # aggregated dofs read Dirichlet dofs
    E.destroy()
    problem.solve()
    space, error = problem.space, 0.0
    for field in (0, 1):
        V, parent = space.field_space(field)
        x = V.tabulate_dof_coordinates()
        bs = V.dofmap.index_map_bs
        k = np.flatnonzero(space.active[parent])
        exact = _rigid_motion(x[k // bs].T)[k % bs, np.arange(k.size)]
        error = max(error, float(np.abs(problem.w.x.array[parent[k]] - exact).max(initial=0.0)))
    error = comm.allreduce(error, op=MPI.MAX)
    print(f"largest error of the side fields: {error:.2e} m")
    assert error <= 1e-11


@pytest.mark.serial
@pytest.mark.parametrize("cell", ["triangle", "quadrilateral"])
def test_a_boundary_sliver_is_aggregated(cell):
    """The crack above (P2, 8 x 8, clamped boundary) cuts cells of the boundary row to
    slivers whose roots hold Dirichlet dofs. Extended with the prescribed part apart, C =
    cond h^2 is 28 (triangles) and 7.6e2 (quadrilaterals), against 3.1e2 and 1.5e4 for
    a generic crack; while those dofs stayed unknowns, 3.1e7 and 1.3e8."""
    C = sliver_and_generic_conditions(cell, BOUNDARY_SLIVER)
    assert C["sliver"] <= CONDITION_FACTOR * C["generic"], C


@pytest.mark.serial
def test_gathered_tip_dofs_bound_the_conditioning():
    """With the zone's branch dofs gathered (one unknown per tip, function and component,
    each shifted by its interpolant), C = cond h^2 of a crack (Q1, aggregation 0.25,
    clamped square) stays flat from n = 8 to 32: 0.55, 0.64, 0.65. With nodal branch
    dofs it grows like h^-5.7: 5.0e2, 2.0e4, 2.0e5; gathered without the shift of the
    gathered columns, 1.45, 1.72, 2.86 (like h^-3)."""
    import dolfinx.mesh

    bench = _bench()
    C = []
    for n in (8, 32):
        mesh = dolfinx.mesh.create_unit_square(
            MPI.COMM_SELF, n, n, dolfinx.mesh.CellType.quadrilateral
        )
        problem = bench.free_crack(mesh, *GENERIC_CRACK, 1, 0.0, THRESHOLD, tip_dofs="gathered")
        C.append(bench.scaled_condition(problem) / n**2)
    print(f"C = cond h^2 at n = 8, 32: {C[0]:.3e}, {C[1]:.3e}")
    assert C[1] <= 1.5 * C[0], C


@pytest.mark.mpi
def test_gathered_tip_dofs_are_one_unknown_per_tip_on_one_and_two_ranks():
    """Gathered branch dofs make 4 gdim reduced unknowns per tip; the solved branch field
    is one value per group over the whole zone; the Williams case (P1 triangles, n = 16,
    r_e = 0.3) gives the same energy error on one process and on all of them."""
    from xfem_contact.cases.cracks import williams_case, williams_energy_error
    from xfem_contact.fem.tip_dofs import branch_groups

    def run(comm):
        case = williams_case(16, 1, comm=comm, tip_dofs="gathered")
        problem = case.problem
        problem.solve()
        space = problem.space
        groups = branch_groups(space)
        n_owned = groups.size
        values = problem.w.x.array[:n_owned]
        active = space.active[:n_owned] & (groups >= 0)
        spread = 0.0
        for g in np.unique(groups[active]):
            v = comm.allgather(values[active & (groups == g)])
            v = np.concatenate(v)
            spread = max(spread, float(v.max() - v.min()))
        R = problem.prolongation()
        columns = R.getSize()[1]
        R.destroy()
        return columns, spread, williams_energy_error(case)

    columns, spread, error = run(MPI.COMM_WORLD)
    columns_self, spread_self, error_self = run(MPI.COMM_SELF)
    print(f"energy error {error:.6e} (1 process {error_self:.6e}), spread {spread:.1e}")
    assert columns == columns_self
    assert spread <= 1e-14 and spread_self <= 1e-14
    assert abs(error - error_self) <= 1e-8 * error_self


def test_tip_dofs_are_checked():
    """An unknown ``tip_dofs``, or gathering without a tip radius, is refused in one line."""
    from xfem_contact.fem.tip_dofs import checked_tip_dofs

    with pytest.raises(ValueError, match="tip_dofs must be one of"):
        checked_tip_dofs("grouped", 0.3)
    with pytest.raises(ValueError, match="needs a tip radius"):
        checked_tip_dofs("gathered", None)


#: The Williams case of the aggregation tests: Q2, gathered branch dofs, r_e = 0.5 (m)
WILLIAMS = {"cell": "quadrilateral", "tip_dofs": "gathered", "aggregation": THRESHOLD}


@pytest.mark.serial
def test_aggregation_keeps_the_williams_rate():
    """Gathered branch dofs with aggregation 0.25 (Q2, r_e = 0.5): energy error 1.80e-2,
    4.88e-3 at n = 16, 32 (rate 1.89). With the cut-off's interpolant of degree 1 for a
    ramp, whose slope jumps across the edges a root's polynomial is extended over,
    1.46e-2, 6.79e-3 (rate 1.11; 1.61e-3 at n = 128 with r_e = 0.3, against 2.08e-3 at
    n = 64)."""
    from xfem_contact.cases.cracks import williams_case, williams_energy_error

    errors = []
    for n in (16, 32):
        case = williams_case(n, 2, tip_radius=0.5, comm=MPI.COMM_SELF, **WILLIAMS)
        case.problem.solve()
        errors.append(williams_energy_error(case))
    rate = np.log2(errors[0] / errors[1])
    print(f"energy error {errors[0]:.3e}, {errors[1]:.3e}: rate {rate:.2f}")
    assert rate >= 1.8, errors


@pytest.mark.serial
def test_a_root_is_never_a_tip_cell():
    """A crack's tip cells and the cells its extension cuts share their two sides' dofs:
    the side polynomial of one is the other side's too, and extended across the crack it
    would erase the jump. The roots of the Williams case (Q2, n = 32, r_e = 0.3, where a
    badly cut cell next to the tip cell found the tip cell as its nearest root) are
    crossed or uncut cells only."""
    from xfem_contact.cases.cracks import williams_case
    from xfem_contact.geometry.crack import CROSSED

    case = williams_case(32, 2, tip_radius=0.3, comm=MPI.COMM_SELF, **WILLIAMS)
    space, cut = case.problem.space, case.problem.cut
    kind = np.full(cut.cell_sides.size, CROSSED)  # uncut cells: roots like crossed ones
    kind[cut.cut_cells] = cut.crack.kind
    aggregation = space.aggregation
    roots = set()
    for field in (0, 1):
        dofmap = space.W.sub(field).dofmap.list
        cells_of = {}
        for cell, dofs in enumerate(dofmap):
            for dof in dofs:
                cells_of.setdefault(int(dof), set()).add(cell)
        rows = np.flatnonzero(np.isin(aggregation.dofs, dofmap.ravel()))
        for row in rows:
            sources = aggregation.sources[aggregation.rows == row]
            (root,) = set.intersection(*(cells_of[int(s)] for s in sources))
            roots.add(root)
    kinds = sorted(set(kind[list(roots)].tolist()))
    print(f"{aggregation.dofs.size} constrained dofs, roots of the kinds {kinds}")
    assert roots and all(kind[r] == CROSSED for r in roots)


@pytest.mark.mpi
def test_aggregated_gathered_crack_is_the_same_on_one_and_two_ranks():
    """The Williams case of the rate test (Q2, gathered dofs, their ramp of degree 2,
    aggregation 0.25, n = 16) gives the same energy error on one process and on all."""
    from xfem_contact.cases.cracks import williams_case, williams_energy_error

    def error(comm):
        case = williams_case(16, 2, tip_radius=0.5, comm=comm, **WILLIAMS)
        case.problem.solve()
        return williams_energy_error(case)

    everywhere, alone = error(MPI.COMM_WORLD), error(MPI.COMM_SELF)
    print(f"energy error {everywhere:.10e} ({alone:.10e} on one process)")
    assert abs(everywhere - alone) <= 1e-8 * alone
