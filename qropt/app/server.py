"""The web application: the pages (one HTML file, its script and style, served from the package: no external
resources) and the JSON API under ``/api`` (Flask). Every answer to bad input is a 4xx with ``{"error": reason}``
in one line; nothing a request sends stops the server.

- ``GET /api/health``; ``GET /api/types`` (every type, its parameters and a valid design to open with);
  ``GET /api/problems`` (the problem files the app was started with)
- ``POST /api/analyze``: ``{type, params, theta2, omega2}`` -> the analysis (``qropt.app.api.analyze``)
- ``POST /api/problem/read``: ``{name, text}`` (a ``.json`` or ``.toml`` problem file) -> the problem in
  ``Problem.to_dict``'s form; a ``.py`` file is refused (code runs only when the command line names it)
- ``POST /api/solve``: a problem (``Problem.to_dict``'s form) -> the Result (``Result.to_dict``'s form)
- ``GET /api/design/options``: what a design may ask for: the objectives (the criteria registry's), the types
  (``design``'s rows and the served user types) and the longest time budget
- ``POST /api/design``: ``{time_ratio, stroke, objective}`` (optional ``bounds``, ``conditions``, ``types``,
  ``omega2``, ``masses``, ``loads``, ``drive``, ``time_limit``) -> the Comparison (``Comparison.to_json``'s form)
- ``POST /api/jobs``: ``{kind: solve | design | report, input}`` -> 202 and the job; ``GET /api/jobs/<id>``
  its state, progress and result; ``DELETE /api/jobs/<id>`` cancels it
- ``POST /api/export/<dxf|svg|json>``: ``{type, params, units?, theta2?}`` -> the file
"""

from __future__ import annotations

import math
import tempfile
from importlib import resources
from pathlib import Path

from qropt import validate
from qropt.app import api
from qropt.app.defaults import remember
from qropt.app.jobs import Busy, Jobs
from qropt.cli import load_problem
from qropt.dynamics.applied import RAM
from qropt.dynamics.drive import Drive
from qropt.dynamics.model import Force, Loads, Masses
from qropt.errors import QroptError
from qropt.studies._design import task_problems

MAX_BODY = 1 << 20  # bytes of a request body
STATIC = {"": ("index.html", "text/html"), "app.js": ("app.js", "text/javascript"), "app.css": ("app.css", "text/css")}


def _problem(payload):
    """A Problem from its JSON form, its type checked first (never imported on a request's word)."""
    from qropt.synthesis.problem import Problem

    if not isinstance(payload, dict):
        raise api.ApiError(f"a problem is a JSON object (Problem.to_dict's form), got {type(payload).__name__}")
    d = dict(payload)
    d["mechanism"] = api.known_type(d.get("mechanism"))
    return Problem.from_dict(d)


def read_problem(payload) -> dict:
    """``{name, text}``: a problem file's text (qropt's ``.json`` or ``.toml``; ``name`` the file's name, whose
    ending says which) as ``Problem.to_dict``'s form, read and checked as ``qropt synth`` reads it. A ``.py``
    problem is code: it is refused (the app runs one only when the command line names it)."""
    import tomllib

    d = api.fields(payload, ("name", "text"))
    name, text = d["name"], d["text"]
    if not isinstance(name, str) or not isinstance(text, str):
        raise api.ApiError("name and text are strings: the file's name and its text")
    kind, short = Path(name).suffix.lower(), Path(name).name[:80]
    if kind == ".py":
        raise api.ApiError(
            f"{short} is a Python problem, which is code: the app runs it only when the command line names it "
            f"(qropt app {short}); here load a .json or .toml problem"
        )
    if kind not in (".json", ".toml"):
        raise api.ApiError(f"{short!r} is not a problem file: qropt's are .json or .toml (or .py on the command line)")
    if validate.nesting(text) > validate.MAX_NESTING:
        raise api.ApiError(f"{short}: nested deeper than {validate.MAX_NESTING} levels")
    if kind == ".json":
        table = validate.json_document(text, short, "problem", error=api.ApiError)
    else:
        try:
            table = tomllib.loads(text)
        except tomllib.TOMLDecodeError as e:
            raise api.ApiError(f"{short} is not TOML: {e}") from None
    return _problem(table).to_dict()


