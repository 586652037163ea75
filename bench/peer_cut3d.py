"""Volume and area of a sphere, a torus and an ellipsoid by our 3D cut rules and by the
isoparametric peer (ngsxfem), on the same meshes.

Relative errors of the volume and area of a sphere (``R = 0.3``), a torus (``R = 0.3``,
``r = 0.12``, axis z) and an ellipsoid (semi-axes 0.35 / 0.25 / 0.15), centred in the unit
cube, on unstructured tetrahedra (gmsh), structured tetrahedra and structured hexahedra
(``create_unit_cube``). Every mesh is written to a gmsh file that both codes read. Ours is
``CutMesh(mesh, level_set, degree)`` with a callable and ``assemble_scalar`` of
``1 * cut.dx(-1)`` and ``1 * cut.dGamma``. The peer's order 2 is ``LevelSetMeshAdaptation``
(P2 level set, uncapped deformation of the mesh) and its order 1 the cut of the P1 level
set. Each code runs in its own process, timed as a whole (start-up, mesh, cut, integrals).
For the peer, the smallest ``det(I + grad d)`` of its deformation ``d`` at the points of
a degree-6 rule in every cell, and the largest ``|d| / h``, show where it tangles. The
peer is optional and never a dependency of the package: ``make bench-peer`` creates
``bench/.peer-venv`` (``pip install xfem ngsolve``) and runs
``python bench/peer_cut3d.py --peer-python bench/.peer-venv/bin/python``; ``make bench``
runs it when that environment exists.
"""

from __future__ import annotations

import argparse
import functools
import json
import math
import pathlib
import subprocess
import sys
import tempfile
import time

import numpy as np

RESULTS = pathlib.Path(__file__).resolve().parent / "results"
CENTRE = (0.5, 0.5, 0.5)
TORUS = (0.3, 0.12)  # major, minor radius (m)
AXES = (0.35, 0.25, 0.15)  # ellipsoid semi-axes (m)
SPHERE = 0.3  # radius (m)
#: The peer's quadrature degree (its errors change by under 1 % from 4 to 8; 2 is too low)
QUADRATURE_DEGREE = 6
SHAPES = ("sphere", "torus", "ellipsoid")
KINDS = ("unstructured-tet", "structured-tet", "structured-hex")
#: gmsh vertex order of a hexahedron from DOLFINx's (tensor-product) order
GMSH_HEX = [0, 1, 3, 2, 4, 5, 7, 6]


def ellipsoid_area(axes: tuple[float, float, float], n: int = 2000) -> float:
    """Area of the ellipsoid with semi-axes ``axes`` (m^2): Gauss-Legendre in the polar
    angle, the trapezoidal rule (spectral for a periodic integrand) in the azimuth."""
    a, b, c = axes
    s, w = np.polynomial.legendre.leggauss(n)
    theta = 0.5 * np.pi * (s + 1.0)
    phi = np.linspace(0.0, 2.0 * np.pi, 2 * n, endpoint=False)
    T, P = np.meshgrid(theta, phi, indexing="ij")
    sin2, cos2 = np.sin(T) ** 2, np.cos(T) ** 2
    norm = np.sin(T) * np.sqrt(
        b**2 * c**2 * sin2 * np.cos(P) ** 2
        + a**2 * c**2 * sin2 * np.sin(P) ** 2
        + a**2 * b**2 * cos2
    )
    return float(0.5 * np.pi * (w @ norm.sum(axis=1)) * (2.0 * np.pi / (2 * n)))


@functools.cache
def exact(shape: str) -> tuple[float, float]:
    """Volume (m^3) and area (m^2) of ``shape``."""
    if shape == "sphere":
        return 4.0 / 3.0 * math.pi * SPHERE**3, 4.0 * math.pi * SPHERE**2
    if shape == "torus":
        big, small = TORUS
        return 2.0 * math.pi**2 * big * small**2, 4.0 * math.pi**2 * big * small
    return 4.0 / 3.0 * math.pi * math.prod(AXES), ellipsoid_area(AXES)


def level_set(shape: str, x, sqrt):
    """The level set of ``shape`` at coordinates ``x = (x, y, z)``, negative inside, from
    ``sqrt``: numpy arrays for us, CoefficientFunctions for the peer."""
    dx, dy, dz = (x[k] - CENTRE[k] for k in range(3))
    if shape == "sphere":
        return sqrt(dx * dx + dy * dy + dz * dz) - SPHERE
    if shape == "torus":
        ring = sqrt(dx * dx + dy * dy) - TORUS[0]
        return sqrt(ring * ring + dz * dz) - TORUS[1]
    a, b, c = AXES
    return (sqrt((dx / a) ** 2 + (dy / b) ** 2 + (dz / c) ** 2) - 1.0) * min(AXES)


# --- meshes (our venv) ---------------------------------------------------------------------


