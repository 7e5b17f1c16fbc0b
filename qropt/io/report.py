"""One self-contained HTML report (pictures inline, no external resources).

Without a problem it works the paper's whole project (Podhorodeski, Nokleby and Wittchen): the task, design
requirements 1 and 2, discussion issues 1-4, analysis tasks 1-3 beside the paper's Tables 2, 3 and 5 (with the
velocity and acceleration polygons), and where the
paper's printed numbers differ from the exact ones. With a problem, the same report for that problem's design.
Every number comes from the library (the code behind the command line); printed values are the paper's claims.
"""

from __future__ import annotations

import base64
import html
import io
import math
from pathlib import Path

import numpy as np

from qropt.errors import InvalidParameter
from qropt.synthesis import analytic
from qropt.validate import output_path

# The paper's printed values (its claims, shown beside the exact ones). Table 5: theta2 = 60 deg, omega2 = 10 rad/s.
TABLE5 = {
    "theta3 [rad]": -0.3247,
    "omega3 [rad/s]": 7.566,
    "alpha3 [rad/s^2]": -51.18,
    "theta4 [rad]": 0.4313,
    "omega4 [rad/s]": 11.69,
    "alpha4 [rad/s^2]": -45.41,
    "theta6 [rad]": 2.931,
    "omega6 [rad/s]": -5.430,
    "alpha6 [rad/s^2]": 44.00,
    "L7 [m]": 0.4296,
    "L7dot [m/s]": -1.074,
    "L7ddot [m/s^2]": -21.67,
}
# The paper's Tables 2 and 3 (relative motion, measured on drawn polygons; r3 = 0.2504 m, theta2 = 60 deg,
# omega2 = 10 rad/s): the printed magnitude beside the term of qropt's polygons it names ('velocity' and
# 'acceleration': the ram's own, exact).
TABLE2 = {
    "|V_B/A| [m/s]": (1.898, "V_B/A"),
    "|V_B| [m/s]": (3.219, "V_B/O4"),
    "|V_C| [m/s]": (1.756, "V_C/O4"),
    "|V_D/C| [m/s]": (1.631, "V_D/C"),
    "|V_D| [m/s]": (1.075, "velocity"),
}
TABLE3 = {
    "|A_A^n| [m/s^2]": (22.50, "A_A/O2^n"),
    "|A_B/A^n| [m/s^2]": (14.39, "A_B/A^n"),
    "|A_B^n| [m/s^2]": (37.68, "A_B/O4^n"),
    "|A_D/C^n| [m/s^2]": (8.87, "A_D/C^n"),
    "|A_D| [m/s^2]": (21.7, "acceleration"),
}
PRINTED = {
    "theta2a, first root [deg] (eq. 12)": 6.18,
    "theta2a, second root [deg] (eq. 12)": 39.38,
    "r3, first root [m]": 0.1544,
    "min of eqs. (14)-(17), first root [deg]": 10.47,
    "transmission quality of the chosen design [deg] (eqs. 14-17)": 35.60,
    "largest TR of the adjustable coupler": 5.538,
}
CSS = (
    "body{font-family:sans-serif;max-width:1100px;margin:2em auto;color:#222;line-height:1.45}"
    "table{border-collapse:collapse;margin:.6em 0}td,th{border:1px solid #bbb;padding:.25em .6em;text-align:right}"
    "th{background:#eee}td:first-child,th:first-child{text-align:left}img{max-width:100%}.bad{color:#b00}"
)


def _png(fig) -> str:
    import matplotlib.pyplot as plt

    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=90)
    plt.close(fig)
    return f'<img alt="figure" src="data:image/png;base64,{base64.b64encode(buf.getvalue()).decode()}">'


def _table(head, rows) -> str:
    h = "".join(f"<th>{html.escape(str(c))}</th>" for c in head)
    body = "".join("<tr>" + "".join(f"<td>{_fmt(c)}</td>" for c in r) + "</tr>" for r in rows)
    return f"<table><tr>{h}</tr>{body}</table>"


def _fmt(v) -> str:
    if isinstance(v, float):
        return f"{v:.6g}"
    return html.escape(str(v))


