"""The one table of solver defaults (xfem_contact.solvers.options)."""

import ast
import pathlib

import pytest

import xfem_contact
from xfem_contact.scenes.schema import SCHEMA
from xfem_contact.solvers.options import (
    LINEAR_PRESETS,
    PRESETS,
    SOLVER_OPTIONS,
    SOLVERS,
    Facts,
    defaults,
    merged_options,
    preset,
    problem_options,
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


def _petsc_option_dicts(tree) -> list[int]:
    """Lines of the dict literals in ``tree`` with a key naming a PETSc solver option."""
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Dict):
            keys = [k.value for k in node.keys if isinstance(k, ast.Constant)]
            if any(isinstance(k, str) and k.startswith(PETSC_KEYS) for k in keys):
                found.append(node.lineno)
    return found


#: Option names of PETSc solvers (a dict with one of these as a key is a set of options)
PETSC_KEYS = ("ksp_", "pc_", "snes_", "mat_mumps_", "mg_", "bmg_")


def test_only_the_table_defines_petsc_options():
    package = pathlib.Path(xfem_contact.__file__).parent
    offenders = {
        str(path.relative_to(package)): lines
        for path in sorted(package.rglob("*.py"))
        if path.name != "options.py" or path.parent.name != "solvers"
        if (lines := _petsc_option_dicts(ast.parse(path.read_text())))
    }
    assert offenders == {}
    # the check sees the table's own rows
    table = ast.parse((package / "solvers" / "options.py").read_text())
    assert len(_petsc_option_dicts(table)) >= len(PRESETS) - 1  # "direct" is empty


def test_every_preset_is_a_row_with_what_selects_it():
    assert set(LINEAR_PRESETS) <= set(PRESETS)
    for name, row in PRESETS.items():
        assert row.selected_by and row.help, name
        assert preset(name) == row.options and preset(name) is not row.options
    with pytest.raises(ValueError, match=r"Unknown solver preset 'lu'; valid: \["):
        preset("lu")


@pytest.mark.parametrize(
    ("facts", "added"),
    [
        (Facts({}), set()),
        (Facts({}, symmetric=True), {"symmetric"}),
        (Facts({"pc_type": "lu"}, symmetric=True), set()),
        (Facts({}, crack_tip=True), set()),
        (Facts({"pc_type": "python"}, crack_tip=True), {"crack"}),
        (Facts({}, crack_tip=True, couplings=True), {"crack", "reused_lu"}),
        (Facts({"ksp_type": "preonly"}, couplings=True), set()),
        (Facts(preset("iterative"), symmetric=True), {"symmetric_band", "band_2d"}),
        (Facts(preset("iterative"), symmetric=False), {"band_2d"}),
        (Facts(preset("iterative"), symmetric=True, tdim=3), {"symmetric_band", "band_3d"}),
        (Facts(preset("iterative"), tdim=3), {"band_3d"}),
        (Facts({}, symmetric=True, tdim=3), {"symmetric"}),
    ],
)
def test_problem_options_add_the_rows_that_apply(facts, added):
    expected = {**defaults("newton")}
    for name in added:
        expected.update(PRESETS[name].options)
    assert problem_options("newton", facts) == {**expected, **facts.options}


def test_cholesky_for_an_unsymmetric_jacobian_is_refused():
    with pytest.raises(ValueError, match="pc_type = 'cholesky' needs a symmetric Jacobian"):
        problem_options("linear", Facts({"pc_type": "cholesky"}, symmetric=False))
