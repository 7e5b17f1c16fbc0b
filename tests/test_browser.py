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


# The pairs of the selected elements whose boxes on the screen overlap (each pair of one picture).
OVERLAPS = """(sel) => {
  const out = [], els = [...document.querySelectorAll(sel)];
  els.forEach((a, i) => els.slice(0, i).forEach((b) => {
    const p = a.getBoundingClientRect(), q = b.getBoundingClientRect();
    const near = a.ownerSVGElement === b.ownerSVGElement;
    if (near && p.left < q.right && q.left < p.right && p.top < q.bottom && q.top < p.bottom) {
      out.push([a.textContent, b.textContent]);
    }
  }));
  return out;
}"""


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


DOCS_SHOTS = ("mechanism", "design", "synthesis")  # the pages docs/images shows (docs/make_images.py)


def _shot(pg, tmp_path, name):
    path = tmp_path / f"{name}.png"
    pg.screenshot(path=path, full_page=True)
    extra = os.environ.get("QROPT_SCREENSHOTS")
    if extra and name in DOCS_SHOTS:
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
    helps = page.eval_on_selector_all("#m-numbers tr[title]", "rows => rows.map((r) => r.title)")  # help texts
    assert len(helps) == 8 and helps[0].startswith("time ratio TR: the time of the working (cutting) stroke")
    assert "The joint in brackets, e.g. (B), is where it occurs" in helps[2]
    assert "assembly branch" in page.get_attribute("#m-params label:has(#p-sigma)", "title")
    assert page.inner_text("#m-legend").startswith("The parameters: Drag-link (r1 shortest, Grashof) driving C")
    assert page.evaluate(OVERLAPS, "#m-vpoly text.term-name, #m-apoly text.term-name") == []  # names spread apart
    assert page.evaluate(OVERLAPS, "#m-svg text.joint-name") == []
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
    assert page.inner_text("#export-mechanism-msg") == "downloaded whitworth.svg (whitworth)"  # beside the button
    page.click("#tab-design")  # a message belongs to its page
    assert page.inner_text("#export-mechanism-msg") == ""
    page.click("#export-design-dxf")
    assert page.inner_text("#export-design-msg") == "no design on this page yet: run it first"
    page.click("#tab-mechanism")
    page.fill("#n-r2", "0.001")  # a design that cannot turn: the page says why and keeps working
    page.dispatch_event("#n-r2", "change")
    page.wait_for_function("document.getElementById('m-error').textContent.length > 0")
    page.click("#m-play")  # nothing to animate or export, and the page says why beside the button
    assert page.inner_text("#m-play-msg").startswith("no animation: the inputs give no design that turns")
    page.click("#export-mechanism-json")
    assert page.inner_text("#export-mechanism-msg").startswith("no export: the inputs give no design that turns")
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
    assert want.rows[2].type == "whitworth" and 0 < abs(p["h"]) < 1e-12  # a rounding residue beside lengths of tenths
    assert page.input_value("#n-h") == "0"  # shows as 0 in its box


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
    """A TOML problem file loads into the JSON and the form alike, a .py one is refused with why; the solve's
    certificate and r3 equal qropt.solve's and its design is drawn; a front on a problem with no freedom left says
    so; the form and the JSON follow each other; a front's point opens its design."""
    from qropt.synthesis.problem import Problem

    page.click("#tab-synthesis")
    toml = Path(qropt.__file__).parents[1] / "problems" / "paper_task.toml"
    page.set_input_files("#s-file", str(toml))
    page.wait_for_function("document.getElementById('s-file-msg').textContent.startsWith('loaded')")
    assert json.loads(page.input_value("#s-json")) == Problem.from_toml(toml.read_text()).to_dict()
    assert page.input_value("#s-v-r1") == "0.1" and page.is_checked("#s-f-r3") and not page.is_checked("#s-f-r1")
    assert page.input_value("#s-lo-r3") == "0.05" and page.input_value("#s-tr") == "1.5"
    assert page.input_value("#s-b-sigma") == "-1" and page.input_value("#s-objective") == "gamma_min"
    page.set_input_files("#s-file", str(toml.with_name("paper_drag_link.py")))
    page.wait_for_function("document.getElementById('s-file-msg').textContent.includes('not loaded')")
    assert "runs it only when the command line names it (qropt app paper_drag_link.py)" in page.inner_text(
        "#s-file-msg"
    )
    page.click("#s-solve")
    page.wait_for_selector("#s-claim", timeout=60_000)
    want = qropt.solve(paper_problem())
    assert page.inner_text("#s-claim") == f"certificate: {want.certificate.global_claim}"
    cell = page.locator("#s-optima tr.pick").nth(0).locator("td").nth(2)
    assert float(cell.inner_text()) == pytest.approx(want.params["r3"], rel=1e-5)
    page.wait_for_function("document.querySelectorAll('#s-svg text.joint-name').length === 6")  # the design drawn
    page.click("#s-front")  # two free parameters, two targets: no freedom left, and the page says so
    page.wait_for_function("document.getElementById('s-front-note').textContent.length > 0", timeout=120_000)
    assert "The front is one design" in page.inner_text("#s-front-note")
    assert page.locator(".front-point").count() == 0
    page.fill("#s-json", json.dumps({**SLIDER_CRANK, "targets": {"time_ratio": 1.35, "stroke": 0.3}}))
    assert page.input_value("#s-type") == "slider-crank" and page.is_checked("#s-f-e")  # the form follows the JSON
    page.fill("#s-tr", "1.3")  # and the JSON the form
    assert json.loads(page.input_value("#s-json"))["targets"] == SLIDER_CRANK["targets"]
    assert json.loads(page.input_value("#s-json"))["free"] == SLIDER_CRANK["free"]
    page.click("#s-solve")
    page.wait_for_function("document.querySelectorAll('#s-svg text.joint-name').length === 3", timeout=60_000)
    assert "minimum transmission angle" not in page.inner_text("#s-optima")  # (gamma_min is the objective's column)
    page.click("#s-front")
    page.wait_for_selector(".front-point", timeout=120_000)
    n = page.locator(".front-point").count()
    assert n >= 3
    assert "[deg]" in page.text_content("#s-front-svg")  # the objective in degrees
    page.wait_for_timeout(200)
    _shot(page, tmp_path, "synthesis")
    page.locator(".front-point").nth(n - 1).click()
    page.wait_for_function("location.hash === '#mechanism' && window.qropt.type === 'slider-crank'")
    page.wait_for_function("!window.qropt.inflight")
    page.wait_for_timeout(200)
    m = mechanism_type("slider-crank")(**page.evaluate("window.qropt.params"))
    assert m.time_ratio() == pytest.approx(1.3, abs=1e-6) and m.stroke() == pytest.approx(0.3, abs=1e-6)


