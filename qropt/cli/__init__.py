"""Command line: ``qropt analyze``, ``synth``, ``family``, ``reachable``, ``bench``, and every command module
of this package (a module defining ``COMMAND``, ``HELP``, ``EXAMPLES`` (command lines its --help ends with),
``add_arguments(parser)`` and ``run(args) -> int``).
Errors print one line."""

from __future__ import annotations

import argparse
import csv
import importlib
import json
import math
import pkgutil
import sys

import numpy as np

from qropt import units as units_
from qropt import validate
from qropt.errors import QroptError
from qropt.io import records
from qropt.mechanisms import REGISTRY, Mechanism, mechanism_type, type_reference
from qropt.synthesis import criteria

QUIET = False  # --quiet: no progress bars
PARAM_NAMES = ("r1", "r2", "r3", "r4", "r5", "r6", "e", "h", "sigma", "sigma_slider")
TIME_LIMIT_HELP = "seconds of wall time: the best certified design found by then, the claim naming what did not run"


class CliError(Exception):
    """A command-line usage error (exit code 2)."""


class _Parser(argparse.ArgumentParser):
    def error(self, message):
        raise CliError(message)


def angle(text: str) -> float:
    """An angle from the command line: '60', '60deg' (degrees) or '1.05rad' (radians) -> radians."""
    t = text.strip().lower()
    try:
        v = float(t[:-3]) if t.endswith("rad") else math.radians(float(t.removesuffix("deg")))
    except ValueError:
        raise argparse.ArgumentTypeError(f"not an angle: {text!r} (use e.g. 60deg or 1.05rad)") from None
    if not math.isfinite(v) or abs(v) > 1e6:
        raise argparse.ArgumentTypeError(f"not a finite angle of sensible size: {text!r}")
    return v


def real(text: str) -> float:
    """A finite number from the command line."""
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not math.isfinite(v):
        raise argparse.ArgumentTypeError(f"not a finite number: {text!r}")
    return v


def _param_pair(text: str) -> tuple[str, str]:
    name, sep, value = text.partition("=")
    if not sep or not name.strip() or not value.strip():
        raise argparse.ArgumentTypeError(f"--param is NAME=VALUE (e.g. r2=0.1, beta=30deg), got {text!r}")
    return name.strip(), value.strip()


def examples(*commands: str) -> dict:
    """add_parser keywords for a subcommand whose --help ends with these example command lines."""
    where = " (problems/: the repository's problem files)" if any("problems/" in c for c in commands) else ""
    return {
        "epilog": f"examples{where}:\n" + "\n".join(f"  {c}" for c in commands),
        "formatter_class": argparse.RawDescriptionHelpFormatter,
    }


def type_argument(parser, name: str = "type", more: str = "") -> None:
    """The optional mechanism TYPE: the registered types, and the default, the paper's mechanism."""
    from qropt.examples import paper_mechanism

    parser.add_argument(
        name,
        nargs="?",
        help="mechanism type: " + ", ".join(sorted(REGISTRY)) + more + f", or module:Class; default: the paper's "
        f"mechanism, a {paper_mechanism().KIND} (qropt.examples.paper_mechanism)",
    )


def param_flags(parser, kind=None) -> None:
    """--r1 ... --sigma-slider (PARAM_NAMES), each naming the registered types that take it (their PARAMS)."""
    for k in PARAM_NAMES:
        takers = {t: cls.kinds()[k] for t, cls in sorted(REGISTRY.items()) if k in cls.PARAMS}
        what = " or ".join(sorted({"branch sign (+1 or -1)" if v == "branch" else v for v in takers.values()}))
        parser.add_argument(
            f"--{k.replace('_', '-')}",
            dest=k,
            type=kind or real,
            help=f"the {what} {k} of the types " + ", ".join(takers),
        )


def objective_help(lead: str = "what the design optimises", more: str = "") -> str:
    """A help text for --objective: each objective of the criteria registry and the criteria it optimises."""
    said = {}
    for c in criteria.CRITERIA.values():
        said.setdefault(c.objective, []).append(c.label)
    return f"{lead}: " + ", ".join(f"{o} ({' or '.join(w)})" for o, w in said.items()) + more


def param_argument(parser) -> None:
    """--param NAME=VALUE, repeatable: any parameter of any type (its kind from ``Mechanism.kinds()``)."""
    parser.add_argument(
        "--param",
        action="append",
        default=[],
        type=_param_pair,
        metavar="NAME=VALUE",
        help="a parameter of the type, repeatable: a length or offset in the length unit, an angle in rad or with "
        "a suffix (30deg, 0.52rad), a branch sign +1 or -1",
    )


def param_value(name: str, text: str, kind: str) -> float:
    """The value of --param NAME=TEXT for a parameter of this kind: an angle in rad or with a suffix deg/rad."""
    t = text.strip().lower()
    if kind == "angle" and t.endswith("deg"):
        v = real_or_none(t[:-3])
        v = None if v is None else math.radians(v)
    else:
        v = real_or_none(t.removesuffix("rad") if kind == "angle" else t)
    if v is None:
        unit = " (rad, or e.g. 30deg)" if kind == "angle" else ""
        raise CliError(f"--param {name}={text}: not a finite number{unit}")
    return v


def real_or_none(text: str) -> float | None:
    try:
        v = float(text)
    except ValueError:
        return None
    return v if math.isfinite(v) else None


