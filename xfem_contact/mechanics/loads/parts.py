"""Boundary parts: by name, as local facet indices, or as a locator of ``x``.

A problem's :class:`~xfem_contact.mechanics.loads.Loads` holds a ``parts`` mapping
(name -> locator or facet array). :func:`named_parts` fills it for the meshes the
package builds: ``left``, ``right``, ``bottom``, ``top`` on a rectangle (and ``back``,
``front`` on a box), ``inner`` and ``outer`` on an annulus centred at the origin,
``boundary`` on every mesh (the names of the scenes' ``rectangle``, ``box`` and
``annulus`` kinds).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

import dolfinx.mesh
import numpy as np
from mpi4py import MPI

#: A boundary part: a name, local facet indices, or a locator ``x -> bool``, (3, n) -> (n,)
Part = str | np.ndarray | Callable[[np.ndarray], np.ndarray]


#: The faces of a box, ``(low, high)`` along x, y and z (a rectangle has the first two):
#: ``front`` is the face of largest z, towards a viewer looking down the z axis
BOX_FACES = (("left", "right"), ("bottom", "top"), ("back", "front"))


def _everywhere(x: np.ndarray) -> np.ndarray:
    return np.ones(x.shape[1], dtype=bool)


def box_parts(corners, tol: float | None = None) -> dict[str, Callable]:
    """Locators of the faces (:data:`BOX_FACES`) of the box ``[[x0, y0, z0], [x1, y1,
    z1]]`` or of the rectangle ``[[x0, y0], [x1, y1]]`` (m), and of the whole boundary,
    within ``tol`` (m; default 1e-8 of the largest side)."""
    low, high = (np.asarray(c, dtype=float) for c in corners)
    tol = 1e-8 * float(np.max(np.abs(high - low))) if tol is None else tol
    parts = {}
    for k, names in enumerate(BOX_FACES[: len(low)]):
        for name, at in zip(names, (low[k], high[k]), strict=True):
            parts[name] = lambda x, k=k, at=at: np.abs(x[k] - at) <= tol
    return parts | {"boundary": _everywhere}


def rectangle_parts(corners, tol: float | None = None) -> dict[str, Callable]:
    """Locators of the sides of the rectangle ``[[x0, y0], [x1, y1]]`` (m) and of the
    whole boundary, within ``tol`` (m; default 1e-8 of the larger side)."""
    return box_parts(corners, tol)


def annulus_parts(r_inner: float, r_outer: float) -> dict[str, Callable]:
    """Locators of the circles ``r = r_inner``, ``r = r_outer`` (m, centred at the
    origin, within 1e-6 r_outer) and of the whole boundary."""
    tol = 1e-6 * r_outer
    return {
        "inner": lambda x: np.abs(np.hypot(x[0], x[1]) - r_inner) < tol,
        "outer": lambda x: np.abs(np.hypot(x[0], x[1]) - r_outer) < tol,
        "boundary": _everywhere,
    }


def named_parts(mesh: dolfinx.mesh.Mesh) -> dict[str, Callable]:
    """The built-in parts of a mesh: ``boundary``, plus the rectangle's sides (the box's
    faces in 3D) when every boundary node lies on the sides of the mesh's bounding box,
    or ``inner`` and ``outer`` when every boundary node of a 2D mesh lies on one of two
    circles about the origin. Collective."""
    fdim = mesh.topology.dim - 1
    mesh.topology.create_connectivity(fdim, fdim + 1)
    facets = dolfinx.mesh.exterior_facet_indices(mesh.topology)
    nodes = dolfinx.mesh.entities_to_geometry(mesh, fdim, facets).ravel()
    gdim = mesh.geometry.dim
    x = mesh.geometry.x[np.unique(nodes), :gdim]
    comm = mesh.comm
    low, high = np.full(gdim, np.inf), np.full(gdim, -np.inf)
    comm.Allreduce(x.min(axis=0) if x.size else low.copy(), low, op=MPI.MIN)
    comm.Allreduce(x.max(axis=0) if x.size else high.copy(), high, op=MPI.MAX)
    size = float(np.max(high - low))
    on_box = np.all(
        np.isclose(x, low, rtol=0, atol=1e-8 * size).any(axis=1)
        | np.isclose(x, high, rtol=0, atol=1e-8 * size).any(axis=1)
    )
    if comm.allreduce(bool(on_box), op=MPI.LAND):
        return box_parts((low, high))
    if gdim == 3:
        return {"boundary": _everywhere}
    r = np.hypot(x[:, 0], x[:, 1])
    r0 = comm.allreduce(float(r.min()) if r.size else np.inf, op=MPI.MIN)
    r1 = comm.allreduce(float(r.max()) if r.size else -np.inf, op=MPI.MAX)
    on_circles = np.all((np.abs(r - r0) < 1e-6 * r1) | (np.abs(r - r1) < 1e-6 * r1))
    if r0 > 1e-6 * r1 and comm.allreduce(bool(on_circles), op=MPI.LAND):
        return annulus_parts(r0, r1)
    return {"boundary": _everywhere}


def boundary_facets(
    mesh: dolfinx.mesh.Mesh, part: Part, parts: Mapping[str, Part] | None = None
) -> np.ndarray:
    """Local exterior facet indices (int32) of a boundary part. Collective.

    Args:
        mesh: The mesh.
        part: A name of ``parts``, local facet indices, or a locator of ``x``
            (shape (3, n)) returning n booleans.
        parts: Named parts (name -> facet indices or locator).

    Raises:
        ValueError: an unknown name (the valid names listed), a locator returning other
            than n booleans, or a part holding no facet on any process (named).
    """
    name = part if isinstance(part, str) else None
    if name is not None:
        parts = parts or {}
        if name not in parts:
            raise ValueError(f"Unknown boundary part {name!r}; valid: {sorted(parts)}")
        part = parts[name]
    label = repr(name) if name is not None else ("of the locator" if callable(part) else "given")
    fdim = mesh.topology.dim - 1
    if callable(part):
        try:  # a bad locator is refused on every process, not on those it failed on
            facets, message = (
                dolfinx.mesh.locate_entities_boundary(mesh, fdim, _checked_locator(part, label)),
                "",
            )
        except (TypeError, ValueError) as error:
            facets, message = np.zeros(0, dtype=np.int32), " ".join(str(error).split())
        messages = [m for m in mesh.comm.allgather(message) if m]
        if messages:
            raise ValueError(messages[0])
    else:
        facets = np.asarray(part)
        if facets.ndim != 1 or not (facets.size == 0 or np.issubdtype(facets.dtype, np.integer)):
            raise ValueError(
                f"The boundary part {label} must be a name, a locator of x or a 1-D array of "
                f"facet indices, got {type(part).__name__} of shape {facets.shape}"
            )
        facets = facets.astype(np.int32)
    if mesh.comm.allreduce(facets.size, op=MPI.SUM) == 0:
        raise ValueError(f"The boundary part {label} holds no boundary facet of the mesh")
    return facets


def _checked_locator(locator: Callable, label: str) -> Callable:
    """``locator`` with its result checked: n booleans for n points."""

    def checked(x: np.ndarray) -> np.ndarray:
        result = np.asarray(locator(x))
        if result.shape != (x.shape[1],):
            raise ValueError(
                f"The boundary part {label} must return {x.shape[1]} booleans for "
                f"points of shape {x.shape}, got shape {result.shape}"
            )
        return result.astype(bool)

    return checked
