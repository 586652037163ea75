"""Expression code generation: FFCx's C generator, unchanged."""

from ffcx.codegeneration.C.expression import generator

__all__ = ["generator"]
