"""The PETSc options of the package's solvers: defaults and presets, in two tables.

:data:`SOLVER_OPTIONS` is declarative, in the style of ``ffcx/options.py``: each
entry maps a PETSc option name (without prefix) to its type, default value, a
help string, the allowed values (``None``: whatever PETSc accepts) and the
solvers it is a default of:

- ``"linear"``: the KSP of :func:`xfem_contact.solvers.linear.solve_reduced`;
- ``"newton"``: the SNES of :class:`xfem_contact.solvers.newton.ReducedNewton`
  (its KSP options are those of the linear solve in every Newton step).

:data:`PRESETS` holds every other set of options the package uses, one row each with
what selects it: the linear-solver choices, the rows a problem adds under the user's
options (:func:`problem_options`), the plain problems' and the sub-solvers'. No other
module writes options of its own.

A problem takes its PETSc options and options prefix at construction, as DOLFINx's
``LinearProblem`` and ``NonlinearProblem`` do; the user's options override the
defaults and presets and are passed to PETSc unchecked, as are any other PETSc options
of the same prefix.
"""

from __future__ import annotations

import contextlib
import itertools
import typing

from petsc4py import PETSc

from xfem_contact._deprecation import renamed

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


#: A Krylov method over a factorisation (``pc_type`` lu or cholesky) keeps the
#: factorisation across the iterates of a Newton solve while it converges within this
#: many iterations
REFACTOR_AFTER = 20

#: The preconditioners that take the fields apart (PETSc's fieldsplit, the band
#: multigrid): they read the diagonal scaling, so a crack's solve does without the change
#: of unknowns
FIELDSPLIT_PRECONDITIONERS = ("fieldsplit", "python")


def uses_fieldsplit(options: dict) -> bool:
    """Whether ``options`` choose a preconditioner of :data:`FIELDSPLIT_PRECONDITIONERS`.
    Not collective."""
    return options.get("pc_type") in FIELDSPLIT_PRECONDITIONERS


def uses_band_multigrid(options: dict) -> bool:
    """Whether ``options`` choose the band multigrid
    (:class:`xfem_contact.solvers.band_multigrid.BandMultigrid`). Not collective."""
    return options.get("pc_type") == "python" and str(options.get("pc_python_type", "")).endswith(
        "band_multigrid.BandMultigrid"
    )


#: The Krylov methods that take a preconditioner varying between applications
FLEXIBLE_KRYLOV = ("fgmres", "gcr")

#: The band multigrid's displacement solve (degree 2) but its coarse level's Krylov
#: method: a two-level PCMG, the fine level by Chebyshev-Jacobi, the coarse by GAMG
_BAND_U: dict[str, OptionValue] = {
    "ksp_type": "preonly",
    "mg_levels_ksp_type": "chebyshev",
    "mg_levels_pc_type": "jacobi",
    "mg_levels_ksp_max_it": 2,
    "mg_levels_esteig_ksp_type": "cg",  # GMRES's basis would stay allocated
    "mg_coarse_pc_type": "gamg",
}


class Facts(typing.NamedTuple):
    """What a problem knows of itself when its options are chosen (:func:`problem_options`).

    Attributes:
        options: The options the user gave (names without prefix).
        symmetric: The Jacobian is symmetric (``Problem.symmetric``).
        crack_tip: The space has a crack's tip enrichment.
        couplings: The problem has terms coupling two cells (large sliding).
        tdim: The mesh's topological dimension.
    """

    options: dict
    symmetric: bool = False
    crack_tip: bool = False
    couplings: bool = False
    tdim: int = 2


class Preset(typing.NamedTuple):
    """One row of :data:`PRESETS`: a set of PETSc options and what selects it.

    Attributes:
        options: Option name (without prefix) to value.
        selected_by: What selects the row, in words.
        help: What the options do.
        applies: For the rows a problem adds itself: whether the row applies, given the
            problem's :class:`Facts`; ``None`` for the rows selected by name.
        prefix: For a sub-solver's defaults: the prefix under the solver's own that they
            are written at (options in the PETSc database win over them).
    """

    options: dict[str, OptionValue]
    selected_by: str
    help: str
    applies: typing.Callable[[Facts], bool] | None = None
    prefix: str = ""


def _reuses_lu(facts: Facts) -> bool:
    chosen = "ksp_type" in facts.options or facts.options.get("pc_type", "lu") != "lu"
    return facts.couplings and not chosen


