"""The FFCx internals xfem_contact relies on, imported in one place.

None of these names is public FFCx API: they may move or change between FFCx
releases. Every other module of xfem_contact imports them from here, so a new
FFCx release needs checking (and, where it moved things, editing) here only.

Checked against FFCx 0.11.0 (``ffcx.__version__``; the ``fenics-ffcx>=0.11,<0.12``
of ``pyproject.toml``), with UFL 2026.1.0 and Basix 0.11.0. :data:`FFCX_VERSION`
is the version found at run time.

What each name is used for:

Code generation (the :mod:`xfem_contact.codegen` back end, loaded by FFCx as the
``language`` module):

- :data:`c_expression_generator`, :data:`c_form_generator`,
  :data:`c_file_generator`, :data:`c_file_suffixes` (``ffcx.codegeneration.C.*``):
  FFCx's C generators, re-exported unchanged by :mod:`~xfem_contact.codegen.expression`,
  :mod:`~xfem_contact.codegen.form` and :mod:`~xfem_contact.codegen.file`.
- :data:`c_integral` (the module ``ffcx.codegeneration.C.integral``): its
  ``generator`` generates standard integrals; for runtime integrals its module
  attribute ``IntegralGenerator`` is swapped for the runtime subclass during one
  call (:mod:`xfem_contact.codegen.integral`), so the module itself is exported.
- :class:`IntegralGenerator` (``ffcx.codegeneration.integral_generator``): base
  class of :class:`~xfem_contact.codegen.integral.RuntimeIntegralGenerator`.
- :data:`lnodes` (the module ``ffcx.codegeneration.lnodes``): FFCx's C syntax
  tree (symbols, statements, loops) the runtime generator builds and edits.

Basis tables (:mod:`xfem_contact.codegen.tables`):

- :data:`piecewise_ttypes` (``ffcx.ir.elementtables``): the table types FFCx
  keeps point-independent (not runtime tables).
- :func:`get_modified_terminal_element` (``ffcx.ir.elementtables``): element,
  averaging, derivatives and component of a modified terminal.
- :func:`get_ffcx_table_values` (``ffcx.ir.elementtables``): tabulates a table
  at given points exactly as FFCx lays it out (at each cell's runtime points).

Intermediate representation (:mod:`xfem_contact.fem.forms`, to read the runtime
table layout of a compiled form):

- :func:`analyze_ufl_objects` (``ffcx.analysis``): FFCx's UFL analysis stage.
- :func:`compute_ir` (``ffcx.ir.representation``): FFCx's IR stage.
- :func:`get_options` (``ffcx.options``): FFCx's options merged with the defaults
  (and the ``ffcx_options.json`` files), as the IR stage expects them.
"""

from __future__ import annotations

import ffcx
import ffcx.codegeneration.C.integral as c_integral
import ffcx.codegeneration.lnodes as lnodes
from ffcx.analysis import analyze_ufl_objects
from ffcx.codegeneration.C.expression import generator as c_expression_generator
from ffcx.codegeneration.C.file import generator as c_file_generator
from ffcx.codegeneration.C.file import suffixes as c_file_suffixes
from ffcx.codegeneration.C.form import generator as c_form_generator
from ffcx.codegeneration.integral_generator import IntegralGenerator
from ffcx.ir.elementtables import (
    get_ffcx_table_values,
    get_modified_terminal_element,
    piecewise_ttypes,
)
from ffcx.ir.representation import compute_ir
from ffcx.options import get_options

#: The FFCx version found at run time
FFCX_VERSION: str = ffcx.__version__
#: The FFCx version this module was checked against
CHECKED_FFCX_VERSION = "0.11.0"

__all__ = [
    "CHECKED_FFCX_VERSION",
    "FFCX_VERSION",
    "IntegralGenerator",
    "analyze_ufl_objects",
    "c_expression_generator",
    "c_file_generator",
    "c_file_suffixes",
    "c_form_generator",
    "c_integral",
    "compute_ir",
    "get_ffcx_table_values",
    "get_modified_terminal_element",
    "get_options",
    "lnodes",
    "piecewise_ttypes",
]