def flag_params(args, names=None) -> dict:
    """The parameters given by the fixed flags (--r1 ... --sigma-slider)."""
    return {k: getattr(args, k) for k in names or PARAM_NAMES if getattr(args, k, None) is not None}


def mechanism_params(args, cls, names=None) -> dict:
    """Every parameter given on the command line for type cls: the fixed flags and each --param NAME=VALUE."""
    given = flag_params(args, names)
    kinds = cls.kinds()
    for name, text in getattr(args, "param", None) or []:
        if name not in kinds:
            raise CliError(f"--param {name}: {cls.__name__} has no parameter {name!r}; it takes {list(kinds)}")
        if name in given:
            raise CliError(f"parameter {name} is given twice")
        given[name] = param_value(name, text, kinds[name])
    return given


def cli_type(name: str) -> type[Mechanism]:
    """A type named on the command line: a KIND, class name or "module:Class" (importable from the current
    directory too, as ``python -m`` finds modules)."""
    import os

    if ":" in name and os.getcwd() not in sys.path:
        sys.path.append(os.getcwd())
    return mechanism_type(name)


MIN_STEP = math.radians(0.01)  # the finest full-cycle table: 36,000 rows


def picture_path(path: str) -> str:
    """A path for a picture, checked before any work (``qropt.validate.picture_path``), or CliError saying why."""
    from qropt.validate import picture_path as check

    try:
        check(path)
    except QroptError as e:
        raise CliError(f"--plot {e}") from None
    return path


def units_argument(parser, what: str = "the design's length unit", default: str | None = None) -> None:
    """--units (or --unit): one of qropt.units.LENGTH_UNITS."""
    parser.add_argument(
        "--units",
        "--unit",
        dest="units",
        default=default,
        choices=list(units_.LENGTH_UNITS),
        help=f"{what} (default: {units_.DEFAULT})",
    )


def stated(m: Mechanism, units: str | None, where: str) -> Mechanism:
    """m, whose unit is stated (a design file's, or the built-in design's metres): --units may repeat it, never
    contradict it."""
    if units is not None and units != m.units:
        raise CliError(f"--units {units} contradicts {where}, which is in {m.units}")
    return m


def build_mechanism(args) -> Mechanism:
    given = {**flag_params(args), **dict(getattr(args, "param", None) or [])}
    units = getattr(args, "units", None)
    if getattr(args, "design", None):
        if given or args.type is not None:
            raise CliError("--from reads the whole design: give no TYPE or parameters with it")
        from qropt.io.export import load_design

        return stated(load_design(args.design), units, f"the design file {args.design}")
    if args.type is None:
        if given:
            raise CliError("give the mechanism TYPE before its parameters (types: " + ", ".join(sorted(REGISTRY)) + ")")
        from qropt.examples import paper_mechanism

        return stated(paper_mechanism(), units, "the built-in paper design")
    cls = cli_type(args.type)
    return cls(**mechanism_params(args, cls), units=units or units_.DEFAULT)


def print_report(r: dict, out=None):
    w = (out or sys.stdout).write
    u = r.get("units", units_.DEFAULT)
    follower = r.get("output", "follower" if r["type"] == "four-bar" else "slider") == "follower"
    out_name = "follower theta4 [rad]" if follower else f"slider x [{u}]"
    w(f"{r['type']} ({u}): " + ", ".join(f"{k}={v:g}" for k, v in r["params"].items()) + "\n")
    if "grashof" in r:
        g = r["grashof"]
        w(
            f"  Grashof class     {g['kind']} (shortest {g['shortest']}; s+l = {g['s_plus_l']:.6g}, "
            f"p+q = {g['p_plus_q']:.6g})\n"
        )
    d = r["dead_centres"]
    w(f"  time ratio        {r['time_ratio']:.10f}\n")
    if follower:
        w(f"  swing             {math.degrees(r['stroke']):.6f} deg\n")
    else:
        w(f"  stroke            {r['stroke']:.10g} {u}\n")
    w(
        f"  dead centres      theta_max = {d['theta_max_deg']:.6f} deg ({out_name} = {d['x_max']:.10g}); "
        f"theta_min = {d['theta_min_deg']:.6f} deg ({d['x_min']:.10g})\n"
    )
    if d["reversals"] != 1:
        w(f"  warning           the output reverses {d['reversals']} times a turn: TR is ill-posed\n")
    sa = r["stroke_angles_deg"]
    w(f"  stroke angles     {sa[0]:.6f} deg working / {sa[1]:.6f} deg return\n")
    w(f"  working stroke    {r['working_direction']} (omega2 = {r['state']['omega2']:g} rad/s)\n")
    g = r["gamma_min"]
    w(f"  gamma_min         {g['value_deg']:.6f} deg at theta2 = {g['theta2_deg']:.6f} deg, joint {g['joint']}\n")
    s = r["state"]
    w(f"  at theta2 = {s['theta2_deg']:g} deg, omega2 = {s['omega2']:g} rad/s, alpha2 = {s['alpha2']:g} rad/s^2:\n")
    if follower:
        w(f"    follower: theta4 = {s['x']:.6g} rad, omega4 = {s['v']:.6g} rad/s, alpha4 = {s['a']:.6g} rad/s^2\n")
    else:
        w(f"    slider: x = {s['x']:.6g} {u}, v = {s['v']:.6g} {u}/s, a = {s['a']:.6g} {u}/s^2\n")
    for k, v in s["links"].items():
        w(
            f"    {k:7s} = {v['angle_deg']:11.5f} deg   omega = {v['omega']:11.5g} rad/s   "
            f"alpha = {v['alpha']:11.5g} rad/s^2\n"
        )


