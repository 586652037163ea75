"""Form code generation: FFCx's C generator, unchanged."""

from ffcx.codegeneration.C.form import generator

__all__ = ["generator"]