def _design_section(title, r, free) -> str:
    from qropt.io import plots

    if not r.success:
        return f"<h2>{title}</h2><p class=bad>{html.escape(r.status)}: {html.escape(r.message)}</p>"
    m, q = r.mechanism, r.quantities
    u, kinds = m.units, m.kinds()

    def named(k):  # a parameter's column: lengths and offsets in the unit, angles in degrees, branch signs bare
        return {"angle": f"{k} [deg]", "branch": k}.get(kinds.get(k), f"{k} [{u}]")

    def shown(k, v):
        return math.degrees(v) if kinds.get(k) == "angle" else v

    rows = [(named(k), shown(k, v)) for k, v in m.params.items()]
    rows += [("time ratio", q["time_ratio"]), ("gamma_min [deg]", math.degrees(q["gamma_min"]))]
    rows += [(f"stroke [{u}]", q["stroke"])] if "stroke" in q else [("swing [deg]", math.degrees(q["swing"]))]
    head = ["status", *(named(k) for k in free), "gamma_min [deg]", "objective"]
    optima = [
        (o.status, *(shown(k, o.params[k]) for k in free), math.degrees(o.quantities["gamma_min"]), o.objective)
        for o in r.local_optima
    ]
    return (
        f"<h2>{title}</h2><p>{html.escape(r.message)}</p>{_table(['quantity', 'value'], rows)}"
        f"<h3>Every certified local optimum</h3>{_table(head, optima)}"
        f"{_png(plots.cycle_figure(m, omega2=r.stats.get('omega2', 1.0)))}"
    )


def _table5(m) -> list[float]:
    s = m.slider(math.radians(60), 10.0, 0.0)
    return [
        s.angles["theta3"][0],
        s.omega["theta3"][0],
        s.alpha["theta3"][0],
        s.angles["theta4"][0],
        s.omega["theta4"][0],
        s.alpha["theta4"][0],
        s.angles["theta6"][0] + math.pi,
        s.omega["theta6"][0],
        s.alpha["theta6"][0],
        s.x[0] - m.params["r1"],
        s.v[0],
        s.a[0],
    ]


