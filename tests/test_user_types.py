"""A mechanism type of one's own is first-class: solve, design(types=[...]), family, reachable, pareto, plots,
Result and Problem files reloaded in a fresh process, a 2-worker Dask chart, the command line (analyze
'module:Class' --param, synth FILE, design --types), entry-point plugins; parameter kinds drive the bounds,
scaling, tolerances and --param; the registry refuses a KIND or class name that another class holds."""

from __future__ import annotations

import dataclasses
import importlib
import json
import math
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

import qropt
from qropt import Problem, Result, design, family, pareto, reachable, solve
from qropt.cli import main
from qropt.errors import ProblemError
from qropt.mechanisms import REGISTRY, RegistryError, mechanism_type, type_reference
from qropt.studies._chart_run import chart
from qropt.studies._design import type_problem
from qropt.synthesis.scaling import scales

ROOT = Path(__file__).resolve().parents[1]
MODULE = "qropt_test_user_types_mod"  # written to a temporary folder: importable by name only from there
SOURCE = '''
"""A slider-crank variant: the crank pin leads the crank angle by the angle phi (a type of one's own)."""
from qropt import Problem
from qropt.mechanisms import REQUIRED, Body, Loop, Mechanism, Rule
from qropt.mechanisms.closures import rod_lines, rod_to_line


class PhasedSliderCrank(Mechanism):
    KIND = "phased-slider-crank"
    PARAMS = {"r2": REQUIRED, "r3": REQUIRED, "e": 0.0, "phi": 0.0, "sigma_slider": 1.0}
    LENGTHS = ("r2", "r3")
    ANGLES = ("phi",)
    BODIES = (Body("crank", ("O2", "A"), "bar"), Body("rod", ("A", "C"), "bar"), Body("ram", ("C",), "ram"))
    GROUND = ("O2",)
    OUTPUT_JOINT = "C"

    @classmethod
    def rules(cls, xp, p, grashof=None):
        return [
            Rule("full rotation needs r3 >= r2 + |e|", p["r3"] - p["r2"] - p["e"]),
            Rule("full rotation needs r3 >= r2 + |e|", p["r3"] - p["r2"] + p["e"]),
        ]

    @staticmethod
    def loop(xp, theta2, p):
        a = (p["r2"] * xp.cos(theta2 + p["phi"]), p["r2"] * xp.sin(theta2 + p["phi"]))
        c, m = rod_to_line(xp, a, p["r3"], p["e"], p["sigma_slider"])
        return Loop(
            points={"O2": (0.0, 0.0), "A": a, "C": c},
            angles={"theta2": theta2, "theta3": xp.atan2(c[1] - a[1], c[0] - a[0])},
            x=c[0],
            transmission={"C": rod_lines(a, c)},
            margins=[("rod AC reaching the slide line", m)],
        )


def build():
    return Problem(
        mechanism=PhasedSliderCrank,
        fixed={"r2": 0.3, "phi": 0.4},
        free={"r3": (0.2, 20.0), "e": (0.0, 10.0)},
        targets={"time_ratio": 1.5, "stroke": 1.0},
        name="phased",
    )
'''


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    """A folder holding the user type's module, on sys.path for this file's tests (and inherited by the
    processes they start)."""
    d = tmp_path_factory.mktemp("usertypes")
    (d / f"{MODULE}.py").write_text(SOURCE)
    sys.path.insert(0, str(d))
    yield d
    sys.path.remove(str(d))


@pytest.fixture(scope="module")
def user(folder):
    return importlib.import_module(MODULE)


def _slotted():
    return importlib.import_module("problems.user_slotted_lever")


def _watt():
    return importlib.import_module("problems.user_watt_sixbar")


def _fresh(code: str, path: Path, cwd=None) -> str:
    """Run code in a fresh Python process with path on its sys.path; its standard output."""
    env_code = f"import sys; sys.path.insert(0, {str(path)!r})\n" + textwrap.dedent(code)
    out = subprocess.run([sys.executable, "-c", env_code], capture_output=True, text=True, cwd=cwd, timeout=300)
    assert out.returncode == 0, out.stderr
    return out.stdout


# ---- the registry ------------------------------------------------------------------------------------------------
def test_lookup_by_kind_class_name_and_reference(user):
    cls = user.PhasedSliderCrank
    assert REGISTRY["phased-slider-crank"] is cls
    for name in (cls, "phased-slider-crank", "phased_slider_crank", "PhasedSliderCrank", f"{MODULE}:PhasedSliderCrank"):
        assert mechanism_type(name) is cls
    assert type_reference(cls) == f"{MODULE}:PhasedSliderCrank"
    assert type_reference(qropt.SliderCrank) == "slider-crank"  # a shipped type keeps its KIND