_DESIGN_FIELDS = (
    "bounds",
    "conditions",
    "types",
    "objective",
    "omega2",
    "size",
    "units",
    "masses",
    "loads",
    "drive",
    "time_limit",
)


def _design_input(payload, max_time: float = math.inf) -> dict:
    """``design``'s arguments from a request, checked as far as they can be before a worker runs them;
    ``time_limit`` (s, the budget of the whole comparison) at most ``max_time``, the app's limit of a job."""
    d = api.fields(payload, ("time_ratio", "stroke"), _DESIGN_FIELDS)
    out = {"time_ratio": api.number(d, "time_ratio", low=1.0 + 1e-9, high=50.0)}
    out["stroke"] = api.number(d, "stroke", low=1e-9, high=1e6)
    if "objective" in d:
        names = api.objective_names()
        if d["objective"] not in names:
            raise api.ApiError(f"objective is one of {', '.join(names)}, got {d['objective']!r:.60}")
        out["objective"] = d["objective"]
    if "types" in d:
        t = d["types"]
        if not isinstance(t, list) or not t or not all(isinstance(x, str) for x in t):
            raise api.ApiError("types is a non-empty list of type names (choose at least one type)")
        out["types"] = [api.design_type(x) for x in t]
    if d.get("time_limit") is not None:
        t = api.number(d, "time_limit", low=0.1)
        if t > max_time:
            raise api.ApiError(
                f"time_limit is at most {max_time:g} s, the app's limit of a job (qropt app --time-limit)"
            )
        out["time_limit"] = t
    for k in ("bounds", "conditions", "masses", "loads", "drive"):
        if d.get(k) is not None:
            if not isinstance(d[k], dict):
                raise api.ApiError(f"{k} is an object, got {type(d[k]).__name__}", field=_PANEL.get(k))
            out[k] = d[k]
    if "omega2" in d:
        out["omega2"] = api.number(d, "omega2", low=-1e4, high=1e4)
    for k in ("size", "units"):
        if k in d:
            if not isinstance(d[k], str):
                raise api.ApiError(f"{k} is a string")
            out[k] = d[k]
    if "bounds" in out:
        out["bounds"] = {k: tuple(v) if isinstance(v, list) else v for k, v in out["bounds"].items()}
    try:
        panel = {
            "masses": Masses.from_dict(out["masses"]) if "masses" in out else None,
            "loads": Loads.from_dict(out["loads"]) if "loads" in out else None,
            "drive": Drive.from_dict(out["drive"]) if "drive" in out else None,
        }
    except QroptError as e:
        raise api.panel_error(e) from None
    plain = {k: v for k, v in out.items() if k not in ("masses", "loads", "drive", "time_limit")}
    try:  # every argument checked here, before a job is queued
        problems = task_problems(**plain, **panel)
    except QroptError as e:
        try:  # the same task with a plain mass model, no loads and a drive: the panel's fault if it passes
            task_problems(**plain, masses=Masses(), loads=Loads(), drive=Drive(1.0))
        except QroptError:
            raise e from None
        raise api.panel_error(e) from None
    _loads_fit(problems, panel["masses"], panel["loads"])
    return out


_PANEL = {"masses": "loads", "loads": "loads", "drive": "loads"}  # the request's fields the panel gives


