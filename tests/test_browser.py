"""The web app in a real browser: Playwright drives the system Chromium (``/usr/bin/chromium``, installed by
``.ci/run``; nothing is downloaded). It loads each page, drags a slider, runs a design, a solve and a front, and
checks the numbers the page shows against the library. Screenshots go to the test's folder (and to
``$QROPT_SCREENSHOTS`` if set)."""

from __future__ import annotations

import json
import math
import os
import shutil
import threading
from pathlib import Path

import pytest

CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
if not Path(CHROMIUM).exists():
    if os.environ.get("CI"):
        raise RuntimeError("CI runs the browser test: .ci/run installs chromium")
    pytest.skip("no Chromium on this machine (.ci/run installs it)", allow_module_level=True)
sync_api = pytest.importorskip("playwright.sync_api")

import qropt  # noqa: E402
from qropt.examples import paper_problem  # noqa: E402
from qropt.mechanisms import mechanism_type  # noqa: E402

ARGS = [
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]
SLIDER_CRANK = {
    "mechanism": "slider-crank",
    "fixed": {"sigma_slider": 1.0},
    "free": {"r2": [0.05, 0.5], "r3": [0.1, 2.0], "e": [-0.5, 0.5]},
    "targets": {"time_ratio": 1.3, "stroke": 0.3},
    "objective": "max_gamma_min",
}


@pytest.fixture(scope="module")
def server():
    from werkzeug.serving import make_server

    from qropt.app import create_app

    app = create_app(workers=1, time_limit=120)
    srv = make_server("127.0.0.1", 0, app, threaded=True)
    t = threading.Thread(target=srv.serve_forever, daemon=True)
    t.start()
    yield f"http://127.0.0.1:{srv.server_port}/"
    srv.shutdown()
    app.extensions["qropt_jobs"].close()


@pytest.fixture(scope="module")
def browser():
    with sync_api.sync_playwright() as p:
        b = p.chromium.launch(executable_path=CHROMIUM, args=ARGS)
        yield b
        b.close()


@pytest.fixture
def page(browser, server, tmp_path):
    pg = browser.new_page(viewport={"width": 1400, "height": 1000}, accept_downloads=True)
    errors = []
    pg.on("pageerror", lambda e: errors.append(str(e)))
    pg.goto(server + "#mechanism")
    pg.wait_for_selector("body[data-ready='1']", timeout=60_000)
    pg.wait_for_function("window.qropt.updates > 0 && !window.qropt.inflight")
    yield pg
    pg.close()
    assert errors == [], errors


def _shot(pg, tmp_path, name):
    path = tmp_path / f"{name}.png"
    pg.screenshot(path=path, full_page=True)
    extra = os.environ.get("QROPT_SCREENSHOTS")
    if extra:
        shutil.copy(path, Path(extra) / f"app_{name}.png")
    assert path.stat().st_size > 10_000


def _shown(pg) -> dict:
    ds = pg.eval_on_selector("#m-numbers", "t => ({...t.dataset})")
    return {k: float(v) for k, v in ds.items()}


