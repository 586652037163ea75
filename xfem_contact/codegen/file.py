"""File-level code generation: FFCx's C generator, unchanged."""

from xfem_contact.codegen.compat import c_file_generator as generator
from xfem_contact.codegen.compat import c_file_suffixes as suffixes

__all__ = ["generator", "suffixes"]