def write_table(m: Mechanism, step: float, omega2: float, alpha2: float, path: str):
    """Full-cycle table at crank-angle steps (rad): every joint, link angle, x, v, a, transmission angle, and the
    length unit of the joints and the slider (x, v, a: unit, unit/s, unit/s^2) in a last column "units"."""
    n = max(1, round(2 * math.pi / step))
    th = np.linspace(0.0, 2 * math.pi, n + 1)
    pos, mo, tr = m.positions(th), m.motion(th, omega2, alpha2), m.transmission_angles(th)
    cols = {"theta2_deg": np.degrees(th)}
    for k, xy in pos.points.items():
        cols[f"{k}_x"], cols[f"{k}_y"] = xy[:, 0], xy[:, 1]
    for k in mo.angles:
        cols[f"{k}_deg"], cols[f"omega_{k}"], cols[f"alpha_{k}"] = np.degrees(mo.angles[k]), mo.omega[k], mo.alpha[k]
    cols.update(x=mo.x, v=mo.v, a=mo.a)
    for k, g in tr.items():
        cols[f"gamma_{k}_deg"] = np.degrees(g)
    f = sys.stdout if path == "-" else open(path, "w", newline="")  # noqa: SIM115
    try:
        wr = csv.writer(f)
        wr.writerow([*cols, "units"])
        for i in range(th.size):
            wr.writerow([*(f"{cols[c][i]:.12g}" for c in cols), m.units])
    finally:
        if f is not sys.stdout:
            f.close()


def cmd_analyze(args):
    if args.omega2 == 0:
        raise CliError("--omega2 must be nonzero (rad/s; its sign is the crank's sense of rotation)")
    if args.table is not None and not MIN_STEP <= args.table <= 2 * math.pi:
        raise CliError(f"--table is a crank-angle step from 0.01 to 360 deg, got {math.degrees(args.table):g} deg")
    if args.json and args.table is not None and args.csv in (None, "-"):
        raise CliError("--json prints JSON on standard output: give the table a file with --csv FILE")
    m = build_mechanism(args)
    if args.polygons:
        return polygons(args, m)
    if args.dynamics:
        return dynamics(args, m)
    r = records.analysis(m, args.theta2, args.omega2, args.alpha2)
    if args.json:
        json.dump(r, sys.stdout, indent=2, allow_nan=False)
        sys.stdout.write("\n")
    else:
        print_report(r)
    if args.table is not None or args.csv is not None:
        write_table(
            m, args.table if args.table is not None else math.radians(1.0), args.omega2, args.alpha2, args.csv or "-"
        )
    if args.plot:
        from qropt.io import plots

        plots.save(plots.cycle_figure(m, args.theta2, args.omega2, args.alpha2), args.plot)
        if not args.json:
            print(f"  picture written to {args.plot}")
    for path in export(args, m, args.theta2):
        if not args.json:
            print(f"  written: {path}")


def polygons(args, m) -> int:
    """``analyze --polygons``: the velocity and acceleration equations term by term (the paper's Tables 1-3),
    directions in degrees counter-clockwise from +x; with --plot, the polygons drawn to scale."""
    rm = m.relative_motion(args.theta2, args.omega2, args.alpha2)
    rows = rm.table()
    if args.json:
        out = {"theta2_deg": math.degrees(args.theta2), "omega2": args.omega2, "alpha2": args.alpha2}
        json.dump({**out, "units": m.units, "terms": rows}, sys.stdout, indent=2, allow_nan=False)
        sys.stdout.write("\n")
    else:
        print(
            f"{type(m).__name__} at theta2 = {math.degrees(args.theta2):g} deg, omega2 = {args.omega2:g} rad/s,"
            f" alpha2 = {args.alpha2:g} rad/s^2 (lengths in {m.units})"
        )
        print(f"  {'joint':5s} {'quantity':12s} {'term':22s} {'kind':10s} {'magnitude':>12s} {'dir [deg]':>9s}")
        for r in rows:
            state = "solved" if r["solved"] else "known"
            print(
                f"  {r['joint']:5s} {r['quantity']:12s} {r['term']:22s} {r['kind']:10s} {r['magnitude']:12.6g}"
                f" {r['direction_deg']:9.2f}  {state}"
            )
    if args.plot:
        rm.plot(args.plot, m.units)
        if not args.json:
            print(f"  picture written to {args.plot}")
    return 0


LOADS_FILE_HELP = (
    "a JSON or TOML file of the loads (qropt.Loads.to_dict: cutting_force, friction, forces, torques with their "
    "windows, gravity, working, pin_friction)"
)


def loads_arguments(parser, flags: bool = True, instead: str = "") -> None:
    """The loads' options, one set for every command that computes or draws dynamics: with ``flags``, --force,
    --friction and --gravity G [GY] (``loads_of`` builds the loads from them); always --point-mass JOINT KG
    (repeatable; ``point_masses``) and --loads FILE (``read_loads``), ``instead`` saying what the file replaces."""
    if flags:
        parser.add_argument("--force", type=real, help="cutting force on the working stroke, N (default 0)")
        parser.add_argument("--friction", type=real, help="the slide's friction coefficient (default 0)")
        parser.add_argument(
            "--gravity",
            type=real,
            nargs="+",
            metavar="G",
            help="gravity, m/s^2: one number g along -y (e.g. 9.81), or GX GY in the frame (0 -9.81; a vertical "
            "slotter: -9.81 0); default none",
        )
    parser.add_argument(
        "--point-mass",
        dest="points",
        nargs=2,
        action="append",
        metavar=("JOINT", "KG"),
        help="a point mass at a joint (repeatable), added to the body that carries it",
    )
    parser.add_argument(
        "--loads",
        dest="loads_file",
        metavar="FILE",
        help=LOADS_FILE_HELP + (" instead of --force, --friction and --gravity" if flags else "") + instead,
    )