def test_a_shared_link_restores_the_page(page, browser, server):
    """The URL holds the page, the type, the parameters, theta2, omega2 and the mass model: a new page opened at
    it shows the same design and numbers; back and forward move through the edits, a drag being one entry."""
    page.select_option("#m-type", "slider-crank")
    page.wait_for_function("window.qropt.type === 'slider-crank' && !window.qropt.inflight")
    page.wait_for_timeout(1100)
    page.fill("#n-r3", "0.41")
    page.dispatch_event("#n-r3", "change")
    page.fill("#m-theta-n", "100")
    page.dispatch_event("#m-theta-n", "change")
    page.fill("#m-omega", "7.5")
    page.dispatch_event("#m-omega", "change")
    page.check("#m-dyn")
    page.wait_for_function("window.qropt.params.r3 === 0.41 && !window.qropt.inflight")
    page.wait_for_timeout(1100)
    box = page.locator("#p-r2").bounding_box()  # a drag: one history entry
    y = box["y"] + box["height"] / 2
    page.mouse.move(box["x"] + 0.3 * box["width"], y)
    page.mouse.down()
    for i in range(1, 11):
        page.mouse.move(box["x"] + (0.3 + 0.01 * i) * box["width"], y)
        page.wait_for_timeout(20)
    page.mouse.up()
    page.wait_for_function("!window.qropt.inflight && !window.qropt.pending")
    page.wait_for_timeout(300)
    url, params = page.url, page.evaluate("window.qropt.params")
    assert "type=slider-crank" in url and "theta2=100" in url and "omega2=7.5" in url and "mass=" in url, url
    assert url.endswith("#mechanism")
    shown = page.inner_text("#m-numbers")
    other = browser.new_page(viewport={"width": 1400, "height": 1000})
    try:
        other.goto(url)
        other.wait_for_selector("body[data-ready='1']", timeout=60_000)
        other.wait_for_function("window.qropt.updates > 0 && !window.qropt.inflight")
        assert other.evaluate("window.qropt.params") == params
        assert other.input_value("#m-theta-n") == "100" and other.input_value("#m-omega") == "7.5"
        assert other.is_checked("#m-dyn") and other.inner_text("#m-numbers") == shown
        other.wait_for_function("document.getElementById('m-forces').textContent.includes('crank torque')")
    finally:
        other.close()
    page.go_back()  # the drag, undone at once
    page.wait_for_function("!window.qropt.inflight")
    page.wait_for_timeout(300)
    back = page.evaluate("window.qropt.params")
    assert back["r3"] == 0.41 and back["r2"] != params["r2"]
    page.go_forward()
    page.wait_for_function(f"window.qropt.params.r2 === {params['r2']!r}")
    page.goto(server + "?type=nonesuch#mechanism")  # a link the app cannot follow says why and opens the default
    page.wait_for_selector("body[data-ready='1']")
    assert "does not serve (nonesuch)" in page.inner_text("#m-url-msg")


