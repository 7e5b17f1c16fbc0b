"""The web app's speed: updates per second while a parameter slider is dragged in the browser, and the time of
one ``/api/analyze`` answer in-process, per type.

The drag is real: Playwright moves the mouse across the r3 slider of the Mechanism page in small steps every
``STEP_MS`` ms for ``SECONDS`` s, as a hand would, with the system Chromium; an update is an analysis the page
received and drew (``window.qropt.updates``). The in-process time is the API function alone (no HTTP), over the
default design of each type: it shows what the server's share of an update is. Writes ``results/app.json``.

Run: ``python -m benchmarks.app`` (repository root; needs Chromium at /usr/bin/chromium and the test extras).
"""

from __future__ import annotations

import statistics
import threading
import time

from benchmarks.report import save
from qropt.app import api, create_app
from qropt.app.defaults import default_params
from qropt.mechanisms import REGISTRY

SECONDS, STEP_MS = 5.0, 5
ARGS = ["--no-sandbox", "--disable-gpu", "--no-first-run", "--disable-background-networking", "--disable-sync"]


def in_process(repeat: int = 30) -> dict:
    """Median ms of one /api/analyze answer (no masses; with polygons), per type."""
    out = {}
    for kind, cls in REGISTRY.items():
        params = default_params(cls)
        if not params:
            continue
        body = {"type": kind, "params": params, "theta2": 1.0, "omega2": 10.0}
        api.analyze(body)
        times = []
        for _ in range(repeat):
            t = time.perf_counter()
            api.analyze(body)
            times.append(time.perf_counter() - t)
        out[kind] = 1e3 * statistics.median(times)
    return out


def dragged(kind: str, name: str, masses: bool = False) -> dict:
    """Updates a second while the slider of parameter ``name`` of ``kind`` is dragged for SECONDS s in Chromium
    (updates: analyses drawn; answers: those and the refusals shown, where the slider left the valid designs)."""
    from playwright.sync_api import sync_playwright
    from werkzeug.serving import make_server

    app = create_app()
    srv = make_server("127.0.0.1", 0, app, threaded=True)
    threading.Thread(target=srv.serve_forever, daemon=True).start()
    try:
        with sync_playwright() as p:
            b = p.chromium.launch(executable_path="/usr/bin/chromium", args=ARGS)
            pg = b.new_page(viewport={"width": 1400, "height": 1000})
            pg.goto(f"http://127.0.0.1:{srv.server_port}/#mechanism")
            pg.wait_for_selector("body[data-ready='1']", timeout=60_000)
            pg.select_option("#m-type", kind)
            pg.wait_for_function(f"window.qropt.type === '{kind}' && !window.qropt.inflight")
            if masses:
                pg.check("#m-dyn")
                pg.wait_for_function("!window.qropt.inflight")
            box = pg.locator(f"#p-{name}").bounding_box()
            y = box["y"] + box["height"] / 2
            pg.mouse.move(box["x"] + 0.3 * box["width"], y)
            pg.mouse.down()
            n0, a0 = pg.evaluate("[window.qropt.updates, window.qropt.answers]")
            t0, i = time.perf_counter(), 0
            while time.perf_counter() - t0 < SECONDS:
                i += 1
                frac = 0.3 + 0.4 * abs(((i * 0.004) % 2) - 1)  # back and forth over 40 % of the slider
                pg.mouse.move(box["x"] + frac * box["width"], y)
                pg.wait_for_timeout(STEP_MS)
            pg.mouse.up()
            elapsed = time.perf_counter() - t0
            pg.wait_for_function("!window.qropt.inflight")
            n, a = pg.evaluate("[window.qropt.updates, window.qropt.answers]")
            n, a = n - n0, a - a0
            b.close()
    finally:
        srv.shutdown()
        app.extensions["qropt_jobs"].close()
    return {
        "type": kind,
        "slider": name,
        "masses": masses,
        "moves": i,
        "updates": n,
        "answers": a,
        "per_second": n / elapsed,
        "answers_per_second": a / elapsed,
    }


def main() -> int:
    import logging

    logging.getLogger("werkzeug").setLevel(logging.WARNING)  # no line per request
    api_ms = in_process()
    drags = [
        dragged("drag-link-slider", "r3"),
        dragged("drag-link-slider", "r3", masses=True),
        dragged("coupler-slider", "r6"),
        dragged("whitworth", "r2", masses=True),
    ]
    save("app.json", {"analyze_ms": api_ms, "drags": drags, "seconds": SECONDS, "step_ms": STEP_MS})
    print("one /api/analyze answer, in-process (median ms):")
    for k, v in api_ms.items():
        print(f"  {k:22s} {v:6.2f}")
    print(f"dragging a slider in Chromium for {SECONDS:g} s (a mouse move every {STEP_MS} ms):")
    for d in drags:
        extra = " with the mass model" if d["masses"] else ""
        print(
            f"  {d['type']} ({d['slider']}){extra}: {d['per_second']:.1f} updates/s ({d['updates']} drawn, "
            f"{d['answers']} answers, {d['moves']} mouse moves)"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
