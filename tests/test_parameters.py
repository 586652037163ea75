"""Parameters are data: new values of moduli, law and bulk parameters change the
solution and compile nothing (the forms hold them as Constants)."""

import dolfinx.fem
import numpy as np
import pytest
import ufl

from xfem_contact.cases.paper import inclusion_problem
from xfem_contact.fem import forms
from xfem_contact.fem.forms import form
from xfem_contact.mechanics.laws import SlidingCoulomb, large_sliding, make_law
from xfem_contact.mechanics.materials import Material, Moduli
from xfem_contact.mechanics.parameters import Parameter, parameter_names

#: (what is set, a new value): every parameter of a Coulomb problem's forms
CHANGES = [
    (("law", "friction"), 0.02),
    (("law", "augmentation"), 3.0),
    (("law", "multiplier_stabilization"), 0.3),
    (("law", "multiplier_extension"), 1e-6),
    (("bulk", "ghost_penalty"), 0.1),
    (("bulk", "ghost_penalty_higher"), 0.01),
    (("inside", "E"), 300e6),
    (("inside", "nu"), 0.3),
]


def owner(problem, which: str):
    return {
        "law": problem.law(),
        "bulk": problem.bulk,
        "inside": problem.materials[-1],
    }[which]


@pytest.fixture(scope="module")
def coulomb():
    """A Coulomb inclusion (8 x 8, P2, two materials so that each modulus matters)."""
    materials = {-1: Material(200e6, 0.1), 1: Material(100e6, 0.0)}
    problem = inclusion_problem(8, 2, "coulomb", friction=0.3, materials=materials)
    problem.solve()
    return problem


@pytest.mark.parametrize("change", CHANGES, ids=[f"{a}.{b}" for (a, b), _ in CHANGES])
def test_a_new_value_changes_the_solution_and_compiles_nothing(coulomb, change):
    (which, name), value = change
    target = owner(coulomb, which)
    signature = coulomb.residual(coulomb.w).signature()
    compiled = forms.compiled_forms()
    before = coulomb.w.x.array.copy()
    old = getattr(target, name)
    setattr(target, name, value)
    try:
        coulomb.w.x.array[:] = 0.0
        coulomb.solve()
        assert coulomb.residual(coulomb.w).signature() == signature
        assert forms.compiled_forms() == compiled, "a parameter value compiled a new form"
        change = np.abs(coulomb.w.x.array - before).max() / np.abs(before).max()
        assert change > 1e-12, f"{which}.{name} = {value} left the solution unchanged"
    finally:
        setattr(target, name, old)


@pytest.mark.parametrize(
    "which, name, bad",
    [
        ("law", "friction", -0.1),
        ("law", "augmentation", 0.0),
        ("inside", "nu", 0.5),
        ("inside", "E", float("nan")),
        ("bulk", "ghost_penalty", "a lot"),
    ],
)
def test_bad_values_are_refused_by_name(coulomb, which, name, bad):
    target = owner(coulomb, which)
    old = getattr(target, name)
    with pytest.raises(ValueError, match=name):
        setattr(target, name, bad)
    assert getattr(target, name) == old


@pytest.mark.parametrize("plane", ["strain", "stress"])
def test_moduli_constants_equal_the_material_values(coulomb, plane):
    """The UFL moduli of Constants equal :class:`Material`'s float ones (the unit
    square's integral of a constant is the constant)."""
    material = Material(210e9, 0.3, plane)
    moduli = Moduli(material, coulomb.mesh)
    dx = ufl.dx(domain=coulomb.mesh)
    for key in ("mu", "lmbda"):
        value = dolfinx.fem.assemble_scalar(form(getattr(moduli, f"ufl_{key}") * dx))
        assert value == pytest.approx(getattr(material, key), rel=1e-14)


def test_ghost_penalty_cannot_be_switched_on_after_the_build():
    problem = inclusion_problem(4, 1, "bonded", ghost_penalty=0.0)
    with pytest.raises(ValueError, match="ghost_penalty was 0"):
        problem.ghost_penalty = 0.01
    problem.ghost_penalty = 0.0


def test_a_parameter_states_its_range():
    assert Parameter("Pa", minimum=0.0, strict=True).requirement() == "> 0 Pa"
    with pytest.raises(ValueError, match=r"x must be a finite number >= 0, got inf"):
        Parameter(minimum=0.0).check(float("inf"), "x")


def given_as(form: str, material: Material, name: str = "interface"):
    """``material`` on both sides, given as one Material, a pair or per interface name
    (a single level set's interface is named ``"interface"``)."""
    return {
        "one": material,
        "pair": {-1: material, 1: Material(material.E, material.nu)},
        "per interface": {-1: {name: material}, 1: material},
    }[form]