def read_loads(path: str):
    """The ``qropt.Loads`` of a JSON or TOML file (``Loads.to_dict``); a one-line error naming the file where it
    does not read, does not parse or is not loads."""
    from qropt.dynamics.model import Loads

    text = validate.read_text(path, "loads file")
    if str(path).lower().endswith(".toml"):
        import tomllib

        try:
            data = tomllib.loads(text)
        except tomllib.TOMLDecodeError as e:
            raise CliError(f"the loads file {path} is not TOML: {e}") from None
    else:
        data = validate.json_document(text, f"the loads file {path}")
    try:
        return Loads.from_dict(data)
    except QroptError as e:
        raise type(e)(f"the loads file {path}: {e}") from None


def loads_of(args):
    """The loads the options state (``loads_arguments``): the --loads file, or --force, --friction and --gravity;
    None where none of them is given."""
    from qropt.dynamics.model import Loads

    force, friction, gravity = (getattr(args, k, None) for k in ("force", "friction", "gravity"))
    flagged = force is not None or friction is not None or gravity is not None
    if args.loads_file is not None:
        if flagged:
            raise CliError("give the loads in the --loads file or by --force, --friction and --gravity, not both")
        return read_loads(args.loads_file)
    if not flagged:
        return None
    if gravity is not None and len(gravity) > 2:
        raise CliError(f"--gravity takes one number (along -y) or two (gx gy), got {len(gravity)}")
    g = 0.0 if gravity is None else gravity[0] if len(gravity) == 1 else tuple(gravity)
    return Loads(force or 0.0, friction=friction or 0.0, gravity=g)


def point_masses(args) -> dict:
    """--point-mass JOINT KG, as joint -> kg (the last one given for a joint)."""
    out = {}
    for joint, kg in getattr(args, "points", None) or []:
        try:
            out[joint] = real(kg)
        except argparse.ArgumentTypeError as e:
            raise CliError(f"--point-mass {joint} {kg}: {e}") from None
    return out


def _loads_words(loads) -> str:
    """The loads in a few words for the header line."""
    g = loads.gravity
    f = loads.cutting_force
    words = f"cutting force {f:g} N, friction " if isinstance(f, float) else "cutting force by a table, friction "
    words += f"{loads.friction:g}, gravity " + (f"({g[0]:g}, {g[1]:g})" if isinstance(g, tuple) else f"{g:g}")
    words += " m/s^2"
    n = len(loads.forces) + len(loads.torques)
    return words + (f", {n} more load{'s' * (n != 1)} (--loads)" if n else "")


def dynamics(args, m) -> int:
    """``analyze --dynamics``: the peak and RMS crank torque, the peak force at every joint, the peak shaking
    force and moment and the flywheel for --cs, at --omega2 (SI); --plot, --csv (the turn degree by degree) and
    --json as for the kinematics."""
    from qropt.dynamics.cycle import CycleDynamics
    from qropt.dynamics.model import Counterweight, Loads, Masses

    try:
        cw = None
        if args.counterweight is not None:
            mass, radius, at = args.counterweight
            cw = Counterweight(real(mass), real(radius), angle(at))
        points = point_masses(args)
        masses = Masses.bars(args.density, args.ram_mass, block=args.block_mass, counterweight=cw, points=points)
        loads = loads_of(args) or Loads()
    except (QroptError, argparse.ArgumentTypeError) as e:
        raise CliError(str(e)) from None
    cd = CycleDynamics(m, args.omega2, args.alpha2, masses, loads)
    ex = cd.extremes()
    fw = cd.flywheel(args.cs) if args.alpha2 == 0 else None
    out = records.dynamics(cd, masses, ex, fw)
    if args.json:
        json.dump(out, sys.stdout, indent=2, allow_nan=False)
        sys.stdout.write("\n")
    else:
        print(
            f"{type(m).__name__} at omega2 = {args.omega2:g} rad/s, alpha2 = {args.alpha2:g} rad/s^2: links "
            f"{args.density:g} kg/m, ram {args.ram_mass:g} kg, {_loads_words(loads)}"
            + (f", points {', '.join(f'{k} {v:g} kg' for k, v in masses.points.items())}" if masses.points else "")
            + (f", counterweight {cw.mass:g} kg at {cw.radius:g} m, {math.degrees(cw.angle):g} deg" if cw else "")
            + " (SI)"
        )
        at = math.degrees(ex.peak_torque.theta2)
        print(f"  peak torque     {ex.peak_torque.value:12.6g} N m at theta2 = {at:.2f} deg")
        print(f"  RMS torque      {ex.rms_torque:12.6g} N m   mean {ex.mean_torque:.6g} N m")
        for k, p in ex.peak_forces.items():
            print(f"  peak force {k:6s}{p.value:12.6g} N   at theta2 = {math.degrees(p.theta2):.2f} deg")
        print(
            f"  shaking force   {ex.peak_shaking_force.value:12.6g} N   moment {ex.peak_shaking_moment.value:.6g} N m"
        )
        if fw is not None:
            print(
                f"  flywheel        {fw.inertia:12.6g} kg m^2 for Cs = {fw.cs:g} (energy fluctuation "
                f"{fw.energy_fluctuation:.6g} J; {fw.energy_per_turn:.6g} J a turn, {fw.working_energy:.6g} J on the "
                "working stroke)"
            )
    if args.csv:
        th = np.radians(np.arange(0.0, 360.0, 1.0))
        d = cd.at(th)
        names = sorted(d.joint_forces)
        rows = [["theta2_deg", "torque_Nm", *(f"{k}_{c}_N" for k in names for c in "xy"), "shaking_x_N", "shaking_y_N"]]
        for i, t in enumerate(th):
            rows.append(
                [
                    f"{math.degrees(t):g}",
                    f"{d.torque[i]:.10g}",
                    *(f"{d.joint_forces[k][i, c]:.10g}" for k in names for c in (0, 1)),
                    *(f"{v:.10g}" for v in d.shaking_force[i]),
                ]
            )
        f = sys.stdout if args.csv == "-" else open(args.csv, "w", newline="")  # noqa: SIM115
        try:
            csv.writer(f).writerows(rows)
        finally:
            if f is not sys.stdout:
                f.close()
    if args.plot:
        from qropt.io import plots

        plots.save(plots.dynamics_figure(m, args.omega2, masses, loads, args.theta2), args.plot)
        if not args.json:
            print(f"  picture written to {args.plot}")
    return 0


