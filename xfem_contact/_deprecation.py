"""Names kept for one release after a rename: a module ``__getattr__`` that warns.

Every step may use it (a private root module, below every step)."""

from __future__ import annotations

import warnings
from collections.abc import Callable, Mapping


def renamed(module: str, names: Mapping[str, str], namespace: dict) -> Callable[[str], object]:
    """A module-level ``__getattr__`` for ``module`` (its ``__name__``) that serves each old
    name of ``names`` (old -> new) as ``namespace[new]`` (the module's ``globals()``),
    with a ``DeprecationWarning`` at each use naming the new one."""

    def __getattr__(name: str):
        if name in names:
            warnings.warn(
                f"{name} is deprecated and will be removed in the next release: use {names[name]}",
                DeprecationWarning,
                stacklevel=2,
            )
            return namespace[names[name]]
        raise AttributeError(f"module {module!r} has no attribute {name!r}")

    return __getattr__


def renamed_keyword(where: str, old: str, new: str, old_value, new_value):
    """The value of keyword ``new`` of ``where`` (e.g. ``"ReducedNewton"``) given as its
    old name ``old``: ``new_value`` when ``old_value`` is None, else ``old_value`` with a
    ``DeprecationWarning`` naming ``new`` (a ``ValueError`` if both are given)."""
    if old_value is None:
        return new_value
    warnings.warn(
        f"{where}({old}=...) is deprecated and will be removed in the next release: use {new}=",
        DeprecationWarning,
        stacklevel=3,
    )
    if new_value is not None:
        raise ValueError(f"{where}: give {new}= only ({old}= is its deprecated name)")
    return old_value


def renamed_attribute(owner: str, old: str, new: str) -> property:
    """A class attribute ``old`` of class ``owner`` that reads and writes attribute
    ``new``, with a ``DeprecationWarning`` naming ``owner.new`` at each use."""
    message = (
        f"{owner}.{old} is deprecated and will be removed in the next release: use {owner}.{new}"
    )

    def get(self):
        warnings.warn(message, DeprecationWarning, stacklevel=2)
        return getattr(self, new)

    def set(self, value):
        warnings.warn(message, DeprecationWarning, stacklevel=2)
        setattr(self, new, value)

    return property(get, set, doc=f"Deprecated name of :attr:`{new}`.")