def write_msh(path: pathlib.Path, points: np.ndarray, cells: np.ndarray, gmsh_type: int) -> None:
    """A gmsh 2.2 ASCII file of ``points`` ``(n, 3)`` and ``cells`` ``(m, k)`` (0-based, gmsh
    vertex order) in physical volume 1."""
    lines = ["$MeshFormat", "2.2 0 8", "$EndMeshFormat", "$PhysicalNames", "1", '3 1 "domain"']
    lines += ["$EndPhysicalNames", "$Nodes", str(len(points))]
    lines += [f"{i + 1} " + " ".join(map(repr, p)) for i, p in enumerate(points.tolist())]
    lines += ["$EndNodes", "$Elements", str(len(cells))]
    lines += [
        f"{i + 1} {gmsh_type} 2 1 1 " + " ".join(str(v + 1) for v in c) for i, c in enumerate(cells)
    ]
    lines += ["$EndElements", ""]
    path.write_text("\n".join(lines))


def make_mesh(kind: str, n: int, folder: pathlib.Path) -> pathlib.Path:
    """The gmsh file of ``kind`` at ``h = 1/n`` in ``folder``."""
    path = folder / f"{kind}-{n}.msh"
    if kind == "unstructured-tet":
        import gmsh

        gmsh.initialize(readConfigFiles=False, interruptible=False)
        try:
            gmsh.option.setNumber("General.Terminal", 0)
            gmsh.model.add("cube")
            gmsh.model.occ.addBox(0, 0, 0, 1, 1, 1)
            gmsh.model.occ.synchronize()
            gmsh.model.addPhysicalGroup(3, [1], 1, "domain")
            gmsh.option.setNumber("Mesh.MeshSizeMax", 1.0 / n)
            gmsh.option.setNumber("Mesh.MeshSizeMin", 1.0 / n)
            gmsh.model.mesh.generate(3)
            gmsh.option.setNumber("Mesh.MshFileVersion", 2.2)
            gmsh.write(str(path))
        finally:
            gmsh.finalize()
        return path
    import dolfinx.mesh
    from mpi4py import MPI

    cell = dolfinx.mesh.CellType.hexahedron if kind == "structured-hex" else None
    cell = cell or dolfinx.mesh.CellType.tetrahedron
    mesh = dolfinx.mesh.create_unit_cube(MPI.COMM_SELF, n, n, n, cell)
    cells = mesh.geometry.dofmaps[0]
    if kind == "structured-hex":
        write_msh(path, mesh.geometry.x, cells[:, GMSH_HEX], 5)
    else:
        write_msh(path, mesh.geometry.x, cells, 4)
    return path


# --- the two sides ------------------------------------------------------------------------


def run_ours(path: pathlib.Path, shape: str, order: int) -> dict:
    """Volume, area and phase times of our cut of ``shape`` on the mesh at ``path``."""
    import xfem_contact  # noqa: F401  (before dolfinx)

    # isort: split
    import dolfinx.fem
    import ufl
    from mpi4py import MPI

    from xfem_contact import CutMesh
    from xfem_contact.io.gmsh import read_gmsh

    start = time.perf_counter()
    mesh = read_gmsh(path, MPI.COMM_SELF).mesh
    read = time.perf_counter()
    cut = CutMesh(mesh, lambda x: level_set(shape, x, np.sqrt), degree=order)
    made = time.perf_counter()
    volume = dolfinx.fem.assemble_scalar(xfem_contact.form(1.0 * cut.dx(-1)))
    area = dolfinx.fem.assemble_scalar(xfem_contact.form(1.0 * cut.dGamma))
    done = time.perf_counter()
    del ufl
    return {
        "volume": float(volume),
        "area": float(area),
        "cells": int(mesh.topology.index_map(3).size_local),
        "read_s": read - start,
        "cut_s": made - read,
        "integrals_s": done - made,
    }


