"""Meshes from gmsh files: ``.geo`` geometries (meshed here) and ``.msh`` meshes.

Boundary parts are the names of the file's 1-D physical groups; the cells are those
of its 2-D physical groups (DOLFINx keeps only cells that lie in a physical group).

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
DEGREES = (1, 2)

# gmsh element type -> (cell, geometry degree) accepted by read_gmsh
_CELL_TYPES = {
    2: ("triangle", 1),
    9: ("triangle", 2),
    3: ("quadrilateral", 1),
    10: ("quadrilateral", 2),
}
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


class GmshMesh(NamedTuple):
    """A mesh read from gmsh with its physical groups.

    ``facet_tags`` values are the tags of the 1-D physical groups (an empty MeshTags
    if there are none); ``cell_tags`` those of the 2-D groups; ``parts`` maps the
    names of the 1-D groups to their tags.
    """

    mesh: dolfinx.mesh.Mesh
    facet_tags: dolfinx.mesh.MeshTags
    cell_tags: dolfinx.mesh.MeshTags
    parts: dict[str, int]


def physical_parts(path: str | Path) -> dict[str, int]:
    """Names -> tags of the 1-D physical groups (boundary parts) of a .geo or .msh file.

    No meshing: gmsh only reads the file (parses a .geo). Serial, for validation.
    Raises FileNotFoundError, or ValueError when the suffix is not .geo/.msh, gmsh
    cannot read the file (with gmsh's message), or the file has no 2-D physical group
    or a surface (of a .msh: holding cells) in none or several of them.
    """
    path = _check_path(path)
    with _gmsh_session() as gmsh:
        _load(gmsh, path)
        return _parts(gmsh, meshed=path.suffix.lower() == ".msh")


def read_gmsh(
    path: str | Path,
    comm: MPI.Comm,
    geometry_degree: int = 1,
    cell: str = "triangle",
    size: float | None = None,
) -> GmshMesh:
    """Mesh (gdim 2) of a .geo geometry or a .msh mesh, distributed over ``comm``.

    A .geo is meshed by gmsh on rank 0 with cells of ``geometry_degree`` (2: 6-node
    triangles or 9-node quadrilaterals whose edge nodes lie on the curved boundary),
    ``cell`` "triangle" or "quadrilateral" (recombined) and, if given, ``size`` (m):
    the characteristic length of every geometry point, also the largest cell size
    (fields of the .geo may refine further). For a .msh the file's cells are used as
    they are and ``geometry_degree``/``cell``/``size`` are ignored; they must be
    triangles or quadrilaterals (complete 9-node ones at degree 2), one kind only,
    in the plane z = 0. Collective; errors are raised on every rank.
    """
    if geometry_degree not in DEGREES:
        raise ValueError(f"geometry_degree must be one of {DEGREES}, got {geometry_degree!r}")
    if cell not in CELLS:
        raise ValueError(f"cell must be one of {CELLS}, got {cell!r}")
    if size is not None and not (np.isfinite(size) and size > 0):
        raise ValueError(f"size must be a positive length, got {size!r}")
    import dolfinx.io.gmsh

    from xfem_contact.io.meshes import ghosted_partitioner

    partitioner = ghosted_partitioner()
    root = 0
    if comm.rank != root:
        _raise_shared(comm.bcast(None, root=root))
        data = dolfinx.io.gmsh.model_to_mesh(None, comm, root, gdim=2, partitioner=partitioner)
        parts = comm.bcast(None, root=root)
    else:
        with contextlib.ExitStack() as stack:
            error = None
            try:
                gmsh = stack.enter_context(_gmsh_session())
                path = _check_path(path)
                _load(gmsh, path)
                parts = _parts(gmsh, meshed=path.suffix.lower() == ".msh")
                if path.suffix.lower() == ".geo":
                    _generate(gmsh, geometry_degree, cell, size)
                _check_mesh(gmsh, path)
            except Exception as e:  # every rank raises it
                error = e
            _raise_shared(comm.bcast(error, root=root))
            data = dolfinx.io.gmsh.model_to_mesh(
                gmsh.model, comm, root, gdim=2, partitioner=partitioner
            )
        parts = comm.bcast(parts, root=root)
    mesh = data.mesh
    assert mesh.geometry.dim == 2
    tdim = mesh.topology.dim
    facet_tags = data.facet_tags
    if facet_tags is None:  # no 1-D physical group
        none = np.zeros(0, dtype=np.int32)
        facet_tags = dolfinx.mesh.meshtags(mesh, tdim - 1, none, none)
    return GmshMesh(mesh, facet_tags, data.cell_tags, parts)


def facets(gm: GmshMesh, name: str) -> np.ndarray:
    """Local indices of the facets of the boundary part ``name`` (a 1-D physical group)."""
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


def _parts(gmsh, meshed: bool) -> dict[str, int]:
    """1-D group names -> tags of the current model; checks that its surfaces (if
    ``meshed``, those with cells) are in exactly one 2-D group."""
    groups = gmsh.model.getPhysicalGroups()
    if not any(dim == 2 for dim, _ in groups):
        raise ValueError(f"The gmsh file has no 2-D physical group: {_NO_CELLS}")
    count: dict[int, int] = {}
    for _, tag in gmsh.model.getPhysicalGroups(2):
        for entity in gmsh.model.getEntitiesForPhysicalGroup(2, tag):
            count[int(entity)] = count.get(int(entity), 0) + 1
    surfaces = [int(t) for _, t in gmsh.model.getEntities(2)]
    if meshed:  # only the surfaces holding cells matter
        surfaces = [t for t in surfaces if any(map(len, gmsh.model.mesh.getElements(2, t)[1]))]
    if missing := [s for s in surfaces if s not in count]:
        raise ValueError(f"Surfaces {missing} are in no 2-D physical group: {_NO_CELLS}")
    if twice := [s for s in surfaces if count[s] > 1]:
        raise ValueError(f"Surfaces {twice} are in several 2-D physical groups (one allowed)")
    return {
        gmsh.model.getPhysicalName(1, t): int(t)
        for _, t in gmsh.model.getPhysicalGroups(1)
        if gmsh.model.getPhysicalName(1, t)
    }


def _generate(gmsh, degree: int, cell: str, size: float | None) -> None:
    """Mesh the current (.geo) model in 2-D."""
    if size is not None:
        gmsh.model.mesh.setSize(gmsh.model.getEntities(0), size)
        gmsh.option.setNumber("Mesh.MeshSizeMax", size)
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


def _check_mesh(gmsh, path: Path) -> None:
    """The current model's mesh is one supported kind of cell in the plane z = 0, with
    nodes numbered 1..n (as DOLFINx's reader needs)."""
    types = [int(t) for t in gmsh.model.mesh.getElementTypes(2)]
    names = [gmsh.model.mesh.getElementProperties(t)[0] for t in types]
    if not types:
        raise ValueError(f"{path}: the mesh has no 2-D cells")
    if len(types) > 1:
        raise ValueError(f"{path}: mixed cells {names} are not supported (one kind only)")
    if types[0] not in _CELL_TYPES:
        raise ValueError(
            f"{path}: {names[0]} cells are not supported; use 3- or 6-node triangles or "
            "4- or 9-node quadrilaterals (not 8-node serendipity ones)"
        )
    gmsh.model.mesh.renumberNodes()
    gmsh.model.mesh.renumberElements()
    _, x, _ = gmsh.model.mesh.getNodes()
    z = np.asarray(x).reshape(-1, 3)[:, 2]
    if z.size and np.abs(z).max() > 1e-12 * max(1.0, np.abs(x).max()):
        raise ValueError(
            f"{path}: the mesh is not in the plane z = 0 (max |z| = {np.abs(z).max()})"
        )
