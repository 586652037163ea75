"""Turn UFL forms with cut-cell measures into DOLFINx forms.

Measures whose ``subdomain_data`` provides ``integration_parts(subdomain_id, degree)``
(:class:`~xfem_contact.quadrature.cell_rules.CellRules`, :class:`~xfem_contact.fem.cutmesh.CutMesh`)
are rewritten into a standard cell integral over the cells their part covers
with the standard rule, and a runtime integral (integrand times the marker) over
the cells with per-cell rules. For a source whose ``compression`` is true, ``degree`` is
the integrand's polynomial degree as FFCx takes it for a standard rule (the integral's
``quadrature_degree`` metadata, else UFL's estimate), so that it may give rules of that
degree; ``None`` for the others. Forms are compiled once per signature with the
:mod:`xfem_contact.codegen` back end and re-created cheaply for new rules.
"""

from __future__ import annotations

import collections.abc
import json
import os
import pathlib
import typing

import dolfinx.fem
import dolfinx.mesh
import numpy as np
import ufl
from dolfinx.fem import IntegralType
from dolfinx.fem.forms import CompiledForm, compile_form, create_form, get_integration_domains
from ufl.algorithms import estimate_total_polynomial_degree
from ufl.algorithms.apply_algebra_lowering import apply_algebra_lowering
from ufl.algorithms.apply_derivatives import apply_derivatives

from xfem_contact.codegen import LANGUAGE, kernel_store, runtime_abi
from xfem_contact.codegen.compat import analyze_ufl_objects, compute_ir, get_options
from xfem_contact.codegen.tables import RuntimeIntegral, runtime_integral
from xfem_contact.quadrature.cell_rules import CellRules

#: DOLFINx JIT options under those of DOLFINx's configuration files and those a caller
#: gives: kernels compiled with -O1, not DOLFINx's -O2 (about half the compile time of
#: the cut forms' large kernels for the same assembly time; see the docs' performance
#: notes), and a wait of up to 5 min (not 10 s) for a module another process is
#: compiling (parallel test runs)
JIT_DEFAULTS = {"cffi_extra_compile_args": ["-O1", "-g0"], "timeout": 300}


def configured_jit_options() -> dict:
    """The JIT options of DOLFINx's configuration files, which DOLFINx documents in
    :func:`dolfinx.jit.get_options`: ``$XDG_CONFIG_HOME/dolfinx/dolfinx_jit_options.json``
    (``~/.config`` without the variable), then ``./dolfinx_jit_options.json`` over it.
    They take precedence over :data:`JIT_DEFAULTS`. Read at each call (two small files
    at most, once per compiled signature)."""
    home = pathlib.Path(os.environ.get("XDG_CONFIG_HOME", pathlib.Path.home() / ".config"))
    options: dict = {}
    for path in (
        home / "dolfinx" / "dolfinx_jit_options.json",
        pathlib.Path.cwd() / "dolfinx_jit_options.json",
    ):
        if path.is_file():
            options |= json.loads(path.read_text())
    return options


_STANDARD_ID0 = 1000
_RUNTIME_ID0 = 2000
_TYPES = {
    "cell": IntegralType.cell,
    "exterior_facet": IntegralType.exterior_facet,
    "interior_facet": IntegralType.interior_facet,
    "vertex": IntegralType.vertex,
}


class _Compiled(typing.NamedTuple):
    """What is kept per form signature: the JIT-compiled module and the runtime
    table layouts. No UFL form is kept, so no mesh or function stays alive."""

    ufcx_form: typing.Any
    module: typing.Any
    code: typing.Any
    dtype: typing.Any
    kernels: dict[int, RuntimeIntegral]


_cache: dict[tuple, _Compiled] = {}


def _is_cut_source(data) -> bool:
    return hasattr(data, "integration_parts")


def _source_key(data, integral) -> tuple[str, int, int, int]:
    """Deterministic order of the cut-cell measures of a form (so of its signature), one
    per integrand degree for a source whose rules depend on it (its ``compression``;
    -1 for the others)."""
    degree = integrand_degree(integral) if data.compression else -1
    return (type(data).__name__, data.id, integral.subdomain_id(), degree)