def run_peer(path: pathlib.Path, shape: str, order: int, h: float) -> dict:
    """Volume, area, phase times and deformation quality of the peer's cut of ``shape``."""
    import ngsolve
    from netgen.read_gmsh import ReadGmsh
    from xfem import IF, NEG, Integrate
    from xfem.lsetcurv import LevelSetMeshAdaptation

    start = time.perf_counter()
    mesh = ngsolve.Mesh(ReadGmsh(str(path)))
    read = time.perf_counter()
    phi = level_set(shape, (ngsolve.x, ngsolve.y, ngsolve.z), ngsolve.sqrt)
    adaptation = LevelSetMeshAdaptation(mesh, order=2)
    deformation = adaptation.CalcDeformation(phi)
    found = {"cells": mesh.ne}
    if order == 2:
        kind = ngsolve.ET.HEX if "hex" in path.name else ngsolve.ET.TET
        points = mesh.MapToAllElements(ngsolve.IntegrationRule(kind, 6), ngsolve.VOL)
        det = ngsolve.Det(ngsolve.Id(3) + ngsolve.Grad(deformation))(points)
        found["min_det"] = float(np.min(det))
        found["max_d_over_h"] = float(np.max(ngsolve.Norm(deformation)(points)) / h)
        mesh.SetDeformation(deformation)
    made = time.perf_counter()
    domain = {"levelset": adaptation.lset_p1, "domain_type": NEG}
    volume = Integrate(domain, cf=1, mesh=mesh, order=QUADRATURE_DEGREE)
    area = Integrate({**domain, "domain_type": IF}, cf=1, mesh=mesh, order=QUADRATURE_DEGREE)
    done = time.perf_counter()
    return found | {
        "volume": float(volume),
        "area": float(area),
        "read_s": read - start,
        "cut_s": made - read,
        "integrals_s": done - made,
    }


# --- the driver (our venv) ----------------------------------------------------------------


