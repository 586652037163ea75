"""Default PETSc options of the solvers, in one table.

:data:`SOLVER_OPTIONS` is declarative, in the style of ``ffcx/options.py``: each
entry maps a PETSc option name (without prefix) to its type, default value, a
help string, the allowed values (``None``: whatever PETSc accepts) and the
solvers it is a default of:

- ``"linear"``: the KSP of :func:`xfem_contact.solvers.linear.solve_restricted`;
- ``"newton"``: the SNES of :class:`xfem_contact.solvers.newton.RestrictedNewton`
  (its KSP options are those of the linear solve in every Newton step).

Options given by the caller override these defaults and are passed to PETSc
unchecked, as are any other PETSc options of the same prefix.
"""

from __future__ import annotations

import contextlib
import itertools
import typing

from petsc4py import PETSc

#: The solvers that have defaults in :data:`SOLVER_OPTIONS`
SOLVERS = ("linear", "newton")

OptionValue = str | int | float


class Option(typing.NamedTuple):
    """One PETSc option: its type, default, meaning and the solvers using the default."""

    type: type
    default: OptionValue
    help: str
    allowed: tuple[OptionValue, ...] | None
    solvers: tuple[str, ...]


_BOTH = ("linear", "newton")
_NEWTON = ("newton",)

#: Default PETSc options (names without prefix) of the linear and Newton solvers
SOLVER_OPTIONS: dict[str, Option] = {
    "ksp_type": Option(
        str, "preonly", "Krylov method; preonly applies the preconditioner once", None, _BOTH
    ),
    "pc_type": Option(
        str,
        "lu",
        "preconditioner; lu is a direct solve, and a problem with a symmetric Jacobian "
        "(sticking, frictionless, bonded) factors LDL^T instead (cholesky, "
        "xfem_contact.solvers.symmetry) unless pc_type is given",
        None,
        _BOTH,
    ),
    "pc_factor_mat_solver_type": Option(
        str, "mumps", "package of the LU factorisation (MUMPS: also in parallel)", None, _BOTH
    ),
    "mat_mumps_icntl_7": Option(
        int,
        4,
        "MUMPS fill-reducing ordering; 4 = PORD (faster than METIS and AMF on these "
        "Jacobians: see the docs' performance page)",
        None,
        _BOTH,
    ),
    "mat_mumps_icntl_8": Option(
        int,
        7,
        "MUMPS row/column scaling; 7 = its cheap iterative one, on top of ours "
        "(xfem_contact.solvers.scaling). Its automatic choice (77: weighted matching) is "
        "slow on large meshes; none (0) runs out of workspace (INFO(1) = -9) on the "
        "delayed pivots of the LBB restriction's systems",
        None,
        _BOTH,
    ),
    "snes_type": Option(str, "newtonls", "nonlinear solver: Newton's method", None, _NEWTON),
    "snes_linesearch_type": Option(
        str, "basic", "line search; basic takes the full Newton step", None, _NEWTON
    ),
    "snes_rtol": Option(
        float, 1e-10, "relative tolerance on the residual norm (reduced space)", None, _NEWTON
    ),
    "snes_atol": Option(
        float, 1e-12, "absolute tolerance on the residual norm (reduced space)", None, _NEWTON
    ),
    "snes_stol": Option(
        float, 0.0, "tolerance on the step relative to the iterate; 0 disables it", None, _NEWTON
    ),
    "snes_max_it": Option(int, 30, "maximum number of Newton iterations per solve", None, _NEWTON),
}


#: Options added under a problem's own for a cut with a crack whose solver does without
#: the tip enrichment's change of unknowns (:mod:`xfem_contact.solvers.block_scaling`:
#: a split preconditioner, or large-sliding couplings): the geometric tip enrichment's
#: branch functions are then nearly dependent on the polynomials far from the tip, and
#: MUMPS's delayed pivots outgrow its default workspace (INFO(1) = -9, KSP reason -11,
#: P1 and P2 at n = 128 in the Williams case): 100 % more workspace. With the change
#: of unknowns (the direct solves) the default workspace suffices.
CRACK_OPTIONS: dict[str, OptionValue] = {"mat_mumps_icntl_14": 100}


#: Options added under a problem's own when its Jacobian is factored by LU and changes
#: little from one Newton iterate to the next (large sliding): GMRES preconditioned by
#: the LU of an earlier iterate of the same solve, refactored only when GMRES needs more
#: than :data:`REFACTOR_AFTER` iterations
#: (:class:`~xfem_contact.solvers.newton.RestrictedNewton`). A tolerance far below
#: Newton's keeps the steps those of the exact Jacobian.
REUSED_LU_OPTIONS: dict[str, OptionValue] = {
    "ksp_type": "gmres",
    "ksp_gmres_restart": 100,
    "ksp_rtol": 1e-12,
    "ksp_atol": 1e-30,
    "ksp_max_it": 100,
}