def test_design_page_link_lengths_and_an_impossible_task(page, tmp_path):
    """TR 20: the page says in a sentence which types reach it and why the others do not (the solver's account
    behind a toggle); the extreme designs are marked doubtful; each row shows its parameters with the unit and the
    peak acceleration names the omega2 it is at."""
    page.click("#tab-design")
    page.fill("#d-tr", "20")
    for box in page.locator("#d-types input").all():
        box.set_checked(box.get_attribute("value") in ("slider-crank", "crank-shaper"))
    page.click("#d-run")
    page.wait_for_selector("#d-table tr.pick", timeout=120_000)
    rows = page.evaluate("window.qropt.designRows")
    head = page.locator("#d-table th").all_text_contents()
    assert "peak accel at omega2 = 10 rad/s [m/s²]" in head and "parameters [m; angles in deg]" in head, head
    assert page.inner_text("#d-summary").startswith("1 of 2 types has a design for TR 20 and stroke 0.3 m")
    cs = page.locator("#d-table tr.pick").nth(0)
    assert "doubtful" in cs.get_attribute("class") and "extreme" in cs.inner_text()
    p = rows[0]["params"]
    cells = cs.locator("td").all_text_contents()
    assert cells[6] == ", ".join(f"{k} {float(format(p[k], '.4g'))!r}" for k in ("r1", "r2", "r4")), cells[6]
    sc = page.locator("#d-table tr.pick").nth(1)
    assert "failed" in sc.get_attribute("class")
    reason = sc.locator("p.reason").inner_text()
    assert reason.startswith("No design: TR 20 is above the highest found for this type within its bounds (1 to")
    toggle = sc.locator("details")
    assert toggle.get_attribute("open") is None and toggle.locator("summary").inner_text() == "the solver's account"
    assert sc.locator("td").last.evaluate("e => getComputedStyle(e).textAlign") == "left"
    page.screenshot(path=tmp_path / "design_impossible.png", full_page=True)


@pytest.mark.parametrize("width", [420, 1400])
def test_pages_at_a_phone_and_a_desktop_width(browser, server, tmp_path, width):
    """Each page at 420 and 1,400 px: nothing wider than the screen, the pictures as wide as their column, and a
    screenshot with something drawn in it."""
    from PIL import Image

    pg = browser.new_page(viewport={"width": width, "height": 900})
    try:
        pg.goto(server + "#mechanism")
        pg.wait_for_selector("body[data-ready='1']", timeout=60_000)
        pg.wait_for_function("window.qropt.updates > 0 && !window.qropt.inflight")
        for name in ("mechanism", "design", "synthesis"):
            pg.click(f"#tab-{name}")
            pg.wait_for_timeout(300)
            over = pg.evaluate("document.documentElement.scrollWidth - document.documentElement.clientWidth")
            assert over <= 0, (name, width, over)
            path = tmp_path / f"{name}_{width}.png"
            pg.screenshot(path=path, full_page=True)
            img = Image.open(path).convert("L")
            assert img.width == width and len(img.getcolors(1 << 16)) > 20, (name, width)  # not blank
        pg.click("#tab-mechanism")
        pg.wait_for_timeout(300)
        assert pg.evaluate(OVERLAPS, "text.term-name, text.joint-name") == [], width
        for svg in ("m-svg", "m-plot", "m-vpoly", "m-apoly"):
            w = pg.locator(f"#{svg}").bounding_box()["width"]
            assert w >= 0.7 * min(width, 700) - 40, (svg, width, w)
    finally:
        pg.close()


def _row(pg, table: str, start: str) -> str:
    """The value cell of the first row of a table whose quantity starts with ``start``."""
    return pg.evaluate(
        "([t, s]) => { const r = [...document.getElementById(t).rows]"
        ".find((r) => r.cells[0].textContent.startsWith(s)); return r ? r.cells[1].textContent : null; }",
        [table, start],
    )


