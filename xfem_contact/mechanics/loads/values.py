"""Load magnitudes checked and turned into data: Constants for forms, nodal arrays for
Dirichlet values.

A magnitude given as a number or a tuple of numbers becomes a
``dolfinx.fem.Constant`` (its value can change without compiling anything); a UFL
expression or a callable of the UFL coordinate enters the form as it is. Every
check raises a one-line ValueError naming the argument.
"""

from __future__ import annotations

from collections.abc import Callable

import dolfinx.fem
import numpy as np
import ufl

from xfem_contact.mechanics.parameters import is_number


def numeric(value, shape: tuple[int, ...], name: str) -> np.ndarray | None:
    """``value`` as a finite float array of ``shape`` if it is a number or a sequence of
    numbers (None if it is something else: an expression, a callable)."""
    if is_number(value):
        array = np.asarray(float(value))
    elif isinstance(value, list | tuple | np.ndarray) and all(
        is_number(v) for v in np.ravel(np.asarray(value, dtype=object))
    ):
        array = np.asarray(value, dtype=float)
    else:
        return None
    if array.shape != shape or not np.isfinite(array).all():
        expected = "a finite number" if shape == () else f"{shape[0]} finite numbers (a vector)"
        raise ValueError(f"{name} must be {expected}, got {value!r}")
    return array


def form_magnitude(
    mesh, value, shape: tuple[int, ...], name: str
) -> tuple[ufl.core.expr.Expr, dolfinx.fem.Constant | None]:
    """A load magnitude for a form: ``(UFL expression, its Constant or None)``.

    Args:
        mesh: The mesh (of the Constant and of the coordinate ``x``).
        value: A number or tuple of numbers (becomes a Constant), a UFL expression, or
            a callable of the UFL coordinate ``x`` returning either.
        shape: ``()`` for a scalar, ``(gdim,)`` for a vector.
        name: The argument's name in messages.
    """
    array = numeric(value, shape, name)
    if array is not None:
        constant = dolfinx.fem.Constant(mesh, array.astype(dolfinx.default_scalar_type))
        return constant, constant
    expr = value(ufl.SpatialCoordinate(mesh)) if _is_callable(value) else value
    if isinstance(expr, list | tuple):
        expr = ufl.as_vector(list(expr))
    try:
        expr = ufl.as_ufl(expr)
    except (TypeError, ValueError, ufl.UFLException):
        raise ValueError(
            f"{name} must be a number, a tuple of numbers, a UFL expression or a callable of "
            f"x returning one, got {type(expr).__name__}"
        ) from None
    if expr.ufl_shape != shape:
        raise ValueError(
            f"{name} must have shape {shape}, got a UFL expression of shape {expr.ufl_shape}"
        )
    return expr, None


def _is_callable(value) -> bool:
    return callable(value) and not isinstance(value, ufl.core.expr.Expr)


def set_constant(constant: dolfinx.fem.Constant, value, name: str) -> None:
    """Set a magnitude's Constant to ``value`` (finite, of the Constant's shape)."""
    array = numeric(value, constant.value.shape, name)
    if array is None:
        raise ValueError(f"{name} must be a number or a tuple of numbers, got {value!r}")
    constant.value = array


def nodal_values(
    V: dolfinx.fem.FunctionSpace, value: float | tuple | Callable, name: str
) -> np.ndarray:
    """The values of a Dirichlet function on the Lagrange space ``V`` (block size ``bs``)
    at its local dofs (owned and ghost): a number (every component), ``bs`` numbers, or a
    callable of the points ``x`` (shape (3, n)) returning ``(n,)`` for ``bs = 1`` or
    ``(bs, n)``.
    Collective (a bad value is refused on every process)."""
    bs = V.dofmap.bs
    shape = () if bs == 1 else (bs,)
    message = ""
    if _is_callable(value):
        x = V.tabulate_dof_coordinates().T  # (3, nodes)
        try:
            array = np.asarray(value(x), dtype=float)
        except (TypeError, ValueError) as error:
            array, message = None, f"{name}: the callable failed on points (3, n): {error}"
        expected = (x.shape[1],) if bs == 1 else (bs, x.shape[1])
        if array is not None and array.shape != expected:
            message = (
                f"{name}: the callable must return shape {expected} for points of shape "
                f"{x.shape}, got {array.shape}"
            )
        elif array is not None and not np.isfinite(array).all():
            message = f"{name}: the callable returned values that are not finite"
        values = array.T.ravel() if not message else None
    else:
        array = numeric(value, () if is_number(value) else shape, name)  # a number: each
        if array is None:
            numbers = "" if bs == 1 else f", {bs} numbers"
            raise ValueError(f"{name} must be a number{numbers} or a callable of x, got {value!r}")
        nodes = V.dofmap.index_map.size_local + V.dofmap.index_map.num_ghosts
        values = np.broadcast_to(array, (nodes, bs)).ravel().copy()
    messages = [m for m in V.mesh.comm.allgather(message) if m]
    if messages:
        raise ValueError(messages[0])
    return values


def finite_number(value, name: str) -> float:
    """``value`` as a float; ValueError naming ``name`` unless a finite number."""
    if not is_number(value) or not np.isfinite(value):
        raise ValueError(f"{name} must be a finite number, got {value!r}")
    return float(value)
