"""Level sets on a mesh: interpolation, per-cell nodal values, and maps between
reference and physical coordinates evaluated per point (vectorised over cells).
"""

from __future__ import annotations

import typing
from collections.abc import Callable, Mapping

import basix
import dolfinx.fem
import dolfinx.mesh
import numpy as np
import numpy.typing as npt
from mpi4py import MPI

#: A level set given as a function of physical points ``x`` of shape
#: ``(gdim, n)`` (or ``(3, n)`` as DOLFINx passes them) returning ``(n,)``.
LevelSetCallable = Callable[[np.ndarray], np.ndarray]


class InterfaceError(ValueError):
    """A level set refused for the interface ``name``: ``message`` says why (a scene
    prefixes it with the interface's key)."""

    def __init__(self, name: str, message: str):
        self.name, self.message = name, message
        super().__init__(f"Interface {name!r}: {message}")


class LevelSet(typing.NamedTuple):
    """A level set interpolated into Lagrange degree 1 or 2.

    Attributes:
        function: The interpolant ``phi_h`` (scalar Lagrange, degree 1 or 2).
        exact: The callable it was interpolated from, or ``None`` when given
            only as nodal values (a DOLFINx Function).
    """

    function: dolfinx.fem.Function
    exact: LevelSetCallable | None

    @property
    def degree(self) -> int:
        return self.function.function_space.ufl_element().embedded_superdegree


#: Nodal level-set values within this fraction of ``max |phi|`` count as exactly zero
ZERO_TOLERANCE = 64 * np.finfo(np.float64).eps


def _values(levelset: LevelSetCallable, x: np.ndarray, gdim: int = 2) -> np.ndarray:
    """``levelset(x)`` checked: one float per point of ``x`` (shape ``(3, n)``). On a 3D mesh
    ``x`` is passed read-only: a 2D callable that writes into ``x[2]`` (``np.hypot(*x)``
    takes it for its output) fails instead of returning a cylinder's values."""
    hint = "" if gdim < 3 else " (a 3D mesh: x[0], x[1], x[2] are x, y, z; x is read-only)"
    if gdim == 3:
        x = x.view()
        x.flags.writeable = False
    try:
        values = np.asarray(levelset(x), dtype=np.float64)
    except (TypeError, ValueError, IndexError) as error:
        raise ValueError(
            f"the level set failed on points x of shape {x.shape}{hint}: {error}"
        ) from None
    if values.shape != (x.shape[1],):
        raise ValueError(
            f"the level set must return one value per point, shape ({x.shape[1]},) for x "
            f"of shape {x.shape}{hint}; it returned shape {values.shape}"
        )
    return values


def _vertex_basis(cell: str, X: np.ndarray) -> np.ndarray:
    """The P1 (Q1) vertex functions of a tetrahedron (hexahedron) at ``X`` ``(m, 3)`` in
    closed form, shape ``(m, nv)`` (Basix vertex order): exact 0, 1/2, 1 at the nodes of
    degree-2 Lagrange elements."""
    x, y, z = X.T
    if cell == "tetrahedron":
        return np.stack([1.0 - x - y - z, x, y, z], axis=1)
    lx, ly, lz = ([1.0 - t, t] for t in (x, y, z))
    return np.stack([lx[i] * ly[j] * lz[k] for k in (0, 1) for j in (0, 1) for i in (0, 1)], 1)


def canonical_dof_points(mesh: dolfinx.mesh.Mesh, V: dolfinx.fem.FunctionSpace) -> np.ndarray:
    """Physical points of the dofs of a degree-1 or 2 Lagrange space on a 3D mesh of
    straight cells, per cell, shape ``(num_cells incl. ghosts, ndofs, 3)`` (m).

    The same point gets the same bits in every cell that holds it, whatever the cell's
    vertex order, i.e. on any number of processes: the vertex terms of the cell map are
    exact (weights 0, 1/2, 1/4, 1/8 by :func:`_vertex_basis`) and summed in sorted order.
    Summed in the cell's order (as DOLFINx's interpolation does), a level set shared by
    cells differs by a few ulps between partitions, which flips the ties of Saye's choice
    of axes in symmetric cells."""
    cell = mesh.topology.cell_name()
    N = _vertex_basis(cell, V.element.interpolation_points)  # (ndofs, nv)
    nodes = mesh.geometry.x[mesh.geometry.dofmaps[0]]  # (ncells, nv, 3)
    terms = N[None, :, None, :] * np.transpose(nodes, (0, 2, 1))[:, None]  # (c, dof, 3, nv)
    return np.sort(terms, axis=3).sum(axis=3)


