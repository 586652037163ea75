"""Loads of a problem (``problem.loads``): parts by name, magnitudes as data (no
compile when a value changes), load paths in pseudo-time, clear errors."""

import warnings

import dolfinx.mesh
import numpy as np
import pytest
import ufl
from mpi4py import MPI
from test_contact import contact_conditions, largest_cell, rigid_modes, tractions
from test_scenes import base

from xfem_contact.cases.paper import INCLUSION_CENTRE, inclusion_problem, integrate
from xfem_contact.fem import forms
from xfem_contact.io.meshes import annulus
from xfem_contact.mechanics.loads import LoadPath, load_steps, named_parts
from xfem_contact.mechanics.materials import Material
from xfem_contact.mechanics.plain import PlainElasticityProblem
from xfem_contact.scenes.builder import build
from xfem_contact.scenes.run import run
from xfem_contact.scenes.scene import SceneError, load_scene


@pytest.fixture(scope="module")
def plain():
    mesh = dolfinx.mesh.create_unit_square(MPI.COMM_WORLD, 4, 4)
    return PlainElasticityProblem(mesh, 1, Material(1e3, 0.3))


@pytest.mark.mpi
def test_built_in_part_names():
    square = dolfinx.mesh.create_unit_square(MPI.COMM_WORLD, 3, 3)
    assert sorted(named_parts(square)) == ["bottom", "boundary", "left", "right", "top"]
    ring = annulus(MPI.COMM_WORLD, 1.0, 2.0, 2, 12)
    assert sorted(named_parts(ring)) == ["boundary", "inner", "outer"]


@pytest.mark.mpi
def test_a_value_change_compiles_nothing_and_changes_the_solution(plain):
    loads = plain.loads
    loads.add_displacement("bottom", 0.0)
    pressure = loads.add_pressure("top", 1.0)
    traction = loads.add_traction("right", (0.5, 0.0))
    spring = loads.add_tangential_spring("left", 10.0)
    signature = (plain.bilinear_form().signature(), loads.linear_form().signature())
    first = plain.solve().w.x.array.copy()
    compiled = forms.compiled_forms()
    pressure.value, traction.value = 2.0, (1.0, 0.0)
    assert (pressure.value, traction.value) == (2.0, (1.0, 0.0))
    doubled = plain.solve().w.x.array.copy()
    assert np.allclose(doubled, 2 * first, rtol=0, atol=1e-12 * np.abs(first).max())
    spring.value = 1e4
    stiffer = plain.solve().w.x.array
    assert np.abs(stiffer - doubled).max() > 1e-3 * np.abs(doubled).max()
    assert (plain.bilinear_form().signature(), loads.linear_form().signature()) == signature
    assert forms.compiled_forms() == compiled


@pytest.mark.mpi
def test_each_load_follows_its_path(plain):
    loads = plain.loads
    loads.add_stage("late", 1.0, 3.0)
    ramp = loads.add_displacement("top", (0.0, 1e-3), path=[(0, 0), (1, 1), (2, 1)])
    late = loads.add_displacement("left", 2e-3, component=0, path="late")
    default = loads.add_point_displacement([1.0, 0.0], 1e-3, 1)
    for t, factors in ((0.5, (0.5, 0.0, 0.5)), (2.0, (1.0, 0.5, 2.0)), (4.0, (1.0, 1.0, 4.0))):
        loads.set_time(t)
        assert loads.time == t
        for load, factor, full in zip(
            (ramp, late, default), factors, (1e-3, 2e-3, 1e-3), strict=True
        ):
            values = np.abs(load.functions[0].x.array)
            assert np.isclose(values.max(), factor * full, rtol=1e-12, atol=0)
    assert loads.end_time == 3.0
    assert np.allclose(load_steps(4, 2.0), [0.5, 1.0, 1.5, 2.0])
    assert LoadPath([(0, 0), (1, 2)])(0.25) == 0.5 and LoadPath()(0.3) == 0.3