def _export_arguments(p, at: str):
    """--animate, --dxf, --svg, --save; ``at``: the crank angle the drawings show."""
    p.add_argument("--animate", help="GIF file: the design over one turn (72 frames)")
    p.add_argument("--dxf", help=f"DXF file: the design {at}, one layer per kind of entity")
    p.add_argument("--svg", help="SVG file: the same drawing")
    p.add_argument("--save", help="JSON design file that qropt analyze --from reads back")


def export(args, m, theta2: float = 0.0) -> list[str]:
    """Write the drawings and the design file the command line asks for; the paths written."""
    from qropt.io import export as ex

    done = []
    if getattr(args, "animate", None):
        from qropt.io.animation import animate

        animate(m, args.animate, omega2=getattr(args, "omega2", None) or 1.0, progress=not QUIET)
        done.append(args.animate)
    for flag, write in (("dxf", ex.to_dxf), ("svg", ex.to_svg)):
        if getattr(args, flag, None):
            write(m, getattr(args, flag), theta2)
            done.append(getattr(args, flag))
    if getattr(args, "save", None):
        ex.save_design(m, args.save)
        done.append(args.save)
    return done


def parser() -> argparse.ArgumentParser:
    from qropt import __version__

    p = _Parser(prog="qropt", description="Quick-return mechanism analysis and synthesis.")
    p.add_argument("--version", action="version", version=f"qropt {__version__}")
    p.add_argument("--quiet", action="store_true", help="no progress bars on standard error")
    sub = p.add_subparsers(dest="command", required=True)
    a = sub.add_parser(
        "analyze",
        help="exact TR, stroke, dead centres, gamma_min and slider state",
        **examples(
            "qropt analyze --omega2 10 --theta2 60deg",
            "qropt analyze crank-shaper --r1 160 --r2 40 --r4 240 --units mm --json",
        ),
    )
    type_argument(a)
    param_flags(a)
    param_argument(a)
    a.add_argument("--theta2", type=angle, default=math.radians(60.0), help="crank angle (deg, or 1.05rad)")
    a.add_argument("--omega2", type=real, default=1.0, help="crank speed, rad/s (sign = direction)")
    a.add_argument("--alpha2", type=real, default=0.0, help="crank acceleration, rad/s^2")
    a.add_argument("--json", action="store_true", help="print JSON instead of text")
    a.add_argument("--table", type=angle, help="full-cycle table step (deg, or rad with suffix)")
    a.add_argument("--csv", help="file for the full-cycle table ('-' for standard output)")
    a.add_argument(
        "--plot",
        help="PNG file: mechanism at theta2 beside x, v, a over the cycle (with --dynamics: its joint forces and "
        "applied loads as arrows beside the torque and the joint forces over the turn)",
    )
    a.add_argument("--from", dest="design", help="a design file (qropt synth --save, or --json output) to analyse")
    a.add_argument("--polygons", action="store_true", help="the equations term by term; with --plot, the polygons")
    a.add_argument("--dynamics", action="store_true", help="crank torque, joint forces, shaking and flywheel (SI)")
    a.add_argument("--density", type=real, default=0.0, help="links as uniform bars of this many kg per metre")
    a.add_argument("--ram-mass", dest="ram_mass", type=real, default=0.0, help="the ram's mass, kg")
    a.add_argument("--block-mass", dest="block_mass", type=real, default=0.0, help="the crank-pin block's mass, kg")
    a.add_argument(
        "--counterweight",
        nargs=3,
        metavar=("MASS", "RADIUS", "ANGLE"),
        help="a crank counterweight: MASS kg at RADIUS m, ANGLE from the crank pin (e.g. 180deg)",
    )
    loads_arguments(a)
    a.add_argument("--cs", type=real, default=0.05, help="coefficient of speed fluctuation for the flywheel")
    units_argument(a, "the length unit of the parameters (a design file states its own; --units may repeat it)")
    _export_arguments(a, "at --theta2")
    a.set_defaults(run=cmd_analyze)
    s = sub.add_parser(
        "synth",
        help="solve a synthesis problem file (build() -> Problem)",
        **examples("qropt synth --save best.json --svg best.svg", "qropt synth problems/paper_drag_link.py --json"),
    )
    s.add_argument("problem", nargs="?", help="a problem file (default: the paper's design task, built in)")
    s.add_argument(
        "--objective",
        choices=[o for o in criteria.objectives() if o] + ["none"],
        help=objective_help(more="; none: a feasibility problem (default: the problem file's)"),
    )
    s.add_argument("--size", choices=["sum", "longest", "footprint"], help="size measure for min_size")
    s.add_argument("--starts", type=int, help="space-filling multi-start points (default: the solver's)")
    s.add_argument("--time-limit", dest="time_limit", type=real, help=TIME_LIMIT_HELP)
    s.add_argument("--json", action="store_true", help="print the Result as JSON")
    s.add_argument("--plot", help="PNG file: the best design over its cycle")
    loads_arguments(s, flags=False, instead=" instead of the problem file's (its dynamic objectives and bounds)")
    _export_arguments(s, "at theta2 = 0 (the crank along +x)")
    s.set_defaults(run=cmd_synth)
    f = sub.add_parser(
        "family",
        help="trace the one-parameter family of a problem file",
        **examples("qropt family problems/paper_family_r1_r3.py --csv family.csv --plot family.png"),
    )
    f.add_argument("problem", help="a problem file with one more free parameter than targets")
    f.add_argument("--along", help="the parameter in which folds are counted (default: the first free one)")
    f.add_argument("--csv", help="file for every traced point with its quantities")
    f.add_argument("--plot", help="PNG file: the family coloured by gamma_min, folds, ends and the best design")
    f.add_argument("--json", action="store_true", help="print branches' ends, folds and the best design as JSON")
    f.set_defaults(run=cmd_family)
    r = sub.add_parser(
        "reachable",
        help="TR range, solution counts and adjustable-link travel of one parameter",
        **examples("qropt reachable --tr 1.5 --tr 2 --plot fig5.png", "qropt reachable --adjust 1.5 2.5"),
    )
    type_argument(r)
    param_flags(r)
    param_argument(r)
    r.add_argument("--free", default="r3", help="the adjustable parameter (default r3)")
    r.add_argument("--bounds", nargs=2, type=real, metavar=("LOW", "HIGH"), help="its interval")
    r.add_argument("--tr", type=real, action="append", default=[], help="count the designs for this TR")
    r.add_argument(
        "--adjust",
        nargs=2,
        type=real,
        metavar=("TR_LOW", "TR_HIGH"),
        help="size the adjustable link for this TR range (default: the whole reachable range)",
    )
    r.add_argument("--json", action="store_true", help="print JSON")
    r.add_argument("--plot", help="PNG file: TR against the parameter (the paper's Fig. 5)")
    units_argument(r, "the length unit of the parameters")
    r.set_defaults(run=cmd_reachable)
    sub.add_parser("bench", help="the benchmark suite, from the repository root (options: qropt bench --help)")
    for info in pkgutil.iter_modules(__path__):
        mod = importlib.import_module(f"{__name__}.{info.name}")
        if hasattr(mod, "COMMAND"):
            c = sub.add_parser(mod.COMMAND, help=mod.HELP, **examples(*mod.EXAMPLES))
            mod.add_arguments(c)
            c.set_defaults(run=mod.run)
    return p