def interpolate(
    mesh: dolfinx.mesh.Mesh,
    levelset: LevelSetCallable | dolfinx.fem.Function,
    degree: int,
    into: dolfinx.fem.Function | None = None,
) -> LevelSet:
    """Interpolate a level set into scalar Lagrange of ``degree`` (1 or 2). Collective.

    Args:
        mesh: The mesh.
        levelset: A callable ``phi(x)`` with ``x`` of shape ``(3, n)``, or a
            scalar DOLFINx Function on ``mesh`` (its nodal values are the data).
        degree: 1 or 2.
        into: A Function of that space to hold the values (a moved interface keeps
            its level-set Function, so that forms using it keep their signature);
            written only once the values are checked. Default: a new one.

    Raises:
        ValueError: for a degree other than 1 or 2, NaN/inf values, or a level
            set that does not change sign on the mesh (no interface).
    """
    if degree not in (1, 2):
        raise ValueError(f"Level-set degree must be 1 or 2, got {degree}")
    V = dolfinx.fem.functionspace(mesh, ("Lagrange", degree))
    phi = dolfinx.fem.Function(V, name="levelset")
    if isinstance(levelset, dolfinx.fem.Function):
        if levelset.function_space.mesh is not mesh:
            raise ValueError(
                "levelset: the Function lives on another mesh; valid: a scalar Function on "
                "the cut mesh, or a callable phi(x)"
            )
        if levelset.function_space.value_size != 1:
            shape = levelset.function_space.value_shape
            raise ValueError(
                f"levelset: a Function of value shape {tuple(shape)} is not a level set; valid: "
                "a scalar Function (value shape ()), or a callable phi(x)"
            )
        phi.interpolate(levelset)
        exact = None
    elif callable(levelset):
        if mesh.topology.dim == 3 and mesh.geometry.cmaps[0].degree == 1:
            points = canonical_dof_points(mesh, V)  # (ncells, ndofs, 3)
            cell_values = _values(levelset, points.reshape(-1, 3).T, 3)
            phi.x.array[V.dofmap.list] = cell_values.reshape(points.shape[:2])
        else:
            phi.interpolate(lambda x: _values(levelset, x, mesh.geometry.dim))
        exact = levelset
    else:
        raise ValueError(f"A level set is a callable or a dolfinx Function, not {type(levelset)}")
    values = phi.x.array
    owned = V.dofmap.index_map.size_local
    bad = np.flatnonzero(~np.isfinite(values[:owned]))
    comm = mesh.comm
    count = comm.allreduce(bad.size, op=MPI.SUM)
    if count:
        # the lowest such node (by y, then x) of all processes: one message for any partition
        local = np.round(V.tabulate_dof_coordinates()[bad, :2], 12) + 0.0  # no 1e-18 or -0
        points = np.concatenate(comm.allgather(local[np.lexsort(local.T)[:1]]))
        x, y = points[np.lexsort(points.T)[0]]
        where = f"({x:.6g}, {y:.6g})"
        if mesh.geometry.dim == 3:  # the same choice of node, with its z
            local = np.round(V.tabulate_dof_coordinates()[bad], 12) + 0.0
            first = np.concatenate(comm.allgather(local[np.lexsort(local[:, :2].T)[:1]]))
            where = "({:.6g}, {:.6g}, {:.6g})".format(*first[np.lexsort(first[:, :2].T)[0]])
        raise ValueError(
            f"The level set is NaN or inf at {count} node(s), e.g. at x = {where}: give one "
            "that is finite on the whole mesh"
        )
    lo = comm.allreduce(values.min(initial=np.inf), op=MPI.MIN)
    hi = comm.allreduce(values.max(initial=-np.inf), op=MPI.MAX)
    # Canonical nodal values. A node shared by several cells is interpolated from one
    # of them, which one depending on the cell numbering (so on the number of
    # processes), and a node on the zero line then gets +-1e-17 by round-off: the sign
    # decides whether a cell touching the interface at that node is cut (a sliver of
    # length 1e-9 appeared on 1 rank and not on 2, moving the multipliers by 2e-8).
    # Values within a few ulps of the level set's scale are zero (side +1), and ghosts
    # take their owner's value.
    values[np.abs(values) <= ZERO_TOLERANCE * max(abs(lo), abs(hi))] = 0.0
    phi.x.scatter_forward()
    if lo >= 0.0:
        raise ValueError(
            f"The interface does not cross the mesh: its level set never crosses zero (it "
            f"is >= 0 at every node, from {lo:.6g} to {hi:.6g}), so no node lies inside it. "
            "Move or enlarge the interface, or refine the mesh, so that it crosses the mesh"
        )
    if hi < 0.0:
        raise ValueError(
            f"The interface does not cross the mesh: its level set never crosses zero (it "
            f"is < 0 at every node, from {lo:.6g} to {hi:.6g}), so every node lies inside "
            "it. Move or shrink the interface so that it crosses the mesh"
        )
    if into is not None:
        into.x.array[:] = phi.x.array
        phi = into
    return LevelSet(phi, exact)