def integrand_degree(integral: ufl.Integral) -> int:
    """The polynomial degree FFCx takes for ``integral``'s standard rule: its
    ``quadrature_degree`` metadata, else UFL's estimate of the integrand's degree (after
    algebra lowering and derivatives, as FFCx estimates it)."""
    degree = integral.metadata().get("quadrature_degree", "auto")
    if degree not in ("auto", None, -1):
        return int(degree)
    integrand = apply_derivatives(apply_algebra_lowering(integral.integrand()))
    return int(estimate_total_polynomial_degree(integrand))


def _integral(
    itg: ufl.Integral, integrand, integral_type: str, sid: int, metadata: dict | None = None
) -> ufl.Integral:
    """``itg`` with a new integrand, type and id, ``metadata`` over its own, and no
    subdomain data."""
    metadata = {**itg.metadata(), **(metadata or {})}
    return ufl.Integral(integrand, integral_type, itg.ufl_domain(), sid, metadata, None)


class _Rewrite(typing.NamedTuple):
    form: ufl.Form
    domains: dict[str, list[tuple[int, np.ndarray]]]
    rules: dict[int, CellRules]


def _rewrite(ufl_form: ufl.Form) -> _Rewrite:
    """Every cut integral rewritten as its standard and runtime parts."""
    ours = [i for i in ufl_form.integrals() if _is_cut_source(i.subdomain_data())]
    if ours:
        for itg in ufl_form.integrals():
            data = itg.subdomain_data()
            if (
                not _is_cut_source(data)
                and data is not None
                and itg.integral_type() in ("cell", *{i.integral_type() for i in ours})
            ):
                raise ValueError(
                    f"A form cannot mix cut measures with {itg.integral_type()} measures "
                    f"carrying other subdomain data ({type(data).__name__}); use the plain "
                    "measure (no subdomain data) or the cut measures"
                )
    key_of = {id(i): _source_key(i.subdomain_data(), i) for i in ours}
    keys = sorted(set(key_of.values()))
    parts = {}
    for key in keys:
        itg = next(i for i in ours if key_of[id(i)] == key)
        degree = None if key[3] < 0 else key[3]
        parts[key] = list(itg.subdomain_data().integration_parts(itg.subdomain_id(), degree))
    # One id per part; the degrees of a measure whose parts are the same share them.
    ids, shared, next_standard, next_runtime = {}, {}, _STANDARD_ID0, _RUNTIME_ID0
    for key in keys:
        for j, part in enumerate(parts[key]):
            same = (key[:3], j, None if part.rules is None else part.rules.id)
            if same not in shared:
                if part.rules is None:
                    shared[same], next_standard = next_standard, next_standard + 1
                else:
                    shared[same], next_runtime = next_runtime, next_runtime + 1
            ids[key, j] = shared[same]

    integrals, domains, rules = [], {}, {}
    for itg in ufl_form.integrals():
        data = itg.subdomain_data()
        if not _is_cut_source(data):
            integrals.append(itg)
            continue
        key = key_of[id(itg)]
        for j, part in enumerate(parts[key]):
            sid = ids[key, j]
            if part.rules is None:
                domains.setdefault(part.integral_type, {})[sid] = part.entities
                integrand, kind = itg.integrand(), part.integral_type
                integrals.append(_integral(itg, integrand, kind, sid, part.metadata))
            else:
                integrand = itg.integrand()
                if part.replace:
                    integrand = ufl.replace(integrand, part.replace)
                domains.setdefault("cell", {})[sid] = part.rules.cells
                rules[sid] = part.rules
                integrals.append(_integral(itg, integrand * part.rules.marker, "cell", sid))
    return _Rewrite(
        ufl.Form(integrals),
        {t: sorted(d.items()) for t, d in domains.items()},
        rules,
    )


