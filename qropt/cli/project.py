"""``qropt project``: a classroom quick-return project (the paper's design and analysis project, drawn per seed) as
one self-contained HTML page, its worked solution, or a class set of them."""

from __future__ import annotations

import argparse
import os
from pathlib import Path

COMMAND = "project"
HELP = "a classroom quick-return project per seed (statement or worked solution) as HTML; --count for a class set"
MAX_COUNT = 500
EXAMPLES = (
    "qropt project --type whitworth --seed 7 --solution -o solution.html",
    "qropt project --type crank-shaper --seed 100 --count 30 -o class",
)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from qropt.classroom import KINDS

    parser.add_argument("--type", default="drag-link-slider", help=f"the mechanism type: {', '.join(KINDS)}")
    parser.add_argument("--seed", type=int, default=0, help="the project's seed, an integer >= 0 (default 0)")
    parser.add_argument("--solution", action="store_true", help="write the worked solution after the statement")
    parser.add_argument(
        "--count",
        type=int,
        default=None,
        help=f"a class set: the seeds SEED..SEED+COUNT-1 (1 to {MAX_COUNT}), one file each in the directory -o",
    )
    parser.add_argument(
        "-o",
        "--output",
        default=None,
        help="the HTML file (default project.html, solution.html with --solution); with --count a directory "
        "(created if missing; default projects) that gets TYPE-SEED.html (TYPE-SEED-solution.html)",
    )


def _targets(args) -> list[tuple[int, Path]]:
    """(seed, path) of every page, every path checked before anything is computed."""
    from qropt.cli import CliError
    from qropt.validate import output_path

    def report_path(p):
        return output_path(p, (".html", ".htm"), "project page")

    if args.seed < 0:
        raise CliError(f"--seed must be >= 0, got {args.seed}")
    if args.output is not None and not args.output.strip():
        raise CliError("-o: the output path is empty")
    if args.count is None:
        path = args.output or ("solution.html" if args.solution else "project.html")
        return [(args.seed, report_path(path))]
    if not 1 <= args.count <= MAX_COUNT:
        raise CliError(f"--count must be from 1 to {MAX_COUNT}, got {args.count}")
    folder = Path(args.output or "projects")
    if folder.suffix.lower() in (".html", ".htm"):
        raise CliError(f"-o {folder}: with --count, -o names a directory (files TYPE-SEED.html go in it)")
    if folder.exists() and not folder.is_dir():
        raise CliError(f"-o {folder}: exists and is not a directory")
    if not folder.exists():
        if not folder.parent.is_dir():
            raise CliError(f"-o {folder}: its parent directory {folder.parent} does not exist")
        try:
            folder.mkdir()
        except OSError as e:
            raise CliError(f"-o {folder}: cannot create the directory: {e.strerror or e}") from None
    if not os.access(folder, os.W_OK | os.X_OK):
        raise CliError(f"-o {folder}: cannot write in the directory: permission denied")
    tail = "-solution" if args.solution else ""
    return [(s, report_path(folder / f"{args.type}-{s}{tail}.html")) for s in range(args.seed, args.seed + args.count)]


def run(args) -> int:
    from qropt.classroom import KINDS, project, render
    from qropt.cli import CliError

    if args.type not in KINDS:
        raise CliError(f"--type {args.type}: unknown project type; the types are {', '.join(KINDS)}")
    for seed, path in _targets(args):
        p = project(args.type, seed)
        try:
            path.write_text(render(p, solution=args.solution))
        except OSError as e:
            raise CliError(f"{path}: cannot write the page: {e.strerror or e}") from None
        what = "solution" if args.solution else "project"
        print(
            f"{what} written to {path} ({p.kind}, seed {seed}: TR {p.time_ratio:.2f}, stroke {p.stroke:.3f} "
            f"{p.units}, {p.redraws} redraw(s))"
        )
    return 0