@pytest.mark.mpi
@pytest.mark.parametrize("given", ["one", "pair", "per interface"])
def test_each_side_owns_its_material(given):
    """Equal materials on the two sides are two materials: a new E inside leaves the
    outside's alone, and the solution equals that of a problem built with the new
    moduli, with no new compile."""
    soft, stiff = Material(100e6, 0.3), Material(1e9, 0.3)
    name = "interface"
    problem = inclusion_problem(8, 2, "sticking", materials=given_as(given, soft))
    problem.solve()
    compiled = forms.compiled_forms()
    inside = problem.materials[-1]
    inside = inside[name] if given == "per interface" else inside
    inside.E = stiff.E
    assert problem.materials[1].E == soft.E
    problem.w.x.array[:] = 0.0
    problem.solve()
    assert forms.compiled_forms() == compiled, "a new modulus compiled a new form"
    inside_given = {name: stiff} if given == "per interface" else stiff
    fresh = inclusion_problem(8, 2, "sticking", materials={-1: inside_given, 1: soft})
    fresh.solve()
    w, reference = problem.w.x.array, fresh.w.x.array
    assert np.abs(w - reference).max() <= 1e-12 * np.abs(reference).max()


@pytest.fixture(scope="module")
def settable():
    """A Coulomb inclusion (4 x 4, P1) with a load of each kind (not solved): every
    settable parameter, by name -> (setter, getter, a value out of range or None, the
    valid range as messages give it)."""
    problem = inclusion_problem(4, 1, "coulomb", friction=0.3)
    loads, law, inside = problem.loads, problem.law(), problem.materials[-1]
    handles = {
        "pressure": loads.add_pressure("top", 1.0),
        "traction": loads.add_traction("top", (1.0, 0.0)),
        "force": loads.add_body_force((0.0, -1.0)),
        "displacement": loads.add_displacement("bottom", 0.0, component=1),
        "angle": loads.add_rotation("left", angle=0.1),
        "stiffness": loads.add_tangential_spring("right", 1e6),
    }

    def attribute(obj, name):
        return (lambda v: setattr(obj, name, v)), (lambda: getattr(obj, name))

    table = {
        "E": (*attribute(inside, "E"), 0.0, "> 0 Pa"),
        "nu": (*attribute(inside, "nu"), 0.5, "> -1 and < 0.5"),
        "friction": (*attribute(law, "friction"), -0.1, ">= 0"),
        "augmentation": (*attribute(law, "augmentation"), 0.0, "> 0"),
        "multiplier_stabilization": (*attribute(law, "multiplier_stabilization"), -1.0, ">= 0"),
        "multiplier_extension": (*attribute(law, "multiplier_extension"), -1.0, ">= 0"),
        "ghost_penalty": (*attribute(problem, "ghost_penalty"), -1.0, ">= 0"),
        "ghost_penalty_higher": (*attribute(problem, "ghost_penalty_higher"), -1.0, ">= 0"),
        "t": (loads.set_time, lambda: loads.time, -1.0, ">= 0"),
        "stiffness": (*attribute(handles.pop("stiffness"), "value"), 0.0, "> 0 Pa/m"),
    }
    for name, handle in handles.items():  # magnitudes: any finite number
        table[name] = (*attribute(handle, "value"), None, "number")
    return table


#: Parameters with a valid range, then the magnitudes (any finite number)
RANGED = [
    "E",
    "nu",
    "friction",
    "augmentation",
    "multiplier_stabilization",
    "multiplier_extension",
    "ghost_penalty",
    "ghost_penalty_higher",
    "t",
    "stiffness",
]
MAGNITUDES = ["pressure", "traction", "force", "displacement", "angle"]
BAD = {"string": "0.3", "nan": float("nan"), "inf": float("inf"), "bool": True}
CASES = [
    *((name, kind) for name in RANGED + MAGNITUDES for kind in BAD),
    *((name, "out of range") for name in RANGED),
]


@pytest.mark.parametrize("name, kind", CASES, ids=[f"{n}-{k}" for n, k in CASES])
def test_every_setter_refuses_bad_values_in_one_line(settable, name, kind):
    """A string, a bool, NaN, inf or a value out of range is refused in one line that
    names the parameter and its valid range, and leaves the value as it was."""
    set_value, get_value, out_of_range, valid = settable[name]
    bad = out_of_range if kind == "out of range" else BAD[kind]
    if name in ("traction", "force") and kind != "string":
        bad = (bad, 0.0)
    before = get_value()
    with pytest.raises(ValueError) as raised:
        set_value(bad)
    text = str(raised.value)
    assert text.splitlines() == [text] and name in text and valid in text, text
    assert get_value() == before


def test_sliding_segments_is_a_bool():
    law = make_law("coulomb", friction=0.3)
    sliding = large_sliding(law)
    with pytest.raises(ValueError, match="segments must be True or False, got 'no'"):
        sliding.segments = "no"
    sliding.segments = False
    assert sliding.segments is False
    with pytest.raises(ValueError, match=r"radius \(of the pairing search\) must be a finite"):
        SlidingCoulomb(0.3, radius=float("nan"))


def test_plane_is_fixed(coulomb):
    with pytest.raises(ValueError, match="plane is fixed when the forms are built"):
        coulomb.materials[1].plane = "stress"


def test_the_setter_table_holds_every_parameter(coulomb):
    """Each Parameter of a material, a contact law and the bulk is tried above."""
    owners = (coulomb.materials[-1], coulomb.law(), coulomb.bulk)
    assert {name for obj in owners for name in parameter_names(obj)} <= set(RANGED)
