"""The ``xfem-contact`` command: run scenes, list the bundled ones, render results.

xfem-contact run SCENE.toml --out DIR [--quiet] [--debug]   (also under mpiexec -n 2)
    exit 0 done, 2 bad input (one line ``error: FILE: KEY: message``), 3 Newton failed
xfem-contact scenes [--show NAME]                (list, or print one bundled scene's TOML)
xfem-contact show DIR
xfem-contact --version                           (xfem-contact, DOLFINx, Basix, FFCx, UFL, PETSc)
"""

from __future__ import annotations

import argparse
import pathlib
import sys
import traceback


def _run(args) -> int:
    """Exit codes: 0 done, 2 bad input (one line ``error: FILE: KEY: message`` on stderr;
    the traceback too with ``--debug``), 3 Newton failed (the step and its iterations)."""
    from mpi4py import MPI

    from xfem_contact.io.progress import note
    from xfem_contact.scenes.scene import bundled_scenes, load_scene
    from xfem_contact.solvers.log_lines import lines_to
    from xfem_contact.solvers.report import SolveError

    path = pathlib.Path(args.scene)
    if not path.exists() and args.scene in bundled_scenes():
        path = bundled_scenes()[args.scene]
    say = print if MPI.COMM_WORLD.rank == 0 else (lambda *a, **k: None)

    def failed(code: int, message: str) -> int:
        if args.debug:
            traceback.print_exc()
        lines = [line.strip() for line in str(message).splitlines() if line.strip()]
        say(f"error: {path}: {' '.join(lines) or 'failed'}", file=sys.stderr)
        return code

    if not path.is_file():
        return failed(2, f"no such scene file or bundled scene; bundled: {list(bundled_scenes())}")
    try:
        scene = load_scene(path)
        out = pathlib.Path(args.out or f"results/{scene.name}")
        from xfem_contact.scenes.run import run

        # the log's lines on stdout, above the progress bar (rank 0)
        silent = args.quiet or MPI.COMM_WORLD.rank != 0
        with lines_to(None if silent else note):
            summary = run(scene, out, progress_bar=not (args.quiet or args.no_progress))
    except SolveError as failure:
        failed(3, str(failure).splitlines()[0])
        say(failure.report.table(), file=sys.stderr)
        return 3
    except (ValueError, NotImplementedError, OSError) as error:
        return failed(2, error)
    if not args.quiet:
        say(f"wrote {out}/summary.json")
    return 0 if summary else 1


def _scenes(args) -> int:
    """List the bundled scenes, or print one (``--show NAME``): exit 2 and one line
    naming the bundled scenes for an unknown name."""
    import tomllib

    from xfem_contact.scenes.scene import bundled_scenes

    scenes = bundled_scenes()
    if args.show is not None:
        if args.show not in scenes:
            valid = ", ".join(scenes)
            print(
                f"error: scenes --show: no bundled scene {args.show!r}; bundled: {valid}",
                file=sys.stderr,
            )
            return 2
        print(scenes[args.show].read_text(encoding="utf-8"), end="")
        return 0
    for name, path in scenes.items():
        with open(path, "rb") as f:
            description = tomllib.load(f).get("scene", {}).get("description", "")
        print(f"{name:28s} {description}")
    return 0


def _show(args) -> int:
    """Render a run folder: result.png, von_mises.png, cut.png (2D), pressure.png and, for
    friction laws, traction.png (those with data); a 3D folder's are drawn in 3D."""
    from xfem_contact.io.pictures import render_folder
    from xfem_contact.solvers.log_lines import lines_to

    try:
        with lines_to(print):
            render_folder(args.dir)
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
    p.add_argument("--quiet", action="store_true", help="no progress lines, no progress bar")
    p.add_argument("--no-progress", action="store_true", help="no progress bar over load steps")
    p.add_argument("--debug", action="store_true", help="show the traceback of an error")
    p.set_defaults(func=_run)
    p = sub.add_parser("scenes", help="list the bundled scenes, or print one")
    p.add_argument("--show", metavar="NAME", help="print the TOML of the bundled scene NAME")
    p.set_defaults(func=_scenes)
    p = sub.add_parser("show", help="render the result of a run folder to PNG")
    p.add_argument("dir")
    p.set_defaults(func=_show)
    args = parser.parse_args(argv)
    return args.func(args)


if __name__ == "__main__":
    sys.exit(main())
