"""Meshes from gmsh files: ``.geo`` geometries (meshed here) and ``.msh`` meshes, in 2D
(triangles, quadrilaterals) and 3D (tetrahedra, hexahedra).

A file is 3D when it has volumes, else 2D. Boundary parts are the names of the file's
physical groups of dimension ``d - 1``; the cells are those of its ``d``-dimensional
physical groups (DOLFINx keeps only cells that lie in a physical group).

gmsh runs on one rank only; :func:`read_gmsh` distributes the mesh. A gmsh session
already opened by the caller is left open (a scratch model is used and removed, and
the options changed here are restored); otherwise one is opened and closed here.
"""

from __future__ import annotations

import contextlib
import uuid
from collections.abc import Iterator
from pathlib import Path
from typing import NamedTuple

import dolfinx.mesh
import numpy as np
from mpi4py import MPI

SUFFIXES = (".geo", ".msh")
CELLS = ("triangle", "quadrilateral")
CELLS_3D = ("tetrahedron", "hexahedron")
DEGREES = (1, 2)

# gmsh element type -> (cell, geometry degree) accepted by read_gmsh
_CELL_TYPES = {
    2: ("triangle", 1),
    9: ("triangle", 2),
    3: ("quadrilateral", 1),
    10: ("quadrilateral", 2),
    4: ("tetrahedron", 1),
    11: ("tetrahedron", 2),
    5: ("hexahedron", 1),
    12: ("hexahedron", 2),
}
_SUPPORTED = {
    2: "3- or 6-node triangles or 4- or 9-node quadrilaterals (not 8-node serendipity ones)",
    3: "4- or 10-node tetrahedra or 8- or 27-node hexahedra (not 20-node serendipity ones)",
}
_ENTITIES = {2: "Surfaces", 3: "Volumes"}
# Options set here; restored afterwards when the caller owns the gmsh session.
_OPTIONS = (
    "General.Terminal",
    "Mesh.Algorithm",
    "Mesh.RecombineAll",
    "Mesh.RecombinationAlgorithm",
    "Mesh.SecondOrderIncomplete",
    "Mesh.MeshSizeMax",
)
_NO_CELLS = (
    "DOLFINx keeps only the cells of physical groups, so the mesh would be empty: "
    'add e.g. Physical Surface("plate") = {...}; to the .geo (or write the .msh with one)'
)
_NO_CELLS_3D = (
    "DOLFINx keeps only the cells of physical groups, so the mesh would be empty: "
    'add e.g. Physical Volume("body") = {...}; to the .geo (or write the .msh with one)'
)


class GmshMesh(NamedTuple):
    """A mesh read from gmsh with its physical groups.

    ``facet_tags`` values are the tags of the physical groups of the facets (1-D in 2D,
    2-D in 3D; an empty MeshTags if there are none); ``cell_tags`` those of the cells'
    groups; ``parts`` maps the names of the facets' groups to their tags.
    """

    mesh: dolfinx.mesh.Mesh
    facet_tags: dolfinx.mesh.MeshTags
    cell_tags: dolfinx.mesh.MeshTags
    parts: dict[str, int]


def physical_parts(path: str | Path) -> dict[str, int]:
    """Names -> tags of the boundary parts (physical groups of the facets: 1-D in 2D, 2-D
    in 3D) of a .geo or .msh file.

    No meshing: gmsh only reads the file (parses a .geo). Serial, for validation.
    Raises FileNotFoundError, or ValueError when the suffix is not .geo/.msh, gmsh
    cannot read the file (with gmsh's message), or the file has no physical group of
    cells (2-D; 3-D for a file with volumes) or a surface (volume; of a .msh: holding
    cells) in none or several of them.
    """
    path = _check_path(path)
    with _gmsh_session() as gmsh:
        _load(gmsh, path)
        return _parts(gmsh, meshed=path.suffix.lower() == ".msh", dim=_dimension(gmsh))