def worker(python: str, side: str, path, shape, order, h, timeout) -> dict:
    """Run one side in a process of ``python``; its result with ``process_s`` (wall time
    of the whole process), or ``{"error": ...}``."""
    command = [python, __file__, "--worker", side, str(path), shape, str(order), repr(h)]
    start = time.perf_counter()
    try:
        done = subprocess.run(command, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return {"error": f"timeout after {timeout} s"}
    elapsed = time.perf_counter() - start
    lines = [line for line in done.stdout.splitlines() if line.startswith("{")]
    if done.returncode or not lines:
        tail = (done.stderr.strip().splitlines() or ["no output"])[-1]
        return {"error": f"exit {done.returncode}: {tail}"}
    return json.loads(lines[-1]) | {"process_s": elapsed}


def errors(result: dict, shape: str) -> tuple[float, float] | None:
    if "error" in result:
        return None
    volume, area = exact(shape)
    return abs(result["volume"] - volume) / volume, abs(result["area"] - area) / area


def table(rows: list[dict]) -> list[str]:
    """Markdown lines of the comparison; rates of each code from the previous size."""
    head = (
        "| mesh | shape | order | h | cells | ours volume | peer volume | ratio | ours area | "
        "peer area | ratio | ours rates (V, A) | peer rates (V, A) | peer min det | "
        "peer max d/h | ours time (s) | peer time (s) |"
    )
    lines = [head, "|" + " --- |" * 17]
    previous: dict = {}
    for row in rows:
        key = (row["mesh"], row["shape"], row["order"])
        ours, peer = errors(row["ours"], row["shape"]), errors(row["peer"], row["shape"])
        rates = []
        for side, err in (("ours", ours), ("peer", peer)):
            last = previous.get((*key, side))
            if err is None or last is None or min(err) == 0.0:
                rates.append("")
            else:
                ratio = row["n"] / last[0]
                rates.append(
                    ", ".join(
                        f"{math.log(last[1][k] / err[k]) / math.log(ratio):.2f}" for k in (0, 1)
                    )
                )
            if err is not None:
                previous[(*key, side)] = (row["n"], err)

        def num(value, fmt=".2e"):
            return "-" if value is None else format(value, fmt)

        def ratio(k, ours=ours, peer=peer):
            if ours is None or peer is None or peer[k] == 0.0:
                return "-"
            return f"{ours[k] / peer[k]:.2g}"

        cells = row["ours"].get("cells", row["peer"].get("cells", "-"))
        lines.append(
            f"| {row['mesh']} | {row['shape']} | {row['order']} | 1/{row['n']} | {cells} | "
            f"{num(ours and ours[0])} | {num(peer and peer[0])} | {ratio(0)} | "
            f"{num(ours and ours[1])} | {num(peer and peer[1])} | {ratio(1)} | "
            f"{rates[0]} | {rates[1]} | {num(row['peer'].get('min_det'), '.3g')} | "
            f"{num(row['peer'].get('max_d_over_h'), '.3g')} | "
            f"{num(row['ours'].get('process_s'), '.1f')} | "
            f"{num(row['peer'].get('process_s'), '.1f')} |"
        )
    return lines


def tangled(rows: list[dict]) -> list[str]:
    """Markdown lines: the order-2 rows where the peer's deformation tangles
    (``det(I + grad d) <= 0``), the peer fails or misses half the volume, with both
    codes' volumes."""
    lines = [
        "Order 2 where the peer's deformation tangles (`det(I + grad d) <= 0`), the peer",
        "fails or it misses half of the volume (volumes in m^3):",
        "",
        "| mesh | shape | h | exact volume | ours volume | peer volume | peer min det | "
        "peer max d/h |",
        "|" + " --- |" * 8,
    ]
    for row in rows:
        peer = row["peer"]
        lost = "volume" in peer and peer["volume"] < 0.5 * exact(row["shape"])[0]
        if row["order"] != 2 or (peer.get("min_det", 0.0) > 0.0 and not lost):
            continue

        def volume(result):
            return f"{result['volume']:.4g}" if "volume" in result else "failed"

        lines.append(
            f"| {row['mesh']} | {row['shape']} | 1/{row['n']} | {exact(row['shape'])[0]:.4g} | "
            f"{volume(row['ours'])} | {volume(peer)} | {peer.get('min_det', '-'):.3g} | "
            f"{peer.get('max_d_over_h', '-'):.3g} |"
            if "min_det" in peer
            else f"| {row['mesh']} | {row['shape']} | 1/{row['n']} | "
            f"{exact(row['shape'])[0]:.4g} | {volume(row['ours'])} | {volume(peer)} | - | - |"
        )
    return [*lines, ""]


def failures(rows: list[dict]) -> list[str]:
    """Markdown lines: the runs that failed or timed out, one each."""
    lines = []
    for row in rows:
        for side in ("ours", "peer"):
            if "error" in row[side]:
                lines.append(
                    f"- {side}, {row['mesh']}, {row['shape']}, order {row['order']}, "
                    f"h = 1/{row['n']}: {row[side]['error']}"
                )
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--peer-python", default="bench/.peer-venv/bin/python")
    parser.add_argument("--sizes", type=int, nargs="+", default=[4, 8, 16, 32, 64])
    parser.add_argument("--kinds", nargs="+", default=list(KINDS), choices=KINDS)
    parser.add_argument("--shapes", nargs="+", default=list(SHAPES), choices=SHAPES)
    parser.add_argument("--orders", type=int, nargs="+", default=[2, 1], choices=[1, 2])
    parser.add_argument("--timeout", type=float, default=900.0, help="per process (s)")
    parser.add_argument("--name", default="peer_cut3d", help="bench/results/NAME.{json,md}")
    parser.add_argument(
        "--add", action="store_true", help="add the rows to (or replace them in) NAME.json"
    )
    parser.add_argument("--worker", nargs=5, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.worker:
        side, path, shape, order, h = args.worker
        run = run_ours if side == "ours" else run_peer
        extra = () if side == "ours" else (float(h),)
        print(json.dumps(run(pathlib.Path(path), shape, int(order), *extra)))
        return
    if not pathlib.Path(args.peer_python).is_file():
        raise SystemExit(f"--peer-python: {args.peer_python} not found; run `make bench-peer`")
    rows = []
    if args.add:
        rows = json.loads((RESULTS / f"{args.name}.json").read_text())
    with tempfile.TemporaryDirectory() as folder:
        for n in args.sizes:
            for kind in args.kinds:
                path = make_mesh(kind, n, pathlib.Path(folder))
                for shape in args.shapes:
                    for order in args.orders:
                        row = {"mesh": kind, "n": n, "shape": shape, "order": order}
                        rows = [r for r in rows if {k: r[k] for k in row} != row]
                        for side, python in (("ours", sys.executable), ("peer", args.peer_python)):
                            row[side] = worker(
                                python, side, path, shape, order, 1.0 / n, args.timeout
                            )
                        rows.append(row)
                        print(table([row])[-1], flush=True)
                        save(rows, args.name)
    print((RESULTS / f"{args.name}.md").read_text())


def save(rows: list[dict], name: str) -> None:
    """Write the rows so far to ``bench/results/NAME.{json,md}``."""
    rows = sorted(rows, key=lambda r: (r["mesh"], r["shape"], -r["order"], r["n"]))
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / f"{name}.json").write_text(json.dumps(rows, indent=1) + "\n")
    text = legend() + table(rows) + [""] + tangled(rows) + failures(rows)
    (RESULTS / f"{name}.md").write_text("\n".join(text) + "\n")


def legend() -> list[str]:
    """Markdown lines: what the columns of :func:`table` hold."""
    values = [f"{s} {exact(s)[0]:.10g} m^3 / {exact(s)[1]:.10g} m^2" for s in SHAPES]
    return [
        f"Exact volumes / areas: {', '.join(values)}",
        "(the ellipsoid's area by a 2000 x 4000-point",
        "product rule). Errors are relative. A ratio is ours / peer's (below 1: ours is",
        "closer). Rates are from the previous h of the same mesh, shape and order. The",
        "peer's order 2 deforms the mesh by `d`; a negative smallest `det(I + grad d)`",
        "means tangled cells, and `max d/h` is its largest displacement in cell sizes.",
        "Times are wall times of each whole process (start-up, reading the mesh, the cut",
        f"and both integrals; the peer integrates with its degree {QUADRATURE_DEGREE}),",
        "on a shared host. A row without a result failed; the reason is listed below it.",
        "",
    ]


if __name__ == "__main__":
    main()
