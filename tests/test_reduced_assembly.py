"""The fast paths of the solvers give what the slow ones gave.

- :func:`xfem_contact.fem.subspaces.collapse` equals DOLFINx's ``collapse``;
- a form assembled straight into the reduced numbering (on node blocks where the
  unknowns group by node) equals ``R^T A R`` by PtAP,
  bit for bit, and a prolongation in ``R`` takes the PtAP path;
- the uncut cells assembled field by field on the fields' own spaces
  (:func:`xfem_contact.fem.field_blocks.uncut_field_blocks`) give the same matrix, a term
  coupling two fields there included, and so do the Newton residuals where the
  Dirichlet data are not met (the lifting);
- the residual assembled as its parts (standard and runtime integrals,
  :func:`xfem_contact.fem.forms.form_parts`) equals the one form, and the uncut
  cells pack no runtime markers;
- the runtime-table layouts read back from disk equal the ones FFCx's IR gives;
- the first Newton iterate reuses the Jacobian assembled for the scaling only when
  it sits at that state.
"""

import itertools

import dolfinx.fem
import dolfinx.fem.petsc
import numpy as np
import pytest
import ufl
from petsc4py import PETSc
from ufl.algorithms import expand_derivatives

from xfem_contact.cases.paper import inclusion_problem
from xfem_contact.cases.solid import sphere_problem
from xfem_contact.codegen import kernel_store
from xfem_contact.fem import forms
from xfem_contact.fem.field_blocks import _coupled, uncut_field_blocks
from xfem_contact.fem.forms import form, form_parts
from xfem_contact.fem.subspaces import collapse
from xfem_contact.solvers.assembly import ReducedMatrix, selection
from xfem_contact.solvers.newton import ReducedNewton


@pytest.fixture(scope="module", params=["quadrilateral", "triangle"])
def problem(request):
    return inclusion_problem(8, 2, "coulomb", request.param, friction=0.3)


def _jacobian(problem):
    F = problem.residual(problem.w)
    return form(ufl.derivative(F, problem.w, ufl.TrialFunction(problem.space.W)))


def test_form_parts_sum_to_the_form(problem):
    """The parts' residuals add up to the one form's, to round-off; the standard part
    packs fewer values per cell: no marker of a runtime rule."""
    w = problem.w
    w.x.array[:] = np.random.default_rng(3).standard_normal(w.x.array.size)
    F = problem.residual(problem.w)
    whole, parts = form(F), form_parts(F)
    assert len(parts) == 2
    expected = dolfinx.fem.assemble_vector(whole).array
    got = sum(dolfinx.fem.assemble_vector(part).array for part in parts)
    assert np.max(np.abs(got - expected)) <= 1e-12 * np.max(np.abs(expected))

    def width(f):
        return max(c.shape[1] for c in dolfinx.fem.pack_coefficients(f).values())

    def markers(f):
        return sum(c.name == "xfem_marker" for c in f._cpp_object.coefficients)

    assert markers(parts[0]) == 0 < markers(whole) == markers(parts[1])
    assert width(parts[0]) < width(whole)
    w.x.array[:] = 0.0


@pytest.mark.parametrize("field", [0, 1, 2])
def test_collapse_matches_dolfinx(problem, field):
    """Same values at the same dof coordinates as DOLFINx's collapse of the sub-space."""
    w = problem.w.copy()
    w.x.array[:] = np.random.default_rng(field).standard_normal(w.x.array.size)
    sub = problem.space.W.sub(field)
    ours, parent = collapse(sub)
    theirs, theirs_parent = sub.collapse()
    bs = ours.dofmap.bs
    assert ours.dofmap.index_map.size_local == theirs.dofmap.index_map.size_local

    def by_position(V, dofs):
        x = V.tabulate_dof_coordinates()[:, :2]
        values = w.x.array[np.asarray(dofs)].reshape(-1, bs)
        order = np.lexsort((x[:, 1].round(12), x[:, 0].round(12)))
        return x[order], values[order]

    x_ours, v_ours = by_position(ours, parent)
    x_theirs, v_theirs = by_position(theirs, theirs_parent)
    assert np.array_equal(x_ours, x_theirs)
    assert np.array_equal(v_ours, v_theirs)


