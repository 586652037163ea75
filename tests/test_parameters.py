"""Parameters are data: new values of moduli, law and bulk parameters change the
solution and compile nothing (the forms hold them as Constants)."""

import dolfinx.fem
import numpy as np
import pytest
import ufl

from xfem_contact.cases.paper import inclusion_problem
from xfem_contact.fem import forms
from xfem_contact.fem.forms import form
from xfem_contact.mechanics.materials import Material, Moduli
from xfem_contact.mechanics.parameters import Parameter

#: (what is set, a new value): every parameter of a Coulomb problem's forms
CHANGES = [
    (("law", "friction"), 0.02),
    (("law", "augmentation"), 3.0),
    (("law", "multiplier_stabilization"), 0.3),
    (("law", "multiplier_extension"), 1e-6),
    (("bulk", "ghost_penalty"), 0.1),
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
    signature = coulomb.residual().signature()
    compiled = forms.compiled_forms()
    before = coulomb.w.x.array.copy()
    old = getattr(target, name)
    setattr(target, name, value)
    try:
        coulomb.w.x.array[:] = 0.0
        coulomb.solve()
        assert coulomb.residual().signature() == signature
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
    with pytest.raises(ValueError, match=r"finite and >= 0"):
        Parameter(minimum=0.0).check(float("inf"), "x")


def given_as(form: str, material: Material, name: str = "interface"):
    """``material`` on both sides, given as one Material, a pair or per interface name
    (a single level set's interface is named ``"interface"``)."""
    return {
        "one": material,
        "pair": {-1: material, 1: Material(material.E, material.nu)},
        "per interface": {-1: {name: material}, 1: material},
    }[form]


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