def _paper(tick, loads=None, points=None) -> str:
    from qropt import family, reachable, solve
    from qropt.examples import paper_mechanism, paper_problem
    from qropt.io import plots
    from qropt.synthesis.problem import Problem

    p = paper_problem()
    r = solve(p)
    parts = [
        "<h1>The paper's quick-return project, worked by qropt</h1>",
        "<p>Task: a drag-link driven slider with r1 = 0.1, r2 = 0.225, r4 = 0.275, r6 = 0.3 m, the slide line "
        "through O2 and O4; find the coupler r3 and the pin location r5 for a time ratio of 1.5 and a stroke of "
        "0.3 m (design requirement 1).</p>",
        _design_section("Design requirement 1: r3 and r5, both roots, chosen by the true gamma_min", r, list(p.free)),
    ]
    roots = analytic.drag_link_r3(1.5, 0.1, 0.225, 0.275)
    rows = []
    for s in roots:
        g_tdc, g_bdc = analytic.paper_transmission_at_dead_centres(0.1, 0.225, s.r3, 0.275)
        m = p.build({"r3": s.r3, "r5": 0.15}, {"sigma": -1.0, "sigma_slider": 1.0})
        rows.append(
            (s.r3, math.degrees(s.theta2a), math.degrees(g_tdc), math.degrees(g_bdc), math.degrees(m.gamma_min().value))
        )
    tick()
    parts.append(
        "<p>Eqs. (7)-(13) give every coupler for the time ratio; eqs. (14)-(17) evaluate the transmission angle at "
        "the dead centres only, while gamma_min is the smallest over the whole turn:</p>"
        + _table(["r3 [m]", "theta2a [deg]", "eq. 14-17 at TDC [deg]", "at BDC [deg]", "true gamma_min [deg]"], rows)
    )
    tick()
    reach = reachable(paper_mechanism(), "r3")
    adj = reach.adjustable(1.5, 2.5)
    t = reach.time_ratio_range
    parts.append(
        "<h2>Design requirement 2 and discussion issues 1-2: the adjustable coupler</h2>"
        f"<p>Grashof drag-link for r3 in {', '.join(f'[{a:.6g}, {b:.6g}]' for a, b in reach.intervals)} m; the time "
        f"ratio ranges from {t.low:.6g} (r3 = {t.low_at:.6g}) to {t.high:.6g} (r3 = {t.high_at:.6g}). "
        f"TR 1.5 is given by {reach.count(1.5)} couplers ({', '.join(f'{x:.6g}' for x in reach.solutions(1.5))} m). "
        f"Adjustable from TR 1.5 to 2.5: {html.escape(adj.explanation)}.</p>"
        + _png(plots.reachable_figure(reach, (1.5, 2.0)))
    )
    fam_problem = Problem(
        "DragLinkSlider",
        fixed={"r2": 0.225, "r4": 0.275, "r5": 0.15, "r6": 0.3},
        free={"r1": (0.02, 0.2), "r3": (0.05, 0.6)},
        targets={"time_ratio": 1.5},
    )
    tick()
    fam = family(fam_problem)
    best = fam.best("max_gamma_min")
    fold = fam.folds[0]["r1"] if fam.folds else float("nan")
    parts.append(
        "<h2>Discussion issues 3-4: r1 and r3 both free, and what isolates a design</h2>"
        f"<p>With r1 free too, TR 1.5 leaves one curve of designs ({len(fam.points())} traced points); it folds at "
        f"r1 = {fold:.9g} m, where eq. (12)'s two roots meet. The ends: "
        + "; ".join(html.escape(e.reason) for e in fam.ends)
        + f". A criterion isolates one design: the largest gamma_min on the curve is "
        f"{math.degrees(best.objective):.4f} deg at r1 = {best.params['r1']:.6g}, r3 = {best.params['r3']:.6g} m.</p>"
        + _png(plots.family_figure(fam, best=best))
    )
    tick()
    m = r.mechanism
    rounded = type(m)(**{**m.params, "r3": round(m.params["r3"], 4)})  # the r3 the paper's GNLINK run was given
    exact, table4 = _table5(m), _table5(rounded)
    rows = [(k, printed, e, t, t - printed) for (k, printed), e, t in zip(TABLE5.items(), exact, table4, strict=True)]
    parts.append(
        "<h2>Analysis 1-2: velocities and accelerations at theta2 = 60 deg, omega2 = 10 rad/s, alpha2 = 0</h2>"
        "<p>Beside the paper's Table 5 (theta6 measured D to C as in the paper; L7 = O4D): the chosen design with "
        "the exact r3, and with the r3 = 0.2504 m of the paper's Table 4, which reproduces every printed digit.</p>"
        + _table(["quantity", "paper (printed)", "exact r3", "r3 = 0.2504", "difference (0.2504)"], rows)
    )
    tick()
    parts.append(_polygons(rounded))
    tick()
    th = np.radians(np.arange(0, 360, 30))
    mo = m.motion(th, 10.0)
    rows = [(f"{math.degrees(a):.0f}", x, v, acc) for a, x, v, acc in zip(th, mo.x, mo.v, mo.a, strict=True)]
    parts.append(
        "<h2>Analysis 3: the full revolution at omega2 = 10 rad/s</h2>"
        + _png(plots.cycle_figure(m, math.radians(60), 10.0))
        + _table(["theta2 [deg]", "x [m]", "v [m/s]", "a [m/s^2]"], rows)
    )
    tick()
    parts.append(_forces(m, loads=loads, points=points, source="as given"))
    g_lo = analytic.paper_transmission_at_dead_centres(0.1, 0.225, roots[0].r3, 0.275)
    exact = [
        math.degrees(roots[0].theta2a),
        math.degrees(roots[1].theta2a),
        roots[0].r3,
        math.degrees(min(g_lo)),
        math.degrees(m.gamma_min().value),
        t.high,
    ]
    rows = [(k, printed, v) for (k, printed), v in zip(PRINTED.items(), exact, strict=True)]
    parts.append(
        "<h2>Where the paper's printed numbers differ from the exact ones</h2>"
        + _table(["quantity", "paper (printed)", "exact"], rows)
        + "<p>The chosen design's true gamma_min is found at theta2 = "
        f"{math.degrees(m.gamma_min().theta2):.4f} deg (joint {m.gamma_min().joint}), not at a dead centre.</p>"
    )
    return "".join(parts)