def test_direct_assembly_equals_ptap(problem):
    """R^T J R straight into the reduced numbering: the same matrix as PtAP."""
    J, R = _jacobian(problem), problem.prolongation()
    reduced = ReducedMatrix(J, problem.loads.bcs, R)
    assert reduced.direct
    A = reduced.assemble()
    assert A.getInfo()["mallocs"] == 0  # the pattern held every nonzero
    full = dolfinx.fem.petsc.assemble_matrix(J, bcs=problem.loads.bcs)
    full.assemble()
    reference = full.PtAP(R)
    assert A.getInfo()["nz_used"] <= reference.getInfo()["nz_used"] < full.getInfo()["nz_used"]
    reference.axpy(-1.0, A, PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
    assert reference.norm() == 0.0
    for mat in (full, reference, R):
        mat.destroy()
    reduced.destroy()


@pytest.mark.parametrize(
    "law, gdim, block_size",
    [("coulomb", 2, 2), ("frictionless", 2, 1), ("sticking", 3, 3), ("frictionless", 3, 1)],
)
def test_pattern_on_node_blocks_only_where_the_unknowns_group(law, gdim, block_size):
    """Vector fields give node blocks (2 x 2, 3 x 3 in 3D), a scalar multiplier does
    not; either way, and with the blocks switched off, the matrix is PtAP's. In 3D the
    sphere on 2 x 2 x 2 cubes (the blocks do not depend on the mesh size; the cut P2
    tetrahedra's kernels make each assembly of n = 4 cost seconds)."""
    options = {"friction": 0.3} if law == "coulomb" else {}
    if gdim == 2:
        problem = inclusion_problem(8, 2, law, **options)
    else:
        problem = sphere_problem(2, 2, law)
    J, R = _jacobian(problem), problem.prolongation()
    full = dolfinx.fem.petsc.assemble_matrix(J, bcs=problem.loads.bcs)
    full.assemble()
    reference = full.PtAP(R)
    for blocks in (True, False):
        reduced = ReducedMatrix(J, problem.loads.bcs, R, blocks=blocks)
        A = reduced.assemble()
        assert A.getBlockSize() == (block_size if blocks else 1)
        difference = reference.copy()
        difference.axpy(-1.0, A, PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
        assert difference.norm() == 0.0
        difference.destroy()
        reduced.destroy()
    for mat in (full, reference, R):
        mat.destroy()


def test_a_facet_term_coupling_two_fields_is_kept():
    """The pattern couples a field with itself across facets; a term that couples two
    fields there adds entries all the same: the matrix is PtAP's."""
    problem = inclusion_problem(8, 2, "sticking")
    W = problem.space.W
    u_minus = ufl.split(ufl.TrialFunction(W))[0]
    v_plus = ufl.split(ufl.TestFunction(W))[1]
    extra = 1e6 * ufl.inner(ufl.avg(u_minus), ufl.avg(v_plus)) * ufl.dS
    J = form(ufl.derivative(problem.residual(problem.w), problem.w, ufl.TrialFunction(W)) + extra)
    R = problem.prolongation()
    reduced = ReducedMatrix(J, problem.loads.bcs, R)
    A = reduced.assemble()
    without = ReducedMatrix(
        form(ufl.derivative(problem.residual(problem.w), problem.w)), problem.loads.bcs, R
    )
    assert A.getInfo()["nz_used"] > without.assemble().getInfo()["nz_used"]  # inserted
    without.destroy()
    full = dolfinx.fem.petsc.assemble_matrix(J, bcs=problem.loads.bcs)
    full.assemble()
    reference = full.PtAP(R)
    reference.axpy(-1.0, A, PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
    assert reference.norm() == 0.0
    for mat in (full, reference, R):
        mat.destroy()
    reduced.destroy()


@pytest.mark.parametrize(
    "law, cell, blocked, coupled",
    [
        ("coulomb", "quadrilateral", True, False),
        ("coulomb", "triangle", True, False),
        ("frictionless", "quadrilateral", False, True),
    ],
)
def test_uncut_cells_on_the_fields_own_spaces(law, cell, blocked, coupled):
    """The Jacobian divided into the uncut cells' field blocks (inserted 2 x 2 where the
    unknowns pair up; the single-component pins of case 2 among the Dirichlet dofs)
    and the rest: PtAP's matrix. A term coupling two fields on uncut cells stays."""
    options = {"friction": 0.3} if law == "coulomb" else {}
    problem = inclusion_problem(8, 2, law, cell, **options)
    W = problem.space.W
    J = ufl.derivative(problem.residual(problem.w), problem.w, ufl.TrialFunction(W))
    if coupled:  # u_- tested with v_+ on the uncut cells of side -1 (inactive dofs aside)
        u_minus, v_plus = ufl.split(ufl.TrialFunction(W))[0], ufl.split(ufl.TestFunction(W))[1]
        J = J + 1e6 * ufl.inner(u_minus, v_plus) * problem.cut.dx(-1)
    parts = uncut_field_blocks(J, problem.space.field_space)
    assert [b.field for b in parts.blocks] == [0, 1]  # the multipliers have no bulk
    R = problem.prolongation()
    blocks = [(form(b.form), b.parent, True) for b in parts.blocks]
    reduced = ReducedMatrix(form(parts.rest), problem.loads.bcs, R, field_blocks=blocks)
    assert [b[2] for b in reduced._blocks] == [blocked, blocked]
    A = reduced.assemble()
    assert A.getInfo()["mallocs"] == 0
    full = dolfinx.fem.petsc.assemble_matrix(form(J), bcs=problem.loads.bcs)
    full.assemble()
    reference = full.PtAP(R)
    scale = reference.norm()
    reference.axpy(-1.0, A, PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
    assert reference.norm() <= 1e-14 * scale
    for mat in (full, reference, R):
        mat.destroy()
    reduced.destroy()


@pytest.mark.mpi
def test_constant_blocks_are_added_from_their_copy(problem):
    """Kept for a solve, the uncut cells' linear bulk is added from a copy: at a new
    state the matrix equals one assembled afresh there."""
    W = problem.space.W
    J = ufl.derivative(problem.residual(problem.w), problem.w, ufl.TrialFunction(W))
    parts = uncut_field_blocks(J, problem.space.field_space)
    blocks = [(form(b.form), b.parent, True) for b in parts.blocks]
    R, rest = problem.prolongation(), form(parts.rest)
    kept = ReducedMatrix(rest, problem.loads.bcs, R, field_blocks=blocks)
    kept.keep_constant_blocks()
    kept.assemble()  # keeps the copy
    assert kept._kept is not None
    problem.w.x.array[:] = np.random.default_rng(1).standard_normal(problem.w.x.array.size)
    problem.w.x.scatter_forward()
    A = kept.assemble()  # the copy, and the rest at the new state
    fresh = ReducedMatrix(rest, problem.loads.bcs, R, field_blocks=blocks)
    B = fresh.assemble()
    B.axpy(-1.0, A, PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
    assert B.norm() <= 1e-14 * A.norm()
    problem.w.x.array[:] = 0.0
    for obj in (kept, fresh, R):
        obj.destroy()


def test_field_block_newton_lifts_unmet_dirichlet_data():
    """Where w misses its Dirichlet data the residual is lifted with the whole
    Jacobian (compiled then): DOLFINx's lifted residual; and the solution is the
    one without the field blocks."""
    problem = inclusion_problem(8, 2, "sticking")
    problem.loads.add_displacement(lambda x: np.isclose(x[1], 0.0), 1e-4)  # not met by w = 0
    R, bcs = problem.prolongation(), problem.loads.bcs
    solutions = []
    for field_space in (problem.space.field_space, None):
        problem.w.x.array[:] = 0.0
        F = problem.residual(problem.w)
        newton = ReducedNewton(F, problem.w, bcs, R, field_space=field_space)
        assert (newton.jacobian_forms._whole is None) == (field_space is not None)
        newton._residual(None, newton.y, newton.F_r)  # at w = R y = 0
        x = problem.w.x.petsc_vec
        b = dolfinx.fem.petsc.assemble_vector(form(problem.residual(problem.w)))
        dolfinx.fem.petsc.apply_lifting(b, [_jacobian(problem)], bcs=[bcs], x0=[x], alpha=-1.0)
        b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        dolfinx.fem.petsc.set_bc(b, bcs, x, -1.0)
        reference = newton.F_r.duplicate()
        newton.R.multTranspose(b, reference)  # (R D)^T b
        reference.axpy(-1.0, newton.F_r)
        assert reference.norm() <= 1e-12 * newton.F_r.norm()
        newton.solve()
        solutions.append(problem.w.x.array.copy())
        for obj in (newton, b, reference):
            obj.destroy()
    assert np.allclose(solutions[0], solutions[1], rtol=0, atol=1e-12 * np.abs(solutions[1]).max())
    R.destroy()


def test_the_jacobian_keeps_its_structure_through_newton():
    """The pattern is stored whole (explicit zeros where the first Jacobian, of an open
    contact, has none): the later iterates' nonzeros land in it, and the LU
    factorisation analyses the matrix once for the whole solve."""
    problem = inclusion_problem(16, 2, "coulomb", friction=0.3)
    PETSc.Log.begin()
    event = PETSc.Log.Event("MatLUFactorSym")
    before = event.getPerfInfo()["count"]
    report = problem.solve()
    assert report.iterations > 2
    J_r = problem.newton.J_r
    assert J_r.getInfo()["mallocs"] == 0
    assert event.getPerfInfo()["count"] - before == 1


def test_prolongation_takes_the_ptap_path():
    """lbb = restriction combines multiplier dofs: R is no selection."""
    problem = inclusion_problem(8, 2, "sticking", lbb="restriction")
    R = problem.prolongation()
    assert selection(R, problem.space.W) is None
    J = _jacobian(problem)
    reduced = ReducedMatrix(J, problem.loads.bcs, R)
    assert not reduced.direct
    A = reduced.assemble()
    assert A.getSize() == (R.getSize()[1],) * 2
    reduced.destroy()
    R.destroy()


def test_stored_layouts_equal_computed(problem, tmp_path):
    """The JSON beside a JIT module gives back the layouts FFCx's IR gave."""
    form(problem.residual(problem.w))  # compiles (or loads) and fills the in-memory cache
    checked = 0
    for compiled in forms._cache.values():
        if not compiled.kernels:
            continue
        path = tmp_path / f"{checked}{kernel_store.SUFFIX}"
        kernel_store.save(path, compiled.kernels)
        assert path.is_file()
        # the elements are found again in a form of the same signature
        loaded = kernel_store.load(path, forms._rewrite(problem.residual(problem.w)).form)
        if loaded is None:  # a cached form of another problem: its elements differ
            continue
        assert loaded.keys() == compiled.kernels.keys()
        for sid, kernel in compiled.kernels.items():
            assert loaded[sid].key == kernel.key
            assert [repr(s) for s in loaded[sid].tables] == [repr(s) for s in kernel.tables]
        checked += 1
    assert checked > 0
    (tmp_path / "bad.json").write_text("{not json")
    assert kernel_store.load(tmp_path / "bad.json", problem.residual(problem.w)) is None


def test_first_jacobian_reused_only_at_its_state(monkeypatch):
    """Assembled once for the scaling: the first iterate at that state reuses it; a
    solver started from another state assembles again, and both give one answer."""
    from xfem_contact.solvers import assembly
    from xfem_contact.solvers.newton import ReducedNewton

    calls = []
    original = assembly.ReducedMatrix.assemble

    def counting(self):
        calls.append(1)
        return original(self)

    monkeypatch.setattr(assembly.ReducedMatrix, "assemble", counting)
    problem = inclusion_problem(8, 2, "sticking")
    report = problem.solve()
    assert report.iterations == 1
    assert len(calls) == 1  # the set-up assembly served the only Newton step
    solution = problem.w.x.array.copy()

    problem.w.x.array[:] = 0.0
    newton = ReducedNewton(
        problem.residual(problem.w), problem.w, problem.loads.bcs, problem.prolongation()
    )
    problem.w.x.array[:] = 0.5 * solution  # moved after the set-up assembly
    calls.clear()
    newton.solve()
    assert len(calls) == newton.report.iterations  # no stale Jacobian reused
    assert np.allclose(problem.w.x.array, solution, rtol=0.0, atol=1e-10 * np.abs(solution).max())
    newton.destroy()


def test_field_pairs_found_without_expanding_each_block():
    """The pairs (trial field, test field) that a bilinear form's integrals hold, read
    off the form once (derivatives expanded): bulk and facet jumps of each side's field
    pair it with itself only; a cross term adds its pair; a use of the whole argument
    (no fixed component) names no pair."""
    problem = inclusion_problem(4, 2, "sticking")
    W, cut = problem.space.W, problem.cut
    u, v = ufl.TrialFunction(W), ufl.TestFunction(W)
    (u0, u1, _), (v0, v1, _) = ufl.split(u), ufl.split(v)
    sizes = [e.reference_value_size for e in W.ufl_element().sub_elements]
    offsets = [0, *itertools.accumulate(sizes)]
    a = ufl.inner(ufl.grad(u0), ufl.grad(v0)) * cut.dx(-1)
    a += ufl.inner(ufl.grad(u1), ufl.grad(v1)) * cut.dx(1)
    a += ufl.inner(ufl.jump(ufl.grad(u1)), ufl.jump(ufl.grad(v1))) * ufl.dS
    assert _coupled(expand_derivatives(a), v, u, offsets) == {(0, 0), (1, 1)}
    cross = ufl.inner(u0, v1) * cut.dx(-1)
    assert _coupled(expand_derivatives(a + cross), v, u, offsets) == {(0, 0), (1, 1), (0, 1)}
    whole = ufl.inner(u, v) * cut.dx(-1)
    assert _coupled(expand_derivatives(a + whole), v, u, offsets) is None