def _number(text: str) -> float:
    return float(text.split()[0])


UP_BACK = (math.cos(math.radians(150)), math.sin(math.radians(150)))


def test_the_panel_loads_give_the_librarys_torque(page, browser, tmp_path):
    """A force, a point mass, gravity along -x, pin friction and a drive added in the panel: the crank torque at
    theta2, the peak torque, the efficiency and the motor's torque shown equal the library's for the same loads; a
    load the library refuses is said beside the panel; a shared link restores the loads."""
    from qropt.dynamics.cycle import CycleDynamics

    page.select_option("#m-type", "slider-crank")
    page.wait_for_function("window.qropt.type === 'slider-crank' && !window.qropt.inflight")
    page.check("#m-dyn")
    page.wait_for_function("document.getElementById('m-forces').textContent.includes('RMS torque')")
    before = _number(_row(page, "m-forces", "crank torque"))
    page.click("#m-more summary")
    page.click("#m-add-forces")  # at the ram's joint C, 500 N against its motion on the working stroke
    row = page.locator("#m-more .load-row.forces").first
    assert row.locator("select.at").input_value() == "C"
    row.locator("input.magnitude").fill("300")
    row.locator("select.direction").select_option("angle")
    row.locator("input.angle").fill("150")  # up and back, 30 degrees from -x
    row.locator("select.window").select_option("always")
    row.locator("select.window").dispatch_event("change")
    page.wait_for_function("!window.qropt.inflight && !window.qropt.pending")
    page.wait_for_function("document.getElementById('m-forces').textContent.includes('RMS torque')")
    params, theta2 = page.evaluate("window.qropt.params"), math.radians(float(page.input_value("#m-theta-n")))
    m = mechanism_type("slider-crank")(**params)
    masses = qropt.Masses.bars(1.57, 20.0)
    loads = qropt.Loads(1000.0, gravity=9.81, forces=[qropt.Force("C", 300.0, UP_BACK, "always")])
    want = float(m.dynamics([theta2], 10.0, masses=masses, loads=loads).torque[0])
    shown = _number(_row(page, "m-forces", "crank torque"))
    assert shown == pytest.approx(want, rel=1e-4) and shown != pytest.approx(before, rel=1e-3)
    peak = CycleDynamics(m, 10.0, 0.0, masses, loads).extremes().peak_torque.value
    assert _number(_row(page, "m-forces", "peak torque")) == pytest.approx(peak, rel=1e-4)
    # a point mass, gravity along -x (a vertical machine), pin friction and a drive
    page.click("#m-add-points")
    page.fill("#m-gdir", "180")
    page.fill("#m-pin-mu", "0.1")
    page.fill("#m-pin-r", "0.02")
    page.fill("#m-ratio", "10")
    page.fill("#m-eta", "0.9")
    page.dispatch_event("#m-eta", "change")
    page.wait_for_function("document.getElementById('m-forces').textContent.includes('motor RMS torque')")
    page.wait_for_function("!window.qropt.inflight && !window.qropt.pending")
    page.wait_for_function("document.getElementById('m-forces').textContent.includes('motor RMS torque')")
    masses = qropt.Masses.bars(1.57, 20.0, points={"C": 2.0})
    loads = qropt.Loads(
        1000.0,
        gravity=(-9.81, 0.0),
        forces=[qropt.Force("C", 300.0, UP_BACK, "always")],
        pin_friction=qropt.PinFriction(0.1, 0.02),
    )
    want = float(m.dynamics([theta2], 10.0, masses=masses, loads=loads).torque[0])
    assert _number(_row(page, "m-forces", "crank torque")) == pytest.approx(want, rel=1e-4)
    eff = m.efficiency(10.0, masses=masses, loads=loads)
    assert _number(_row(page, "m-forces", "efficiency, working")) == pytest.approx(
        100 * eff.working.efficiency, rel=1e-3
    )
    assert _number(_row(page, "m-forces", "efficiency, turn")) == pytest.approx(100 * eff.turn.efficiency, rel=1e-3)
    dc = m.drive_check(qropt.Drive(10.0, 0.9), 10.0, masses=masses, loads=loads)
    assert _number(_row(page, "m-forces", "motor peak torque")) == pytest.approx(dc.peak_torque.value, rel=1e-4)
    assert _number(_row(page, "m-forces", "motor RMS torque")) == pytest.approx(dc.rms_torque, rel=1e-4)
    assert page.inner_text("#m-more-sum") == "more loads (1 force, 1 point mass, gravity at 180°, pin friction, drive)"
    _shot(page, tmp_path, "mechanism_loads")
    url, shown = page.url, page.inner_text("#m-forces")
    assert "force=C%2C300%2C150%2Calways" in url and "point=C%2C2" in url and "gdir=180" in url, url
    other = browser.new_page(viewport={"width": 1400, "height": 1000})
    try:  # the link restores the loads, and the numbers they give
        other.goto(url)
        other.wait_for_selector("body[data-ready='1']", timeout=60_000)
        other.wait_for_function("document.getElementById('m-forces').textContent.includes('motor RMS torque')")
        assert other.evaluate("panelState('m')") == page.evaluate("panelState('m')")
        assert other.evaluate("document.getElementById('m-more').open")
        assert other.inner_text("#m-forces") == shown
    finally:
        other.close()
    # a load the library refuses: said beside the panel, the results marked as the last good inputs'
    page.locator("#m-more .load-row.points input.mass").fill("-1")
    page.dispatch_event("#m-more .load-row.points input.mass", "change")
    page.wait_for_function("document.getElementById('m-load-msg').textContent.length > 0")
    assert "the point mass at C (kg) must be zero or positive" in page.inner_text("#m-load-msg")
    assert page.locator("#m-forces.stale").count() == 1
    page.locator("#m-more .load-row.points button.remove").click()
    page.wait_for_function("document.getElementById('m-load-msg').textContent === ''")