def test_mechanism_page_drag_a_slider(page, tmp_path):
    state = page.evaluate("({type: window.qropt.type, params: window.qropt.params})")
    assert state["type"] == "drag-link-slider"
    m = mechanism_type("drag-link-slider")(**state["params"])
    assert _shown(page)["timeRatio"] == pytest.approx(m.time_ratio(), rel=1e-12)
    assert page.locator("#m-svg line[data-part='link']").count() >= 4  # the links drawn
    names = sorted(page.locator("#m-svg text.joint-name").all_text_contents())  # every joint named, as the tables
    assert names == ["A", "B", "C", "D", "O2", "O4"], names
    assert page.locator("#m-svg .path-working").count() >= 1 and page.locator("#m-svg .path-return").count() >= 1
    assert page.locator("#m-vpoly line").count() >= 4 and page.locator("#m-plot polyline").count() == 3
    # the forces appear with a mass model, the exact peaks once the inputs rest
    page.check("#m-dyn")
    page.wait_for_function("document.getElementById('m-forces').textContent.includes('RMS torque')")
    page.wait_for_timeout(200)
    _shot(page, tmp_path, "mechanism")
    # the animation plays the turn's frames
    page.wait_for_function("window.qropt.frames && window.qropt.frames.frames.length === 72")
    page.click("#m-play")
    page.wait_for_timeout(300)
    assert page.evaluate("window.qropt.playing")
    page.click("#m-play")
    before = page.evaluate("window.qropt.updates")
    box = page.locator("#p-r3").bounding_box()
    y = box["y"] + box["height"] / 2
    page.mouse.move(box["x"] + 0.40 * box["width"], y)
    page.mouse.down()
    for i in range(1, 21):  # a real drag: the thumb moves, the page asks for each new value
        page.mouse.move(box["x"] + (0.40 + 0.01 * i) * box["width"], y)
        page.wait_for_timeout(20)
    page.mouse.up()
    page.wait_for_function("!window.qropt.inflight && !window.qropt.pending")
    page.wait_for_timeout(100)
    after = page.evaluate("({n: window.qropt.updates, params: window.qropt.params})")
    assert after["n"] >= before + 3
    assert after["params"]["r3"] != pytest.approx(state["params"]["r3"])
    assert float(page.input_value("#n-r3")) == pytest.approx(after["params"]["r3"], rel=1e-5)
    m2 = mechanism_type("drag-link-slider")(**after["params"])
    shown = _shown(page)
    assert shown["timeRatio"] == pytest.approx(m2.time_ratio(), rel=1e-12)
    assert shown["stroke"] == pytest.approx(m2.stroke(), rel=1e-12)
    assert shown["gammaMin"] == pytest.approx(math.degrees(m2.gamma_min().value), rel=1e-12)


def test_type_change_and_export(page, tmp_path):
    page.select_option("#m-type", "whitworth")
    page.wait_for_function("window.qropt.type === 'whitworth' && !window.qropt.inflight")
    page.wait_for_timeout(200)
    p = page.evaluate("window.qropt.params")
    assert _shown(page)["timeRatio"] == pytest.approx(mechanism_type("whitworth")(**p).time_ratio(), rel=1e-12)
    with page.expect_download() as dl:
        page.click("#export-mechanism-json")
    saved = json.loads(Path(dl.value.path()).read_text())
    assert saved["type"] == "whitworth" and saved["params"] == pytest.approx(p)
    with page.expect_download() as dl:
        page.click("#export-mechanism-svg")
    assert "<svg" in Path(dl.value.path()).read_text()
    page.fill("#n-r2", "0.001")  # a design that cannot turn: the page says why and keeps working
    page.dispatch_event("#n-r2", "change")
    page.wait_for_function("document.getElementById('m-error').textContent.length > 0")
    page.fill("#n-r2", str(p["r2"]))
    page.dispatch_event("#n-r2", "change")
    page.wait_for_function("document.getElementById('m-error').textContent.length === 0")


def test_design_page(page, tmp_path):
    from qropt.studies._design import TYPES as ROWS

    page.click("#tab-design")
    page.fill("#d-tr", "1.5")
    page.fill("#d-stroke", "0.3")
    boxes = page.locator("#d-types input").all()
    assert all(b.is_checked() for b in boxes)  # every type at first
    for b in boxes:  # design's built-in rows, as qropt.design(1.5, 0.3) (a user type another test loaded: out)
        b.set_checked(b.get_attribute("value") in ROWS)
    page.click("#d-run")
    page.wait_for_selector("#d-table tr.pick", timeout=120_000)
    page.wait_for_function("document.querySelectorAll('#d-pictures .card svg line').length >= 8")
    rows = page.locator("#d-table tr.pick")
    want = qropt.design(1.5, 0.3)
    assert rows.count() == len(want.rows)
    first = rows.nth(0).locator("td")
    assert first.nth(1).inner_text() == want.rows[0].type
    assert float(first.nth(3).inner_text()) == pytest.approx(math.degrees(want.rows[0].criteria["gamma_min"]), abs=0.01)
    _shot(page, tmp_path, "design")
    rows.nth(2).click()  # a row opens on the Mechanism page
    page.wait_for_function("location.hash === '#mechanism' && !window.qropt.inflight")
    page.wait_for_timeout(200)
    p = page.evaluate("window.qropt.params")
    assert p == pytest.approx(want.rows[2].result.params), (want.rows[2].type, want.rows[2].result.message)