#: Every preset of the package's solvers: the linear-solver choices (``--solver`` of the
#: demo, ``[solver] preset`` of a scene), the rows a problem adds under the user's options
#: (``applies``), the plain problems' and the band multigrid's sub-solvers'. No other
#: module writes PETSc options of its own.
PRESETS: dict[str, Preset] = {
    "direct": Preset(
        {}, "the linear-solver choice 'direct' (the default)", "MUMPS LU (the defaults)"
    ),
    "iterative": Preset(
        {
            "ksp_gmres_restart": 10,  # a short basis: its W-sized vectors are memory
            "ksp_rtol": 1e-12,
            "ksp_atol": 1e-30,
            "ksp_max_it": 500,
            "pc_type": "python",
            "pc_python_type": "xfem_contact.solvers.band_multigrid.BandMultigrid",
        },
        "the linear-solver choice 'iterative' (contact problems)",
        "GMRES(10) on 2D meshes, FGMRES(10) on 3D ones (the rows 'band_2d' and "
        "'band_3d'), preconditioned by the band multigrid "
        "(xfem_contact.solvers.band_multigrid): an exact solve on the band of the "
        "interface (cut cells, their neighbours, the multipliers) after a two-level "
        "p-multigrid V-cycle on the displacements",
    ),
    "symmetric": Preset(
        {"pc_type": "cholesky"},
        "a symmetric Jacobian (sticking, frictionless, bonded; small kinematics) and no "
        "pc_type given",
        "MUMPS LDL^T: about half the factor entries and flops of the LU "
        "(xfem_contact.solvers.symmetry checks every matrix first)",
        lambda facts: facts.symmetric and "pc_type" not in facts.options,
    ),
    "symmetric_band": Preset(
        {"bmg_band_pc_type": "cholesky"},
        "a symmetric Jacobian (as for 'symmetric') preconditioned by the band multigrid",
        "MUMPS LDL^T of the band: about half the memory of its LU "
        "(xfem_contact.solvers.symmetry checks the band's matrix first)",
        lambda facts: facts.symmetric and uses_band_multigrid(facts.options),
    ),
    "band_2d": Preset(
        {"ksp_type": "gmres"},
        "the band multigrid on a 2D mesh",
        "GMRES: the preconditioner is a fixed linear operator (its coarse level three "
        "Richardson iterations of GAMG, the row 'band_u')",
        lambda facts: facts.tdim == 2 and uses_band_multigrid(facts.options),
    ),
    "band_3d": Preset(
        {
            "ksp_type": "fgmres",
            "bmg_band_mat_mumps_icntl_7": 5,
            "bmg_band_mat_mumps_icntl_13": 1,
        },
        "the band multigrid on a 3D mesh",
        "FGMRES, which lets the band multigrid solve its coarse level to a relative "
        "tolerance (the row 'band_u_flexible': a contraction that does not degrade with "
        "h, as three Richardson iterations of GAMG do); the band's MUMPS factorisation "
        "ordered by METIS (fewer factor entries and flops than PORD on the shell of cells "
        "around a surface) and its root front factored without ScaLAPACK (on 2 ranks the "
        "triangular solves then share the work instead of each doing more than one rank "
        "alone)",
        lambda facts: facts.tdim == 3 and uses_band_multigrid(facts.options),
    ),
    "crack": Preset(
        {"mat_mumps_icntl_14": 100},
        "a crack's tip enrichment without the change of unknowns "
        "(xfem_contact.solvers.block_scaling): a fieldsplit preconditioner, or large sliding",
        "100 % more MUMPS workspace: the branch functions are then nearly dependent on the "
        "polynomials far from the tip and the delayed pivots outgrow the default workspace "
        "(INFO(1) = -9)",
        lambda facts: facts.crack_tip and (uses_fieldsplit(facts.options) or facts.couplings),
    ),
    "reused_lu": Preset(
        {
            "ksp_type": "gmres",
            "ksp_gmres_restart": 100,
            "ksp_rtol": 1e-12,
            "ksp_atol": 1e-30,
            "ksp_max_it": 100,
        },
        "large sliding (couplings) with neither a ksp_type nor a pc_type other than lu given",
        "GMRES preconditioned by the LU of an earlier iterate of the same Newton solve, "
        "refactored when GMRES needs more than REFACTOR_AFTER iterations; the tolerance "
        "far below Newton's keeps the steps those of the exact Jacobian",
        _reuses_lu,
    ),
    "plain": Preset(
        {"ksp_type": "preonly", "pc_type": "lu"},
        "PlainElasticityProblem (a scene without interfaces), under the user's options",
        "PETSc's LU of the uncut elasticity matrix",
    ),
    "fitted": Preset(
        {"ksp_type": "preonly", "pc_type": "lu", "pc_factor_mat_solver_type": "mumps"},
        "the body-fitted Nitsche reference (xfem_contact.cases.fitted_nitsche)",
        "MUMPS LU of the two bodies' block system",
    ),
    "band_u": Preset(
        _BAND_U | {"mg_coarse_ksp_type": "richardson", "mg_coarse_ksp_max_it": 3},
        "the band multigrid's displacement solve, degree 2, under a Krylov method that "
        "needs a fixed preconditioner (not in FLEXIBLE_KRYLOV)",
        "PCMG with 2 levels (interpolation set by the preconditioner), the coarse level "
        "by three Richardson iterations of GAMG (a fixed linear operator)",
        prefix="bmg_u_",
    ),
    "band_u_flexible": Preset(
        _BAND_U
        | {
            "mg_coarse_ksp_type": "gmres",  # the coarse level of a Coulomb law: unsymmetric
            "mg_coarse_ksp_gmres_restart": 10,
            "mg_coarse_ksp_rtol": 1e-2,
            "mg_coarse_ksp_max_it": 30,
        },
        "the band multigrid's displacement solve, degree 2, under a flexible Krylov "
        "method (FLEXIBLE_KRYLOV)",
        "PCMG with 2 levels, the coarse level by GMRES + GAMG to a relative tolerance "
        "of 1e-2 (the preconditioner then varies between applications)",
        prefix="bmg_u_",
    ),
    "band_u_degree1": Preset(
        {
            "ksp_type": "preonly",
            "pc_type": "gamg",
            "mg_levels_pc_type": "sor",
            "mg_levels_ksp_max_it": 2,
        },
        "the band multigrid's displacement solve, degree 1",
        "algebraic multigrid on the displacements augmented by the multipliers' rows",
        prefix="bmg_u_",
    ),
    "band": Preset(
        {
            "ksp_type": "preonly",
            "pc_type": "lu",
            "pc_factor_mat_solver_type": "mumps",
            "mat_mumps_icntl_7": 4,
        },
        "the band multigrid's band solve",
        "MUMPS LU of the band (cut cells, their neighbours, the multipliers)",
        prefix="bmg_band_",
    ),
}

