"""The runtime-table layouts of a compiled form, kept on disk beside its JIT module.

FFCx caches a form's compiled module on disk, but the layout of its runtime
kernels (:class:`~xfem_contact.codegen.tables.RuntimeIntegral`) comes from FFCx's
intermediate representation, which is slow to build (a large part of a warm
start-up). :func:`save` writes the layouts as JSON next to
the module (same name, suffix ``.xfem-tables.json``); :func:`load` reads them back
for a form with the same signature, finding each table's element again among the
form's own elements by its ``repr``. A missing, unreadable or foreign file just
means computing the layouts again.
"""

from __future__ import annotations

import contextlib
import json
import os
import pathlib
import tempfile

import ufl

from xfem_contact.codegen.runtime_abi import LAYOUT_VERSION
from xfem_contact.codegen.tables import RuntimeIntegral, TableSpec

SUFFIX = ".xfem-tables.json"


def store_path(module) -> pathlib.Path | None:
    """Where the layouts of a JIT module live (``None`` for a module without a file)."""
    file = getattr(module, "__file__", None)
    if not file:
        return None
    path = pathlib.Path(file)
    return path.with_name(path.name.split(".")[0] + SUFFIX)


def _elements(ufl_form: ufl.Form) -> dict[str, object]:
    """Every element of the form (arguments, coefficients, coordinates, and their
    sub-elements), by ``repr``."""
    found: dict[str, object] = {}
    pending = [f.ufl_function_space().ufl_element() for f in ufl_form.arguments()]
    pending += [f.ufl_function_space().ufl_element() for f in ufl_form.coefficients()]
    pending += [d.ufl_coordinate_element() for d in ufl_form.ufl_domains()]
    while pending:
        element = pending.pop()
        key = repr(element)
        if key in found:
            continue
        found[key] = element
        pending += list(getattr(element, "sub_elements", []))
        if (sub := getattr(element, "sub_element", None)) is not None:
            pending.append(sub)
    return found


def save(path: pathlib.Path | None, kernels: dict[int, RuntimeIntegral]) -> None:
    """Write ``kernels`` (subdomain id: layout) atomically; silently skipped where the
    cache directory is not writable. Not collective (each process may write: the
    content is the same)."""
    if path is None:
        return
    data = {
        "layout": LAYOUT_VERSION,
        "kernels": {
            str(sid): {
                "key": kernel.key,
                "tables": [
                    [
                        s.name,
                        repr(s.element),
                        s.averaged,
                        list(s.local_derivatives),
                        s.flat_component,
                        s.codim,
                        s.ncols,
                    ]
                    for s in kernel.tables
                ],
            }
            for sid, kernel in kernels.items()
        },
    }
    with contextlib.suppress(OSError):
        fd, tmp = tempfile.mkstemp(dir=path.parent, suffix=".tmp")
        with os.fdopen(fd, "w") as stream:
            json.dump(data, stream)
        os.replace(tmp, path)


def load(path: pathlib.Path | None, ufl_form: ufl.Form) -> dict[int, RuntimeIntegral] | None:
    """The layouts saved for a form of the same signature, or ``None`` (no file, another
    layout version, or an element not found in ``ufl_form``). Not collective."""
    if path is None or not path.is_file():
        return None
    try:
        data = json.loads(path.read_text())
    except (OSError, ValueError):
        return None
    if data.get("layout") != LAYOUT_VERSION:
        return None
    elements = _elements(ufl_form)
    kernels = {}
    for sid, entry in data["kernels"].items():
        tables = []
        for name, element, averaged, derivatives, component, codim, ncols in entry["tables"]:
            if element not in elements:
                return None
            tables.append(
                TableSpec(
                    name, elements[element], averaged, tuple(derivatives), component, codim, ncols
                )
            )
        kernels[int(sid)] = RuntimeIntegral(int(entry["key"]), tuple(tables), None)
    return kernels