# The report's assumptions for the forces (the paper gives none): steel bars 20 mm x 10 mm, a 20 kg ram, a 1000 N
# cutting force on the working stroke, gravity, and a flywheel for a speed fluctuation of 5 % at 10 rad/s.
FORCES = {"area": 2e-4, "ram": 20.0, "force": 1000.0, "gravity": 9.81, "omega2": 10.0, "cs": 0.05}
STROKE_WORDS = {"working": "on the working stroke", "return": "on the return stroke", "both": "always"}


def _amount(v, unit: str, against: str, units: str) -> str:
    """A load's magnitude: a constant, or a table's rows, range and abscissa."""
    if not isinstance(v, tuple):
        return f"{v:.6g} {unit}"
    lo, hi = min(r[1] for r in v), max(r[1] for r in v)
    by = f"x [{units}]" if against == "x" else "theta2"
    rows = "; ".join(
        f"{(r[0] if against == 'x' else math.degrees(r[0])):.4g}{'' if against == 'x' else ' deg'}: {r[1]:.4g}"
        for r in v[:6]
    )
    more = f"; ... ({len(v)} rows)" if len(v) > 6 else ""
    return f"{lo:.4g} .. {hi:.4g} {unit}, a table against {by} ({rows}{more})"


def _window(w, units: str) -> str:
    """Where a load acts, in words (``qropt.Window``)."""
    if w.theta2 is not None:
        a, b = (math.degrees(v) for v in w.theta2)
        return f"theta2 from {a:.4g} to {b:.4g} deg"
    if w.x is not None:
        x = f"x from {w.x[0]:.4g} to {w.x[1]:.4g} {units}"
        return x if w.stroke == "both" else f"{x}, {STROKE_WORDS[w.stroke]}"
    return STROKE_WORDS[w.stroke]


def _direction(d) -> str:
    if d == "against":
        return "against its point's velocity"
    if d == "slide":
        return "along the slide line's +x (signed)"
    return f"fixed: ({d[0]:.4g}, {d[1]:.4g}), {math.degrees(math.atan2(d[1], d[0])):.4g} deg from +x"


def loads_table(loads, masses=None, units: str = "m") -> str:
    """The loads as a table: the cutting force, the slide's and the pins' friction, the follower's torque, each
    force (F1, F2, ... as the dynamics figure names them: its point, direction, magnitude and window) and torque
    (T1, ...), gravity, the named working stroke and the point masses (``masses.points``); ``units``: the
    mechanism's length unit (windows and tables against x)."""
    rows = []
    f = loads.cutting_force
    if isinstance(f, tuple) or f:
        rows.append(
            (
                "cutting force",
                "the ram",
                "against the ram's motion",
                _amount(f, "N", "x", units),
                "on the working stroke",
            )
        )
    if loads.friction:
        rows.append(("slide friction", "the slide", "against the ram's velocity", f"mu {loads.friction:.4g}", "always"))
    if loads.follower_torque:
        rows.append(
            (
                "follower torque",
                "the follower",
                "against its working swing",
                f"{loads.follower_torque:.6g} N m",
                "on the working stroke",
            )
        )
    for i, v in enumerate(loads.forces, 1):
        rows.append(
            (
                f"F{i}",
                v.where,
                _direction(v.direction),
                _amount(v.magnitude, "N", v.against, units),
                _window(v.window, units),
            )
        )
    for i, v in enumerate(loads.torques, 1):
        amount = _amount(v.magnitude, "N m", v.against, units)
        rows.append((f"T{i}", f"the {v.on}", "counter-clockwise positive", amount, _window(v.window, units)))
    gx, gy = loads.gravity_vector
    if gx or gy:
        angle = math.degrees(math.atan2(gy, gx))
        rows.append(
            (
                "gravity",
                "every body's centre of mass",
                f"({gx:.4g}, {gy:.4g}), {angle:.4g} deg from +x",
                f"{math.hypot(gx, gy):.4g} m/s^2",
                "always",
            )
        )
    pf = loads.pin_friction
    if pf is not None:
        where = "every pin" + (f" (r {pf.radius:.4g} m)" if pf.radius is not None else "")
        where += "".join(f"; {j}: mu {mu:.4g}, r {r:.4g} m" for j, (mu, r) in pf.joints.items())
        rows.append(("pin friction", where, "against each pin's relative rotation", f"mu {pf.mu:.4g}", "always"))
    if loads.working is not None:
        rows.append(("working stroke", "the ram", f"moves {loads.working}", "", "(named: the strokes take equal time)"))
    for joint, kg in (masses.points if masses is not None else {}).items():
        rows.append(("point mass", joint, "", f"{kg:.6g} kg", ""))
    if not rows:
        return "<p>No loads: the forces are the inertia's alone.</p>"
    return _table(["load", "at / on", "direction", "magnitude", "acts"], rows)


