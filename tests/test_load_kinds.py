"""The scene's load types in one registry: the schema lists its rows, and each row
checks its value and adds its load through one method of ``Loads``."""

import pytest

from xfem_contact.mechanics.loads import Loads
from xfem_contact.scenes.load_kinds import LOAD_KINDS
from xfem_contact.scenes.records import LoadSpec
from xfem_contact.scenes.schema import LOAD_KEYS, LOAD_TYPES, SceneError

#: The method of Loads each load type adds through
METHODS = {
    "pressure": "add_pressure",
    "traction": "add_traction",
    "displacement": "add_displacement",
    "point_displacement": "add_point_displacement",
    "body_force": "add_body_force",
    "rotation": "add_rotation",
    "tangential_spring": "add_tangential_spring",
}


class _Recorder:
    """Records the Loads method called."""

    def __getattr__(self, name):
        assert hasattr(Loads, name), name
        return lambda *args, **kwargs: self.calls.append(name)


def test_the_schema_lists_the_registry():
    assert LOAD_TYPES == tuple(LOAD_KINDS) == tuple(METHODS)
    assert LOAD_KEYS == {k: (row.required, row.optional) for k, row in LOAD_KINDS.items()}


@pytest.mark.parametrize("kind", list(LOAD_KINDS))
def test_each_row_adds_its_load(kind):
    loads = _Recorder()
    loads.calls = []
    spec = LoadSpec("top", kind, 1.0, component=0, point=(0.0, 0.0))
    LOAD_KINDS[kind].add(loads, spec, 1.0, {"path": None})
    assert loads.calls == [METHODS[kind]]


@pytest.mark.parametrize(
    ("kind", "value"),
    [("pressure", [1.0, 2.0]), ("traction", 1.0), ("rotation", "x"), ("tangential_spring", 0.0)],
)
def test_each_row_checks_the_form_of_its_value(kind, value):
    with pytest.raises(SceneError, match=r"^loads\[0\]\.value: "):
        LOAD_KINDS[kind].check(value, False, "loads[0].value")
