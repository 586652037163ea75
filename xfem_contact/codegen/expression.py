"""Expression code generation: FFCx's C generator, unchanged."""

from xfem_contact.codegen.compat import c_expression_generator as generator

__all__ = ["generator"]