def read_gmsh(
    path: str | Path,
    comm: MPI.Comm,
    geometry_degree: int = 1,
    cell: str | None = None,
    size: float | None = None,
) -> GmshMesh:
    """Mesh (gdim 2, or 3 for a file with volumes) of a .geo geometry or a .msh mesh,
    distributed over ``comm``.

    A .geo is meshed by gmsh on rank 0 with cells of ``geometry_degree`` (2: 6-node
    triangles or 9-node quadrilaterals, 10-node tetrahedra or 27-node hexahedra, whose
    edge nodes lie on the curved boundary), ``cell`` "triangle" (the default in 2D) or
    "quadrilateral" (recombined), "tetrahedron" (the default in 3D) or "hexahedron" (the
    .geo must make hexahedra itself, e.g. by transfinite volumes with Recombine) and, if
    given, ``size`` (m): the characteristic length of every geometry point, also the
    largest cell size (fields of the .geo may refine further). For a .msh the file's cells
    are used as they are and ``geometry_degree``/``cell``/``size`` are ignored; they must
    be one kind of the cells above (complete ones at degree 2), in the plane z = 0 in 2D.
    Collective; errors are raised on every rank.
    """
    if geometry_degree not in DEGREES:
        raise ValueError(f"geometry_degree must be one of {DEGREES}, got {geometry_degree!r}")
    if cell is not None and cell not in CELLS + CELLS_3D:
        raise ValueError(f"cell must be one of {CELLS + CELLS_3D}, got {cell!r}")
    if size is not None and not (np.isfinite(size) and size > 0):
        raise ValueError(f"size must be a positive length, got {size!r}")
    import dolfinx.io.gmsh

    from xfem_contact.io.meshes import ghosted_partitioner

    partitioner = ghosted_partitioner()
    root = 0
    if comm.rank != root:
        _raise_shared(comm.bcast(None, root=root))
        dim = comm.bcast(None, root=root)
        data = dolfinx.io.gmsh.model_to_mesh(None, comm, root, gdim=dim, partitioner=partitioner)
        parts = comm.bcast(None, root=root)
    else:
        with contextlib.ExitStack() as stack:
            error, dim = None, 2
            try:
                gmsh = stack.enter_context(_gmsh_session())
                path = _check_path(path)
                _load(gmsh, path)
                dim = _dimension(gmsh)
                parts = _parts(gmsh, meshed=path.suffix.lower() == ".msh", dim=dim)
                if path.suffix.lower() == ".geo":
                    _generate(gmsh, geometry_degree, _cell(cell, dim), size, dim)
                _check_mesh(gmsh, path, dim)
            except Exception as e:  # every rank raises it
                error = e
            _raise_shared(comm.bcast(error, root=root))
            comm.bcast(dim, root=root)
            data = dolfinx.io.gmsh.model_to_mesh(
                gmsh.model, comm, root, gdim=dim, partitioner=partitioner
            )
        parts = comm.bcast(parts, root=root)
    mesh = data.mesh
    tdim = mesh.topology.dim
    facet_tags = data.facet_tags
    if facet_tags is None:  # no 1-D physical group
        none = np.zeros(0, dtype=np.int32)
        facet_tags = dolfinx.mesh.meshtags(mesh, tdim - 1, none, none)
    return GmshMesh(mesh, facet_tags, data.cell_tags, parts)


def facets(gm: GmshMesh, name: str) -> np.ndarray:
    """Local indices of the facets of the boundary part ``name`` (a physical group of the
    facets: 1-D in 2D, 2-D in 3D)."""
    if name not in gm.parts:
        raise ValueError(f"Unknown part {name!r}; the gmsh file has {sorted(gm.parts)}")
    return gm.facet_tags.find(gm.parts[name])


def _check_path(path: str | Path) -> Path:
    path = Path(path)
    if path.suffix.lower() not in SUFFIXES:
        raise ValueError(f"{path}: gmsh mesh files must be .geo or .msh, got {path.suffix!r}")
    if not path.is_file():
        raise FileNotFoundError(f"gmsh file not found: {path}")
    return path


def _raise_shared(error: Exception | None) -> None:
    if error is not None:
        raise error


@contextlib.contextmanager
def _gmsh_session() -> Iterator:
    """gmsh, silenced, with a fresh current model; the caller's session is kept."""
    import gmsh

    owned = not gmsh.isInitialized()
    if owned:
        gmsh.initialize(readConfigFiles=False, interruptible=False)
    else:
        previous = gmsh.model.getCurrent()
        options = {name: gmsh.option.getNumber(name) for name in _OPTIONS}
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        name = f"xfem_contact-{uuid.uuid4().hex}"
        gmsh.model.add(name)
        yield gmsh
    finally:
        if owned:
            gmsh.finalize()
        else:
            with contextlib.suppress(Exception):
                gmsh.model.setCurrent(name)
                gmsh.model.remove()
            with contextlib.suppress(Exception):
                gmsh.model.setCurrent(previous)
            for key, value in options.items():
                gmsh.option.setNumber(key, value)


def _load(gmsh, path: Path) -> None:
    """Read ``path`` into the current model; a gmsh failure becomes a ValueError."""
    try:
        gmsh.merge(str(path))
    except Exception as e:
        raise ValueError(f"gmsh cannot read {path}: {e}") from None


def _dimension(gmsh) -> int:
    """3 when the current model has volumes, else 2."""
    return 3 if gmsh.model.getEntities(3) else 2


def _cell(cell: str | None, dim: int) -> str:
    """The cell kind to mesh a ``dim``-dimensional .geo with (``None``: simplices)."""
    valid = CELLS if dim == 2 else CELLS_3D
    if cell is None:
        return valid[0]
    if cell not in valid:
        raise ValueError(f"cell must be one of {valid} for a {dim}-D geometry, got {cell!r}")
    return cell


