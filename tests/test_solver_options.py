"""The one table of solver defaults (xfem_contact.solvers.options)."""

import pytest

from xfem_contact.scenes.schema import SCHEMA
from xfem_contact.solvers.options import (
    SOLVER_OPTIONS,
    SOLVERS,
    defaults,
    merged_options,
)


def test_table_is_consistent():
    for name, option in SOLVER_OPTIONS.items():
        assert isinstance(option.default, option.type), name
        assert option.solvers and set(option.solvers) <= set(SOLVERS), name
        if option.allowed is not None:
            assert option.default in option.allowed, name


def test_defaults_per_solver():
    linear, newton = defaults("linear"), defaults("newton")
    assert linear == {
        "ksp_type": "preonly",
        "pc_type": "lu",
        "pc_factor_mat_solver_type": "mumps",
        "mat_mumps_icntl_7": 4,  # PORD
        "mat_mumps_icntl_8": 7,  # its iterative scaling, not the weighted matching
    }
    assert linear.items() <= newton.items()  # Newton's linear solves are the linear solver's
    assert all(key.startswith("snes_") for key in newton.keys() - linear.keys())
    with pytest.raises(ValueError, match="Unknown solver"):
        defaults("multigrid")


def test_overrides_replace_and_extend():
    options = merged_options("newton", {"snes_max_it": 1, "ksp_monitor": None})
    assert options["snes_max_it"] == 1
    assert "ksp_monitor" in options
    assert options["snes_rtol"] == SOLVER_OPTIONS["snes_rtol"].default
    assert merged_options("linear") == defaults("linear")


def test_scene_schema_states_the_table_defaults():
    solver = SCHEMA["solver"]
    for key, option in (
        ("max_iterations", "snes_max_it"),
        ("rtol", "snes_rtol"),
        ("atol", "snes_atol"),
    ):
        assert f"(default {SOLVER_OPTIONS[option].default})" in solver[key]
