"""Runtime basis tables: which tables a runtime kernel reads, and their values.

The same functions serve the code generator (to lay out the kernel) and the
Python side (to tabulate the values at each cell's own points), so both agree
on the order and the shape of every table by construction.
"""

from __future__ import annotations

import typing

import basix
import numpy as np
import numpy.typing as npt
import ufl

from xfem_contact.codegen.compat import (
    get_ffcx_table_values,
    get_modified_terminal_element,
    piecewise_ttypes,
)
from xfem_contact.codegen.runtime_abi import is_marker_element, is_placeholder_rule, kernel_key


class TableSpec(typing.NamedTuple):
    """A point-dependent table of a runtime kernel (FFCx layout ``[point][dof]``)."""

    name: str
    element: typing.Any
    averaged: str | None
    local_derivatives: tuple[int, ...]
    flat_component: int
    codim: int
    ncols: int


class RuntimeIntegral(typing.NamedTuple):
    """What a runtime kernel needs from memory."""

    key: int
    tables: tuple[TableSpec, ...]
    marker: ufl.Coefficient | None  # the marker coefficient (code generation only)


def _modified_terminals(integrand: dict):
    """(modified terminal, table reference) pairs of one quadrature-rule integrand."""
    for attr in integrand["factorization"].nodes.values():
        mt, tr = attr.get("mt"), attr.get("tr")
        if mt is not None and tr is not None:
            yield mt, tr
    margs = integrand["modified_arguments"]
    for contributions in integrand["block_contributions"].values():
        for blockdata in contributions:
            for mad in blockdata.ma_data:
                yield margs[mad.ma_index], mad.tabledata


def runtime_integral(expression_ir, domain) -> RuntimeIntegral | None:
    """Describe the runtime data of an integral, or ``None`` for a standard one.

    Args:
        expression_ir: FFCx ``CommonExpressionIR`` of a cell integral.
        domain: Basix cell type the kernel is generated for.
    """
    rules = [rule for (cell, rule) in expression_ir.integrand if cell == domain]
    if not any(is_placeholder_rule(rule.points) for rule in rules):
        return None
    if expression_ir.integral_type != "cell" or len(rules) != 1:
        raise NotImplementedError(
            "Runtime quadrature needs a cell integral with one quadrature rule; got "
            f"{expression_ir.integral_type!r} with {len(rules)} rules"
        )
    integrand = expression_ir.integrand[(domain, rules[0])]
    markers, candidates = set(), {}
    for mt, tr in _modified_terminals(integrand):
        element = getattr(mt.terminal, "ufl_element", lambda: None)()
        if element is not None and is_marker_element(element):
            markers.add(mt.terminal)
            continue
        if tr.ttype in piecewise_ttypes:
            continue
        if tr.ttype == "quadrature":
            raise NotImplementedError(
                "A runtime (cut-cell) integral cannot contain quadrature-element "
                f"coefficients other than the marker (table {tr.name})"
            )
        element, avg, derivatives, component = get_modified_terminal_element(mt)
        if avg is not None:
            raise NotImplementedError("Cell/facet averages inside runtime integrals")
        codim = _tdim(ufl.domain.extract_unique_domain(mt.terminal)) - _tdim(element)
        spec = TableSpec(
            tr.name, element, avg, tuple(derivatives), component, codim, tr.values.shape[-1]
        )
        candidates.setdefault(tr.name, {})[_descriptor(spec)] = spec
    if len(markers) != 1:
        raise RuntimeError(f"A runtime integral must hold exactly one marker, found {len(markers)}")
    # FFCx's table names and its choice among equal tables vary between processes
    # (set ordering); the kernel (possibly compiled by another process) and the
    # Python side must agree, so tables are ordered and keyed by a canonical
    # descriptor: the smallest of the descriptors of the terminals sharing a table.
    chosen = sorted((min(c), c[min(c)]) for c in candidates.values())
    tables = tuple(spec for _, spec in chosen)
    key = kernel_key(tuple(descriptor for descriptor, _ in chosen))
    return RuntimeIntegral(key, tables, markers.pop())


def _tdim(owner) -> int:
    """Topological dimension of the cell of a UFL domain or a Basix element, from its
    Basix cell type (``ufl_cell()`` and ``cell`` build a new ``ufl.Cell`` and all its
    sub-entities at each call: seconds over a large form)."""
    if isinstance(owner, ufl.AbstractDomain):
        owner = owner.ufl_coordinate_element()
    return len(basix.topology(owner.cell_type)) - 1


def _descriptor(spec: TableSpec) -> str:
    """Process-independent description of a table (names excluded)."""
    return repr(
        (repr(spec.element), spec.local_derivatives, spec.flat_component, spec.codim, spec.ncols)
    )


def tabulate(
    spec: TableSpec, points: npt.NDArray[np.float64], cell: ufl.Cell
) -> npt.NDArray[np.float64]:
    """Values of one runtime table at reference ``points`` (shape ``(n, tdim)``).

    Returns:
        C-contiguous array of shape ``(n, spec.ncols)``. Unlike FFCx's static
        tables, values are not clamped: tiny basis values at points near a
        vertex are real data on cut cells.
    """
    if points.shape[0] == 0:
        return np.zeros((0, spec.ncols))
    values = get_ffcx_table_values(
        points,
        cell,
        "cell",
        spec.element,
        spec.averaged,
        "cell",
        spec.local_derivatives,
        spec.flat_component,
        spec.codim,
    )["array"]
    table = values[0, 0]
    if table.shape[1] != spec.ncols:
        raise RuntimeError(
            f"Table {spec.name}: {table.shape[1]} columns, kernel expects {spec.ncols}"
        )
    return np.ascontiguousarray(table, dtype=np.float64)