class CellMaps:
    """Evaluate geometry and level-set data at reference points of given cells.

    All methods take ``cells`` (m,) local cell indices and ``X`` (m, tdim)
    reference points, one point per row, and are vectorised.
    """

    def __init__(self, mesh: dolfinx.mesh.Mesh, levelset: LevelSet):
        self.mesh = mesh
        cmap = mesh.geometry.cmaps[0]
        self._cmap = basix.create_element(
            basix.ElementFamily.P, mesh.basix_cell(), cmap.degree, cmap.variant
        )
        self._gdim = mesh.geometry.dim
        self._geom = mesh.geometry.x[mesh.geometry.dofmaps[0], : self._gdim]
        space = levelset.function.function_space
        self._phi_element = space.element.basix_element
        self._phi = levelset.function.x.array[space.dofmap.list]
        self._exact = levelset.exact

    @property
    def coordinate_element(self) -> basix.finite_element.FiniteElement:
        """The scalar Basix element of the cell maps (the mesh's coordinate element)."""
        return self._cmap

    def cell_nodes(self, cells: npt.NDArray[np.int32]) -> npt.NDArray[np.float64]:
        """Geometry nodes of cells, shape ``(len(cells), ndofs, gdim)`` (m)."""
        return self._geom[cells]

    def nodal_values(self, cells: npt.NDArray[np.int32]) -> npt.NDArray[np.float64]:
        """Level-set nodal values in basix order, shape ``(len(cells), ndofs)``."""
        return self._phi[cells]

    def push_forward(self, cells, X) -> npt.NDArray[np.float64]:
        """Physical points ``x = F_cell(X)``, shape ``(m, gdim)``."""
        basis = self._cmap.tabulate(0, X)[0, :, :, 0]
        return np.matmul(basis[:, None, :], self._geom[cells])[:, 0]  # BLAS, not einsum

    def push_forward_lattice(self, cells, X) -> npt.NDArray[np.float64]:
        """``x = F_cell(X_k)`` for the same reference points ``X`` (k, tdim) in every
        cell (the map tabulated once), shape ``(len(cells) * k, gdim)``, cell by cell."""
        basis = self._cmap.tabulate(0, X)[0, :, :, 0]  # (k, ndofs)
        return np.einsum("ki,cid->ckd", basis, self._geom[cells]).reshape(-1, self._gdim)

    def jacobian_lattice(self, cells, X) -> npt.NDArray[np.float64]:
        """Jacobians ``dx/dX`` at the same reference points ``X`` (k, tdim) in every cell
        (the map tabulated once), shape ``(len(cells) * k, gdim, tdim)``, cell by cell."""
        tab = self._cmap.tabulate(1, X)[1:, :, :, 0]  # (tdim, k, ndofs)
        J = np.matmul(tab[None], self._geom[cells][:, None])  # (cells, tdim, k, gdim)
        return J.transpose(0, 2, 3, 1).reshape(-1, self._gdim, tab.shape[0])

    def jacobian(self, cells, X) -> npt.NDArray[np.float64]:
        """Jacobians ``dx/dX`` of the cell maps, shape ``(m, gdim, tdim)``."""
        tab = self._cmap.tabulate(1, X)[1:, :, :, 0]  # (tdim, m, ndofs)
        return np.matmul(self._geom[cells].transpose(0, 2, 1), tab.transpose(1, 2, 0))

    def values(self, cells, X) -> npt.NDArray[np.float64]:
        """The interpolated level set at the points, shape ``(m,)``."""
        tab = self._phi_element.tabulate(0, X)[0, :, :, 0]
        return np.einsum("pi,pi->p", tab, self._phi[cells])

    def grad_ref(self, cells, X) -> npt.NDArray[np.float64]:
        """Reference gradient of the interpolated level set, shape ``(m, tdim)``."""
        tab = self._phi_element.tabulate(1, X)[1:, :, :, 0]
        return np.einsum("kpi,pi->pk", tab, self._phi[cells])

    def exact(self, cells) -> Callable | None:
        """The exact level set as a function of ``(rows, X)`` for the given cells, if known."""
        if self._exact is None:
            return None

        def phi(rows: np.ndarray, X: np.ndarray) -> np.ndarray:
            x = self._exact_points(cells[rows], X)
            x3 = np.zeros((3, x.shape[0]))
            x3[: self._gdim] = x.T
            values = _values(self._exact, x3, self._gdim)
            bad = np.flatnonzero(~np.isfinite(values))
            if bad.size:
                where = ", ".join(f"{v:.6g}" for v in x3[: self._gdim, bad[0]])
                raise ValueError(
                    f"The level set is NaN or inf at x = ({where}), a point of a cut cell "
                    "(or next to one, where its gradient is taken): give one that is finite "
                    "on and around the mesh"
                )
            return values

        return phi

    def _exact_points(self, cells, X) -> npt.NDArray[np.float64]:
        """``x = F_cell(X)`` where the exact level set is evaluated, shape ``(m, gdim)``: on
        straight tetrahedra and hexahedra by the closed-form vertex functions, summed node
        by node, so that a point gets the same bits whatever the other points of the batch
        (Basix's tabulation of a batch differs by ulps with its size, which the gradient's
        central differences would amplify into a partition-dependent rule)."""
        if self._gdim < 3 or self._cmap.degree != 1:
            return self.push_forward(cells, X)
        N = _vertex_basis(self.mesh.topology.cell_name(), X)
        nodes = self._geom[cells]
        x = N[:, :1] * nodes[:, 0]
        for i in range(1, N.shape[1]):
            x += N[:, i : i + 1] * nodes[:, i]
        return x