def _forces(m, masses=None, loads=None, omega2=None, points=None, source: str = "as given", loads_from=None) -> str:
    """Forces and torque of a design over the turn, with its loads' table and the dynamics figure (the applied
    loads drawn as arrows): under the report's assumptions (``FORCES``) for what is not given (masses None: the
    assumed steel bars and ram; loads None: the assumed cutting force and gravity), ``source`` naming where the
    given ones come from ("the problem's"; ``loads_from``, the loads', where it differs); ``points``: point masses
    (joint -> kg) added to the masses."""
    from qropt.dynamics.cycle import CycleDynamics
    from qropt.dynamics.model import Loads, Masses
    from qropt.io import plots

    f = FORCES
    loads_from = source if loads_from is None else loads_from
    masses_assumed, loads_assumed = masses is None, loads is None
    masses = Masses.steel(f["area"], f["ram"]) if masses_assumed else masses
    if points:
        masses = masses.replace(points={**masses.points, **points})
    loads = Loads(f["force"], gravity=f["gravity"]) if loads_assumed else loads
    omega2 = f["omega2"] if omega2 is None else omega2
    cd = CycleDynamics(m, omega2, 0.0, masses, loads)
    ex, fw = cd.extremes(), cd.flywheel(f["cs"])
    rows = [
        ("peak crank torque [N m]", ex.peak_torque.value, math.degrees(ex.peak_torque.theta2)),
        ("RMS crank torque [N m]", ex.rms_torque, ""),
        ("mean crank torque [N m]", ex.mean_torque, ""),
        *((f"peak force at {k} [N]", p.value, math.degrees(p.theta2)) for k, p in ex.peak_forces.items()),
        ("peak shaking force [N]", ex.peak_shaking_force.value, math.degrees(ex.peak_shaking_force.theta2)),
        (
            "peak shaking moment about O2 [N m]",
            ex.peak_shaking_moment.value,
            math.degrees(ex.peak_shaking_moment.theta2),
        ),
        (f"flywheel for Cs = {f['cs']:g} [kg m^2]", fw.inertia, ""),
        ("energy fluctuation [J]", fw.energy_fluctuation, ""),
        ("energy a turn [J]", fw.energy_per_turn, ""),
        ("energy on the working stroke [J]", fw.working_energy, ""),
    ]
    if masses_assumed:
        said = (
            "The paper gives no masses. Assumed here: steel links (7850 kg/m^3) of a 20 mm x 10 mm section "
            f"({masses.density:.4g} kg/m, uniform bars; the follower a bar over its longer arm), a {f['ram']:g} kg ram"
        )
    else:
        said = f"The masses are {html.escape(source)}: links {masses.density:.4g} kg/m (uniform bars)"
        said += f", ram {masses.ram:g} kg" + (f", crank-pin block {masses.block:g} kg" if masses.block else "")
        cw = masses.counterweight
        said += f", a counterweight of {cw.mass:.4g} kg at {cw.radius:.4g} m" if cw is not None and not cw.free else ""
    if masses.points:
        said += ", point masses " + ", ".join(f"{k} {v:g} kg" for k, v in masses.points.items())
    if loads_assumed:
        said += f"; a {f['force']:g} N cutting force resisting the working stroke, gravity {f['gravity']:g} m/s^2"
    else:
        said += f"; the loads are {html.escape(loads_from)} (the table)"
    if masses_assumed and loads_assumed:
        heading = "assumed masses and load"
    elif not masses_assumed and not loads_assumed and loads_from == source:
        heading = f"{source} masses and loads"
    else:
        heading = ("assumed masses" if masses_assumed else f"{source} masses") + ", "
        heading += (
            "assumed load"
            if loads_assumed
            else f"loads {loads_from}"
            if loads_from == "as given"
            else f"{loads_from} loads"
        )
    figure = plots.dynamics_figure(m, omega2, masses, loads, math.radians(60))
    return (
        f"<h2>Forces and torque ({html.escape(heading)})</h2>"
        f"<p>{said}; omega2 = {omega2:g} rad/s. Exact over the turn (inverse dynamics from the same loop code; the "
        "torque agrees with the power balance to rounding).</p>"
        "<h3>The loads</h3>"
        + loads_table(loads, masses, m.units)
        + _table(["quantity", "value", "at theta2 [deg]"], rows)
        + "<p>At theta2 = 60 deg: each joint's force on the driven body and the applied loads (F1, T1, ... as in "
        "the table; a load off at that angle faded), to one scale; over the turn: the crank torque and the joint "
        "forces.</p>" + _png(figure)
    )