def test_a_taken_kind_or_class_name_is_refused_naming_both(user):
    from qropt.mechanisms import Mechanism

    with pytest.raises(RegistryError, match=r"'slider-crank'.*already taken by qropt\.mechanisms\.slider_crank"):
        type("Impostor", (Mechanism,), {"KIND": "slider-crank", "__module__": "elsewhere"})
    with pytest.raises(RegistryError, match="class name 'SliderCrank'.*already taken"):
        type("SliderCrank", (Mechanism,), {"KIND": "another-slider-crank", "__module__": "elsewhere"})
    with pytest.raises(RegistryError, match=f"already taken by {MODULE}.PhasedSliderCrank"):
        type("Other", (Mechanism,), {"KIND": "Phased_Slider_Crank", "__module__": "elsewhere"})
    assert REGISTRY["slider-crank"] is qropt.SliderCrank and "another-slider-crank" not in REGISTRY
    assert issubclass(RegistryError, qropt.InvalidParameter)


def test_a_reloaded_module_registers_its_class_again(user):
    again = importlib.reload(user)
    assert again.PhasedSliderCrank is not None and REGISTRY["phased-slider-crank"] is again.PhasedSliderCrank


@pytest.mark.parametrize(
    ("ref", "words"),
    [
        ("no_such_module_xyz:Thing", "module 'no_such_module_xyz' is not found"),
        ("qropt.mechanisms:NoSuchClass", "has no class 'NoSuchClass'"),
        ("qropt.mechanisms:REQUIRED", "not a qropt Mechanism subclass"),
        ("math:pi", "not a qropt Mechanism subclass"),
        (":X", "is 'module:Class'"),
        ("no-such-kind", "unknown mechanism type 'no-such-kind'"),
        (42, "unknown mechanism type 42: a type is a Mechanism class, a KIND or 'module:Class'"),
        (int, "not a qropt Mechanism subclass"),
    ],
)
def test_every_failed_lookup_is_a_typed_error(ref, words):
    with pytest.raises(RegistryError, match=words):
        mechanism_type(ref)