def cmd_bench(argv):
    """Hand over to benchmarks/suite.py of the repository in the current directory."""
    from pathlib import Path

    if not (Path.cwd() / "benchmarks" / "suite.py").is_file():
        raise CliError("qropt bench runs from the qropt repository root (benchmarks/ and problems/ are not installed)")
    sys.path.insert(0, str(Path.cwd()))
    from benchmarks.suite import main as bench_main

    return bench_main(argv)


def progress_bar(what: str, total=None, unit="point"):
    """A tqdm bar on standard error, silent when it is not a terminal or with --quiet."""
    from tqdm import tqdm

    return tqdm(total=total, desc=what, unit=unit, disable=QUIET or not sys.stderr.isatty(), leave=False)


def cmd_family(args):
    from qropt.studies._family import family

    problem = load_problem(args.problem)
    with progress_bar("tracing") as bar:
        fam = family(problem, along=args.along, progress=bar.update)
    best = fam.best(problem.objective or "max_gamma_min")
    if args.json:
        out = {
            "branches": [len(b) for b in fam.branches],
            "ends": [{"branch": e.branch, "side": e.side, "reason": e.reason, "params": e.params} for e in fam.ends],
            "folds": fam.folds,
            "best": best.to_dict(),
            "units": problem.units,
        }
        json.dump(out, sys.stdout, indent=2, default=str)
        sys.stdout.write("\n")
    else:
        free = list(problem.free)
        print(
            f"{problem.name or args.problem}: {len(fam.branches)} branch(es), {sum(map(len, fam.branches))} points "
            f"(lengths in {problem.units})"
        )
        for e in fam.ends:
            at = ", ".join(f"{k}={e.params[k]:.10g}" for k in free)
            print(f"  branch {e.branch + 1} {'start' if e.side == 0 else 'end'}: {at}  ({e.reason})")
        for fold in fam.folds:
            print("  fold: " + ", ".join(f"{k}={fold[k]:.12g}" for k in free))
        print("best " + (problem.objective or "max_gamma_min") + ":")
        print("  " + best.summary().replace("\n", "\n  "))
    if args.csv:
        with open(args.csv, "w", newline="") as fh:
            w = csv.writer(fh)
            head = [
                "branch",
                "arclength",
                *problem.free,
                "theta_max_deg",
                "theta_min_deg",
                "time_ratio",
                "stroke",
                "gamma_min_deg",
                "peak_accel",
                "grashof",
                "units",
            ]
            w.writerow(head)
            bar = progress_bar("exact quantities", total=sum(map(len, fam.branches)))
            for b, pts in enumerate(fam.branches):
                for p in pts:
                    bar.update()
                    q = p.quantities
                    w.writerow(
                        [
                            b + 1,
                            f"{p.arclength:.12g}",
                            *(f"{p.params[k]:.15g}" for k in problem.free),
                            *(f"{math.degrees(t):.12g}" for t in p.theta),
                            q.get("time_ratio"),
                            q.get("stroke", q.get("swing")),
                            math.degrees(q["gamma_min"]) if q else None,
                            q.get("peak_accel"),
                            q.get("grashof"),
                            problem.units,
                        ]
                    )
            bar.close()
    if args.plot:
        from qropt.io import plots

        plots.save(plots.family_figure(fam, best=best), args.plot)