def _polygons(m) -> str:
    """Analysis 1 by relative motion: the paper's Tables 2-3 beside qropt's polygons, the polygons drawn, and
    every term."""
    from qropt.io.plots import polygon_figure

    rm = m.relative_motion(math.radians(60), 10.0, 0.0)
    terms = rm.terms()
    ram = {e.quantity: float(np.hypot(*e.exact)) for e in rm.equations if e.joint == m.output_joint()}

    def rows(table):
        out = []
        for label, (printed, key) in table.items():
            v = ram[key] if key in ram else terms[key].magnitude
            name = f"{m.output_joint()} ({key}, exact)" if key in ram else key
            out.append((label, printed, name, v, f"{100 * (printed - v) / v:+.2f} %"))
        return out

    head = ["quantity", "paper (printed)", "qropt term", "qropt", "paper - qropt"]
    every = [
        (
            r["quantity"],
            r["joint"],
            r["term"],
            r["kind"],
            r["magnitude"],
            r["direction_deg"],
            "solved" if r["solved"] else "known",
        )
        for r in rm.table()
    ]
    return (
        "<h2>Analysis 1 by relative motion: the velocity and acceleration polygons (Tables 2-3, Fig. 7b-c)</h2>"
        "<p>The vector equations written dyad by dyad at theta2 = 60 deg, omega2 = 10 rad/s, alpha2 = 0 for the "
        "design of the paper's Table 4 (r3 = 0.2504 m). The paper measured its values on drawn polygons; qropt's "
        "terms sum to the exact velocities and accelerations to rounding.</p>"
        + _table(head, rows(TABLE2))
        + _table(head, rows(TABLE3))
        + _png(polygon_figure(rm))
        + "<p>Every term (directions counter-clockwise from +x; 'known' from what came before or from a link's "
        "rate and length, 'solved' from the polygon):</p>"
        + _table(["equation", "joint", "term", "kind", "magnitude", "direction [deg]", ""], every)
    )


def _problem(problem, loads_from: str = "the problem's") -> str:
    """A problem's design; with its forces and torque under its masses and loads where it states either
    (``loads_from``: where its loads come from, for the words)."""
    from qropt import solve
    from qropt.dynamics.model import Loads, Masses

    r = solve(problem)
    title = f"{problem.mechanism.__name__}: objective {problem.objective}, lengths in {problem.units}"
    out = f"<h1>{html.escape(problem.name or problem.mechanism.__name__)}</h1>" + _design_section(
        title, r, list(problem.free)
    )
    if r.success and (problem.masses is not None or problem.loads is not None):
        settled = problem.settled(r)
        masses = settled.masses if settled.masses is not None else Masses()
        loads = settled.loads if settled.loads is not None else Loads()
        out += _forces(r.mechanism, masses, loads, problem.omega2, source="the problem's", loads_from=loads_from)
    return out