def union(
    mesh: dolfinx.mesh.Mesh, levelsets: dict[str, LevelSetCallable], degree: int
) -> LevelSetCallable:
    """One level set for several interfaces: ``min_i phi_i``, negative inside any. Collective.

    The interfaces must be apart: no mesh node inside two of them (nested or
    intersecting interfaces) and no cell cut by two (the minimum would bend the
    interface inside that cell). Each is checked on its interpolant of ``degree``.

    Args:
        mesh: The mesh.
        levelsets: Level-set callables by interface name.
        degree: Interpolation degree (1 or 2) used for the checks.

    Raises:
        InterfaceError: naming the interface that does not cross the mesh, or the
            second of two interfaces whose insides overlap or that cut the same cells.
    """
    names = list(levelsets)
    inside, cut = {}, {}
    for name in names:
        try:
            phi = interpolate(mesh, levelsets[name], degree).function
        except ValueError as error:
            raise InterfaceError(name, str(error)) from None
        values = phi.x.array
        owned = phi.function_space.dofmap.index_map.size_local
        inside[name] = values[:owned] < 0.0
        num_cells = mesh.topology.index_map(mesh.topology.dim).size_local
        nodal = values[phi.function_space.dofmap.list[:num_cells]]
        cut[name] = (nodal.min(axis=1) < 0.0) & (nodal.max(axis=1) >= 0.0)
    comm = mesh.comm
    for i, a in enumerate(names):
        for b in names[i + 1 :]:
            if comm.allreduce(int(np.count_nonzero(inside[a] & inside[b])), op=MPI.SUM):
                raise InterfaceError(
                    b,
                    f"overlaps interface {a!r} (mesh nodes lie inside both): nested or "
                    "intersecting interfaces are not supported",
                )
            shared = comm.allreduce(int(np.count_nonzero(cut[a] & cut[b])), op=MPI.SUM)
            if shared:
                raise InterfaceError(
                    b,
                    f"cuts the same {shared} cell(s) as interface {a!r}: keep at least one "
                    "cell between them (refine the mesh or move them apart)",
                )
    functions = [levelsets[name] for name in names]

    def phi(x: np.ndarray) -> np.ndarray:
        return np.minimum.reduce([np.asarray(f(x), dtype=np.float64) for f in functions])

    return phi


def named_interfaces(
    mesh: dolfinx.mesh.Mesh, levelset, degree: int, known: tuple[str, ...] | None = None
) -> tuple[tuple[str, ...], dict | None, typing.Any]:
    """The interfaces of a level set given to a cut: one (named ``"interface"``) for a
    callable or a Function, or those of a mapping ``{name: callable}``, cut as their
    :func:`union` (collective then). ``known``: the names of an earlier cut of the same
    mesh, which the new level set must repeat.

    Returns:
        ``(names, components, levelset)``: the names, the mapping (``None`` for a single
        level set) and the level set to interpolate.
    """
    if not isinstance(levelset, Mapping):
        if known not in (None, ("interface",)):
            raise ValueError(
                f"This CutMesh has the interfaces {list(known)}: "
                "update() takes a mapping of their level sets"
            )
        return ("interface",), None, levelset
    components = dict(levelset)
    names = tuple(components)
    if not names:
        raise ValueError("Give at least one interface level set")
    if known is not None and names != known:
        raise ValueError(f"update() needs the interfaces {list(known)}, got {list(names)}")
    one = components[names[0]] if len(names) == 1 else union(mesh, components, degree)
    return names, components, one