def test_design_page_sends_the_panels_loads_and_drive(page, tmp_path):
    """min_rms_motor_torque opens "more loads" with a drive; a new force is at "ram" (each type's ram joint); a
    force at a joint some ticked types lack is refused beside the panel, naming the load and the type; with one type
    the row's RMS motor torque, with the force at "ram", is the library's for the panel's loads and drive at the
    type's ram joint."""
    from qropt.dynamics.cycle import CycleDynamics
    from qropt.dynamics.drive import rms_motor_torque
    from qropt.studies._design import TYPES as ROWS

    page.click("#tab-design")
    for box in page.locator("#d-types input").all():  # design's rows (a user type another test loaded: out)
        box.set_checked(box.get_attribute("value") in ROWS)
    page.select_option("#d-objective", "rms_motor_torque")
    assert page.is_checked("#d-dyn") and page.evaluate("document.getElementById('d-more').open")
    assert page.input_value("#d-ratio") == "10" and page.input_value("#d-eta") == "0.9"
    page.click("#d-add-forces")  # at "ram": each type's ram joint (C or D)
    row = page.locator("#d-more .load-row.forces").first
    assert row.locator("select.at").input_value() == "ram"
    row.locator("select.at").select_option("D")  # the slider-crank and crank-shaper lack it
    assert row.locator("select.at option:checked").inner_text() == "D (not in 2 types)"
    page.fill("#d-budget", "5")
    page.click("#d-run")
    page.wait_for_function("document.getElementById('d-load-msg').textContent.length > 0")
    said = page.inner_text("#d-load-msg")  # (by the criterion's check or the app's, whichever sees it first)
    assert said.startswith("slider-crank") or "the slider-crank row's" in said, said
    assert "the force at D: " in said and "has no joint 'D'" in said, said
    for box in page.locator("#d-types input").all():
        box.set_checked(box.get_attribute("value") == "slider-crank")
    assert row.locator("select.at option:checked").inner_text() == "D (not in slider-crank)"
    row.locator("select.at").select_option("ram")  # the slider-crank's C
    row.locator("input.magnitude").fill("300")
    page.click("#d-run")
    page.wait_for_selector("#d-table tr.pick", timeout=60_000)
    assert page.inner_text("#d-load-msg") == ""
    (got,) = page.evaluate("window.qropt.designRows")
    m = mechanism_type("slider-crank")(**got["params"])
    loads = qropt.Loads(1000.0, gravity=9.81, forces=[qropt.Force("C", 300.0)])  # against its motion, working
    cd = CycleDynamics(m, 10.0, 0.0, qropt.Masses.bars(1.57, 20.0), loads)
    want = rms_motor_torque(cd, qropt.Drive(10.0, 0.9), split=False)
    assert got["objective"] == pytest.approx(want, rel=1e-9)
    head = page.locator("#d-table th").all_text_contents()
    col = head.index("RMS motor torque [N m]")
    assert float(page.locator("#d-table tr.pick td").nth(col).inner_text()) == pytest.approx(want, rel=1e-3)