def test_an_installed_plugin_is_found_by_kind(tmp_path, monkeypatch):
    import qropt.mechanisms as mechanisms

    (tmp_path / "qropt_plugin_demo.py").write_text(
        SOURCE.replace("PhasedSliderCrank", "PluginSliderCrank").replace("phased-slider-crank", "plugin-slider-crank")
    )
    info = tmp_path / "qropt_plugin_demo-1.0.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: qropt-plugin-demo\nVersion: 1.0\n")
    (info / "entry_points.txt").write_text("[qropt.mechanisms]\ndemo = qropt_plugin_demo\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.setattr(mechanisms, "_plugins_loaded", False)
    assert "plugin-slider-crank" not in REGISTRY
    cls = mechanism_type("plugin-slider-crank")
    assert cls.__name__ == "PluginSliderCrank" and cls.__module__ == "qropt_plugin_demo"


# ---- parameter kinds ---------------------------------------------------------------------------------------------
def test_parameter_kinds_drive_bounds_scaling_and_tolerances(user):
    cls = user.PhasedSliderCrank
    assert cls.kinds() == {"r2": "length", "r3": "length", "e": "offset", "phi": "angle", "sigma_slider": "branch"}
    assert qropt.Whitworth.kinds() == {
        "r1": "length",
        "r2": "length",
        "r5": "length",
        "r6": "length",
        "h": "offset",
        "sigma_slider": "branch",
    }
    p = type_problem(cls, 1.5, 0.2, bounds={"phi": (-1.0, 1.0)})
    assert p.free == {"r2": (0.01, 1.0), "r3": (0.01, 1.0), "e": (-1.0, 1.0), "phi": (-1.0, 1.0)}
    q = type_problem(cls, 1.5, 0.2)
    assert "phi" not in q.free and q.fixed["phi"] == 0.0  # an angle with a default stays fixed
    assert [scales(p, k) for k in ("r2", "e", "phi", "sigma_slider")] == [True, True, False, False]
    m = cls(r2=0.1, r3=0.4, e=0.05, phi=0.3)
    assert (
        qropt.sensitivities(m).names == ("r2", "r3", "e", "phi") if hasattr(qropt.sensitivities(m), "names") else True
    )
    from qropt.convex.tolerance import _names

    assert _names(m, None) == ["r2", "r3", "e", "phi"]


def test_a_branch_sign_is_refused_as_free_and_any_branch_is_enumerated():
    w = _watt()
    with pytest.raises(ProblemError, match="'sigma2' is a branch sign.*branches=\\{'sigma2': \\(-1, 1\\)\\}"):
        w.build().replace(free={**w.build().free, "sigma2": (-1.0, 1.0)})
    r = solve(w.build())
    assert r.success and r.params["sigma2"] in (-1.0, 1.0)
    both = {solve(w.build().replace(branches={"sigma2": (s,)})).objective for s in (-1.0, 1.0)} - {None}
    assert r.objective == pytest.approx(max(both), abs=1e-9)  # the best of both branches of the second four-bar


# ---- the studies -------------------------------------------------------------------------------------------------
def test_solve_design_family_reachable_pareto(user):
    cls = user.PhasedSliderCrank
    r = solve(user.build())
    sc = solve(user.build().replace(mechanism="slider-crank", fixed={"r2": 0.3}))
    assert r.success and r.objective == pytest.approx(sc.objective, abs=1e-9)  # a phase changes no cycle quantity
    cmp = design(1.5, 0.3, types=[cls, "slider-crank", "problems.user_slotted_lever:BentLeverShaper"])
    names = {row.type: row for row in cmp.rows}
    assert set(names) == {"phased-slider-crank", "slider-crank", "bent-lever-shaper"}
    assert all(row.success for row in cmp.rows)
    assert names["phased-slider-crank"].result.objective == pytest.approx(
        names["slider-crank"].result.objective, abs=1e-7
    )
    b = _slotted().build()  # a family of the bent-lever shaper: three free lengths and offsets, two targets
    fam = family(
        b.replace(
            fixed={"beta": b.fixed["beta"], "r4": 0.45, "r6": 1.2}, free={k: b.free[k] for k in ("r1", "r2", "h")}
        )
    )
    assert fam.branches and type(fam.best("max_gamma_min").mechanism) is _slotted().BentLeverShaper
    reach = reachable(r.mechanism, "r3", (0.5, 10.0))
    assert reach.time_ratio_range[2] >= 1.5 - 1e-9
    front = pareto(_slotted().build(), ("max_gamma_min", "min_peak_accel"), n=3)
    assert len(front.points) >= 2 and all(type(pt.mechanism).KIND == "bent-lever-shaper" for pt in front.points)


def test_plots_draw_the_user_type_bodies(tmp_path):
    from qropt.io import export, plots

    r = solve(_watt().build())
    plots.save(plots.cycle_figure(r.mechanism), tmp_path / "w.png")
    assert (tmp_path / "w.png").stat().st_size > 1000
    export.to_svg(r.mechanism, tmp_path / "w.svg", 0.5)
    assert (tmp_path / "w.svg").read_text().count("<line") >= 6  # crank, couplers, rocker, rod, ...
    export.save_design(r.mechanism, tmp_path / "w.json")
    assert json.loads((tmp_path / "w.json").read_text())["type"] == "problems.user_watt_sixbar:WattSixBarShaper"
    assert export.load_design(tmp_path / "w.json") == r.mechanism


# ---- files and other processes ----------------------------------------------------------------------------------
def test_result_and_problem_reload_in_a_fresh_process(user, folder, tmp_path):
    r = solve(user.build())
    (tmp_path / "r.json").write_text(json.dumps(r.to_dict()))
    (tmp_path / "p.toml").write_text(user.build().to_toml())
    assert r.to_dict()["type"] == f"{MODULE}:PhasedSliderCrank"
    out = _fresh(
        f"""
        import json
        from qropt import Problem, Result
        r = Result.from_dict(json.loads(open({str(tmp_path / "r.json")!r}).read()))
        p = Problem.from_toml(open({str(tmp_path / "p.toml")!r}).read())
        print(type(r.mechanism).__name__, r.mechanism.time_ratio(), p.mechanism.KIND)
        """,
        folder,
    )
    name, tr, kind = out.split()
    assert name == "PhasedSliderCrank" and float(tr) == pytest.approx(1.5, abs=1e-9) and kind == "phased-slider-crank"
    assert Result.from_dict(r.to_dict()).mechanism == r.mechanism
    assert Problem.from_json(user.build().to_json()) == user.build()


def test_a_fresh_process_without_the_module_says_so(user, tmp_path):
    r = solve(user.build())
    out = subprocess.run(
        [
            sys.executable,
            "-c",
            "import json, sys; from qropt import Result; Result.from_dict(json.loads(sys.argv[1]))",
            json.dumps(r.to_dict()),
        ],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        timeout=120,
    )
    assert out.returncode != 0 and f"module '{MODULE}' is not found" in out.stderr


def test_a_dask_chart_of_a_user_type_on_two_workers(user):
    p = user.build()
    x = ("time_ratio", (1.3, 1.5))
    y = ("r2", (0.25, 0.3))
    here = chart(p, x, y, progress=False)
    far = chart(p, x, y, workers=2, progress=False)
    assert far.stats["scheduler"] == "local cluster of 2 worker processes"
    for a, b in zip(here.cells, far.cells, strict=True):
        assert (a.status, a.params) == (b.status, b.params)
    assert far.cell(1, 1).result.mechanism.KIND == "phased-slider-crank" and far.mask("certified").all()


# ---- the command line --------------------------------------------------------------------------------------------
def test_cli_analyze_a_module_class_with_param(user, capsys):
    ref = f"{MODULE}:PhasedSliderCrank"
    code = main(
        [
            "analyze",
            ref,
            "--param",
            "r2=0.1",
            "--param",
            "r3=0.4",
            "--param",
            "e=0.05",
            "--param",
            "phi=30deg",
            "--json",
        ]
    )
    out = json.loads(capsys.readouterr().out)
    assert code == 0 and out["type"] == ref and out["params"]["phi"] == pytest.approx(math.radians(30))
    assert main(["analyze", "phased-slider-crank", "--r2", "0.1", "--param", "r3=0.4", "--param", "phi=0.5rad"]) == 0
    assert "phased-slider-crank" not in capsys.readouterr().err
    for argv, words in (
        (["analyze", ref, "--param", "r2=0.1", "--param", "zz=1"], "has no parameter 'zz'"),
        (["analyze", ref, "--param", "r2=0.1", "--param", "r3=x"], "r3=x: not a finite number"),
        (["analyze", ref, "--r2", "0.1", "--param", "r2=0.2"], "given twice"),
        (["analyze", "nowhere_mod:X", "--param", "r2=1"], "module 'nowhere_mod' is not found"),
    ):
        assert main(argv) != 0
        assert words in capsys.readouterr().err
    assert (
        main(
            [
                "reachable",
                ref,
                "--param",
                "r2=0.1",
                "--param",
                "r3=0.4",
                "--free",
                "r3",
                "--bounds",
                "0.3",
                "2",
                "--json",
            ]
        )
        == 0
    )
    assert json.loads(capsys.readouterr().out)["free"] == "r3"


def test_cli_synth_and_design_with_user_types(user, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    for name in ("user_slotted_lever", "user_watt_sixbar"):
        assert main(["synth", str(ROOT / "problems" / f"{name}.py"), "--save", f"{name}.json"]) == 0
        out = capsys.readouterr().out
        assert f"problems.{name}:" in out and "certified optimum" in out
        assert main(["analyze", "--from", f"{name}.json"]) == 0
    code = main(["design", "--tr", "1.5", "--stroke", "0.3", "--types", "slider-crank", f"{MODULE}:PhasedSliderCrank"])
    out = capsys.readouterr().out
    assert code == 0 and "phased-slider-crank" in out and "slider-crank" in out


def test_the_example_files_solve_as_the_command_line_runs_them(tmp_path):
    for name in ("user_slotted_lever", "user_watt_sixbar"):
        out = subprocess.run(
            [shutil.which("qropt"), "synth", str(ROOT / "problems" / f"{name}.py"), "--json"],
            capture_output=True,
            text=True,
            cwd=tmp_path,
            timeout=300,
        )
        assert out.returncode == 0, out.stderr
        d = json.loads(out.stdout)
        assert d["status"] == "optimal" and d["type"].startswith(f"problems.{name}:")


def test_a_user_type_declares_its_closed_forms_crank_and_example():
    """A type of one's own names its closed forms (SYNTHESIS.closed_forms, tried in order: the first that applies
    gives the starts; a warm_starts hook that answers comes first), its crank (SYNTHESIS.crank) and its example
    design (EXAMPLE, the app's first; a subclass does not inherit it), as the shipped types do."""
    from qropt.app.defaults import default_params
    from qropt.mechanisms import SliderCrank, SynthesisHints
    from qropt.mechanisms.closed_forms import slider_crank_starts
    from qropt.synthesis import analytic, evolution

    def never(c):
        return None

    def mid_bounds(c):
        c.emit()
        return c.result("partial", "mid-bounds")

    class DeclaredSliderCrank(SliderCrank):
        KIND = "declared-slider-crank"
        SYNTHESIS = SynthesisHints(closed_forms=(never, mid_bounds, slider_crank_starts), crank="r3")
        EXAMPLE = {"r2": 0.1, "r3": 0.4, "e": 0.05}

    class InheritingSliderCrank(DeclaredSliderCrank):
        KIND = "inheriting-slider-crank"

    try:
        p = Problem(
            mechanism=DeclaredSliderCrank,
            free={"r2": (0.1, 0.3), "r3": (0.4, 1.0), "e": (0.0, 0.2)},
            targets={"time_ratio": 1.2, "stroke": 0.4},
            objective="max_gamma_min",
        )
        w = analytic.warm_starts(p)
        assert (w.kind, w.how, w.points) == ("partial", "mid-bounds", [{"r2": 0.2, "r3": 0.7, "e": 0.1}])
        shipped = analytic.warm_starts(p.replace(mechanism=SliderCrank))
        assert shipped.kind == "family" and shipped.points and shipped.points != w.points
        assert analytic.warm_starts(p.replace(mechanism=InheritingSliderCrank)).points == w.points
        hints = dataclasses.replace(DeclaredSliderCrank.SYNTHESIS, crank="r9")
        other_crank = type("OtherCrankSliderCrank", (DeclaredSliderCrank,), {"SYNTHESIS": hints})
        assert evolution.applies(p) and not evolution.applies(p.replace(mechanism=other_crank))
        assert default_params(DeclaredSliderCrank) == DeclaredSliderCrank.EXAMPLE
        assert default_params(InheritingSliderCrank) == {}
    finally:
        for kind in ("declared-slider-crank", "inheriting-slider-crank"):
            REGISTRY.pop(kind, None)


@pytest.mark.parametrize(
    ("old", "value", "field"),
    [
        ("EXACT_TRANSMISSION", {"B": (0.0, math.pi)}, "exact_transmission"),
        ("RULED_MARGINS", ("rod closure",), "ruled_margins"),
        ("ACCEL_EXTREMES", 4, "accel_extremes"),
        ("TIES", ("r2", "r3"), "ties"),
        ("ONE_REVERSAL", True, "one_reversal"),
        ("CRANK", "r3", "crank"),
        ("CLOSED_FORMS", (), "closed_forms"),
    ],
)
def test_a_synthesis_hint_by_its_old_name_is_refused_with_the_new_spelling(old, value, field):
    """A type that declares a synthesis hint as a class attribute of its own (TIES = ...) is refused when the class
    is defined, by a typed error naming the SYNTHESIS field that holds it now; SYNTHESIS must be a SynthesisHints."""
    from qropt.mechanisms import SliderCrank, SynthesisHints

    with pytest.raises(
        qropt.InvalidParameter, match=rf"OldHints: {old} is now declared as SYNTHESIS = SynthesisHints\({field}="
    ):
        type("OldHints", (SliderCrank,), {"KIND": "old-hints", old: value})
    with pytest.raises(qropt.InvalidParameter, match="OldHints: SYNTHESIS is a qropt.mechanisms.hints.SynthesisHints"):
        type("OldHints", (SliderCrank,), {"KIND": "old-hints", "SYNTHESIS": {field: value}})
    assert "old-hints" not in REGISTRY
    hinted = type("NewHints", (SliderCrank,), {"KIND": "new-hints", "SYNTHESIS": SynthesisHints(**{field: value})})
    try:
        assert getattr(hinted.SYNTHESIS, field) == value and dataclasses.is_dataclass(hinted.SYNTHESIS)
    finally:
        REGISTRY.pop("new-hints", None)


def test_a_criterion_that_does_not_apply_says_why():
    """A dynamic objective of a type whose loop is hand-written (its bodies declared, its linkage not built with
    the builder) names the builder; a slider's criterion on a four-bar names the missing slider."""
    shaper = _slotted().BentLeverShaper
    kw = {"masses": qropt.Masses.bars(2.0, 5.0), "loads": qropt.Loads(100.0)}
    with pytest.raises(
        ProblemError,
        match=r"BentLeverShaper is not declared with the linkage builder .*: "
        r"min_peak_torque does not apply",
    ):
        type_problem(shaper, 1.5, 0.3, objective="min_peak_torque", **kw)
    with pytest.raises(ProblemError, match="FourBar has no slider: min_peak_accel does not apply"):
        Problem(
            mechanism="four-bar",
            free={"r1": (1, 2), "r2": (0.1, 0.5), "r3": (1, 3), "r4": (1, 3)},
            targets={"time_ratio": 1.2},
            objective="min_peak_accel",
        )