def _loads_fit(problems: dict, masses, loads) -> None:
    """Each load and point mass at a joint or body of every row's type (as ``design`` builds it), else the panel's
    400 naming the load and the row: a design checks this only when a row's solve reaches it."""
    for row, p in problems.items():
        where = api.row_points(row)
        if not where["bodies"]:  # a type without a body declaration: the dynamic criteria refuse it by name
            continue
        name, joints, bodies = p.mechanism.__name__, where["joints"], where["bodies"]
        for load in (*(loads.forces if loads else ()), *(loads.torques if loads else ())):
            if isinstance(load, Force) and isinstance(load.at, str):
                if load.at == RAM and RAM not in joints:
                    if where["ram"] is None:
                        raise api.ApiError(
                            f"{load}: the {row} row's {name} has no ram (untick that type or choose a joint)",
                            field="loads",
                        )
                    continue
                if load.at not in joints:
                    raise api.ApiError(
                        f"{load}: the {row} row's {name} has no joint {load.at!r}; its joints: {joints} "
                        "(untick that type or choose another joint)",
                        field="loads",
                    )
                continue
            body = load.at[0] if isinstance(load, Force) else load.on
            if body not in bodies:
                raise api.ApiError(
                    f"{load}: the {row} row's {name} has no body {body!r}; its bodies: {bodies} "
                    "(untick that type or choose another body)",
                    field="loads",
                )
        for joint in masses.points if masses else ():
            if joint not in joints:
                raise api.ApiError(
                    f"the point mass at {joint}: the {row} row's {name} has no joint {joint!r}; its joints: {joints}",
                    field="loads",
                )