def test_design_page_dynamic_objective_and_stale_results(page, tmp_path):
    """A dynamic objective from the registry's list brings the mass model and a 30 s budget; with a 3 s budget and one
    type the row comes with its exact peak torque; new inputs mark the rows stale, and a refused request says why."""
    from qropt.dynamics.cycle import CycleDynamics
    from qropt.dynamics.model import Loads, Masses

    page.click("#tab-design")
    assert page.locator("#d-objective option[value='peak_torque']").count() == 1
    page.select_option("#d-objective", "peak_torque")
    assert page.is_checked("#d-dyn") and page.input_value("#d-budget") == "30"
    page.fill("#d-budget", "3")
    for box in page.locator("#d-types input").all():
        box.set_checked(box.get_attribute("value") == "slider-crank")
    page.click("#d-run")
    page.wait_for_selector("#d-table tr.pick", timeout=60_000)
    assert "of a 3 s budget" in page.inner_text("#d-progress")
    (row,) = page.evaluate("window.qropt.designRows")
    m = mechanism_type("slider-crank")(**row["params"])
    masses, loads = Masses(1.57, 20.0), Loads(1000.0, gravity=9.81)  # the panel's defaults
    want = CycleDynamics(m, 10.0, 0.0, masses, loads).extremes().peak_torque.value
    cells = page.locator("#d-table tr.pick td")
    assert float(cells.nth(6).inner_text()) == pytest.approx(want, rel=1e-3)  # "peak crank torque [N m]"
    assert page.locator("#d-table.stale").count() == 0
    _shot(page, tmp_path, "design_dynamic")
    page.fill("#d-tr", "1.8")  # new inputs: the rows are the old task's
    page.wait_for_selector("#d-table.stale")
    assert "Results for TR = 1.5" in page.inner_text("#design-note")
    page.locator("#d-types input[value='slider-crank']").uncheck()
    page.click("#d-run")
    page.wait_for_function("document.getElementById('design-note').textContent.includes('choose at least one type')")
    assert page.locator("#d-pictures.stale").count() == 1


def test_a_bad_r3_marks_the_results_stale(page, tmp_path):
    """r3 past where the drag-link assembles: the numbers, drawing, curves and polygons are dimmed and say the r3
    they belong to; a good r3 clears the mark."""
    r3 = page.evaluate("window.qropt.params.r3")
    page.fill("#n-r3", "0.6")
    page.dispatch_event("#n-r3", "change")
    page.wait_for_function("document.getElementById('m-error').textContent.includes('GrashofError')")
    note = page.inner_text("#m-error")
    assert f"Results for r3 = {float(f'{r3:.6g}'):g}" in note and "r3 = 0.6" in note, note
    for panel in ("m-numbers", "m-svg", "m-plot", "m-vpoly", "m-apoly"):
        assert "stale" in page.get_attribute(f"#{panel}", "class"), panel
    _shot(page, tmp_path, "stale")
    page.fill("#n-r3", str(r3))
    page.dispatch_event("#n-r3", "change")
    page.wait_for_function("document.getElementById('m-error').textContent.length === 0")
    assert page.locator(".stale").count() == 0


def test_synthesis_page(page, tmp_path):
    page.click("#tab-synthesis")
    page.click("#s-solve")
    page.wait_for_selector("#s-claim", timeout=60_000)
    want = qropt.solve(paper_problem())
    assert page.inner_text("#s-claim") == f"certificate: {want.certificate.global_claim}"
    cell = page.locator("#s-optima tr.pick").nth(0).locator("td").nth(2)
    assert float(cell.inner_text()) == pytest.approx(want.params["r3"], rel=1e-5)
    page.fill("#s-json", json.dumps(SLIDER_CRANK))
    page.click("#s-front")
    page.wait_for_selector(".front-point", timeout=120_000)
    n = page.locator(".front-point").count()
    assert n >= 3
    _shot(page, tmp_path, "synthesis")
    page.locator(".front-point").nth(n - 1).click()
    page.wait_for_function("location.hash === '#mechanism' && window.qropt.type === 'slider-crank'")
    page.wait_for_function("!window.qropt.inflight")
    page.wait_for_timeout(200)
    m = mechanism_type("slider-crank")(**page.evaluate("window.qropt.params"))
    assert m.time_ratio() == pytest.approx(1.3, abs=1e-6) and m.stroke() == pytest.approx(0.3, abs=1e-6)
