"""The contract between generated runtime kernels and the Python side.

Marker
    A scalar quadrature element on :func:`placeholder_points` (one point set per
    cell type). Per cell, dof 0 holds the rule index (a float holding an integer)
    and dof 1 the address of the rule registry, bit-cast into a float64. The other
    dofs are unused. Marker values are local to a process: never scatter them.

Registry (``int64`` array)
    ``[n, key_0, block_0, key_1, block_1, ...]``: ``n`` pairs of a kernel key
    (:func:`kernel_key`) and the address of that kernel's block.

Block (``int64`` array) for a kernel with ``T`` runtime tables and ``R`` rules
    ``[R, off_0, ..., off_R, weights, table_0, ..., table_{T-1}]`` where rule ``r``
    is points ``off_r:off_{r+1}`` of every array, ``weights`` is the address of a
    float64 array of all weights and ``table_t`` the address of a C-contiguous
    float64 array of shape ``(num_points, ncols_t)``.

A kernel that finds no block for its key, or a rule index out of range, writes
NaN into its element tensor: missing data never reads as zero.

Layout version
    :data:`LAYOUT_VERSION` numbers this layout and the code that reads it. It enters
    every kernel key and, as the form-compiler option :data:`LAYOUT_OPTION`, the
    signature of every JIT module :func:`xfem_contact.form` compiles (FFCx and DOLFINx
    name their on-disk cache entries by that signature): a new version compiles new
    modules instead of loading kernels of an older layout from the cache.
"""

from __future__ import annotations

import functools
import hashlib

import basix
import basix.ufl
import numpy as np
import numpy.typing as npt

LANGUAGE = "xfem_contact.codegen"

#: Number of placeholder points. Any number >= 2 makes FFCx's table
#: classification (zeros / ones / piecewise / quadrature) reflect the functions,
#: not the points, with probability one; more points make accidental near-zero
#: or near-one values (clamped by FFCx) even less likely.
NUM_PLACEHOLDER_POINTS = 13

#: Version of the memory layout above and of the generated code that reads it. Bump it
#: with any change to either (marker, registry, block, table order, kernel prologue).
LAYOUT_VERSION = 1
#: The form-compiler option that carries :data:`LAYOUT_VERSION` into FFCx's module
#: signature (FFCx keeps options it does not know, and hashes all of them)
LAYOUT_OPTION = "xfem_contact_layout_version"

_SEEDS = {
    "triangle": 20261122,
    "quadrilateral": 20261123,
    "tetrahedron": 20261124,
    "hexahedron": 20261125,
}
_DIMS = {"triangle": 2, "quadrilateral": 2, "tetrahedron": 3, "hexahedron": 3}


@functools.cache
def placeholder_points(cell: str) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """Fixed generic points and weights that identify runtime integrals.

    Args:
        cell: ``"triangle"``, ``"quadrilateral"``, ``"tetrahedron"`` or ``"hexahedron"``.

    Returns:
        Points of shape ``(NUM_PLACEHOLDER_POINTS, tdim)`` strictly inside the
        reference cell, and positive weights of shape ``(NUM_PLACEHOLDER_POINTS,)``.
    """
    if cell not in _SEEDS:
        raise NotImplementedError(f"Runtime quadrature on cell {cell!r}; valid: {sorted(_SEEDS)}")
    rng = np.random.default_rng(_SEEDS[cell])
    pts = rng.uniform(0.05, 0.95, size=(NUM_PLACEHOLDER_POINTS, _DIMS[cell]))
    if cell == "triangle":
        flip = pts.sum(axis=1) > 0.95
        pts[flip] = 0.95 - pts[flip][:, ::-1]
    elif cell == "tetrahedron":  # gaps of sorted coordinates: sum <= 1, shrunk inside
        s = np.sort(pts, axis=1)
        pts = 0.05 + 0.8 * np.diff(s, axis=1, prepend=0.0)
    weights = rng.uniform(0.5, 1.5, size=NUM_PLACEHOLDER_POINTS)
    return pts, weights


def marker_element(cell: str) -> basix.ufl._ElementBase:
    """The quadrature element of the marker coefficient on ``cell``."""
    pts, wts = placeholder_points(cell)
    cell_type = basix.CellType[cell]
    return basix.ufl.quadrature_element(cell_type, value_shape=(), points=pts, weights=wts)


def is_marker_element(element) -> bool:
    """True if ``element`` is a marker element (any supported cell)."""
    if not getattr(element, "has_custom_quadrature", False):
        return False
    pts, _ = element.custom_quadrature()
    for cell in _SEEDS:
        ref, _ = placeholder_points(cell)
        if pts.shape == ref.shape and np.array_equal(pts, ref):
            return True
    return False


def is_placeholder_rule(points: npt.NDArray[np.floating]) -> bool:
    """True if quadrature ``points`` are one of the placeholder point sets."""
    for cell in _SEEDS:
        ref, _ = placeholder_points(cell)
        if points.shape == ref.shape and np.allclose(points, ref, rtol=0, atol=1e-15):
            return True
    return False


def kernel_key(spec: tuple) -> int:
    """Deterministic positive int64 key of a kernel's runtime-table specification
    under the current :data:`LAYOUT_VERSION`."""
    digest = hashlib.sha256(repr((LAYOUT_VERSION, spec)).encode()).digest()
    return int.from_bytes(digest[:8], "little") & 0x7FFF_FFFF_FFFF_FFFF