def create_app(files=(), workers: int = 1, queue_size: int = 8, time_limit: float = 300.0):
    """The Flask application: problem ``files`` loaded (their types served), ``workers`` solver processes, at most
    ``queue_size`` jobs waiting, each stopped after ``time_limit`` s."""
    from flask import Flask, Response, jsonify, request
    from werkzeug.exceptions import HTTPException

    problems = {}
    for f in files:
        problems[str(f)] = load_problem(f)
    jobs = Jobs(workers, queue_size, time_limit, files)
    startup = {name: jobs.submit("solve", p.to_dict()) for name, p in problems.items()}
    for name, job in startup.items():  # a user type opens with its problem's design
        job.ended.wait(time_limit)
        if job.state == "done" and job.result.get("params"):
            remember(problems[name].mechanism, job.result["params"])
    app = Flask("qropt", static_folder=None)
    app.config["MAX_CONTENT_LENGTH"] = MAX_BODY
    app.json.sort_keys = False  # parameters in their type's order
    app.extensions["qropt_jobs"] = jobs

    def body():
        return validate.json_document(request.get_data(cache=True), "the request body", error=api.ApiError)

    @app.errorhandler(api.ApiError)
    def _api_error(e):
        return jsonify(error=str(e), **({"field": e.field} if e.field else {})), e.status

    @app.errorhandler(QroptError)
    def _qropt_error(e):
        return jsonify(error=f"{type(e).__name__}: {e}".replace("\n", " ")), 400

    @app.errorhandler(HTTPException)
    def _http_error(e):
        return jsonify(error=f"{e.code} {e.name}: {e.description}"), e.code

    @app.errorhandler(Exception)
    def _internal(e):  # a bug: said in one line; the server goes on
        app.logger.exception("internal error")
        return jsonify(error=f"internal error ({type(e).__name__}): {e}"), 500

    @app.get("/")
    @app.get("/<name>")
    def page(name=""):
        if name not in STATIC:
            raise api.ApiError(f"no page {name!r}", 404)
        file, mime = STATIC[name]
        text = resources.files("qropt.app").joinpath("static", file).read_text()
        return Response(text, mimetype=mime)

    @app.get("/favicon.ico")
    def favicon():
        return Response(status=204)

    @app.get("/api/health")
    def health():
        from qropt import __version__

        return jsonify(status="ok", version=__version__, types=api.types(), workers=len(jobs._slots))

    @app.get("/api/types")
    def types():
        return jsonify(api.type_info())

    @app.get("/api/problems")
    def problem_files():
        out = []
        for name, p in problems.items():
            job = startup[name]
            out.append({"file": name, "problem": p.to_dict(), "job": job.to_dict(result=False)})
        return jsonify(out)

    @app.post("/api/analyze")
    def analyze():
        return jsonify(api.analyze(body()))

    def submit_job(kind, payload):
        try:
            return jobs.submit(kind, payload)
        except Busy as e:
            raise api.ApiError(str(e), 429) from None

    def run(kind, payload):
        job = submit_job(kind, payload)
        job.ended.wait(jobs.time_limit + 30)
        if job.state == "done":
            return job.result
        if job.state == "timeout":
            raise api.ApiError(f"the {kind} stopped at the time limit of {jobs.time_limit:g} s", 408)
        raise api.ApiError(job.error or job.state, 400 if job.error and "internal error" not in job.error else 500)

    @app.post("/api/problem/read")
    def problem_read():
        return jsonify(read_problem(body()))

    @app.post("/api/solve")
    def solve():
        return jsonify(run("solve", _problem(body()).to_dict()))

    @app.post("/api/design")
    def design():
        return jsonify(run("design", _design_input(body(), jobs.time_limit)))

    @app.get("/api/design/options")
    def design_options():
        return jsonify(objectives=api.objectives(), types=api.design_types(), time_limit=jobs.time_limit)

    @app.post("/api/jobs")
    def submit():
        d = api.fields(body(), ("kind", "input"))
        kind, payload = d["kind"], d["input"]
        if kind == "solve":
            payload = _problem(payload).to_dict()
        elif kind == "design":
            payload = _design_input(payload, jobs.time_limit)
        elif kind == "pareto":
            p = api.fields(payload, ("problem", "objectives"), ("n",))
            prob = _problem(p["problem"])
            n = p.get("n", 9)
            ok = isinstance(p["objectives"], list) and len(p["objectives"]) == 2
            if not ok or not all(o in api.objective_names() for o in p["objectives"]):
                raise api.ApiError(f"objectives are two of {', '.join(api.objective_names())}")
            if isinstance(n, bool) or not isinstance(n, int) or not 2 <= n <= 50:
                raise api.ApiError(f"n (points of the front) is an integer from 2 to 50, got {n!r:.20}")
            payload = {"problem": prob.to_dict(), "objectives": p["objectives"], "n": n}
        elif kind == "report":
            payload = api.report_input(payload)
        else:
            raise api.ApiError(f"kind is solve, design, pareto or report, got {kind!r:.40}")
        return jsonify(submit_job(kind, payload).to_dict()), 202

    @app.get("/api/jobs/<jid>")
    def job_state(jid):
        job = jobs.get(jid)
        if job is None:
            raise api.ApiError(f"no job {jid!r:.40}", 404)
        return jsonify(job.to_dict())

    @app.delete("/api/jobs/<jid>")
    def job_cancel(jid):
        job = jobs.cancel(jid)
        if job is None:
            raise api.ApiError(f"no job {jid!r:.40}", 404)
        return jsonify(job.to_dict())

    @app.post("/api/export/<fmt>")
    def export(fmt):
        from qropt.io import export as ex

        d = api.fields(body(), ("type", "params"), ("units", "theta2"))
        if fmt not in ("dxf", "svg", "json"):
            raise api.ApiError(f"export formats are dxf, svg and json, got {fmt!r:.20}", 404)
        m = api.mechanism(d)
        theta2 = api.number(d, "theta2", 0.0, low=-1e6, high=1e6)
        name = f"{type(m).__name__}.{fmt}"
        with tempfile.TemporaryDirectory() as tmp:
            path = Path(tmp) / name
            if fmt == "dxf":
                ex.to_dxf(m, path, theta2)
            elif fmt == "svg":
                ex.to_svg(m, path, theta2)
            else:
                ex.save_design(m, path, theta2_deg=math.degrees(theta2))
            data = path.read_bytes()
        mime = {"dxf": "application/dxf", "svg": "image/svg+xml", "json": "application/json"}[fmt]
        return Response(data, mimetype=mime, headers={"Content-Disposition": f'attachment; filename="{name}"'})

    return app