def cmd_reachable(args):
    from qropt.studies._reachable import reachable

    given = {**flag_params(args), **dict(args.param)}
    if args.type is None and not given:
        from qropt.examples import paper_mechanism

        m = stated(paper_mechanism(), args.units, "the built-in paper design")
    elif args.type is None:
        raise CliError("give the mechanism TYPE before its parameters")
    else:
        cls = cli_type(args.type)
        m = cls(**mechanism_params(args, cls), units=args.units or units_.DEFAULT)
    with progress_bar(f"scanning {args.free}", total=301) as bar:
        r = reachable(m, args.free, tuple(args.bounds) if args.bounds else None, progress=bar.update)
    tmin, xmin, tmax, xmax = r.time_ratio_range
    low, high = args.adjust if args.adjust else (tmin, tmax)
    if low > high:
        raise CliError(f"--adjust {low:g} {high:g}: TR_LOW is above TR_HIGH; give the lower time ratio first")
    if not tmin <= low <= high <= tmax:
        raise CliError(f"--adjust {low:g} {high:g} must lie within the reachable TR {tmin:.6g}..{tmax:.6g}")
    adj = r.adjustable(low, high)
    counts = {t: r.solutions(t) for t in args.tr}
    if args.json:
        out = {
            "free": args.free,
            "units": m.units,
            "intervals": r.intervals,
            "time_ratio_range": r.time_ratio_range,
            "stroke_range": r.stroke_range,
            "solutions": {str(k): v for k, v in counts.items()},
            "adjustable": {
                "time_ratios": [low, high],
                "interval": adj.interval,
                "worst_gamma_min_deg": math.degrees(adj.gamma_min),
                "explanation": adj.explanation,
            },
        }
        json.dump(out, sys.stdout, indent=2, default=float, allow_nan=False)
        sys.stdout.write("\n")
    else:
        u = m.units
        print(f"{type(m).__name__}: {args.free} varies, the rest as given (lengths in {u})")
        print("  feasible " + " and ".join(f"{args.free} in [{a:.10g}, {b:.10g}] {u}" for a, b in r.intervals))
        print(
            f"  time ratio {tmin:.10g} (at {args.free} = {xmin:.10g} {u}) .. {tmax:.10g} "
            f"(at {args.free} = {xmax:.10g} {u})"
        )
        print(f"  stroke {r.stroke_range.low:.10g} .. {r.stroke_range.high:.10g} {u}")
        for t, xs in counts.items():
            print(f"  TR {t:g}: {len(xs)} design(s)" + (": " + ", ".join(f"{x:.10g}" for x in xs) if xs else ""))
        print(f"  adjustable {args.free}: {adj.explanation}")
    if args.plot:
        from qropt.io import plots

        plots.save(plots.reachable_figure(r, args.tr), args.plot)


def load_problem(path: str):
    """The Problem of a file: a ``.py`` file's ``build()``, or a ``.toml`` / ``.json`` problem table."""
    import importlib.util
    from pathlib import Path

    from qropt.errors import ProblemError
    from qropt.synthesis.problem import Problem
    from qropt.validate import read_text, regular_file

    file = Path(path)
    if not file.exists():
        raise CliError(f"no problem file {path!r}")
    if file.suffix not in (".toml", ".json", ".py"):
        raise CliError(f"{path}: a problem file is .py (with build()), .toml or .json")
    if file.suffix in (".toml", ".json"):
        text = read_text(file, "problem file", error=ProblemError)
        _importable(file)  # a type of one's own named "module:Class" may sit beside the file
        try:
            return Problem.from_toml(text) if file.suffix == ".toml" else Problem.from_json(text)
        except ProblemError as e:
            raise ProblemError(f"{path}: {e}") from None
    regular_file(file, "problem file", error=ProblemError)  # before Python opens it
    _importable(file)
    name = _module_name(file)
    spec = importlib.util.spec_from_file_location(name, file)
    module = importlib.util.module_from_spec(spec)
    if not name.startswith("qropt_problem_"):  # importable by its name: a type it defines travels by reference
        sys.modules[name] = module
    try:
        spec.loader.exec_module(module)
        built = module.build() if callable(getattr(module, "build", None)) else None
    except QroptError as e:
        sys.modules.pop(name, None)
        raise type(e)(f"{path}: {e}") from None
    except (Exception, SystemExit) as e:  # noqa: BLE001 - a user's file may fail in any way: one line naming it
        sys.modules.pop(name, None)
        raise CliError(f"{path} does not load: {type(e).__name__}: {e}") from None
    if not callable(getattr(module, "build", None)):
        raise CliError(f"{path} has no build() function")
    if not isinstance(built, Problem):
        raise CliError(f"{path}: build() must return a qropt.Problem, got {type(built).__name__}")
    return built