#: The presets a user chooses by name (``--solver``, ``[solver] preset``)
LINEAR_PRESETS = ("direct", "iterative")


def preset(name: str) -> dict[str, OptionValue]:
    """The options of the row ``name`` of :data:`PRESETS` (a new dict). Not collective.

    Raises:
        ValueError: ``name`` is not a key of :data:`PRESETS`.
    """
    if name not in PRESETS:
        raise ValueError(f"Unknown solver preset {name!r}; valid: {sorted(PRESETS)}")
    return dict(PRESETS[name].options)


def problem_options(solver: str, facts: Facts) -> dict[str, OptionValue]:
    """The PETSc options (without prefix) of a problem's ``solver``: the defaults of
    :data:`SOLVER_OPTIONS`, the rows of :data:`PRESETS` whose ``applies`` holds for
    ``facts``, and the user's ``facts.options``, later ones winning. Not collective.

    Raises:
        ValueError: ``pc_type = "cholesky"`` given for an unsymmetric Jacobian.
    """
    if facts.options.get("pc_type") == "cholesky" and not facts.symmetric:
        raise ValueError(
            "solver option pc_type = 'cholesky' needs a symmetric Jacobian; this problem's "
            "is not (Coulomb friction or large sliding): use pc_type = 'lu'"
        )
    added = {}
    for row in PRESETS.values():
        if row.applies is not None and row.applies(facts):
            added.update(row.options)
    return {**defaults(solver), **added, **facts.options}


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
    """``base`` made unique in this process (``"xfem_problem_"`` -> ``"xfem_problem_3_"``),
    so two solvers never share options (DOLFINx's problems require a prefix from the
    caller; ours make one when none is given). Not collective, but the same on every
    process when solvers are created in the same order (they are: construction is
    collective)."""
    return f"{base.rstrip('_')}_{next(_prefixes)}_"


def checked_prefix(prefix: str | None, base: str) -> str:
    """A solver's options prefix: ``prefix`` as given, or for ``None`` a unique one made
    from ``base`` (:func:`unique_prefix`). Not collective.

    Raises:
        ValueError: ``prefix`` is empty (DOLFINx's problems refuse it too: the options
            of every solver would mix in the database).
    """
    if prefix is None:
        return unique_prefix(base)
    if not isinstance(prefix, str) or not prefix:
        raise ValueError(
            f"petsc_options_prefix must be a non-empty string, got {prefix!r}; give e.g. "
            "'mine_', or None for a unique one"
        )
    return prefix


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


__getattr__ = renamed(__name__, {"SPLIT_PRECONDITIONERS": "FIELDSPLIT_PRECONDITIONERS"}, globals())
