"""One word per concept: the renamed API answers to its new names, and each old name
still works for one release with a DeprecationWarning naming the new one
(docs/architecture.md, "Names")."""

import importlib

import pytest
from test_scenes import base

import xfem_contact.mechanics.loads as loads_package
from xfem_contact.cases.paper import inclusion_problem
from xfem_contact.cases.rotation import rotating_annulus_problem
from xfem_contact.mechanics.fieldsplit_data import fieldsplit_dofs
from xfem_contact.mechanics.sliding import segments
from xfem_contact.scenes.scene import SceneError, load_scene
from xfem_contact.solvers import linear, newton, options


def test_problem_prolongation_and_its_old_name():
    problem = inclusion_problem(4, 1, "sticking", "triangle")
    R = problem.prolongation()
    with pytest.warns(DeprecationWarning, match=r"Problem\.prolongation\(\)"):
        old = problem.restriction()
    assert old.getSize() == R.getSize()
    assert (old - R).norm() == 0.0
    R.destroy(), old.destroy()


@pytest.mark.parametrize(
    "module, old, new",
    [
        (newton, "RestrictedNewton", "ReducedNewton"),
        (linear, "solve_restricted", "solve_reduced"),
        (linear, "assemble_restricted", "assemble_reduced"),
    ],
)
def test_old_solver_names_warn(module, old, new):
    with pytest.warns(DeprecationWarning, match=new):
        assert getattr(module, old) is getattr(module, new)


def test_old_prolongation_module_warns():
    import xfem_contact.fem.prolongation as prolongation

    with pytest.warns(DeprecationWarning, match="xfem_contact.fem.prolongation"):
        old = importlib.reload(importlib.import_module("xfem_contact.fem.restriction"))
    assert old.restriction_matrix is prolongation.prolongation_matrix


def test_unknown_name_is_an_attribute_error():
    with pytest.raises(AttributeError, match="no_such_name"):
        linear.no_such_name  # noqa: B018


def test_load_path_keyword_and_its_old_name():
    problem = inclusion_problem(4, 1, "sticking", "triangle")
    loads = problem.loads
    loads.add_stage("late", 1.0, 2.0)
    new = loads.add_pressure("top", 1.0, path="late")
    with pytest.warns(DeprecationWarning, match="use path="):
        old = loads.add_pressure("top", 1.0, history="late")
    assert repr(new.path) == repr(old.path) == "LoadPath([[1.0, 0.0], [2.0, 1.0]])"
    with pytest.warns(DeprecationWarning, match="Load.path"):
        assert old.history is old.path
    with pytest.raises(ValueError, match="give the load path once"):
        with pytest.warns(DeprecationWarning):
            loads.add_pressure("top", 1.0, path="late", history="late")


@pytest.mark.parametrize(
    "old, new", [("History", "LoadPath"), ("SpringSupport", "TangentialSpring")]
)
def test_old_load_class_names_warn(old, new):
    with pytest.warns(DeprecationWarning, match=new):
        assert getattr(loads_package, old) is getattr(loads_package, new)


def test_old_scene_load_names_are_read_with_a_warning():
    data = base()
    data["stages"] = {"first": [0, 1]}
    data["loads"] += [
        {"part": "left", "type": "tangential_support", "value": 1e9},
        {"part": "right", "type": "pressure", "value": 2.0, "history": "first"},
    ]
    with pytest.warns(DeprecationWarning) as caught:
        scene = load_scene(data)
    messages = sorted(str(w.message) for w in caught if w.category is DeprecationWarning)
    assert any("'tangential_support' is now 'tangential_spring'" in m for m in messages)
    assert any("'history' is now 'path'" in m for m in messages)
    assert [load.type for load in scene.loads][-2:] == ["tangential_spring", "pressure"]
    assert scene.loads[-1].path == "first"


