"""``qropt project``: a classroom quick-return project (the paper's design and analysis project, drawn per seed) as
one self-contained HTML page, its worked solution, or a class set of them with the instructor's key.

A statement shows a project code, never the seed. With ``--count`` (a class set) or ``--key`` the draws and the
codes are keyed by the instructor's secret (``--secret``, or a fresh random one written into the key file), so a
student with qropt cannot find the seed or the solution from the statement; the key file (CSV) maps each
statement's file and code to its seed, the secret, the task, the solution's headline numbers and the solution's
file. Without either, the page is an open project (the seed's draw alone, for practice)."""

from __future__ import annotations

import argparse
import csv
import os
import shlex
from pathlib import Path

COMMAND = "project"
HELP = (
    "a classroom quick-return project per seed (statement or worked solution) as HTML; --count for a class set "
    "with its key"
)
MAX_COUNT = 500
EXAMPLES = (
    "qropt project --type crank-shaper --seed 100 --count 30 --due 2027-01-15 --solution -o class",
    "qropt project --type whitworth --seed 7 --key key.csv -o project.html",
)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from qropt.classroom import KINDS
    from qropt.classroom.project import MIN_SECRET

    parser.add_argument("--type", default="drag-link-slider", help=f"the mechanism type: {', '.join(KINDS)}")
    parser.add_argument("--seed", type=int, default=0, help="the project's seed, an integer >= 0 (default 0)")
    parser.add_argument(
        "--solution",
        action="store_true",
        help="write the worked solution after the statement (with --count: beside each statement)",
    )
    parser.add_argument(
        "--count",
        type=int,
        default=None,
        help=f"a class set: the seeds SEED..SEED+COUNT-1 (1 to {MAX_COUNT}), one statement each in the directory "
        "-o, named by its code (TYPE-CODE.html; with --solution also TYPE-CODE-solution.html), and the key -o/key.csv",
    )
    parser.add_argument(
        "--secret",
        default=None,
        help=f"the instructor's secret (at least {MIN_SECRET} characters) that keys the draws and the statement "
        "codes; default with --count or --key: a fresh random one, written into the key file. Give the key's secret "
        "again to write the same statements or their solutions later",
    )
    parser.add_argument(
        "--key",
        default=None,
        help="write the key (CSV: file, code, seed, secret, task, the solution's headline numbers, solution file) "
        "here; with --count the default is key.csv in the directory -o; without --count no key unless given",
    )
    parser.add_argument("--due", default=None, help="the due date written on each statement, YYYY-MM-DD (else a blank)")
    parser.add_argument(
        "-o",
        "--output",
        default=None,
        help="the HTML file (default project.html, solution.html with --solution); with --count a directory "
        "(created if missing; default projects)",
    )


def _targets(args, secret) -> tuple[list[tuple[int, Path, Path | None]], Path | None]:
    """((seed, statement path, solution path or None) of every page, the key path or None), every path checked
    before anything is computed (a class set's files are named by their codes, which take no solve)."""
    from qropt.classroom.project import statement_code
    from qropt.cli import CliError
    from qropt.validate import output_path

    def report_path(p):
        return output_path(p, (".html", ".htm"), "project page")

    if args.seed < 0:
        raise CliError(f"--seed must be >= 0, got {args.seed}")
    if args.output is not None and not args.output.strip():
        raise CliError("-o: the output path is empty")
    if args.key is not None:
        key = output_path(args.key, (".csv",), "key")
    if args.count is None:
        path = report_path(args.output or ("solution.html" if args.solution else "project.html"))
        return [(args.seed, path, None)], (key if args.key is not None else None)
    if not 1 <= args.count <= MAX_COUNT:
        raise CliError(f"--count must be from 1 to {MAX_COUNT}, got {args.count}")
    folder = Path(args.output or "projects")
    if folder.suffix.lower() in (".html", ".htm"):
        raise CliError(f"-o {folder}: with --count, -o names a directory (files TYPE-CODE.html go in it)")
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
    key = key if args.key is not None else output_path(folder / "key.csv", (".csv",), "key")
    out = []
    for s in range(args.seed, args.seed + args.count):
        code = statement_code(args.type, s, secret)
        sol = report_path(folder / f"{args.type}-{code}-solution.html")
        out.append((s, report_path(folder / f"{args.type}-{code}.html"), sol))
    return out, key


def _options(args) -> tuple[str | None, str | None]:
    """(secret, due) checked: a bad --secret or --due is one line before anything is written."""
    from qropt.classroom.project import _due, _secret, new_secret
    from qropt.cli import CliError
    from qropt.errors import InvalidParameter

    try:
        _secret(args.secret)
    except InvalidParameter as e:
        raise CliError(f"--secret: {e}") from None
    try:
        due = _due(args.due)
    except InvalidParameter as e:
        raise CliError(f"--due: {e}") from None
    keyed = args.count is not None or args.key is not None
    return (args.secret or new_secret()) if keyed else args.secret, due


def run(args) -> int:
    from qropt.classroom import KINDS, project, render
    from qropt.classroom.project import headline
    from qropt.cli import CliError

    if args.type not in KINDS:
        raise CliError(f"--type {args.type}: unknown project type; the types are {', '.join(KINDS)}")
    secret, due = _options(args)
    targets, key = _targets(args, secret)
    rows = []
    for seed, path, sol in targets:
        p = project(args.type, seed, secret)
        single_solution = args.solution and sol is None
        pages = [(path, single_solution)] + ([(sol, True)] if sol is not None and args.solution else [])
        for where, solution in pages:
            try:
                where.write_text(render(p, solution=solution, due=due))
            except OSError as e:
                raise CliError(f"{where}: cannot write the page: {e.strerror or e}") from None
            what = "solution" if solution else "project"
            print(
                f"{what} written to {where} ({p.kind}, code {p.code}, seed {seed}: TR {p.time_ratio:.2f}, stroke "
                f"{p.stroke:.3f} {p.units}, {p.redraws} redraw(s))"
            )
        if key is not None:
            rows.append(_key_row(p, path, path if single_solution else sol, secret, headline(p)))
    if key is not None:
        _write_key(key, rows)
        print(f"key written to {key} ({len(rows)} row(s); it holds the secret: keep it from the students)")
    return 0


def _key_row(p, path: Path, sol: Path | None, secret: str, numbers: dict) -> dict:
    """The key's row of one statement (``path``); its solution's file ``sol`` (None: FILE-solution.html beside it)."""
    solution = sol if sol is not None else path.with_name(f"{path.stem}-solution.html")
    command = (
        f"qropt project --type {p.kind} --seed {p.seed} --secret {shlex.quote(secret)} --solution -o {solution.name}"
    )
    return {
        "file": path.name,
        "code": p.code,
        "type": p.kind,
        "seed": p.seed,
        "secret": secret,
        "time_ratio": p.time_ratio,
        "stroke": p.stroke,
        **numbers,
        "solution_file": solution.name,
        "solution_command": command,
    }


def _write_key(path: Path, rows: list[dict]) -> None:
    from qropt.cli import CliError

    try:
        with path.open("w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(rows[0]))
            w.writeheader()
            w.writerows(rows)
    except OSError as e:
        raise CliError(f"{path}: cannot write the key: {e.strerror or e}") from None
