"""The ``xfem-contact`` command: run scenes, list the bundled ones, render results.

xfem-contact run SCENE.toml --out DIR [--quiet]   (also under mpiexec -n 2)
xfem-contact scenes
xfem-contact show DIR
xfem-contact --version                           (xfem-contact, DOLFINx, Basix, FFCx, UFL, PETSc)
"""

from __future__ import annotations

import argparse
import pathlib
import sys


def _run(args) -> int:
    from mpi4py import MPI

    from xfem_contact.scenes.run import run
    from xfem_contact.scenes.scene import bundled_scenes, load_scene

    path = pathlib.Path(args.scene)
    if not path.exists() and args.scene in bundled_scenes():
        path = bundled_scenes()[args.scene]
    scene = load_scene(path)
    out = pathlib.Path(args.out or f"results/{scene.name}")
    summary = run(scene, out, log=None if args.quiet else print)
    if MPI.COMM_WORLD.rank == 0 and not args.quiet:
        print(f"wrote {out}/summary.json")
    return 0 if summary else 1


def _scenes(args) -> int:
    import tomllib

    from xfem_contact.scenes.scene import bundled_scenes

    for name, path in bundled_scenes().items():
        with open(path, "rb") as f:
            description = tomllib.load(f).get("scene", {}).get("description", "")
        print(f"{name:28s} {description}")
    return 0


def _show(args) -> int:
    """Render a run folder: result.png, cut.png and pressure.png (those with data)."""
    from xfem_contact.io.pictures import render_folder

    try:
        render_folder(args.dir, log=print)
    except FileNotFoundError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    return 0


class _Version(argparse.Action):
    """``--version``: one ``name version`` line per package, then exit. An action
    rather than ``action="version"``, which would import DOLFINx for every command."""

    def __init__(self, option_strings, dest, **kwargs):
        kwargs.setdefault("help", "print the versions of xfem-contact and its stack, then exit")
        super().__init__(option_strings, dest, nargs=0, default=argparse.SUPPRESS, **kwargs)

    def __call__(self, parser, namespace, values, option_string=None):
        from xfem_contact._version import versions

        for name, version in versions().items():
            print(f"{name:14s}{version or 'not available'}")
        parser.exit()


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="xfem-contact", description=__doc__.splitlines()[0])
    parser.add_argument("--version", action=_Version)
    sub = parser.add_subparsers(dest="command", required=True)
    p = sub.add_parser("run", help="run a scene (a TOML file or a bundled scene name)")
    p.add_argument("scene")
    p.add_argument("--out", default=None, help="output folder (default results/NAME)")
    p.add_argument("--quiet", action="store_true", help="no progress lines")
    p.set_defaults(func=_run)
    p = sub.add_parser("scenes", help="list the bundled scenes")
    p.set_defaults(func=_scenes)
    p = sub.add_parser("show", help="render the result of a run folder to PNG")
    p.add_argument("dir")
    p.set_defaults(func=_show)
    args = parser.parse_args(argv)
    return args.func(args)


if __name__ == "__main__":
    sys.exit(main())