#: A Krylov method over a factorisation (``pc_type`` lu or cholesky) keeps the
#: factorisation across the iterates of a Newton solve while it converges within this
#: many iterations
REFACTOR_AFTER = 20


def reused_lu(options: dict, couplings: bool) -> dict:
    """:data:`REUSED_LU_OPTIONS` for a problem with ``couplings`` (large sliding) whose
    ``options`` choose neither a Krylov method nor a preconditioner; else none. Not
    collective."""
    chosen = "ksp_type" in options or options.get("pc_type", "lu") != "lu"
    return {} if chosen or not couplings else dict(REUSED_LU_OPTIONS)


#: Linear-solver presets of the Newton steps (``--solver`` of the demo, ``[solver] linear``
#: of a scene): option name (without prefix) to value, merged over the defaults. The
#: iterative one is GMRES(10) preconditioned by
#: :class:`~xfem_contact.solvers.band_multigrid.BandMultigrid`: an exact solve on the
#: band of the interface (cut cells, their neighbours, the multipliers) after a
#: two-level p-multigrid V-cycle on the displacements (iteration counts:
#: ``bench/iterative.py``).
LINEAR_PRESETS: dict[str, dict[str, OptionValue]] = {
    "direct": {},
    "iterative": {
        "ksp_type": "gmres",
        "ksp_gmres_restart": 10,  # a short basis: its W-sized vectors are memory
        "ksp_rtol": 1e-12,
        "ksp_atol": 1e-30,
        "ksp_max_it": 500,
        "pc_type": "python",
        "pc_python_type": "xfem_contact.solvers.band_multigrid.BandMultigrid",
    },
}


def preset(name: str) -> dict[str, OptionValue]:
    """The options of a linear-solver preset (a new dict). Not collective.

    Raises:
        ValueError: ``name`` is not a key of :data:`LINEAR_PRESETS`.
    """
    if name not in LINEAR_PRESETS:
        raise ValueError(f"Unknown linear solver {name!r}; valid: {sorted(LINEAR_PRESETS)}")
    return dict(LINEAR_PRESETS[name])


def defaults(solver: str) -> dict[str, OptionValue]:
    """The default PETSc options of one solver. Not collective.

    Args:
        solver: One of :data:`SOLVERS`.

    Returns:
        A new dict, option name (without prefix) to default value.
    """
    if solver not in SOLVERS:
        raise ValueError(f"Unknown solver {solver!r}, expected one of {SOLVERS}")
    return {name: opt.default for name, opt in SOLVER_OPTIONS.items() if solver in opt.solvers}


def merged_options(solver: str, overrides: dict | None = None) -> dict[str, OptionValue]:
    """The defaults of ``solver`` updated by ``overrides``. Not collective.

    Args:
        solver: One of :data:`SOLVERS`.
        overrides: PETSc options (names without prefix) that replace or extend
            the defaults; not checked.

    Returns:
        A new dict, option name (without prefix) to value.
    """
    return {**defaults(solver), **(overrides or {})}


def set_petsc_options(prefix: str, options: dict[str, OptionValue]) -> None:
    """Write ``options`` under ``prefix`` into the global PETSc options database.

    Not collective: each process writes its own database, so call it on every
    process with the same options before a collective ``setFromOptions``.
    Options already in the database under ``prefix`` and not in ``options`` are
    kept.

    Args:
        prefix: Options prefix, e.g. ``"xfem_linear_"``.
        options: Option name (without prefix) to value.
    """
    database = PETSc.Options()
    for key, value in options.items():
        database[f"{prefix}{key}"] = value


def remove_options(prefix: str) -> None:
    """Remove every option under ``prefix`` from the PETSc options database (after a
    solver that writes its own, e.g. DOLFINx's ``LinearProblem``, has read them).
    Not collective."""
    database = PETSc.Options()
    for key in list(database.getAll()):
        if key.startswith(prefix):
            database.delValue(key)


_prefixes = itertools.count()


def unique_prefix(base: str) -> str:
    """``base`` made unique in this process (``"xfem_newton_"`` -> ``"xfem_newton_3_"``),
    as DOLFINx's ``NonlinearProblem`` does, so two solvers never share options.
    Not collective, but the same on every process when solvers are created in the same
    order (they are: construction is collective)."""
    return f"{base.rstrip('_')}_{next(_prefixes)}_"


@contextlib.contextmanager
def applied_options(prefix: str, options: dict[str, OptionValue]):
    """Write ``options`` under ``prefix`` into the PETSc options database for the
    duration of the block (wrap the ``setFromOptions`` call), then remove them: the
    database holds nothing of ours afterwards. Not collective."""
    set_petsc_options(prefix, options)
    try:
        yield
    finally:
        database = PETSc.Options()
        for key in options:
            database.delValue(f"{prefix}{key}")