def _runtime_kernels(ufl_form: ufl.Form, options: dict, cell) -> dict[int, RuntimeIntegral]:
    """Runtime-table layout of each runtime cell integral, by subdomain id."""
    analysis = analyze_ufl_objects([ufl_form], options["scalar_type"])
    ir = compute_ir(analysis, {}, "", options, False)
    by_name = {integral.expression.name: integral for integral in ir.integrals}
    (form_ir,) = ir.forms
    kernels = {}
    for name, sid in zip(
        form_ir.integral_names["cell"], form_ir.subdomain_ids["cell"], strict=False
    ):
        kernel = runtime_integral(by_name[name].expression, cell)
        if kernel is not None:  # drop the marker: the cache must not keep meshes alive
            kernels[sid] = kernel._replace(marker=None)
    return kernels


def _compile(
    comm, ufl_form: ufl.Form, options: dict, jit_options: dict | None
) -> tuple[_Compiled, CompiledForm]:
    jit_options = JIT_DEFAULTS | configured_jit_options() | (jit_options or {})
    key = (
        ufl_form.signature(),
        tuple(sorted((k, str(v)) for k, v in options.items())),
        str(jit_options),
        comm.size,
    )
    if key not in _cache:
        compiled = compile_form(
            comm, ufl_form, form_compiler_options=options, jit_options=jit_options
        )
        store = kernel_store.store_path(compiled.module)
        kernels = kernel_store.load(store, ufl_form)
        if kernels is None:  # first use of this JIT module: ask FFCx for the layouts
            cell = ufl_form.ufl_domain().ufl_coordinate_element().cell_type
            kernels = _runtime_kernels(ufl_form, get_options(options), cell)
            kernel_store.save(store, kernels)
        _cache[key] = _Compiled(
            compiled.ufcx_form, compiled.module, compiled.code, compiled.dtype, kernels
        )
    cached = _cache[key]
    # Equal signatures: the compiled kernels serve this form (same coefficient order).
    return cached, CompiledForm(
        ufl_form, cached.ufcx_form, cached.module, cached.code, cached.dtype
    )


def _other_domains(ufl_form: ufl.Form, ids: dict[str, list[int]]) -> dict:
    """Integration entities of the non-rewritten integral types (as dolfinx.fem.form does)."""
    domain = ufl_form.ufl_domain()
    data = ufl_form.subdomain_data().get(domain, {})
    out = {}
    for name, itype in _TYPES.items():
        sd = [d for d in data.get(name, []) if d is not None]
        out[itype] = get_integration_domains(itype, sd[0] if sd else None, ids.get(name, []))
    return out


def compiled_forms() -> int:
    """Number of distinct forms (signatures) compiled or loaded by this process."""
    return len(_cache)


def form(
    ufl_form: ufl.Form | collections.abc.Iterable,
    form_compiler_options: dict | None = None,
    jit_options: dict | None = None,
):
    """Create a DOLFINx form from a UFL form that may use cut-cell measures.

    Collective. The form is compiled once per UFL signature (FFCx with the
    :mod:`xfem_contact.codegen` back end) and bound to the *current* rules of
    its measures: after :meth:`CutMesh.update`, call :func:`form` again (cheap)
    to integrate on the new cut. The returned form keeps its rules alive.

    Args:
        ufl_form: A UFL form, or a (nested) list of them.
        form_compiler_options: FFCx options (``scalar_type`` defaults to
            ``dolfinx.default_scalar_type``; ``language`` and the layout version
            :data:`~xfem_contact.codegen.runtime_abi.LAYOUT_OPTION` are set here).
        jit_options: DOLFINx JIT options (over :data:`JIT_DEFAULTS` and
            :func:`configured_jit_options`).

    Returns:
        A :class:`dolfinx.fem.Form` (or a nested list of them) for
        ``dolfinx.fem.assemble_*`` and ``dolfinx.fem.petsc``.
    """
    if isinstance(ufl_form, ufl.ZeroBaseForm):
        return dolfinx.fem.form(ufl_form)
    if not isinstance(ufl_form, ufl.Form):
        if isinstance(ufl_form, collections.abc.Iterable):
            return [form(f, form_compiler_options, jit_options) for f in ufl_form]
        return ufl_form
    return _build(_rewrite(ufl_form), ufl_form.ufl_domain(), form_compiler_options, jit_options)