def _module_name(file) -> str:
    """The name under which a problem file is loaded: the one ``import`` finds it by from its folder (``stem``, or
    ``package.stem`` in a package folder), so that a mechanism type it defines is found by its "module:Class"
    reference in other processes (Dask workers, a Result reloaded); a private name where that name finds another
    module."""
    import importlib.util
    from pathlib import Path

    here = file.resolve()
    folder = here.parent
    names = ([f"{folder.name}.{file.stem}"] if (folder / "__init__.py").is_file() else []) + [file.stem]
    for name in names:
        if not all(part.isidentifier() for part in name.split(".")):
            continue
        try:
            spec = importlib.util.find_spec(name)
        except Exception:  # noqa: BLE001 - a folder that does not import as a package: the private name
            continue
        if spec is not None and spec.origin and Path(spec.origin).resolve() == here:
            return name
    return f"qropt_problem_{file.stem}"


def _importable(file) -> None:
    """A problem file may import its siblings: its own folder goes on sys.path, and the folder above it too
    where its folder is a package (``from problems import _bases``)."""
    folder = file.resolve().parent
    for d in ([folder.parent] if (folder / "__init__.py").is_file() else []) + [folder]:
        if str(d) not in sys.path:
            sys.path.insert(0, str(d))


def stated_dynamics(problem, args) -> dict:
    """The changes --loads FILE and --point-mass make to a problem: its loads replaced, point masses added to its
    masses (``Problem.replace`` keywords)."""
    from qropt.dynamics.model import Masses

    changes = {}
    loads = loads_of(args)
    if loads is not None:
        changes["loads"] = loads
    points = point_masses(args)
    if points:
        masses = problem.masses if problem.masses is not None else Masses()
        masses = masses if isinstance(masses, Masses) else Masses.from_dict(masses)
        changes["masses"] = masses.replace(points={**masses.points, **points})
    return changes


def cmd_synth(args):
    from qropt.synthesis.solver import solve

    if args.problem is None:
        from qropt.examples import paper_problem

        problem = paper_problem()
    else:
        problem = load_problem(args.problem)
    changes = {}
    if args.objective:
        changes["objective"] = None if args.objective == "none" else args.objective
    if args.size:
        if (changes.get("objective", problem.objective)) != "min_size":
            raise CliError("--size applies to the min_size objective only (give --objective min_size)")
        changes["size"] = args.size
    changes.update(stated_dynamics(problem, args))
    if changes:
        problem = problem.replace(**changes)
    if args.starts is not None and args.starts < 0:
        raise CliError(f"--starts must be >= 0, got {args.starts}")
    r = solve(problem, starts_n=args.starts, time_limit=args.time_limit)
    if args.json:
        json.dump(r.to_dict(), sys.stdout, indent=2, default=str, allow_nan=False)
        sys.stdout.write("\n")
    else:
        print(f"{problem.name or args.problem}: {type_reference(problem.mechanism)}, objective {problem.objective}")
        print(r.summary())
        for k, (lo, hi) in r.reachable.items():
            unit = {"stroke": f" {problem.units}", "swing": " rad"}.get(k, "")
            print(f"reachable {k}: {lo:.10g} .. {hi:.10g}{unit}")
        if r.local_optima:
            print(f"local optima ({len(r.local_optima)}):")
            for o in r.local_optima:
                free = ", ".join(f"{k}={o.params[k]:.10g}" for k in problem.free)
                obj = "" if o.objective is None else f"  objective {o.objective:.10g}"
                print(f"  {free}  gamma_min {math.degrees(o.quantities['gamma_min']):.6f} deg{obj}")
        st = r.stats
        print(f"stats: {st.get('starts')} starts, {st.get('t_total', 0):.3f} s total")
    if args.plot and r.mechanism is not None:
        from qropt.io import plots

        plots.save(plots.cycle_figure(r.mechanism, omega2=problem.omega2), args.plot)
    if r.mechanism is not None:
        export(args, r.mechanism)
    return 0 if r.success else 1


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    try:
        lead = next((i for i, a in enumerate(argv) if a not in ("--quiet", "-q")), len(argv))
        if argv[lead : lead + 1] == ["bench"]:  # its options are the benchmark suite's own
            return cmd_bench(argv[lead + 1 :])
        args = parser().parse_args(argv)
        global QUIET
        QUIET = args.quiet
        if getattr(args, "plot", None):
            picture_path(args.plot)
        return args.run(args) or 0
    except CliError as e:
        print(f"qropt: error: {e}", file=sys.stderr)
        return 2
    except QroptError as e:
        print(f"qropt: {type(e).__name__}: {e}", file=sys.stderr)
        return 1
    except RecursionError:  # a file nested too deeply for Python's parsers, wherever it was read
        print("qropt: error: an input is nested too deeply to read", file=sys.stderr)
        return 1
    except BrokenPipeError:
        sys.stderr.close()
        return 0
    except OSError as e:
        print(f"qropt: error: {e}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:  # Ctrl-C: one line (a design's worker processes are stopped already)
        print("qropt: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