def test_a_scene_load_path_given_twice_is_refused():
    data = base()
    load = {"type": "body_force", "value": [0.0, 1.0], "path": [[0, 0], [1, 1]]}
    data["loads"].append(load | {"history": [[0, 0], [1, 1]]})
    with pytest.raises(SceneError, match="give it once"):
        load_scene(data)


def test_old_solver_preset_key_is_read_with_a_warning():
    with pytest.warns(DeprecationWarning, match="'linear' is now 'preset'"):
        scene = load_scene(base(law="sticking") | {"solver": {"linear": "iterative"}})
    assert (
        scene.petsc_options
        == load_scene(base(law="sticking") | {"solver": {"preset": "iterative"}}).petsc_options
    )


def test_a_report_gives_the_displacement_of_a_side():
    problem = inclusion_problem(4, 1, "sticking", "triangle")
    report = problem.solve()
    for side, field in ((-1, 0), (1, 1)):
        u = report.displacement(side)
        assert u.name == ("u_minus", "u_plus")[field]
        assert (u.x.array == report.field(field).x.array).all()
    with pytest.raises(ValueError, match=r"side must be one of \[-1, 1\], got 0"):
        report.displacement(0)


def _newton(problem, **fieldsplit):
    """A ReducedNewton of ``problem`` with PETSc's fieldsplit preconditioner."""
    options = {"ksp_type": "gmres", "pc_type": "fieldsplit"}
    R = problem.prolongation()
    solver = newton.ReducedNewton(
        problem.residual(problem.w), problem.w, problem.loads.bcs, R, options, **fieldsplit
    )
    R.destroy()
    return solver


def test_fieldsplit_dofs_keyword_and_its_old_name():
    problem = inclusion_problem(4, 1, "sticking", "triangle")
    dofs = fieldsplit_dofs(problem.space)
    new = _newton(problem, fieldsplit_dofs=dofs)
    with pytest.warns(DeprecationWarning, match="use fieldsplit_dofs="):
        old = _newton(problem, splits=dofs)
    indices = [[s.getIndices().tolist() for s in n._fieldsplit_objects] for n in (new, old)]
    assert len(indices[0]) == 3 and indices[0] == indices[1]  # u, lambda, band
    new.destroy(), old.destroy()
    with pytest.raises(ValueError, match="give fieldsplit_dofs= only"):
        with pytest.warns(DeprecationWarning):
            _newton(problem, splits=dofs, fieldsplit_dofs=dofs)


def test_old_fieldsplit_preconditioners_name_warns():
    with pytest.warns(DeprecationWarning, match="FIELDSPLIT_PRECONDITIONERS"):
        assert options.SPLIT_PRECONDITIONERS is options.FIELDSPLIT_PRECONDITIONERS


@pytest.mark.parametrize(
    "old, new", [("split", "break_pieces"), ("split_gradient", "breakpoint_gradient")]
)
def test_old_breakpoint_function_names_warn(old, new):
    with pytest.warns(DeprecationWarning, match=new):
        assert getattr(segments, old) is getattr(segments, new)


def test_breakpoint_linearisation_and_its_old_name():
    coupling = rotating_annulus_problem(4, 1, 0.3).couplings["interface"]
    assert coupling.breakpoint_linearisation is True
    with pytest.warns(DeprecationWarning, match="SlidingCoupling.breakpoint_linearisation"):
        coupling.split_linearisation = False
    assert coupling.breakpoint_linearisation is False
    with pytest.warns(DeprecationWarning, match="SlidingCoupling.breakpoint_linearisation"):
        assert coupling.split_linearisation is False


def test_side_measure_ids_and_its_old_name():
    cut = inclusion_problem(4, 1, "sticking", "triangle").cut
    for side in (-1, 1):
        measure = cut.dx(side).subdomain_id()
        with pytest.warns(DeprecationWarning, match="CutMesh.side_measure_ids"):
            assert cut.split_side_measure(measure) == cut.side_measure_ids(measure)
        assert len(set(cut.side_measure_ids(measure)) | {measure}) == 3
    assert cut.side_measure_ids(cut.dGamma.subdomain_id()) is None