def form_parts(
    ufl_form: ufl.Form,
    form_compiler_options: dict | None = None,
    jit_options: dict | None = None,
) -> list:
    """:func:`form` as a sum of DOLFINx forms: the integrals with standard rules, and
    the runtime integrals (the cut cells' per-cell rules) apart.

    Collective. Assembling every part into one tensor gives what ``form(ufl_form)``
    assembles. The point is the coefficient packing: DOLFINx packs every
    coefficient of a form on every entity of each of its integrals, so in one form
    the uncut cells would carry the markers of all runtime rules (most of the packed
    values per cell of a contact residual). Parts without integrals are left out.

    Args:
        ufl_form: A UFL form that may use cut-cell measures.
        form_compiler_options: As for :func:`form`.
        jit_options: As for :func:`form`.

    Returns:
        A list of one or two :class:`dolfinx.fem.Form` (standard part first).
    """
    if not isinstance(ufl_form, ufl.Form) or isinstance(ufl_form, ufl.ZeroBaseForm):
        return [form(ufl_form, form_compiler_options, jit_options)]
    rewrite = _rewrite(ufl_form)
    parts = []
    for runtime in (False, True):
        integrals = [
            i for i in rewrite.form.integrals() if (i.subdomain_id() in rewrite.rules) == runtime
        ]
        if integrals:
            kept = {i.subdomain_id() for i in integrals}
            rules = {sid: r for sid, r in rewrite.rules.items() if sid in kept}
            domains = {
                t: [(sid, e) for sid, e in d if sid in kept] for t, d in rewrite.domains.items()
            }
            part = _Rewrite(ufl.Form(integrals), domains, rules)
            parts.append(_build(part, ufl_form.ufl_domain(), form_compiler_options, jit_options))
    return parts


def _build(rewrite: _Rewrite, domain, form_compiler_options: dict | None, jit_options: dict | None):
    """Compile (once per signature) and create the DOLFINx form of a rewritten form."""
    options = {"scalar_type": dolfinx.default_scalar_type, **(form_compiler_options or {})}
    options["language"] = LANGUAGE
    # In the JIT module's signature: a new layout never loads a cached kernel of an old one
    options[runtime_abi.LAYOUT_OPTION] = runtime_abi.LAYOUT_VERSION
    mesh = dolfinx.mesh.Mesh(domain.ufl_cargo(), domain)
    compiled, compiled_form = _compile(mesh.comm, rewrite.form, options, jit_options)

    dropped = set()
    for sid, rules in rewrite.rules.items():
        kernel = compiled.kernels.get(sid)
        if kernel is None:  # FFCx removed the integral (a zero integrand)
            dropped.add(sid)
            continue
        rules.register(kernel, domain.ufl_cell())

    ufcx = compiled.ufcx_form
    offsets = [ufcx.form_integral_offsets[i] for i in range(len(IntegralType) + 1)]
    ids: dict[str, list[int]] = {}
    for itype in IntegralType:
        if itype.value + 1 < len(offsets):
            ids[itype.name] = [
                ufcx.form_integral_ids[j]
                for j in range(offsets[itype.value], offsets[itype.value + 1])
            ]
    subdomains = _other_domains(rewrite.form, ids)
    for name, entries in rewrite.domains.items():
        itype = _TYPES[name]
        entries = [(sid, e) for sid, e in entries if sid not in dropped]
        subdomains[itype] = sorted(subdomains.get(itype, []) + entries, key=lambda e: e[0])

    coeffs = ufl.algorithms.extract_coefficients(rewrite.form)
    consts = ufl.algorithms.analysis.extract_constants(rewrite.form)
    spaces = [arg.ufl_function_space() for arg in rewrite.form.arguments()]
    result = create_form(
        compiled_form, spaces, mesh, subdomains, {c: c for c in coeffs}, {c: c for c in consts}
    )
    result._xfem_rules = list(rewrite.rules.values())
    return result