def design_page(m, theta2: float = 0.0, omega2: float = 1.0) -> str:
    """One design's report as a whole HTML page: its parameters and exact cycle quantities, x, v, a over the turn,
    the velocity and acceleration polygons at theta2 (rad) and omega2 (rad/s) for a type built from dyads, and
    its forces under the report's assumed masses and load (``FORCES``)."""
    from qropt.errors import QroptError
    from qropt.io import plots
    from qropt.io.plots import polygon_figure

    u, kinds = m.units, m.kinds()
    g, d = m.gamma_min(), m.dead_centres()
    rows = [
        (
            {"angle": f"{k} [deg]", "branch": k}.get(kinds.get(k), f"{k} [{u}]"),
            math.degrees(v) if kinds.get(k) == "angle" else v,
        )
        for k, v in m.params.items()
    ]
    rows += [("time ratio", m.time_ratio()), (f"stroke [{u}]", m.stroke())]
    rows += [
        ("gamma_min [deg]", math.degrees(g.value)),
        ("theta_max, theta_min [deg]", f"{math.degrees(d.theta_max):.4f}, {math.degrees(d.theta_min):.4f}"),
    ]
    rows += [(f"peak acceleration at omega2 = {omega2:g} rad/s [{u}/s^2]", m.peak_acceleration(omega2).value)]
    body = f"<h1>{html.escape(type(m).__name__)}</h1>" + _table(["quantity", "value"], rows)
    body += _png(plots.cycle_figure(m, theta2, omega2))
    try:
        rm = m.relative_motion(theta2, omega2, 0.0)
    except QroptError:
        rm = None
    if rm is not None:
        body += f"<h2>Velocity and acceleration polygons at theta2 = {math.degrees(theta2):g} deg</h2>"
        body += _png(polygon_figure(rm, u))
    try:
        body += _forces(m)
    except QroptError as e:
        body += f"<p class=bad>No forces: {html.escape(str(e))}</p>"
    head = f"<meta charset='utf-8'><title>qropt design: {html.escape(type(m).__name__)}</title><style>{CSS}</style>"
    return f"<!DOCTYPE html><html><head>{head}</head><body>{body}</body></html>\n"


def render(problem=None, path=None, progress=None, *, loads=None, points=None) -> str:
    """The report's HTML (also written to ``path`` if given): the paper's project, or the given problem's design.

    progress: callable() after each section; loads (``qropt.Loads``): instead of the report's assumed load (the
    paper's project) or the problem's loads; points: point masses (joint -> kg) added to the masses. The paper's
    design is checked against them before any section is computed."""
    from qropt.dynamics.model import Loads, Masses
    from qropt.synthesis.problem import Problem

    if problem is not None and not isinstance(problem, Problem):
        raise InvalidParameter(f"render takes a qropt.Problem or None, got {type(problem).__name__}")
    if loads is not None and not isinstance(loads, Loads):
        raise InvalidParameter(f"render's loads are a qropt.Loads or None, got {type(loads).__name__}")
    if path is not None:
        report_path(path)  # before any section is computed
    tick = progress if callable(progress) else (lambda: None)
    if problem is not None and (loads is not None or points):
        masses = problem.masses if problem.masses is not None else Masses()
        stated = {"masses": masses.replace(points={**masses.points, **points})} if points else {}
        problem = problem.replace(**stated, **({"loads": loads} if loads is not None else {}))
    if problem is None and (loads is not None or points):
        from qropt.examples import paper_mechanism

        f = FORCES  # an unknown joint or body fails here, in one line, before the sections
        masses = Masses.steel(f["area"], f["ram"]).replace(points=dict(points or {}))
        paper_mechanism().dynamics([math.radians(60)], f["omega2"], masses=masses, loads=loads)
    if problem is None:
        body = _paper(tick, loads, points)
    else:
        body = _problem(problem, "the problem's" if loads is None else "as given")
    title = "qropt report" if problem is None else f"qropt report: {problem.name or problem.mechanism.__name__}"
    head = f"<meta charset='utf-8'><title>{html.escape(title)}</title><style>{CSS}</style>"
    text = f"<!DOCTYPE html><html><head>{head}</head><body>{body}</body></html>\n"
    if path is not None:
        try:
            Path(path).write_text(text)
        except OSError as e:
            raise InvalidParameter(f"{path}: cannot write the report: {e.strerror or e}") from None
    return text


def report_path(path) -> Path:
    """A path for the report: an .html (or .htm) file in an existing directory that can be written."""
    return output_path(path, (".html", ".htm"), "report")


__all__ = ["render", "report_path", "design_page"]
