"""Tolerance allocation (qropt.tolerance): AD sensitivities vs finite differences, closed-form allocations,
Monte Carlo against the exact per-mechanism analysis, bad input, and the command line."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import qropt
from qropt import cli as qropt_cli
from qropt.convex.tolerance import allocate, sensitivities
from qropt.errors import InvalidParameter
from qropt.examples import paper_mechanism

OMEGA2 = 10.0
MECHANISMS = [
    paper_mechanism(),
    qropt.SliderCrank(r2=0.1, r3=0.35, e=0.06),
    qropt.CrankShaper(r1=160, r2=40, r4=240),
    qropt.CrankShaper(r1=0.3, r2=0.1, r4=0.5, r6=0.4, h=0.45),
    qropt.Whitworth(r1=0.1, r2=0.2, r5=0.12, r6=0.3, h=0.02),
    qropt.CrankRockerSlider(r1=0.4, r2=0.1, r3=0.35, r4=0.3, r5=0.4, r6=0.5, h=0.1),
    qropt.FourBar(r1=0.4, r2=0.1, r3=0.35, r4=0.3),
]
SC = qropt.SliderCrank(r2=0.1, r3=0.35, e=0.06)


def exact(m, q):
    if q == "time_ratio":
        return m.time_ratio()
    if q == "stroke":
        return m.stroke()
    if q == "gamma_min":
        return m.gamma_min().value
    return m.peak_acceleration(OMEGA2).value


def with_param(m, p, value):
    return type(m)(**{**m.params, p: value})


@pytest.mark.parametrize("m", MECHANISMS, ids=lambda m: type(m).__name__)
def test_sensitivities_match_central_differences(m):
    s = sensitivities(m, omega2=OMEGA2)
    assert set(s) == {"time_ratio", "stroke", "gamma_min", "peak_acceleration"}
    for q, row in s.items():
        scale = max(abs(v) for v in row.values())
        for p, d in row.items():
            h = 1e-5 * max(abs(m.params[p]), 0.01 * m.params.get("r2", 1.0))
            fd = (exact(with_param(m, p, m.params[p] + h), q) - exact(with_param(m, p, m.params[p] - h), q)) / (2 * h)
            assert abs(d - fd) <= 1e-6 * max(abs(fd), scale), (q, p, d, fd)


def test_a_shared_transmission_minimum_gives_the_steeper_one_sided_slope():
    # h = 0: the Whitworth's slide line through O4 gives two equal minima of gamma at D, so gamma_min(h) has a
    # kink; the sensitivity is the larger one-sided slope (a safe bound for the stack-up)
    m = qropt.Whitworth(r1=0.1, r2=0.2, r5=0.12, r6=0.3)
    d = sensitivities(m, ["h"])["gamma_min"]["h"]
    g0, h = m.gamma_min().value, 1e-6
    up = (with_param(m, "h", h).gamma_min().value - g0) / h
    down = (g0 - with_param(m, "h", -h).gamma_min().value) / h
    assert up < 0 < down  # a ridge: gamma_min falls either way
    assert abs(d) == pytest.approx(max(abs(up), abs(down)), rel=1e-4)


def test_default_parameters_and_exact_zeros():
    s = sensitivities(paper_mechanism())
    assert list(s["stroke"]) == ["r1", "r2", "r3", "r4", "r5", "r6", "h"]  # lengths, then offsets; no signs
    assert s["stroke"]["r5"] == pytest.approx(2.0, rel=1e-12)  # C sweeps a full circle: stroke = 2 r5
    assert all(s["stroke"][p] == 0.0 for p in ("r1", "r2", "r3", "r4", "r6"))
    assert "peak_acceleration" not in s
    assert list(sensitivities(qropt.CrankShaper(r1=160, r2=40, r4=240))["stroke"]) == ["r1", "r2", "r4"]


def test_one_worst_case_limit_equal_weights_closed_form():
    E = 0.01
    a = allocate(SC, {"time_ratio": E})
    S = sensitivities(SC)["time_ratio"]
    assert a.status == "optimal" and a.usage["time_ratio"] == pytest.approx(1.0, rel=1e-10)
    for p, t in a.tolerances.items():
        assert t == pytest.approx(E / (3 * abs(S[p])), rel=1e-10)


def test_one_rss_limit_equal_weights_closed_form():
    E, k = 0.002, 3.0
    a = allocate(SC, {"stroke": E}, method="rss", k=k)
    S = sensitivities(SC)["stroke"]
    for p, t in a.tolerances.items():
        assert t == pytest.approx(E / (k * math.sqrt(3) * abs(S[p])), rel=1e-10)


def test_weights_and_bounds_closed_forms():
    E = 0.01
    S = sensitivities(SC)["time_ratio"]
    w = {"r2": 1.0, "r3": 2.0, "e": 5.0}
    a = allocate(SC, {"time_ratio": E}, weights=w)
    for p, t in a.tolerances.items():
        assert t == pytest.approx(w[p] * E / (8.0 * abs(S[p])), rel=1e-10)  # t_i = w_i E / (sum w |S_i|)
    cap = 0.5 * E / (3 * abs(S["e"]))
    b = allocate(SC, {"time_ratio": E}, bounds={"e": (None, cap)})
    assert b.tolerances["e"] == pytest.approx(cap, rel=1e-10)
    rest = E - abs(S["e"]) * cap
    for p in ("r2", "r3"):
        assert b.tolerances[p] == pytest.approx(rest / (2 * abs(S[p])), rel=1e-10)


def test_infeasible_lower_bounds_name_the_limit():
    a = allocate(SC, {"time_ratio": 0.01, "stroke": 1.0}, bounds={"r2": (0.1, None)})
    assert a.status == "infeasible" and "time_ratio" in a.message and "stroke" not in a.message
    assert a.tolerances == {}
    with pytest.raises(InvalidParameter, match="status 'infeasible'"):
        a.monte_carlo(10)


def test_parameter_without_influence_is_unbounded():
    a = allocate(paper_mechanism(), {"stroke": 0.001})
    assert a.tolerances["r5"] == pytest.approx(0.0005, rel=1e-10)
    assert all(math.isinf(a.tolerances[p]) for p in ("r1", "r2", "r3", "r4", "r6", "h"))
    assert "no limited quantity depends on" in a.message


def test_monte_carlo_worst_case_keeps_every_sample_within_limit_plus_linearisation_error():
    m = paper_mechanism()
    limits = {"time_ratio": 0.01, "stroke": 0.001, "gamma_min": 0.01}
    a = allocate(m, limits)
    mc = a.monte_carlo(10_000, seed=0, progress=False)
    assert mc.n == 10_000 and mc.failed == 0
    for q, E in limits.items():
        dev = np.abs(mc.deviations[q])
        assert dev.max() <= E + mc.linearisation[q]  # the linear stack-up never exceeds E
        assert mc.linearisation[q] < 0.05 * E  # second-order terms: a few percent of the limit at most
        assert mc.within[q] >= 0.999
    # halving the limits halves every tolerance: the linearisation error drops ~4x (second order)
    half = allocate(m, {q: E / 2 for q, E in limits.items()}).monte_carlo(10_000, seed=0, progress=False)
    ratio = mc.linearisation["time_ratio"] / half.linearisation["time_ratio"]
    assert 3.0 < ratio < 5.0


def test_monte_carlo_rss_keeps_at_least_99_7_percent():
    m = paper_mechanism()
    a = allocate(m, {"time_ratio": 0.01, "stroke": 0.001}, method="rss", k=3.0)
    mc = a.monte_carlo(10_000, seed=1, progress=False)
    assert mc.within["time_ratio"] >= 0.997 and mc.within["stroke"] >= 0.997
    # the errors are normal with sigma = t / k, so dQ has sigma ~ ||S t|| / k = usage E / k^2
    for q, E in a.limits.items():
        sigma = a.usage[q] * E / a.k**2
        assert np.std(mc.deviations[q]) == pytest.approx(sigma, rel=0.05)
    for p, e in mc.errors.items():
        assert np.std(e) == pytest.approx(a.tolerances[p] / 3.0, rel=0.05)


def test_monte_carlo_equals_the_per_mechanism_analysis():
    m = qropt.CrankRockerSlider(r1=0.4, r2=0.1, r3=0.35, r4=0.3, r5=0.4, r6=0.5, h=0.1)
    limits = {"time_ratio": 0.02, "stroke": 0.002, "gamma_min": 0.02, "peak_acceleration": 2.0}
    a = allocate(m, limits, omega2=OMEGA2)
    mc = a.monte_carlo(40, seed=3, progress=False)
    base = {q: exact(m, q) for q in limits}
    for j in range(40):
        mm = type(m)(**{**m.params, **{p: m.params[p] + e[j] for p, e in mc.errors.items()}})
        for q in limits:
            assert mc.deviations[q][j] == pytest.approx(exact(mm, q) - base[q], abs=1e-9 * max(1.0, abs(base[q])))


def test_monte_carlo_bad_n():
    a = allocate(SC, {"time_ratio": 0.01})
    for n in (0, -5, 2.5, True):
        with pytest.raises(InvalidParameter, match="n must be"):
            a.monte_carlo(n)


@pytest.mark.parametrize(
    "limits, kw, match",
    [
        ({"time_ratio": 0.0}, {}, "limit time_ratio must be positive"),
        ({"time_ratio": -0.01}, {}, "limit time_ratio must be positive"),
        ({"stroke": float("inf")}, {}, "limit stroke"),
        ({"speed": 0.1}, {}, "unknown quantity 'speed'"),
        ({}, {}, "non-empty"),
        ({"peak_acceleration": 1.0}, {}, "needs omega2"),
        ({"time_ratio": 0.01}, {"params": ["r9"]}, "'r9': unknown parameter"),
        ({"time_ratio": 0.01}, {"params": ["sigma_slider"]}, "branch signs have no tolerance"),
        ({"time_ratio": 0.01}, {"params": []}, "distinct"),
        ({"time_ratio": 0.01}, {"method": "monte-carlo"}, "method"),
        ({"time_ratio": 0.01}, {"k": 0}, "k must be positive"),
        ({"time_ratio": 0.01}, {"weights": {"r2": -1.0}}, "weight of r2"),
        ({"time_ratio": 0.01}, {"weights": {"r6": 1.0}}, "not among"),
        ({"time_ratio": 0.01}, {"bounds": {"r2": (0.2, 0.1)}}, "low <= high"),
        ({"time_ratio": 0.01}, {"bounds": {"r2": 0.1}}, r"must be \(low, high\)"),
    ],
)
def test_bad_input_raises_a_typed_error(limits, kw, match):
    with pytest.raises(InvalidParameter, match=match):
        allocate(SC, limits, **kw)


def test_sensitivities_bad_input():
    with pytest.raises(InvalidParameter, match="unknown parameter"):
        sensitivities(SC, ["r4"])
    with pytest.raises(InvalidParameter, match="omega2"):
        sensitivities(SC, omega2=0.0)
    with pytest.raises(InvalidParameter, match="qropt mechanism"):
        sensitivities({"r2": 0.1})


# ---- command line ---------------------------------------------------------------------------------------
def cli(argv, capsys):
    """(exit code, stdout, stderr) of ``qropt ...`` through ``qropt.cli.main`` (one line on error)."""
    code = qropt_cli.main(argv)
    out = capsys.readouterr()
    return code, out.out, out.err


def test_cli_text_with_monte_carlo(capsys):
    code, out, _ = cli(
        ["tolerance", "--limit", "time_ratio=0.01", "--limit", "stroke=1mm", "--monte-carlo", "2000"], capsys
    )
    a = allocate(paper_mechanism(), {"time_ratio": 0.01, "stroke": 0.001})
    assert code == 0
    assert f"+/- {a.tolerances['r1']:.4g}" in out and "+/- inf" in out
    assert "time_ratio: limit 0.01, stack-up uses 100% of it" in out
    assert "Monte Carlo, 2000 mechanisms" in out and "every limit met" in out


def test_cli_json_from_a_design_file(tmp_path, capsys):
    f = tmp_path / "design.json"
    f.write_text(json.dumps({"type": "slider-crank", "params": {"r2": 0.1, "r3": 0.35, "e": 0.06}}))
    code, out, _ = cli(["tolerance", str(f), "--limit", "time_ratio=0.01", "--rss", "--json"], capsys)
    r = json.loads(out)
    a = allocate(SC, {"time_ratio": 0.01}, method="rss")
    assert code == 0 and r["method"] == "rss" and r["status"] == "optimal"
    for p, t in a.tolerances.items():
        assert r["tolerances"][p] == pytest.approx(t, rel=1e-12)
    code, out, _ = cli(["tolerance", "--limit", "stroke=1mm", "--json"], capsys)
    assert json.loads(out)["tolerances"]["r1"] is None  # infinite: strict JSON null


def test_cli_units_and_bad_input(capsys):
    code, out, _ = cli(
        [
            "tolerance",
            "slider-crank",
            "--r2",
            "0.1",
            "--r3",
            "0.35",
            "--e",
            "0.06",
            "--limit",
            "gamma_min=0.5deg",
            "--json",
        ],
        capsys,
    )
    assert code == 0 and json.loads(out)["limits"]["gamma_min"] == pytest.approx(math.radians(0.5))
    code, _, err = cli(["tolerance", "--limit", "time_ratio=-1"], capsys)
    assert code == 1 and err.count("\n") == 1 and "limit time_ratio must be positive" in err
    code, _, err = cli(["tolerance", "--limit", "time_ratio=0.01", "--params", "r1,sigma"], capsys)
    assert code == 1 and "branch signs have no tolerance" in err
    code, _, err = cli(["tolerance", "missing.json", "--limit", "time_ratio=0.01"], capsys)
    assert code == 1 and "no design file missing.json" in err
    code, _, err = cli(["tolerance", "--limit", "speed=1"], capsys)
    assert code == 2 and "not a limit: 'speed=1'" in err and err.count("\n") == 1


def test_readme_example():
    m = paper_mechanism()
    s = sensitivities(m)["time_ratio"]
    assert (s["r1"], s["r2"], s["h"]) == pytest.approx((6.877057, -5.881010, 8.799837), abs=1e-6)
    a = allocate(m, {"time_ratio": 0.01, "stroke": 0.001})
    want = {"r1": 0.000291, "r2": 0.000340, "r3": 0.001024, "r4": 0.003755, "r5": 0.0005, "h": 0.000227}
    assert {p: a.tolerances[p] for p in want} == pytest.approx(want, abs=6e-7) and math.isinf(a.tolerances["r6"])
    mc = a.monte_carlo(10_000, seed=0, progress=False)
    assert mc.within == pytest.approx({"time_ratio": 1.0, "stroke": 0.9998})
    assert mc.linearisation["stroke"] == pytest.approx(1.2e-7, abs=0.05e-7)
    assert mc.worst["stroke"] - 0.001 <= mc.linearisation["stroke"]
    r = allocate(m, {"time_ratio": 0.01, "stroke": 0.001}, method="rss").monte_carlo(10_000, seed=0, progress=False)
    assert r.within == {"time_ratio": 1.0, "stroke": 1.0}
