"""The interface-law protocol: what callers ask of a law is declared on the base class,
each law answers it, and no module outside ``mechanics/laws`` tests a law's type, its
attributes or its name."""

import xfem_contact  # noqa: F401

# isort: split
import ast
import pathlib

import numpy as np
import pytest

from xfem_contact.mechanics.laws import (
    LAWS,
    Bonded,
    Coulomb,
    Fields,
    Free,
    Frictionless,
    InterfaceLaw,
    Sticking,
    large_sliding,
)
from xfem_contact.mechanics.laws.base import OPEN, SLIP, STICK

PACKAGE = pathlib.Path(xfem_contact.__file__).parent
#: Builtins that test a type or an attribute
PROBES = ("isinstance", "hasattr", "getattr", "type")
#: What ``isinstance`` may check of a user's input: a law given by name, or a law at all
INPUT_TYPES = ("str", "InterfaceLaw")


def law_probes(source: str, filename: str) -> list[str]:
    """Places in ``source`` that probe a law: ``isinstance(law, ...)``, ``hasattr(law,
    ...)``, ``getattr(law, ...)``, ``type(law)`` or ``law.name == ...`` for any name
    containing ``law``."""

    def is_law(node) -> bool:
        name = node.attr if isinstance(node, ast.Attribute) else getattr(node, "id", "")
        return "law" in name.lower()

    found = []
    for node in ast.walk(ast.parse(source, filename)):
        if (
            isinstance(node, ast.Call)
            and isinstance(node.func, ast.Name)
            and node.func.id in PROBES
            and node.args
            and is_law(node.args[0])
            and not (node.func.id == "isinstance" and ast.unparse(node.args[1]) in INPUT_TYPES)
        ):
            found.append(f"{filename}:{node.lineno}: {node.func.id}({ast.unparse(node.args[0])}")
        if isinstance(node, ast.Compare):
            for side in (node.left, *node.comparators):
                if isinstance(side, ast.Attribute) and side.attr == "name" and is_law(side.value):
                    found.append(f"{filename}:{node.lineno}: {ast.unparse(node)}")
    return found


def test_no_caller_probes_a_law():
    laws = PACKAGE / "mechanics" / "laws"
    found = [
        probe
        for path in sorted(PACKAGE.rglob("*.py"))
        if laws not in path.parents
        for probe in law_probes(path.read_text("utf-8"), str(path.relative_to(PACKAGE)))
    ]
    assert not found, "ask the law through its protocol (laws/base.py):\n" + "\n".join(found)


@pytest.mark.parametrize(
    "source, count",
    [
        ("if isinstance(law, Free): pass", 1),
        ("x = hasattr(self.law, 'traction_vector')", 1),
        ("code = 1 if law.name == 'bonded' else 0", 1),
        ("f = getattr(law, 'friction', None)", 1),
        ("t = law.transmits", 0),
        ("if isinstance(value, str): pass", 0),
        ("if isinstance(law, str): law = make_law(law)", 0),
        ("if isinstance(law, (Free, Bonded)): pass", 1),
    ],
)
def test_the_probe_check_finds_probes(source, count):
    assert len(law_probes(source, "x.py")) == count


def test_what_each_law_transmits():
    assert Free().transmits == "none"
    assert Bonded().transmits == "full"
    assert Frictionless().transmits == "normal"
    assert Sticking().transmits == "full"
    coulomb = Coulomb(0.3)
    assert coulomb.transmits == "full"
    coulomb.friction = 0.0  # a parameter set later: the answer follows
    assert coulomb.transmits == "normal"
    assert large_sliding(Frictionless()).transmits == "normal"
    assert large_sliding(Coulomb(0.2)).transmits == "full"
    assert {law().transmits for law in (Free, Bonded, Frictionless, Sticking)} <= {
        "none",
        "normal",
        "full",
    }


def test_multipliers_and_tractions_by_default():
    lam = object()
    fields = Fields(None, None, lam)
    assert Bonded().multipliers(None, fields) == (lam, None)
    assert Free().multipliers(None, Fields(None, None)) == (None, None)
    assert Free().traction_vector(None, Fields(None, None)) is None
    assert Bonded().traction_vector(None, fields) is lam


def test_point_status():
    state = {
        "P_n": np.array([0.0, -1.0, -1.0, -2.0]),
        "trial_t": np.array([5.0, 0.1, 0.5, -0.9]),
    }
    assert Free().point_status({}, 3).tolist() == [OPEN] * 3
    assert Bonded().point_status({}, 2).tolist() == [STICK] * 2
    assert Frictionless().point_status(state, 4).tolist() == [OPEN, SLIP, SLIP, SLIP]
    assert Sticking().point_status(state, 4).tolist() == [OPEN, STICK, STICK, STICK]
    # |trial_t| <= mu |P_n| sticks: 0.1 <= 0.3, 0.5 > 0.3, 0.9 > 0.6
    coulomb = Coulomb(0.3)
    assert coulomb.point_status(state, 4).tolist() == [OPEN, STICK, SLIP, SLIP]
    assert coulomb.status(state) == {"contact": 3, "stick": 1, "slip": 2}


def test_large_sliding_keeps_every_option():
    small = Coulomb(0.25, augmentation=3.0, lbb="none", multiplier_extension=2e-3)
    large = large_sliding(small, slave=1, pairing="step")
    assert large.sliding and large.name == "coulomb"
    assert {k: v for k, v in large.options().items() if k in small.options()} == small.options()
    assert (large.slave, large.pairing) == (1, "step")
    with pytest.raises(ValueError, match="not available in large sliding"):
        large_sliding(Sticking())


@pytest.mark.parametrize("name", sorted(LAWS))
def test_every_law_answers_the_protocol(name):
    law = LAWS[name](0.1) if name == "coulomb" else LAWS[name]()
    assert isinstance(law, InterfaceLaw)
    assert law.transmits in ("none", "normal", "full")
    assert isinstance(law.options(), dict)
    assert law.lbb in ("stabilized", "restriction", "none")


@pytest.mark.parametrize(
    "law, name, value",
    [
        (Coulomb(0.3), "lbb", "none"),
        (Bonded(), "lbb", "restriction"),
        (large_sliding(Frictionless(lbb="none")), "slave", 1),
        (large_sliding(Frictionless(lbb="none")), "pairing", "step"),
        (large_sliding(Coulomb(0.1, lbb="none")), "radius", 0.5),
    ],
)
def test_options_that_shape_the_forms_are_fixed_at_construction(law, name, value):
    """Setting them later would be ignored by the forms and pairing built on them: refused
    in one line naming the option, the value kept."""
    before = getattr(law, name)
    with pytest.raises(ValueError, match=f"^{name} is fixed when the law is built") as error:
        setattr(law, name, value)
    assert "\n" not in str(error.value)
    assert getattr(law, name) == before
    assert law.options()[name] == before