@pytest.mark.parametrize(
    "call, message",
    [
        (lambda L: L.add_pressure("top_", 1.0), "Unknown boundary part 'top_'; valid: ['bottom',"),
        (lambda L: L.add_pressure("top", float("nan")), "pressure must be a finite number"),
        (lambda L: L.add_traction("top", (1.0, 2.0, 3.0)), "traction must be 2 finite numbers"),
        (lambda L: L.add_traction("top", 1.0), "2 finite numbers (a vector), got 1.0"),
        (lambda L: L.add_body_force(lambda x: x[0]), "force must have shape (2,)"),
        (lambda L: L.add_pressure("top", 1.0, side=-1), "side must be one of [None]"),
        (lambda L: L.add_pressure(lambda x: x[0] > 5, 1.0), "holds no boundary facet"),
        (lambda L: L.add_pressure(lambda x: True, 1.0), "must return 16 booleans"),
        (lambda L: L.add_displacement("top", lambda x: x[0]), "must return shape (2, 25)"),
        (lambda L: L.add_displacement("top", 0.0, component=2), "component must be None or"),
        (lambda L: L.add_point_displacement([0.3, 0.1], 0.0, 0), "no mesh node at [0.3, 0.1]"),
        (lambda L: L.add_rotation("top", angle_deg=np.inf), "angle_deg must be a finite"),
        (lambda L: L.add_rotation("top"), "Give the rotation as angle= (rad) or angle_deg="),
        (lambda L: L.add_tangential_spring("top", -1.0), "a finite number > 0 Pa/m"),
        (lambda L: L.add_pressure("top", 1.0, path=[(1, 0), (0, 1)]), "increase strictly"),
        (lambda L: L.add_pressure("top", 1.0, path="never"), "Unknown load stage 'never'"),
        (lambda L: L.set_time(np.inf), "t must be a finite number"),
    ],
)
def test_bad_loads_are_refused_in_one_line(plain, call, message):
    with pytest.raises(ValueError) as raised:
        call(plain.loads)
    text = str(raised.value)
    assert message in text and text.splitlines() == [text], text


def test_a_handle_of_an_expression_has_no_settable_value(plain):
    load = plain.loads.add_pressure("top", lambda x: 1.0 + x[0])
    with pytest.raises(ValueError, match="given as an expression"):
        load.value = 2.0


def test_rotation_angle_in_radians_or_degrees(plain):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        degrees = plain.loads.add_rotation("right", angle_deg=30.0, centre=(0.5, 0.5))
    assert np.isclose(degrees.value, np.pi / 6)
    with pytest.warns(UserWarning, match="more than a full turn; for degrees use angle_deg="):
        plain.loads.add_rotation("right", angle=30.0)
    with pytest.warns(UserWarning, match="more than a full turn"):  # the handle too
        degrees.value = 30.0


def test_coulomb_inclusion_depends_on_the_load_path():
    """Compressed first, then sheared (two stages) against the same final loads applied
    proportionally: different final states (Coulomb friction depends on the path), both
    in equilibrium (the traction the residual applies on the inclusion balances the body
    force on it to 1e-8) and inside the Coulomb cone at the rule points."""
    mu, tau, steps = 0.3, 0.8, load_steps(4, 2.0)
    final = {}
    for path in ("staged", "proportional"):
        problem = inclusion_problem(10, 2, "coulomb", loading="paper", friction=mu)
        loads = problem.loads
        loads.add_stage("compress", 0.0, 1.0)
        loads.add_stage("shear", 1.0, 2.0)
        shear = [
            loads.add_traction(part, value, path="shear")
            for part, value in (
                ("top", (tau, 0.0)),
                ("bottom", (-tau, 0.0)),
                ("right", (0.0, tau)),
                ("left", (0.0, -tau)),
            )
        ]
        weight = loads.add_body_force((0.0, -5.0), side=-1, path="compress")
        for load in loads.items:
            if load.kind == "pressure":
                load.path = LoadPath([(0.0, 0.0), (1.0, 1.0)])
            if path == "proportional" and load.kind != "point displacement":
                load.path = LoadPath([(0.0, 0.0), (2.0, 1.0)])
        assert len(shear) == 4 and weight.value == (0.0, -5.0)
        for t in steps:
            problem.accept_step()  # the last step's state is checked before its accept
            loads.set_time(t)
            problem.solve()
        final[path] = np.concatenate([problem.space.field(problem.w, i).x.array for i in (0, 1)])

        applied = np.array(
            [
                integrate(ufl.action(loads.linear_form(), m))
                for m in rigid_modes(problem, INCLUSION_CENTRE)
            ]
        )
        d = ufl.SpatialCoordinate(problem.mesh) - ufl.as_vector(INCLUSION_CENTRE)
        _, P = tractions(problem)
        dG = problem.cut.dGamma
        resultant = np.array(
            [
                integrate(P[0] * dG),
                integrate(P[1] * dG),
                integrate((d[0] * P[1] - d[1] * P[0]) * dG),
            ]
        )
        scale = np.linalg.norm(applied[:2])
        assert scale > 0.5
        assert np.all(np.abs(resultant + applied) <= 1e-8 * scale), (path, resultant, applied)
        state = problem.interface_state(problem.w)
        cone = np.abs(state["P_t"]) - mu * np.maximum(-state["P_n"], 0.0)
        assert np.all(cone <= 1e-10 * np.abs(state["P_n"]).max())
        violations, kinds = contact_conditions(state, mu, largest_cell(problem), problem.mesh.comm)
        assert violations["|lambda_t| <= mu |lambda_n| + tol"] == 0, violations
        assert kinds["slip"] > 0, kinds
        print(f"\n{path}: resultant error {np.abs(resultant + applied).max() / scale:.2e}, {kinds}")
    difference = np.abs(final["staged"] - final["proportional"]).max()
    largest = np.abs(final["staged"]).max()
    print(f"displacements differ by {difference / largest:.3f} of the largest")
    assert difference > 1e-2 * largest, difference