def _parts(gmsh, meshed: bool, dim: int = 2) -> dict[str, int]:
    """Names -> tags of the ``dim - 1``-dimensional groups of the current model; checks
    that its ``dim``-dimensional entities (if ``meshed``, those with cells) are in exactly
    one ``dim``-dimensional group."""
    groups = gmsh.model.getPhysicalGroups()
    no_cells = _NO_CELLS if dim == 2 else _NO_CELLS_3D
    entities = _ENTITIES[dim]
    if not any(d == dim for d, _ in groups):
        raise ValueError(f"The gmsh file has no {dim}-D physical group: {no_cells}")
    count: dict[int, int] = {}
    for _, tag in gmsh.model.getPhysicalGroups(dim):
        for entity in gmsh.model.getEntitiesForPhysicalGroup(dim, tag):
            count[int(entity)] = count.get(int(entity), 0) + 1
    found = [int(t) for _, t in gmsh.model.getEntities(dim)]
    if meshed:  # only the entities holding cells matter
        found = [t for t in found if any(map(len, gmsh.model.mesh.getElements(dim, t)[1]))]
    if missing := [s for s in found if s not in count]:
        raise ValueError(f"{entities} {missing} are in no {dim}-D physical group: {no_cells}")
    if twice := [s for s in found if count[s] > 1]:
        raise ValueError(f"{entities} {twice} are in several {dim}-D physical groups (one allowed)")
    return {
        gmsh.model.getPhysicalName(dim - 1, t): int(t)
        for _, t in gmsh.model.getPhysicalGroups(dim - 1)
        if gmsh.model.getPhysicalName(dim - 1, t)
    }


def _generate(gmsh, degree: int, cell: str, size: float | None, dim: int = 2) -> None:
    """Mesh the current (.geo) model in ``dim`` dimensions."""
    if size is not None:
        gmsh.model.mesh.setSize(gmsh.model.getEntities(0), size)
        gmsh.option.setNumber("Mesh.MeshSizeMax", size)
    if dim == 3:
        try:
            gmsh.model.mesh.generate(3)
        except Exception as e:
            raise ValueError(f"gmsh cannot mesh the geometry: {e}") from None
        types = gmsh.model.mesh.getElementTypes(3)
        kinds = sorted({_CELL_TYPES.get(int(t), ("other",))[0] for t in types})
        if kinds != [cell]:
            hint = " (make the .geo recombine transfinite volumes)" if cell == "hexahedron" else ""
            raise ValueError(f"gmsh made {kinds} cells, not {cell}s only{hint}")
        gmsh.option.setNumber("Mesh.SecondOrderIncomplete", 0)  # 27-node hexahedra
        gmsh.model.mesh.setOrder(degree)
        return
    quads = cell == "quadrilateral"
    if quads:
        gmsh.option.setNumber("Mesh.Algorithm", 8)  # Frontal-Delaunay for quads
        gmsh.option.setNumber("Mesh.RecombineAll", 1)
    # Blossom recombination, then (if it left triangles) its full-quad variant
    for algorithm in (1, 3) if quads else (None,):
        if algorithm is not None:
            gmsh.option.setNumber("Mesh.RecombinationAlgorithm", algorithm)
        gmsh.model.mesh.clear()
        try:
            gmsh.model.mesh.generate(2)
        except Exception as e:
            raise ValueError(f"gmsh cannot mesh the geometry: {e}") from None
        types = gmsh.model.mesh.getElementTypes(2)
        kinds = sorted({_CELL_TYPES.get(int(t), ("other",))[0] for t in types})
        if kinds == [cell]:
            break
    else:
        hint = "" if quads else " (does the .geo recombine surfaces itself?)"
        raise ValueError(f"gmsh made {kinds} cells, not {cell}s only{hint}")
    gmsh.option.setNumber("Mesh.SecondOrderIncomplete", 0)  # 9-node quads
    gmsh.model.mesh.setOrder(degree)


def _check_mesh(gmsh, path: Path, dim: int = 2) -> None:
    """The current model's mesh is one supported kind of ``dim``-dimensional cell (in the
    plane z = 0 in 2D), with nodes numbered 1..n (as DOLFINx's reader needs)."""
    types = [int(t) for t in gmsh.model.mesh.getElementTypes(dim)]
    names = [gmsh.model.mesh.getElementProperties(t)[0] for t in types]
    if not types:
        raise ValueError(f"{path}: the mesh has no {dim}-D cells")
    if len(types) > 1:
        raise ValueError(f"{path}: mixed cells {names} are not supported (one kind only)")
    if types[0] not in _CELL_TYPES:
        raise ValueError(f"{path}: {names[0]} cells are not supported; use {_SUPPORTED[dim]}")
    gmsh.model.mesh.renumberNodes()
    gmsh.model.mesh.renumberElements()
    if dim == 3:
        return
    _, x, _ = gmsh.model.mesh.getNodes()
    z = np.asarray(x).reshape(-1, 3)[:, 2]
    if z.size and np.abs(z).max() > 1e-12 * max(1.0, np.abs(x).max()):
        raise ValueError(
            f"{path}: the mesh is not in the plane z = 0 (max |z| = {np.abs(z).max()})"
        )
