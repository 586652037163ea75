"""File-level code generation: FFCx's C generator, unchanged."""

from ffcx.codegeneration.C.file import generator, suffixes

__all__ = ["generator", "suffixes"]