def test_a_scene_without_interfaces_takes_every_load_type():
    """A plain scene builds the same Loads: a rotation and a spring work there too."""
    data = base()
    data["loads"] += [
        {"part": "right", "type": "rotation", "angle_deg": 1.0, "centre": [1.0, 0.5]},
        {"part": "left", "type": "tangential_spring", "value": 1e9},
        {"type": "body_force", "value": [0.0, -1e3], "path": [[0, 0], [2, 1]]},
    ]
    scene = load_scene(data)
    problem, _ = build(scene)
    assert [load.kind for load in problem.loads.items][-3:] == [
        "rotation",
        "tangential spring",
        "body force",
    ]
    assert np.isclose(problem.loads.items[2].value, np.pi / 180)
    summary = run(scene)
    assert summary["load_steps"] == 1 and problem.loads.end_time == 2.0


def test_scene_load_paths_and_stages():
    data = base(law="bonded")
    data["stages"] = {"first": [0, 1], "second": [1, 2]}
    data["loads"][1]["path"] = "first"
    data["loads"].append({"part": "right", "type": "pressure", "value": 2.0, "path": "second"})
    data["solver"] = {"load_steps": 2, "end_time": 2.0}
    scene = load_scene(data)
    assert scene.stages == {"first": (0.0, 1.0), "second": (1.0, 2.0)} and scene.end_time == 2.0
    problem, _ = build(scene)
    first, second = (problem.loads.items[k] for k in (1, 2))
    problem.loads.set_time(1.0)
    assert (first.factor.value, second.factor.value) == (1.0, 0.0)
    summary = run(scene)
    assert summary["load_steps"] == 2


@pytest.mark.parametrize(
    "change, key, message",
    [
        ({"path": "third"}, "loads[1].path", "'third': no such stage; known: ['first']"),
        ({"path": [[1, 0], [0, 1]]}, "loads[1].path", "times must increase strictly"),
        ({"path": [[0, 0, 1]]}, "loads[1].path[0]", "expected a list of 2 entries"),
        ({"path": 3}, "loads[1].path", "expected a stage name or a list of [time, factor]"),
        ({"part": "top", "type": "rotation"}, "loads[1].value", "value (rad) or angle_deg"),
    ],
)
def test_bad_scene_load_paths_are_refused(change, key, message):
    data = base()
    data["stages"] = {"first": [0, 1]}
    data["loads"][1] |= change
    if change.get("type") == "rotation":
        del data["loads"][1]["value"]
    with pytest.raises(SceneError) as raised:
        load_scene(data)
    text = str(raised.value)
    assert text.startswith(f"{key}: ") and message in text and text.splitlines() == [text], text


def test_scene_stage_and_end_time_checked():
    data = base()
    data["stages"] = {"late": [2, 1]}
    with pytest.raises(SceneError, match=r"^stages.late: start 2 must be before end 1$"):
        load_scene(data)
    data["stages"] = {}
    data["solver"] = {"end_time": 0.0}
    with pytest.raises(SceneError, match=r"^solver.end_time: must be > 0.0, got 0.0$"):
        load_scene(data)


def test_point_constraints_share_a_space_per_component():
    """Case 2's three point constraints (u_x twice, u_y once, each on both sides' fields)
    put their values on one space per field component, made once, not one per condition."""
    problem = inclusion_problem(4, 2, "sticking")
    spaces = [bc.g.function_space for bc in problem.loads.bcs]
    assert len(spaces) == 6
    assert len({id(V) for V in spaces}) == 4  # (field, component): (0|1, x), (0|1, y)
