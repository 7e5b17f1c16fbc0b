// qropt app: the pages over the JSON API (no external resources; SVG drawn here from the API's shapes).
"use strict";

const $ = (id) => document.getElementById(id);
const SVGNS = "http://www.w3.org/2000/svg";
const DEG = Math.PI / 180;
const COLOURS = { absolute: "#000", relative: "#1565c0", normal: "#2e7d32", tangential: "#ef6c00",
  sliding: "#6a1b9a", coriolis: "#c62828" };
const WORK = "#2e7d32", RET = "#e65100";

// What each quantity a student reads means: a row's or a heading's tooltip (title=).
const HELP = {
  time_ratio: "time ratio TR: the time of the working (cutting) stroke over the time of the return stroke at a steady "
    + "crank speed; TR 1.5 means the return takes 2/3 of the working stroke's time",
  stroke: "stroke: the distance the ram travels between its two ends (its dead centres)",
  swing: "swing: the angle the output link turns through between its two ends",
  gamma_min: "gamma_min: the least transmission angle over the turn, the angle at which a link pushes what it drives "
    + "(folded to 0-90 deg): 90 deg transmits the force best, near 0 the mechanism jams. The joint in brackets, "
    + "e.g. (B), is where it occurs",
  dead_centres: "dead centres: the crank angles theta2 at which the ram stops and turns back (the ends of the stroke)",
  peak_accel: "peak acceleration: the largest acceleration of the ram over one turn at the omega2 given, and the crank "
    + "angle where it occurs",
  peak_accel_design: "peak acceleration: the largest acceleration of the ram over one turn at the omega2 of the task "
    + "(it grows as omega2 squared)",
  footprint: "footprint: the area of the smallest rectangle that holds the mechanism over its whole turn",
  x: "x: the ram's position at theta2", v: "v: the ram's velocity at theta2", a: "a: the ram's acceleration at theta2",
  theta2: "theta2: the crank angle, in degrees from the line of centres",
  omega2: "omega2: the crank's speed in rad/s (its sign is its sense of rotation); 10 rad/s is about 95 rpm",
  sigma: "sigma: the assembly branch, which of the two ways the links fit together at one crank angle (+1 or -1); "
    + "a mechanism stays on its branch while it turns",
  torque: "crank torque: the torque the motor must give the crank at theta2 to keep omega2 steady",
  force: "joint force: the magnitude of the force the joint passes on at theta2",
  rms: "RMS torque: the root mean square of the crank torque over a turn (what heats the motor)",
  shaking: "peak shaking force: the largest force the mechanism puts on its frame over a turn",
  flywheel: "flywheel: the moment of inertia that keeps the crank's speed within a coefficient of fluctuation "
    + "Cs = 0.05 (plus or minus 2.5%)",
  efficiency: "mechanical efficiency: the work the loads absorb over the work the crank gives (net of friction at "
    + "the pins and the slide) over the working stroke and over the whole turn, at a steady omega2",
  friction: "friction work: the energy the pins' and the slide's friction take per turn",
  motor: "motor torque: the crank torque through the drive's gearbox, T / (i eta) where the motor drives and "
    + "T eta / i where the crank drives it; the RMS is what heats the motor",
  objective: "objective: the quantity the solve makes as large (max_) or as small (min_) as it can",
  status: "status: optimal (certified best of its kind), feasible (meets the task, not proved best), infeasible (no "
    + "design exists within the bounds) or failed (none found)",
  parameters: "parameters: the design's link lengths and offsets in the unit named, angles in degrees (the branch "
    + "signs are on the Mechanism page); the line under the Mechanism page's sliders says which is which link",
  free: "free: the solve chooses this parameter between its low and high bounds; unticked, it stays at its value",
};

// The app's state; window.qropt lets a test read what the page shows and how fast it updates.
const state = {
  types: {}, type: null, params: {}, units: "m", analysis: null, frames: null, playing: false,
  inflight: false, pending: false, updates: 0, answers: 0, designRows: [], selected: null, result: null, job: null,
  objectives: {}, results: {}, restoring: false, solved: null,
};
window.qropt = state;

// ---- the API --------------------------------------------------------------------------------------------
async function call(method, url, body) {
  const opts = { method, headers: {} };
  if (body !== undefined) {
    opts.headers["Content-Type"] = "application/json";
    opts.body = JSON.stringify(body);
  }
  const r = await fetch(url, opts);
  const text = await r.text();
  let data = null;
  try { data = JSON.parse(text); } catch (e) { data = null; }
  if (!r.ok) {
    const e = new Error((data && data.error) || `${r.status} ${r.statusText}`);
    e.field = data && data.field;  // "loads": the mass model and load panel's fault, said beside it
    throw e;
  }
  return data === null ? text : data;
}

// A message beside what caused it: the element `id` (an export bar's, the Animate button's), "" clears it.
function say(id, text, bad = false) {
  const e = $(id);
  e.textContent = text || "";
  e.classList.toggle("bad", bad);
}

// ---- results and the inputs they belong to ----------------------------------------------------------------
// Every page's results are a group: its panels, a note above them and a function giving the page's inputs
// (name -> the value as shown). A new result is fresh(group, inputs it was asked with). When a request fails, or
// (on a page that does not recompute as one types) the inputs change after a result, the panels are dimmed and
// the note says which inputs they belong to; the next result clears both. Before any result the note shows the
// error alone.
function resultGroup(name, { panels, inputs, note, watch, live }) {
  const g = { name, panels: panels.map((id) => $(id)), inputs, shown: null, live: !!live, stale: false };
  g.note = note ? $(note) : document.createElement("div");
  if (!note) (g.panels[0].closest(".scroll") || g.panels[0]).before(g.note);
  g.note.classList.add("stale-note");
  g.note.id = g.note.id || `${name}-note`;
  if (!g.live) {
    for (const w of watch || []) for (const ev of ["input", "change"]) $(w).addEventListener(ev, () => inputsChanged(name));
  }
  state.results[name] = g;
  return g;
}

function changes(was, now) {
  return Object.keys({ ...was, ...now }).filter((k) => was[k] !== now[k]);
}
const FEW = 3;  // changed inputs named one by one; more are counted
function listed(values, keys) {
  const one = (k) => (values[k] === undefined ? `no ${k}` : `${k} = ${values[k]}`);
  if (keys.length <= FEW) return keys.map(one).join(", ");
  return `${keys.slice(0, 2).map(one).join(", ")} and ${keys.length - 2} other inputs since changed`;
}
// One line: the inputs the results belong to ("Results for r3 = 0.25"), then what the inputs now give.
function belongs(was, now, keys, gives) {
  const current = keys.length <= FEW ? ` (${listed(now, keys)})` : "";
  return `Results for ${listed(was, keys)}; the inputs now${current} ${gives}`;
}
function markStale(g, text) {
  g.stale = !!text;
  for (const p of g.panels) p.classList.toggle("stale", g.stale);
  g.note.textContent = text || "";
}
function fresh(name, inputs) {
  const g = state.results[name];
  g.shown = inputs || g.inputs();
  markStale(g, "");
  if (!g.live) inputsChanged(name);  // the inputs may have moved on while it was computed
}
function stale(name, why) {
  const g = state.results[name];
  if (!g.shown) { markStale(g, ""); g.note.textContent = why; return; }
  const now = g.inputs(), keys = changes(g.shown, now);
  markStale(g, keys.length ? belongs(g.shown, now, keys, `give: ${why}`)
    : `Results for the inputs shown, which now give: ${why}`);
}
function inputsChanged(name) {
  const g = state.results[name];
  if (!g.shown) return;
  const now = g.inputs(), keys = changes(g.shown, now);
  markStale(g, keys.length ? belongs(g.shown, now, keys, "have no results yet") : "");
}
const shownNumber = (v) => (typeof v === "number" ? String(+v.toPrecision(6)) : String(v));

async function runJob(kind, input, progressEl, cancelBtn, note = "") {
  const job = await call("POST", "/api/jobs", { kind, input });
  state.job = job.id;
  const t0 = performance.now();
  if (cancelBtn) {
    cancelBtn.disabled = false;
    cancelBtn.onclick = () => call("DELETE", `/api/jobs/${job.id}`);
  }
  try {
    for (;;) {
      const s = await call("GET", `/api/jobs/${job.id}`);
      const p = s.progress, secs = ((performance.now() - t0) / 1000).toFixed(1);
      if (progressEl) {
        progressEl.textContent = `${kind}: ${s.state}` + (p.total ? `, ${p.done} of ${p.total}` : "") + ` (${secs} s${note})`;
      }
      if (s.state === "done") return s.result;
      if (["failed", "cancelled", "timeout"].includes(s.state)) throw new Error(`${kind} ${s.state}: ${s.error}`);
      await new Promise((ok) => setTimeout(ok, 250));
    }
  } finally {
    if (cancelBtn) cancelBtn.disabled = true;
    state.job = null;
  }
}

// ---- SVG ------------------------------------------------------------------------------------------------
function el(tag, attrs, parent, text) {
  const e = document.createElementNS(SVGNS, tag);
  for (const [k, v] of Object.entries(attrs || {})) e.setAttribute(k, v);
  if (text !== undefined) e.textContent = text;
  if (parent) parent.appendChild(e);
  return e;
}
function clear(svg) { while (svg.firstChild) svg.removeChild(svg.firstChild); }

// A sentence in an empty picture (why it has nothing to draw), wrapped to the picture's width.
function note(svg, text) {
  const w = svg.clientWidth || 300, h = svg.clientHeight || 150, per = Math.max(20, Math.floor(w / 7));
  svg.setAttribute("viewBox", `0 0 ${w} ${h}`);
  const t = el("text", { x: 8, y: 20, class: "note" }, svg);
  const words = text.split(" ");
  let line = "", n = 0;
  for (const word of words) {
    if ((line + " " + word).length > per && line) {
      el("tspan", { x: 8, dy: n++ ? 16 : 0 }, t, line);
      line = word;
    } else line = line ? `${line} ${word}` : word;
  }
  el("tspan", { x: 8, dy: n ? 16 : 0 }, t, line);
}
// The size in drawing units of `px` pixels in an svg whose viewBox is w x h (shown with "meet").
// The view box x, y, w, h widened (or heightened) to the svg's own shape, so that it fills the svg and text placed
// at its corner is at the picture's corner; set on the svg and returned.
function fitView(svg, x, y, w, h) {
  const r = svg.getBoundingClientRect();
  if (r.width > 0 && r.height > 0) {
    const want = r.width / r.height;
    if (w / h < want) { const w2 = h * want; x -= (w2 - w) / 2; w = w2; } else { const h2 = w / want; y -= (h2 - h) / 2; h = h2; }
  }
  svg.setAttribute("viewBox", `${x} ${y} ${w} ${h}`);
  return { x, y, w, h };
}
function unitsPerPixel(svg, w, h, px) {
  const r = svg.getBoundingClientRect();
  const scale = Math.min((r.width || 400) / w, (r.height || 300) / h);
  return px / scale;
}
// A number as a person reads it: d significant digits, trailing zeros dropped, 0 for a value within `tiny` of
// zero (a rounding residue such as h = -1.9e-17 of a design whose lengths are tenths of a metre).
function num(v, d = 6, tiny = 0) {
  if (v === null || v === undefined || Number.isNaN(Number(v))) return "-";
  if (Math.abs(v) <= tiny) return "0";
  return String(+Number(v).toPrecision(d));
}
// The residue below which a parameter of this design is zero: 1e-9 of its longest length or offset.
function tinyOf(params, kinds) {
  const sizes = Object.entries(params).filter(([k]) => ["length", "offset"].includes(kinds[k])).map(([, v]) => Math.abs(v));
  return 1e-9 * Math.max(0, ...sizes);
}
// A design's parameters in one line: lengths and offsets in the unit (named in the column's head), angles in
// degrees; the branch signs left out.
function paramText(params, kinds, unit) {
  const tiny = tinyOf(params, kinds), out = [];
  for (const [k, v] of Object.entries(params)) {
    const kind = kinds[k];
    if (kind === "branch" || kind === undefined) continue;
    out.push(kind === "angle" ? `${k} ${num(v / DEG, 4)}°` : `${k} ${num(v, 4, tiny)}`);
  }
  return out.join(", ");
}
// d significant digits, zeros kept (90.00); an exponent only outside 1e-4..1e9.
function fmt(v, d = 4) {
  if (v === null || v === undefined || Number.isNaN(v)) return "-";
  const s = Number(v).toPrecision(d), a = Math.abs(v);
  return s.includes("e") && a >= 1e-4 && a < 1e9 ? String(+s) : s;
}
const pts = (p) => p.map((q) => `${q[0]},${q[1]}`).join(" ");

const STYLE = {
  link: { stroke: "#37474f", "stroke-width": 4, fill: "none", "stroke-linecap": "round" },
  plate: { stroke: "#37474f", "stroke-width": 2, fill: "#b0bec5", "fill-opacity": 0.6 },
  slot: { stroke: "#37474f", "stroke-width": 1.5, fill: "#fff", "fill-opacity": 0.4 },
  block: { stroke: "#263238", "stroke-width": 1.5, fill: "#90a4ae" },
  ram: { stroke: "#263238", "stroke-width": 1.5, fill: "#607d8b" },
  slide: { stroke: "#9e9e9e", "stroke-width": 1, "stroke-dasharray": "6 4", fill: "none" },
  pivot: { stroke: "#000", "stroke-width": 1.5, fill: "#ffcc80" },
  joint: { stroke: "#000", "stroke-width": 1.5, fill: "#fff" },
};

// A mechanism drawn in an svg: the view of its whole turn, the output's path coloured by stroke, the shapes.
function drawMechanism(svg, drawing, shapes, label) {
  clear(svg);
  const [x, y, w, h] = drawing.view, pad = 0.06 * Math.max(w, h);
  const view = fitView(svg, x - pad, -(y + h) - pad, w + 2 * pad, h + 2 * pad);
  svg.setAttribute("preserveAspectRatio", "xMidYMid meet");
  const g = el("g", { transform: "scale(1,-1)" }, svg);
  if (drawing.path) {
    const p = drawing.path.points, wk = drawing.path.working;
    let run = [p[0]];
    for (let i = 1; i < p.length; i++) {
      run.push(p[i]);
      if (i === p.length - 1 || wk[i] !== wk[i - 1]) {
        el("polyline", { points: pts(run), fill: "none", stroke: wk[i - 1] ? WORK : RET, "stroke-width": 2.5,
          "vector-effect": "non-scaling-stroke", class: wk[i - 1] ? "path-working" : "path-return" }, g);
        run = [p[i]];
      }
    }
  }
  for (const s of shapes) {
    const a = { ...(STYLE[s.part] || STYLE.link), "vector-effect": "non-scaling-stroke", "data-part": s.part };
    if (s.kind === "line") {
      el("line", { ...a, x1: s.points[0][0], y1: s.points[0][1], x2: s.points[1][0], y2: s.points[1][1] }, g);
    } else if (s.kind === "circle") {
      el("circle", { ...a, cx: s.points[0][0], cy: s.points[0][1], r: s.radius }, g);
    } else if (s.kind === "polygon") {
      el("polygon", { ...a, points: pts(s.points) }, g);
    } else {
      el("polyline", { ...a, points: pts(s.points) }, g);
    }
  }
  if (label) {
    const fs = unitsPerPixel(svg, view.w, view.h, 13), per = Math.max(12, Math.floor(view.w / (0.58 * fs)) - 2);
    const lines = [];  // the label wrapped to the picture's width
    for (const word of label.split(" ")) {
      if (lines.length && (lines[lines.length - 1] + " " + word).length <= per) lines[lines.length - 1] += " " + word;
      else lines.push(word);
    }
    const t = el("text", { x: view.x + fs * 0.5, y: view.y + fs * 1.2, "font-size": fs, fill: "#333" }, svg);
    lines.forEach((line, i) => el("tspan", { x: view.x + fs * 0.5, dy: i ? 1.2 * fs : 0 }, t, line));
    const longest = Math.max(...lines.map((l) => l.length));
    const boxes = [[view.x, view.y, view.x + 0.62 * fs * longest, view.y + (0.4 + 1.2 * lines.length) * fs]];  // its box
    // each joint's name, as the tables name it, beside its joint where it overlaps no name before it
    const around = [[0.5, -0.5], [-0.5, -0.5], [0.5, 1.3], [-0.5, 1.3], [0.9, 0.4], [-0.9, 0.4], [0, -1], [0, 1.8]];
    for (const s of shapes) {
      if (s.part !== "pivot" && s.part !== "joint") continue;
      const [jx, jy] = s.points[0], w = 0.68 * fs * s.name.length;
      let spot = null;
      for (const [dx, dy] of around) {
        const tx = jx + dx * fs + (dx < 0 ? -w : dx === 0 ? -w / 2 : 0), ty = -jy + dy * fs;
        const b = [tx, ty - fs, tx + w, ty];
        if (!boxes.some((o) => b[0] < o[2] && o[0] < b[2] && b[1] < o[3] && o[1] < b[3])) { spot = [tx, ty, b]; break; }
      }
      if (!spot) spot = [jx + 0.5 * fs, -jy - 0.5 * fs, null];
      if (spot[2]) boxes.push(spot[2]);
      el("text", { x: spot[0], y: spot[1], "font-size": fs, fill: "#1a237e", stroke: "#fff",
        "stroke-width": 0.25 * fs, "paint-order": "stroke", "font-weight": "bold", class: "joint-name" }, svg, s.name);
    }
  }
}

// Panels of curves over the crank angle in one svg: each its own y axis and label with units.
function plotCycle(svg, th, panels, working, mark) {
  clear(svg);
  const W = Math.max(360, Math.min(900, svg.clientWidth || 640)), H = 90 * panels.length + 40, L = 70, R = 15, T = 10;
  svg.setAttribute("viewBox", `0 0 ${W} ${H}`);
  const ph = (H - T - 35) / panels.length;
  const X = (t) => L + ((W - L - R) * t) / 360;
  panels.forEach((pnl, k) => {
    const top = T + k * ph, bottom = top + ph - 12;
    const lo = Math.min(...pnl.y, 0), hi = Math.max(...pnl.y, 0), span = hi - lo || 1;
    const Y = (v) => bottom - ((bottom - top) * (v - lo)) / span;
    if (working) {
      for (let i = 0; i + 1 < th.length; i++) {
        if (working[i]) el("rect", { x: X(th[i]), y: top, width: X(th[i + 1]) - X(th[i]) + 0.5, height: bottom - top,
          fill: "#e8f5e9" }, svg);
      }
    }
    el("rect", { x: L, y: top, width: W - L - R, height: bottom - top, fill: "none", stroke: "#999" }, svg);
    el("line", { x1: L, x2: W - R, y1: Y(0), y2: Y(0), stroke: "#bbb", "stroke-dasharray": "3 3" }, svg);
    el("polyline", { points: th.map((t, i) => `${X(t)},${Y(pnl.y[i])}`).join(" "), fill: "none",
      stroke: pnl.colour || "#1565c0", "stroke-width": 1.6 }, svg);
    el("text", { x: 4, y: (top + bottom) / 2, "font-size": 11, fill: "#333" }, svg, pnl.label);
    el("text", { x: L - 4, y: top + 10, "font-size": 9, "text-anchor": "end", fill: "#555" }, svg, fmt(hi, 3));
    el("text", { x: L - 4, y: bottom, "font-size": 9, "text-anchor": "end", fill: "#555" }, svg, fmt(lo, 3));
    if (mark !== undefined) {
      el("line", { x1: X(mark), x2: X(mark), y1: top, y2: bottom, stroke: "#c62828", "stroke-width": 1 }, svg);
    }
  });
  for (let t = 0; t <= 360; t += 60) {
    el("text", { x: X(t), y: H - 20, "font-size": 10, "text-anchor": "middle", fill: "#333" }, svg, String(t));
  }
  el("text", { x: (L + W - R) / 2, y: H - 5, "font-size": 11, "text-anchor": "middle" }, svg,
    "crank angle theta2 [deg]" + (working ? " (shaded: working stroke)" : ""));
}

// A velocity or acceleration polygon: each equation's terms head to tail from the pole o, the exact vector dashed.
function drawPolygon(svg, equations, quantity, unit) {
  clear(svg);
  const eqs = equations.filter((e) => e.quantity === quantity);
  const xs = [0], ys = [0], segs = [];
  for (const e of eqs) {
    let hx = 0, hy = 0;
    for (const t of e.terms) {
      const tx = hx + t.vector[0], ty = hy + t.vector[1];
      segs.push({ from: [hx, hy], to: [tx, ty], term: t });
      xs.push(tx); ys.push(ty);
      hx = tx; hy = ty;
    }
    xs.push(e.exact[0]); ys.push(e.exact[1]);
  }
  const x0 = Math.min(...xs), x1 = Math.max(...xs), y0 = Math.min(...ys), y1 = Math.max(...ys);
  const span = Math.max(x1 - x0, y1 - y0, 1e-12), pad = 0.18 * span;
  const view = fitView(svg, x0 - pad, -y1 - pad, x1 - x0 + 2 * pad, y1 - y0 + 2 * pad);
  const defs = el("defs", {}, svg);
  for (const [k, c] of Object.entries(COLOURS)) {
    const mk = el("marker", { id: `arrow-${quantity}-${k}`, viewBox: "0 0 10 10", refX: 10, refY: 5,
      markerWidth: 7, markerHeight: 7, orient: "auto-start-reverse" }, defs);
    el("path", { d: "M 0 0 L 10 5 L 0 10 z", fill: c }, mk);
  }
  const fs = unitsPerPixel(svg, view.w, view.h, 11);
  const g = el("g", { transform: "scale(1,-1)" }, svg);
  const drawn = new Set(), named = [];
  for (const s of segs) {
    const key = s.from.concat(s.to).map((v) => Math.round(v / (1e-6 * span))).join(",");
    if (drawn.has(key) || Math.hypot(s.term.vector[0], s.term.vector[1]) < 1e-12 * span) continue;
    drawn.add(key);
    el("line", { x1: s.from[0], y1: s.from[1], x2: s.to[0], y2: s.to[1], stroke: COLOURS[s.term.kind],
      "stroke-width": 1.8, "vector-effect": "non-scaling-stroke",
      "marker-end": `url(#arrow-${quantity}-${s.term.kind})` }, g);
    if (Math.hypot(s.term.vector[0], s.term.vector[1]) < 0.15 * span) continue;  // short terms: no room to name
    named.push(s);
  }
  // Each term named beside its arrow's middle, moved along the arrow's normal until it overlaps no name before it.
  const title = `${quantity} polygon [${unit}]`, tx = view.x + fs * 0.4, ty = view.y + fs * 1.3;
  const boxes = [[tx, ty - 1.2 * fs, tx + 0.62 * 1.2 * fs * title.length, ty]];  // the title's
  const free = (b) => !boxes.some((o) => b[0] < o[2] && o[0] < b[2] && b[1] < o[3] && o[1] < b[3]);
  for (const s of named) {
    const mx = (s.from[0] + s.to[0]) / 2, my = -(s.from[1] + s.to[1]) / 2;  // (y down, as the svg's)
    const dx = s.to[0] - s.from[0], dy = -(s.to[1] - s.from[1]), len = Math.hypot(dx, dy) || 1;
    const nx = -dy / len, ny = dx / len, w = 0.62 * fs * s.term.name.length, h = fs;
    let spot = null;
    for (let k = 0; k < 16 && !spot; k++) {
      const d = (k % 2 ? -1 : 1) * (0.7 + 1.1 * Math.floor(k / 2)) * fs;
      const x = mx + nx * d, y = my + ny * d + 0.35 * h;
      const b = [x - w / 2, y - 1.15 * h, x + w / 2, y + 0.15 * h];  // (with a margin)
      if (free(b)) spot = [x, y, b];
    }
    if (!spot) continue;  // no room near its arrow: left unnamed (its colour and the legend say its kind)
    boxes.push(spot[2]);
    el("text", { x: spot[0], y: spot[1], "font-size": fs, fill: COLOURS[s.term.kind], "text-anchor": "middle",
      stroke: "#fff", "stroke-width": 0.2 * fs, "paint-order": "stroke", class: "term-name" }, svg, s.term.name);
  }
  for (const e of eqs) {
    el("line", { x1: 0, y1: 0, x2: e.exact[0], y2: e.exact[1], stroke: "#777", "stroke-dasharray": "4 3",
      "vector-effect": "non-scaling-stroke" }, g);
  }
  el("circle", { cx: 0, cy: 0, r: 0.012 * span, fill: "#000" }, g);
  el("text", { x: tx, y: ty, "font-size": fs * 1.2 }, svg, title);
}

// A scatter of two criteria whose points open their designs.
function scatter(svg, pts2, xlabel, ylabel, onPick) {
  clear(svg);
  const W = Math.max(360, Math.min(900, svg.clientWidth || 640)), H = 300, L = 70, B = 40, T = 10, R = 15;
  svg.setAttribute("viewBox", `0 0 ${W} ${H}`);
  const xs = pts2.map((p) => p[0]), ys = pts2.map((p) => p[1]);
  const xl = Math.min(...xs), xh = Math.max(...xs), yl = Math.min(...ys), yh = Math.max(...ys);
  const X = (v) => L + ((W - L - R) * (v - xl)) / ((xh - xl) || 1) * 0.9 + 0.05 * (W - L - R);
  const Y = (v) => H - B - (((H - B - T) * (v - yl)) / ((yh - yl) || 1)) * 0.9 - 0.05 * (H - B - T);
  el("rect", { x: L, y: T, width: W - L - R, height: H - B - T, fill: "none", stroke: "#999" }, svg);
  el("polyline", { points: pts2.map((p) => `${X(p[0])},${Y(p[1])}`).join(" "), fill: "none", stroke: "#90caf9" }, svg);
  pts2.forEach((p, i) => {
    const c = el("circle", { cx: X(p[0]), cy: Y(p[1]), r: 6, fill: "#1565c0", class: "front-point" }, svg);
    c.style.cursor = "pointer";
    el("title", {}, c, `${xlabel} ${fmt(p[0])}, ${ylabel} ${fmt(p[1])}`);
    c.addEventListener("click", () => onPick(i));
  });
  el("text", { x: L, y: H - 22, "font-size": 10 }, svg, fmt(xl));
  el("text", { x: W - R, y: H - 22, "font-size": 10, "text-anchor": "end" }, svg, fmt(xh));
  el("text", { x: L - 4, y: H - B, "font-size": 10, "text-anchor": "end" }, svg, fmt(yl));
  el("text", { x: L - 4, y: T + 10, "font-size": 10, "text-anchor": "end" }, svg, fmt(yh));
  el("text", { x: (L + W) / 2, y: H - 5, "font-size": 11, "text-anchor": "middle" }, svg, xlabel);
  el("text", { x: 12, y: (H - B) / 2, "font-size": 11, transform: `rotate(-90 12 ${(H - B) / 2})`,
    "text-anchor": "middle" }, svg, ylabel);
}

// A table: a header row and rows of cells, each a text or a DOM node; onPick(i) when row i is clicked.
function table(tbl, head, rows, onPick) {
  tbl.innerHTML = "";
  const tr = tbl.insertRow();
  for (const h of head) {
    const th = document.createElement("th");
    if (h instanceof Node) th.appendChild(h); else th.textContent = h;
    tr.appendChild(th);
  }
  rows.forEach((r, i) => {
    const row = tbl.insertRow();
    r.forEach((c, k) => {
      const td = row.insertCell();
      td.dataset.label = head[k] instanceof Node ? head[k].textContent : head[k];  // its heading on a narrow screen
      if (c instanceof Node) td.appendChild(c); else td.textContent = c;
    });
    if (onPick) { row.className = "pick"; row.addEventListener("click", () => onPick(i)); }
  });
}

// Each row of a quantity table gets its quantity's help as a tooltip, found by the row's first words.
const HELP_ROWS = [["time ratio", "time_ratio"], ["stroke", "stroke"], ["swing", "swing"], ["gamma_min", "gamma_min"],
  ["dead centres", "dead_centres"], ["peak acceleration", "peak_accel"], ["x ", "x"], ["v ", "v"], ["a ", "a"],
  ["theta4", "x"], ["omega4", "v"], ["alpha4", "a"], ["crank torque", "torque"], ["force at", "force"],
  ["peak torque", "torque"], ["RMS torque", "rms"], ["peak shaking", "shaking"], ["flywheel", "flywheel"],
  ["efficiency", "efficiency"], ["friction work", "friction"], ["motor", "motor"]];
function helpRows(tbl) {
  for (const tr of tbl.rows) {
    const text = tr.cells[0].textContent, hit = HELP_ROWS.find(([start]) => text.startsWith(start));
    if (hit) tr.title = HELP[hit[1]];
  }
}

// A block of text elements: [tag, text, class] each, in a <div> (a table cell's content).
function block(parts) {
  const div = document.createElement("div");
  for (const [tag, text, cls] of parts) {
    if (!text) continue;
    const e = document.createElement(tag);
    e.textContent = text;
    if (cls) e.className = cls;
    div.appendChild(e);
  }
  return div;
}
// Details behind a toggle: <details><summary>summary</summary>text</details>.
function toggle(summary, text) {
  const d = document.createElement("details"), s = document.createElement("summary");
  s.textContent = summary;
  d.append(s, text);
  d.addEventListener("click", (ev) => ev.stopPropagation());  // opening it does not pick the row
  return d;
}

// ---- pages ----------------------------------------------------------------------------------------------
function route() {
  const page = (location.hash || "#mechanism").slice(1);
  for (const m of document.querySelectorAll(".msg")) say(m.id, "");  // a message belongs to the page it was said on
  for (const p of ["design", "mechanism", "synthesis"]) {
    $(`page-${p}`).classList.toggle("shown", p === page);
    $(`tab-${p}`).classList.toggle("active", p === page);
  }
  redraw();
}

// The shown page's pictures drawn again at the size they are shown (drawn while hidden, or the window resized).
function redraw() {
  if ($("page-mechanism").classList.contains("shown") && state.analysis) showAnalysis(state.analysis);
  if ($("page-synthesis").classList.contains("shown") && state.solved) {
    drawMechanism($("s-svg"), state.solved[0], state.solved[0].shapes, state.solved[1]);
  }
}
let resized = null;
window.addEventListener("resize", () => { clearTimeout(resized); resized = setTimeout(redraw, 200); });

// Mechanism: a slider and a number box per parameter; every change analysed at once (one request in flight).
function paramRange(kind, v, all) {
  const longest = Math.max(0.05, ...Object.entries(all).filter(([k]) => state.types[state.type].kinds[k] === "length")
    .map(([, x]) => Math.abs(x)));
  if (kind === "angle") return [-180, 180, 0.1];
  if (kind === "offset") return [-2 * longest, 2 * longest, longest / 500];
  const hi = Math.max(2.5 * Math.abs(v), 0.2 * longest);
  return [hi / 1000, hi, hi / 1000];
}

function showParams(type, params) {
  state.type = type;
  state.params = { ...params };
  $("m-type").value = type;
  const box = $("m-params");
  box.innerHTML = "";
  const kinds = state.types[type].kinds, summary = state.types[type].summary.replace(/``/g, "");
  $("m-legend").textContent = summary ? `The parameters: ${summary}` : "";
  const tiny = tinyOf(state.params, kinds);
  for (const [k, kind] of Object.entries(kinds)) {
    if (!(k in state.params)) continue;
    const label = document.createElement("label");
    label.innerHTML = `<span>${k} <span class="unit">${{ angle: "deg", branch: "" }[kind] ?? state.units}</span></span>`;
    label.title = kind === "branch" ? HELP.sigma : `${k}: a ${kind} of the ${state.types[type].class}. ${summary}`;
    if (kind === "branch") {
      const s = document.createElement("select");
      s.id = `p-${k}`;
      for (const v of [1, -1]) s.add(new Option(v > 0 ? "+1" : "-1", v));
      s.value = String(state.params[k]);
      s.addEventListener("change", () => { state.params[k] = Number(s.value); analyze(); });
      label.appendChild(s);
    } else {
      const shown = kind === "angle" ? state.params[k] / DEG : state.params[k];
      const [lo, hi, step] = paramRange(kind, state.params[k], state.params);
      const r = document.createElement("input");
      Object.assign(r, { type: "range", min: lo, max: hi, step, value: shown, id: `p-${k}` });
      const n = document.createElement("input");
      Object.assign(n, { type: "number", step: "any", value: num(shown, 6, kind === "angle" ? 0 : tiny), id: `n-${k}` });
      const set = (v) => { state.params[k] = kind === "angle" ? v * DEG : v; analyze(); };
      r.addEventListener("input", () => { n.value = +Number(r.value).toPrecision(6); set(Number(r.value)); });
      n.addEventListener("change", () => { if (n.value !== "") { r.value = n.value; set(Number(n.value)); } });
      label.append(r, n);
    }
    box.appendChild(label);
  }
  analyze();
}

// The mass model and load: one panel, built into every <div class="mass-model" data-prefix="P"> (the Mechanism
// and Design pages), its inputs P-dyn (ticked: used), P-density, P-ram, P-force and P-gravity, and behind "more
// loads" (P-more) the lists of forces, torques and point masses (rows in P-list-forces, -torques, -points), gravity's
// direction P-gdir (deg from +x; -90 straight down), the slide's friction P-mu, pin friction P-pin-mu and
// P-pin-r (every pin) and a drive P-ratio, P-eta (none while the ratio is empty). What the server refuses is said
// in P-load-msg, beside the panel.
const MASS_FIELDS = [["density", "links [kg/m]", 1.57, 0.1], ["ram", "ram [kg]", 20, 1],
  ["force", "cutting force [N]", 1000, 100], ["gravity", "gravity [m/s²]", 9.81, 0.1]];
// The single inputs behind "more loads": key, label, default ("" none), step, help, and the group (a line) it is in.
const MORE_FIELDS = [
  ["gdir", "gravity direction [deg]", -90, 1, "the direction gravity pulls, in degrees counter-clockwise from +x: "
    + "-90 straight down (-y); a vertical machine whose ram moves up and down has gravity along -x, 180", ""],
  ["mu", "slide friction mu", 0, 0.01, "the ram's guide: a friction force mu |N| against the ram's velocity", ""],
  ["pin-mu", "mu", 0, 0.01, "Coulomb friction at every pin (revolute joint): a moment mu r |F| against "
    + "the pin's relative rotation; 0: none", "pin friction"],
  ["pin-r", "radius [m]", 0.01, 0.001, "the radius r of every pin, for its friction moment mu r |F|", "pin friction"],
  ["ratio", "ratio", "", 1, "a gearbox between motor and crank: motor speed / crank speed; empty: no drive", "drive"],
  ["eta", "efficiency", 0.9, 0.01, "the gearbox's efficiency (0 to 1): the motor gives T / (i eta) where it "
    + "drives, T eta / i where the crank drives it", "drive"],
];
const FIELD_TEXT = { "pin-mu": "pin friction mu", "pin-r": "pin radius", ratio: "drive ratio", eta: "drive efficiency" };
const WINDOWS = [["working", "working"], ["return", "return"], ["always", "always"]];
// The lists: each its add button, the heading over its rows and the button's help.
const ROWS = {
  forces: { add: "+ force", label: "forces: joint, N, direction, stroke", title: "a force at a joint: its magnitude "
    + "(N), its direction (against the joint's motion, along the slide's +x, or at a fixed angle from +x) and the "
    + "stroke it acts on" },
  torques: { add: "+ torque", label: "torques: body, N m (counter-clockwise), stroke",
    title: "a torque on a body (N m, counter-clockwise positive) over the strokes chosen" },
  points: { add: "+ point mass", label: "point masses: joint, kg",
    title: "a point mass (kg) at a joint, added to the body that carries it" },
};

function massPanel(div) {
  const p = div.dataset.prefix, fs = document.createElement("fieldset");
  fs.innerHTML = `<legend><label><input id="${p}-dyn" type="checkbox"> mass model and load</label></legend>`;
  for (const [k, text, value, step] of MASS_FIELDS) {
    const label = document.createElement("label"), input = document.createElement("input");
    Object.assign(input, { id: `${p}-${k}`, type: "number", value, step, className: "num" });
    label.append(`${text} `, input);
    fs.appendChild(label);
  }
  const more = document.createElement("details");
  more.id = `${p}-more`;
  more.className = "more-loads";
  more.innerHTML = `<summary id="${p}-more-sum">more loads</summary>`;
  for (const [kind, { add, title, label }] of Object.entries(ROWS)) {
    const list = document.createElement("div"), b = document.createElement("button");
    list.id = `${p}-list-${kind}`;
    list.className = "load-list";
    list.dataset.label = label;
    Object.assign(b, { type: "button", id: `${p}-add-${kind}`, textContent: add, title });
    b.addEventListener("click", () => { addLoadRow(p, kind); panelChanged(p); });
    more.append(list, b);
  }
  const singles = document.createElement("div"), groups = {};
  singles.className = "load-singles";
  for (const [k, text, value, step, help, group] of MORE_FIELDS) {
    const label = document.createElement("label"), input = document.createElement("input");
    Object.assign(input, { id: `${p}-${k}`, type: "number", value, step, className: "num" });
    if (k === "ratio") input.placeholder = "none";
    label.title = help;
    label.append(`${text} `, input);
    if (group && !groups[group]) {
      groups[group] = document.createElement("div");
      groups[group].className = "load-group";
      groups[group].innerHTML = `<span class="group"></span>`;
      groups[group].firstChild.textContent = group;
      singles.appendChild(groups[group]);
    }
    (group ? groups[group] : singles).appendChild(label);
  }
  more.appendChild(singles);
  fs.appendChild(more);
  const msg = document.createElement("p");
  Object.assign(msg, { id: `${p}-load-msg`, className: "msg bad load-msg" });
  msg.setAttribute("role", "status");
  fs.appendChild(msg);
  div.appendChild(fs);
  fs.addEventListener("change", () => summarise(p));
}

// The panel edited on the page that owns it: the Mechanism page analyses again, the Design page's rows go stale.
function panelChanged(p) {
  summarise(p);
  if (p === "m") analyze();
  else inputsChanged("design");
}

// Where loads may act on a panel's page: the Mechanism page's type ({joints, bodies, ram} of its design), or on the
// Design page every ticked type's (each joint or body with the ticked types that lack it). A force's joints
// (forceJoints) begin on the Design page with "ram": each type's output joint, whatever the type names it.
function loadTargets(p) {
  if (p === "m") {
    const t = state.types[state.type] || {}, a = state.analysis && state.analysis.type_key === state.type ? state.analysis : t;
    const joints = a.joints || [];
    const ram = a.ram || null;
    return { joints, forceJoints: joints, bodies: a.bodies || [], ram, ramJoint: ram, lack: { joints: {}, bodies: {} }, what: t.class };
  }
  const rows = (state.designTypes || []).filter((t) => $(`d-type-${t.name}`) && $(`d-type-${t.name}`).checked);
  const joints = [...new Set(rows.flatMap((t) => t.joints))].sort(), bodies = [...new Set(rows.flatMap((t) => t.bodies))];
  const lack = { joints: {}, bodies: {} };
  for (const [names, key] of [[joints, "joints"], [bodies, "bodies"]]) {
    for (const n of names) {
      const without = rows.filter((t) => !t[key].includes(n)).map((t) => t.name);
      if (without.length) lack[key][n] = without;
    }
  }
  const noRam = rows.filter((t) => !t.ram).map((t) => t.name);
  if (noRam.length) lack.joints.ram = noRam;
  const forceJoints = noRam.length < rows.length && !joints.includes("ram") ? ["ram", ...joints] : joints;
  const rams = rows.map((t) => t.ram).filter(Boolean);  // a new point mass's joint: the ram's of the most types
  const ramJoint = rams.sort((a, b) => rams.filter((r) => r === b).length - rams.filter((r) => r === a).length)[0] || null;
  const what = rows.length && rows.length <= 2 ? rows.map((t) => t.name).join(", ") : "the types ticked";
  return { joints, forceJoints, bodies, ram: forceJoints[0] === "ram" ? "ram" : ramJoint, ramJoint, lack, what };
}

// A select's options: the names given (each ticked type lacking it named: ``lack``, the names' map), and its value
// kept even where the page's type has no such name (said in the option: the server then refuses the load by name,
// never drops it).
function fillSelect(sel, names, value, t, lacks) {
  sel.innerHTML = "";
  for (const n of names) {
    const lack = lacks[n] || [];
    const o = new Option(lack.length > 1 ? `${n} (not in ${lack.length} types)` : lack.length ? `${n} (not ${lack[0]})` : n, n);
    if (lack.length) o.title = `not in ${lack.join(", ")}: untick them, or the design refuses the load`;
    else if (n === "ram" && !t.joints.includes("ram")) o.title = "the ram's joint of each type (C or D)";
    sel.add(o);
  }
  if (value !== undefined && value !== null && value !== "") {
    if (!names.includes(value)) sel.add(new Option(`${value} (not in ${t.what})`, value));
    sel.value = value;
  }
}

// The joints a row's select offers: a force's (with "ram" on the Design page) or a point mass's.
function jointsOf(t, kind) {
  return kind === "forces" ? t.forceJoints : t.joints;
}

function rowInput(cls, value, step, title) {
  const i = document.createElement("input");
  Object.assign(i, { type: "number", step, value, className: `num ${cls}`, title });
  return i;
}
function rowSelect(cls, options, value, title) {
  const s = document.createElement("select");
  s.className = cls;
  s.title = title;
  for (const [v, text] of options) s.add(new Option(text, v));
  if (value !== undefined) s.value = value;
  return s;
}

// One row of a list: a force {at, magnitude, direction: "against" | "slide" | angle in deg, window}, a torque
// {on, magnitude, window} or a point mass {at, mass}.
function addLoadRow(p, kind, v = {}) {
  const t = loadTargets(p), row = document.createElement("div"), list = $(`${p}-list-${kind}`);
  row.className = `load-row ${kind}`;
  const place = document.createElement("select");
  if (kind === "torques") {
    place.className = "on";
    place.title = "the body it acts on";
    fillSelect(place, t.bodies, v.on ?? (t.bodies.find((b) => b !== "crank" && b !== "ram" && b !== "yoke") || t.bodies[0]), t, t.lack.bodies);
  } else {
    place.className = "at";
    place.title = "the joint it acts at";
    fillSelect(place, jointsOf(t, kind), v.at ?? ((kind === "forces" ? t.ram : t.ramJoint) || t.joints[0]), t, t.lack.joints);
  }
  row.appendChild(place);
  if (kind === "forces") {
    const dir = typeof v.direction === "number" ? "angle" : v.direction || "against";
    const mag = rowInput("magnitude", v.magnitude ?? 500, 10, "N: a force's magnitude (its sign turns it)");
    const d = rowSelect("direction", [["against", "against motion"], ["slide", "along slide +x"],
      ["angle", "angle [deg]"]], dir, "its direction: against the joint's motion, along the slide's +x, or "
      + "at a fixed angle from +x");
    const ang = rowInput("angle", typeof v.direction === "number" ? v.direction : -90, 5, "deg from +x (-90: down)");
    ang.hidden = dir !== "angle";
    d.addEventListener("change", () => { ang.hidden = d.value !== "angle"; });
    const w = rowSelect("window", WINDOWS, v.window || "working", "the stroke it acts on");
    row.append(" ", mag, " N ", d, ang, " ", w);
  } else if (kind === "torques") {
    const mag = rowInput("magnitude", v.magnitude ?? 10, 1, "N m, counter-clockwise positive");
    const w = rowSelect("window", WINDOWS, v.window || "always", "the stroke it acts on");
    row.append(" ", mag, " N m ", w);
  } else {
    row.append(" ", rowInput("mass", v.mass ?? 2, 0.5, "kg at the joint"), " kg");
  }
  const x = document.createElement("button");
  Object.assign(x, { type: "button", textContent: "×", className: "remove", title: "remove this row" });
  x.setAttribute("aria-label", "remove");
  x.addEventListener("click", () => { row.remove(); panelChanged(p); });
  row.appendChild(x);
  list.appendChild(row);
  return row;
}

// The panel's selects refilled for the page's type(s), each value kept.
function refreshTargets(p) {
  const t = loadTargets(p);
  for (const sel of document.querySelectorAll(`#${p}-more select.at, #${p}-more select.on`)) {
    const on = sel.classList.contains("on"), kind = sel.closest(".load-row").classList.contains("forces") ? "forces" : "points";
    fillSelect(sel, on ? t.bodies : jointsOf(t, kind), sel.value, t, on ? t.lack.bodies : t.lack.joints);
  }
}

// The panel's state as plain data: {forces, torques, points} rows and each single input (as typed).
function panelState(p) {
  const rows = (kind) => [...$(`${p}-list-${kind}`).children];
  const val = (r, cls) => r.querySelector(`.${cls}`).value;
  return {
    forces: rows("forces").map((r) => ({ at: val(r, "at"), magnitude: val(r, "magnitude"),
      direction: val(r, "direction") === "angle" ? Number(val(r, "angle")) : val(r, "direction"), window: val(r, "window") })),
    torques: rows("torques").map((r) => ({ on: val(r, "on"), magnitude: val(r, "magnitude"), window: val(r, "window") })),
    points: rows("points").map((r) => ({ at: val(r, "at"), mass: val(r, "mass") })),
    ...Object.fromEntries(MORE_FIELDS.map(([k]) => [k, $(`${p}-${k}`).value])),
  };
}
// Set the panel to a state (panelState's form; what it lacks at its default).
function setPanel(p, st) {
  for (const kind of Object.keys(ROWS)) {
    $(`${p}-list-${kind}`).innerHTML = "";
    for (const v of st[kind] || []) addLoadRow(p, kind, v);
  }
  for (const [k, , value] of MORE_FIELDS) $(`${p}-${k}`).value = st[k] ?? value;
  summarise(p);
}
const isDefault = (p, k) => String($(`${p}-${k}`).value) === String(MORE_FIELDS.find((f) => f[0] === k)[2]);
// "more loads (2 forces, pin friction)": what the closed section holds.
function summarise(p) {
  const st = panelState(p), parts = [];
  const n = (k, one) => { if (st[k].length) parts.push(`${st[k].length} ${one}${st[k].length > 1 ? "s" : ""}`); };
  n("forces", "force"); n("torques", "torque"); n("points", "point mass");
  if (!isDefault(p, "gdir")) parts.push(`gravity at ${st.gdir}°`);
  if (Number(st.mu)) parts.push("slide friction");
  if (Number(st["pin-mu"])) parts.push("pin friction");
  if (st.ratio !== "") parts.push("drive");
  $(`${p}-more-sum`).textContent = parts.length ? `more loads (${parts.join(", ")})` : "more loads";
}

// A number as the library reads it: "" and text stay as given (the server says what is wrong with them).
const asNumber = (v) => (v === "" || v === null || v === undefined ? v : (Number.isFinite(Number(v)) ? Number(v) : v));
// A unit vector at deg degrees from +x, with the exact zeros of the axes (-90 deg: (0, -1), not (6e-17, -1)).
function unitAt(deg) {
  const r = deg * DEG, snap = (x) => (Math.abs(x) < 1e-12 ? 0 : x);
  return [snap(Math.cos(r)), snap(Math.sin(r))];
}

// The panel's masses and loads (Masses.to_dict and Loads.to_dict forms) and its drive (Drive.to_dict's), or null
// when not ticked. Everything shown is sent: the server applies it or says why it cannot.
function massModel(p) {
  if (!$(`${p}-dyn`).checked) return null;
  const v = (k) => asNumber($(`${p}-${k}`).value), st = panelState(p);
  const masses = { density: v("density"), ram: v("ram"), block: 0, bodies: {} };
  if (st.points.length) masses.points = Object.fromEntries(st.points.map((r) => [r.at, asNumber(r.mass)]));
  const g = v("gravity"), gdir = asNumber(st.gdir);
  let gravity = g;
  if (typeof gdir !== "number") gravity = [g, gdir];  // (the server says gravity's direction is not a number)
  else if (((gdir % 360) + 360) % 360 !== 270 && typeof g === "number") gravity = unitAt(gdir).map((c) => g * c);
  const loads = { cutting_force: v("force"), friction: asNumber(st.mu), gravity, follower_torque: 0 };
  if (st.forces.length) {
    loads.forces = st.forces.map((f) => ({ at: f.at, magnitude: asNumber(f.magnitude),
      direction: typeof f.direction === "number" ? unitAt(f.direction) : f.direction, window: f.window }));
  }
  if (st.torques.length) loads.torques = st.torques.map((t) => ({ on: t.on, magnitude: asNumber(t.magnitude), window: t.window }));
  const pinMu = asNumber(st["pin-mu"]);
  if (pinMu !== 0 && pinMu !== "") loads.pin_friction = { mu: pinMu, radius: asNumber(st["pin-r"]) };
  const out = { masses, loads };
  if (st.ratio !== "") out.drive = { ratio: asNumber(st.ratio), efficiency: asNumber(st.eta) };
  return out;
}
// The panel as a results note names its inputs: each field, and each list and single load where it has any.
function massInputs(p) {
  if (!$(`${p}-dyn`).checked) return {};
  const out = Object.fromEntries(MASS_FIELDS.map(([k, text]) => [text.split(" [")[0], $(`${p}-${k}`).value]));
  const st = panelState(p);
  const dirText = (d) => (typeof d === "number" ? `${d}°` : d);
  if (st.forces.length) out.forces = st.forces.map((f) => `${f.at} ${f.magnitude} N ${dirText(f.direction)} ${f.window}`).join("; ");
  if (st.torques.length) out.torques = st.torques.map((t) => `${t.on} ${t.magnitude} N m ${t.window}`).join("; ");
  if (st.points.length) out["point masses"] = st.points.map((r) => `${r.at} ${r.mass} kg`).join("; ");
  for (const [k, text] of MORE_FIELDS) if (!isDefault(p, k)) out[FIELD_TEXT[k] || text.split(" [")[0]] = st[k];
  return out;
}

// The Mechanism page's inputs as shown (lengths in the unit, angles in degrees).
function mechanismInputs() {
  const out = { type: state.type };
  const kinds = (state.types[state.type] || {}).kinds || {};
  for (const [k, v] of Object.entries(state.params)) out[k] = shownNumber(kinds[k] === "angle" ? v / DEG : v);
  out.theta2 = `${$("m-theta").value} deg`;
  out.omega2 = $("m-omega").value;
  return { ...out, ...massInputs("m") };
}

// The live request (frames 0: no animation, no exact extremes) and the settled one (the turn's frames and,
// with a mass model, the exact peaks), sent once the inputs rest.
function request(frames) {
  const body = { type: state.type, params: state.params, theta2: Number($("m-theta").value) * DEG,
    omega2: Number($("m-omega").value), units: state.units, frames, polygons: frames === 0, extremes: frames > 0 };
  const dyn = massModel("m");
  if (dyn) Object.assign(body, dyn);
  return body;
}

// What the server refused of the panel, beside it ("" clears it).
function panelSays(p, e) {
  say(`${p}-load-msg`, e && e.field === "loads" ? e.message : "", true);
}

// ---- the state in the URL: the page in its hash, the Mechanism page's design in its query -------------------
// ?type=drag-link-slider&r1=0.1&...&theta2=60&omega2=10&mass=1.57,20,1000,9.81: the parameters as the library
// takes them (lengths in the unit, angles in rad), theta2 in deg, omega2 in rad/s, the mass model (links kg/m,
// ram kg, cutting force N, gravity m/s²) only when it is ticked, and with it the panel's other loads:
// force=D,500,against,working (joint, N, against | slide | an angle in deg, working | return | always) and
// torque=lever,10,always (body, N m, window), one each; point=C,2 (joint, kg); gdir=-90, mu, pin=mu,radius and
// drive=ratio,efficiency where they differ from the defaults. A burst of edits (a slider dragged) is one
// entry of the browser's history: the first edit after a pause adds an entry, the next ones rewrite it.
const EDIT_PAUSE = 1000;  // ms
let lastEdit = -Infinity;
function stateQuery() {
  const q = new URLSearchParams();
  q.set("type", state.type);
  for (const [k, v] of Object.entries(state.params)) q.set(k, String(v));
  q.set("theta2", $("m-theta").value);
  q.set("omega2", $("m-omega").value);
  if ($("m-dyn").checked) {
    q.set("mass", MASS_FIELDS.map(([k]) => $(`m-${k}`).value).join(","));
    const st = panelState("m");
    for (const f of st.forces) q.append("force", [f.at, f.magnitude, f.direction, f.window].join(","));
    for (const t of st.torques) q.append("torque", [t.on, t.magnitude, t.window].join(","));
    for (const r of st.points) q.append("point", [r.at, r.mass].join(","));
    for (const k of ["gdir", "mu"]) if (!isDefault("m", k)) q.set(k, st[k]);
    if (!isDefault("m", "pin-mu") || !isDefault("m", "pin-r")) q.set("pin", [st["pin-mu"], st["pin-r"]].join(","));
    if (st.ratio !== "" || !isDefault("m", "eta")) q.set("drive", [st.ratio, st.eta].join(","));
  }
  return q;
}
function keepState() {
  const restoring = state.restoring;
  state.restoring = false;
  if (!state.type) return;
  const url = `${location.pathname}?${stateQuery()}${location.hash}`;
  if (url === location.pathname + location.search + location.hash) return;
  if (restoring) { history.replaceState(null, "", url); return; }
  const now = performance.now();
  if (now - lastEdit < EDIT_PAUSE) history.replaceState(null, "", url);
  else history.pushState(null, "", url);
  lastEdit = now;
}
// The design the URL names ({type, params, theta2, omega2, mass}), null if it names none; what it gets wrong is
// said beside the type and left at the type's default.
function fromURL() {
  const q = new URLSearchParams(location.search), type = q.get("type");
  if (!type) return null;
  const t = state.types[type], bad = [];
  if (!t) {
    say("m-url-msg", `The link names a type this app does not serve (${type}): the default design is shown.`, true);
    return null;
  }
  const params = { ...t.params };
  const number = (k) => {
    const v = q.get(k) === null || q.get(k) === "" ? NaN : Number(q.get(k));
    if (!Number.isFinite(v)) bad.push(k);
    return v;
  };
  for (const k of Object.keys(t.kinds)) if (q.has(k)) { const v = number(k); if (Number.isFinite(v)) params[k] = v; }
  const out = { type, params };
  for (const k of ["theta2", "omega2"]) if (q.has(k)) { const v = number(k); if (Number.isFinite(v)) out[k] = v; }
  if (q.has("mass")) {
    const m = q.get("mass").split(",").map(Number);
    if (m.length === MASS_FIELDS.length && m.every(Number.isFinite)) out.mass = m; else bad.push("mass");
    out.panel = panelFromQuery(q, bad);
  }
  if (bad.length) say("m-url-msg", `The link's ${bad.join(", ")} ${bad.length > 1 ? "do" : "does"} not read: left as before.`, true);
  return out;
}
// The panel's loads a link names (setPanel's form); each one that does not read is named in `bad` and left out.
function panelFromQuery(q, bad) {
  const nums = (text, n) => { const v = text.split(","); return v.length === n ? v : null; };
  const finite = (x) => x !== "" && Number.isFinite(Number(x));
  const windows = WINDOWS.map((w) => w[0]), out = { forces: [], torques: [], points: [] };
  for (const text of q.getAll("force")) {
    const v = nums(text, 4);
    const dirOk = v && (["against", "slide"].includes(v[2]) || finite(v[2]));
    if (v && v[0] && finite(v[1]) && dirOk && windows.includes(v[3])) {
      out.forces.push({ at: v[0], magnitude: Number(v[1]), direction: finite(v[2]) ? Number(v[2]) : v[2], window: v[3] });
    } else bad.push(`force ${text}`);
  }
  for (const text of q.getAll("torque")) {
    const v = nums(text, 3);
    if (v && v[0] && finite(v[1]) && windows.includes(v[2])) out.torques.push({ on: v[0], magnitude: Number(v[1]), window: v[2] });
    else bad.push(`torque ${text}`);
  }
  for (const text of q.getAll("point")) {
    const v = nums(text, 2);
    if (v && v[0] && finite(v[1])) out.points.push({ at: v[0], mass: Number(v[1]) }); else bad.push(`point ${text}`);
  }
  for (const k of ["gdir", "mu"]) if (q.has(k)) { if (finite(q.get(k))) out[k] = Number(q.get(k)); else bad.push(k); }
  const pair = (k, a, b, emptyFirst) => {
    if (!q.has(k)) return;
    const v = nums(q.get(k), 2);
    if (v && (finite(v[0]) || (emptyFirst && v[0] === "")) && finite(v[1])) { out[a] = v[0] === "" ? "" : Number(v[0]); out[b] = Number(v[1]); }
    else bad.push(k);
  };
  pair("pin", "pin-mu", "pin-r", false);
  pair("drive", "ratio", "eta", true);
  return out;
}

// The Mechanism page set to the design the URL names; false if it names none.
function applyURL() {
  const u = fromURL();
  if (!u) return false;
  if (u.theta2 !== undefined) { $("m-theta").value = u.theta2; $("m-theta-n").value = u.theta2; }
  if (u.omega2 !== undefined) $("m-omega").value = u.omega2;
  $("m-dyn").checked = !!u.mass;
  if (u.mass) MASS_FIELDS.forEach(([k], i) => { $(`m-${k}`).value = u.mass[i]; });
  state.type = u.type;  // (the panel's joints and bodies are this type's)
  setPanel("m", u.panel || {});
  $("m-more").open = $("m-more-sum").textContent !== "more loads";
  state.restoring = true;
  showParams(u.type, u.params);
  return true;
}

let framesTimer = null;
async function analyze() {
  keepState();
  if (state.inflight) { state.pending = true; return; }
  state.inflight = true;
  state.pending = false;
  stopAnimation();
  const asked = mechanismInputs(), type = state.type;
  try {
    const a = await call("POST", "/api/analyze", request(0));
    a.type_key = type;
    state.analysis = a;
    state.updates += 1;
    state.answers += 1;
    showAnalysis(a);
    fresh("mechanism", asked);
    say("m-play-msg", "");
    panelSays("m", null);
    const key = JSON.stringify([a.joints, a.bodies]);
    if (key !== state.targetsKey) { state.targetsKey = key; refreshTargets("m"); }
  } catch (e) {
    state.answers += 1;
    stale("mechanism", e.message);
    panelSays("m", e);
  } finally {
    state.inflight = false;
    if (state.pending) analyze();
  }
  clearTimeout(framesTimer);
  state.frames = null;
  framesTimer = setTimeout(loadFrames, 400);
}

async function loadFrames() {
  const asked = state.updates;
  try {
    const a = await call("POST", "/api/analyze", request(72));
    if (asked !== state.updates) return;  // the design moved on meanwhile
    state.frames = a.drawing;
    if (a.dynamics) {
      state.analysis.dynamics = a.dynamics;  // (a redraw shows the exact peaks too)
      showForces(a.dynamics, Number($("m-theta").value), a.cycle.working);
    }
  } catch (e) {
    state.frames = null;
    if (asked === state.updates && e.field === "loads") { stale("mechanism", e.message); panelSays("m", e); }
  }
}

function showAnalysis(a) {
  const u = a.units, d = a.dead_centres, g = a.gamma_min, th = Number($("m-theta").value);
  const out = a.output === "follower";
  table($("m-numbers"), ["quantity", "value"], [
    ["time ratio", fmt(a.time_ratio, 6)],
    [out ? "swing [deg]" : `stroke [${u}]`, out ? fmt(a.stroke / DEG, 6) : fmt(a.stroke, 6)],
    ["gamma_min [deg]", `${fmt(g.value_deg, 5)} at ${(g.theta2_deg % 360).toFixed(2)} deg (${g.joint})`],
    ["dead centres [deg]", `${d.theta_max_deg.toFixed(2)}, ${d.theta_min_deg.toFixed(2)}`],
    [`peak acceleration [${out ? "rad" : u}/s²]`, `${fmt(a.peak_accel.value, 5)} at ${a.peak_accel.theta2_deg.toFixed(2)} deg`],
    [out ? "theta4 [rad]" : `x [${u}]`, fmt(a.state.x, 6)],
    [out ? "omega4 [rad/s]" : `v [${u}/s]`, fmt(a.state.v, 6)],
    [out ? "alpha4 [rad/s²]" : `a [${u}/s²]`, fmt(a.state.a, 6)],
  ]);
  helpRows($("m-numbers"));
  $("m-numbers").dataset.timeRatio = a.time_ratio;
  $("m-numbers").dataset.stroke = a.stroke;
  $("m-numbers").dataset.gammaMin = g.value_deg;
  const working = a.cycle.working;
  drawMechanism($("m-svg"), a.drawing, a.drawing.shapes,
    `theta2 = ${th} deg, ${working[Math.round(th / 2) % working.length] ? "working" : "return"} stroke`);
  const ou = out ? "rad" : u;
  plotCycle($("m-plot"), a.cycle.theta2_deg, [
    { y: a.cycle.x, label: `x [${ou}]`, colour: "#1565c0" },
    { y: a.cycle.v, label: `v [${ou}/s]`, colour: "#2e7d32" },
    { y: a.cycle.a, label: `a [${ou}/s²]`, colour: "#c62828" },
  ], working, th);
  if (a.polygons) {
    drawPolygon($("m-vpoly"), a.polygons, "velocity", `${u}/s`);
    drawPolygon($("m-apoly"), a.polygons, "acceleration", `${u}/s²`);
  } else {
    for (const id of ["m-vpoly", "m-apoly"]) {
      clear($(id));
      if (a.polygons_reason) note($(id), `No polygons: ${a.polygons_reason}`);
    }
  }
  if (a.dynamics) {
    showForces(a.dynamics, th, working);
  } else {
    clear($("m-torque"));
    $("m-torque").classList.add("none");
    $("m-forces").innerHTML = "";
  }
}

function showForces(dy, th, working) {
  $("m-torque").classList.remove("none");
  plotCycle($("m-torque"), dy.torque.theta2_deg, [{ y: dy.torque.value, label: "torque [N m]", colour: "#6a1b9a" }],
    working, th);
  const rows = [
    ["crank torque [N m]", fmt(dy.at.torque, 5)],
    ...Object.entries(dy.at.joint_forces).map(([k, f]) => [`force at ${k} [N]`, fmt(Math.hypot(f[0], f[1]), 5)]),
  ];
  if (dy.peak_torque) {
    rows.push(["peak torque [N m]", `${fmt(dy.peak_torque.value, 5)} at ${dy.peak_torque.theta2_deg.toFixed(2)} deg`]);
    rows.push(["RMS torque [N m]", fmt(dy.rms_torque, 5)]);
    rows.push(["peak shaking force [N]", fmt(dy.peak_shaking_force, 5)]);
    if (dy.flywheel) rows.push(["flywheel for Cs 0.05 [kg m²]", fmt(dy.flywheel.inertia, 5)]);
    if (dy.efficiency) {
      const eff = (w) => (w.efficiency === null ? "- (the loads do no work)"
        : `${fmt(100 * w.efficiency, 4)} %` + (w.driven_by === "loads" ? " (the loads drive)" : ""));
      rows.push(["efficiency, working stroke", eff(dy.efficiency.working)]);
      rows.push(["efficiency, turn", eff(dy.efficiency.turn)]);
      rows.push(["friction work per turn [J]", fmt(dy.efficiency.turn.friction, 5)]);
    }
    if (dy.drive) {
      rows.push(["motor peak torque [N m]", `${fmt(dy.drive.peak_torque.value, 5)} at ${dy.drive.peak_torque.theta2_deg.toFixed(2)} deg`]);
      rows.push(["motor RMS torque [N m]", fmt(dy.drive.rms_torque, 5)]);
      rows.push(["motor speed [rad/s]", fmt(dy.drive.motor_speed, 5)]);
    }
  } else {
    rows.push(["peak torque [N m]", "(when the inputs rest)"]);
    const m = massModel("m");
    if (m && (m.loads.friction || m.loads.pin_friction)) rows.push(["efficiency", "(when the inputs rest)"]);
    if (m && m.drive) rows.push(["motor torque [N m]", "(when the inputs rest)"]);
  }
  table($("m-forces"), ["at theta2", "value"], rows);
  helpRows($("m-forces"));
}

let animation = null;
function stopAnimation() {
  if (animation) cancelAnimationFrame(animation);
  animation = null;
  state.playing = false;
  $("m-play").textContent = "Animate";
}
function play() {
  if (state.playing) return stopAnimation();
  const g = state.results.mechanism;
  if (g.stale) { say("m-play-msg", "no animation: the inputs give no design that turns (the reason is above the numbers)", true); return; }
  if (!state.frames || !state.frames.frames.length) {
    say("m-play-msg", "the turn's frames are still being computed: try again in a moment");
    return;
  }
  say("m-play-msg", "");
  state.playing = true;
  $("m-play").textContent = "Stop";
  const turn = state.frames, f = turn.frames, t0 = performance.now();
  const step = (now) => {
    if (!state.playing) return;
    const i = Math.floor((Math.max(0, now - t0) / 1000) * 24) % f.length;  // (a frame's time may precede t0)
    drawMechanism($("m-svg"), turn, f[i].shapes,
      `theta2 = ${f[i].theta2_deg.toFixed(0)} deg, ${f[i].working ? "working" : "return"} stroke`);
    if (state.playing) animation = requestAnimationFrame(step);
  };
  animation = requestAnimationFrame(step);
}

function openDesign(type, params) {
  location.hash = "#mechanism";
  route();
  lastEdit = performance.now();  // the design opened rewrites the page change's history entry
  showParams(type, params);
}

// Design: the task solved for every chosen type in a worker (a dynamic objective with the mass model and load,
// within a time budget), the rows ranked, each with its picture.
function objectiveOptions(select, entries, first = true) {
  for (const o of entries) {
    const text = o.objective + (o.size ? ` (${o.size})` : "") + ` — ${o.label}`
      + (o.drive ? ", mass model and drive" : o.dynamic ? ", mass model" : "");
    const opt = new Option(text, o.criterion);
    opt.dataset.dynamic = o.dynamic ? "1" : "";
    select.add(opt);
  }
  if (first) select.value = "gamma_min";
}

function chosenObjective(select) {
  if (select.value === "") return { objective: null };
  const o = state.objectives[select.value];
  return o.size ? { objective: o.objective, size: o.size } : { objective: o.objective };
}

// A dynamic objective needs the mass model and gets a time budget (30 s) unless one was typed; a kinematic one none.
// One that needs the drive also opens "more loads" and gives the drive a ratio of 10 if it has none.
function designObjectiveChanged() {
  const o = state.objectives[$("d-objective").value], b = $("d-budget");
  if (o.dynamic) $("d-dyn").checked = true;
  if (o.drive) {
    $("d-more").open = true;
    if ($("d-ratio").value === "") $("d-ratio").value = 10;
    summarise("d");
  }
  if (!b.dataset.typed) b.value = o.dynamic ? 30 : "";
}

function designTypes(types) {
  const box = $("d-types");
  for (const t of types) {
    const label = document.createElement("label"), box1 = document.createElement("input");
    Object.assign(box1, { type: "checkbox", checked: true, value: t.type, id: `d-type-${t.name}` });
    box1.dataset.name = t.name;
    label.title = `${t.class}` + (t.built_in ? "" : ` (${t.type}, served from its problem file)`);
    label.append(box1, ` ${t.name}`);
    box.appendChild(label);
  }
}

function designInput() {
  const input = { time_ratio: Number($("d-tr").value), stroke: Number($("d-stroke").value),
    ...chosenObjective($("d-objective")), omega2: Number($("d-omega").value),
    types: [...document.querySelectorAll("#d-types input:checked")].map((b) => b.value) };
  if ($("d-gamma").value !== "") input.conditions = { gamma_min: Number($("d-gamma").value) * DEG };
  if ($("d-budget").value !== "") input.time_limit = Number($("d-budget").value);
  const dyn = massModel("d");
  if (dyn) Object.assign(input, dyn);
  return input;
}

function designInputs() {
  const types = [...document.querySelectorAll("#d-types input:checked")].map((b) => b.dataset.name);
  return { TR: $("d-tr").value, stroke: $("d-stroke").value, objective: $("d-objective").value,
    "gamma_min at least": $("d-gamma").value || "none", omega2: $("d-omega").value,
    budget: $("d-budget").value ? `${$("d-budget").value} s` : "none", types: types.join(" ") || "none",
    ...massInputs("d") };
}

async function runDesign(ev) {
  ev.preventDefault();
  const asked = designInputs();
  $("d-run").disabled = true;
  try {
    const input = designInput();
    const budget = input.time_limit ? ` of a ${input.time_limit} s budget` : "";
    const c = await runJob("design", input, $("d-progress"), $("d-cancel"), budget);
    state.designRows = c.rows;
    showDesign(c, input);
    fresh("design", asked);
    panelSays("d", null);
  } catch (e) {
    $("d-progress").textContent = "";
    stale("design", e.message);
    panelSays("d", e);
  } finally {
    $("d-run").disabled = false;
  }
}

const unitText = (u) => String(u).replace("^2", "²");

// The Design page's rows: each type's criteria, its parameters, and its certificate; a row without a design
// says why in words (the solver's own account behind a toggle); a doubtful design says what is doubtful.
function showDesign(c, input) {
  const u = c.units, length = u.length, obj = state.objectives[$("d-objective").value];
  const at = `at omega2 = ${num(c.omega2)} rad/s`;
  const cols = [["gamma_min", "gamma_min [deg]", (v) => fmt(v / DEG, 4)], ["footprint", `footprint [${unitText(u.footprint)}]`],
    ["peak_accel", `peak accel ${at} [${unitText(u.peak_accel)}]`]];
  if (!cols.some((col) => col[0] === obj.criterion)) {
    const deg = obj.unit === "rad";
    const unit = deg ? "deg" : unitText(u[obj.criterion] || obj.unit.replace(/length/g, length));
    cols.push([obj.criterion, `${obj.label} [${unit}]`, deg ? (v) => fmt(v / DEG, 4) : fmt]);
  }
  if (input.masses && obj.criterion !== "peak_torque") cols.push(["peak_torque", `peak torque [${u.peak_torque}]`]);
  const head = ["#", "type", "status", ...cols.map((col) => col[1]), `parameters [${length}; angles in deg]`,
    "certificate or reason"];
  const help = { "gamma_min [deg]": HELP.gamma_min, [cols[1][1]]: HELP.footprint, [cols[2][1]]: HELP.peak_accel_design,
    status: HELP.status, [head[head.length - 2]]: HELP.parameters };
  table($("d-table"), head,
    c.rows.map((r, i) => {
      const bad = !r.mechanism, doubt = (r.warnings || []).length > 0;
      const status = block([["span", bad ? `no design (${r.status})` : doubt ? `${r.status}, doubtful` : r.status,
        bad ? "status-failed" : doubt ? "status-doubtful" : `status-${r.status}`]]);
      let why;
      if (bad) {
        why = block([["p", r.words || firstClause(r.reason), "reason"]]);
        why.appendChild(toggle("the solver's account", r.reason));
      } else {
        why = block([...(r.warnings || []).map((w) => ["p", w, "warning"]), ["p", r.claim || "", "claim"]]);
      }
      return [i + 1, r.type, status,
        ...cols.map(([k, , f]) => (r[k] === null || r[k] === undefined ? "-" : (f || fmt)(r[k]))),
        r.params && r.kinds ? paramText(r.params, r.kinds, length) : "-", why];
    }),
    (i) => c.rows[i].mechanism && openDesign(c.rows[i].mechanism, c.rows[i].params));
  $("d-table").querySelectorAll("th").forEach((th) => { if (help[th.textContent]) th.title = help[th.textContent]; });
  c.rows.forEach((r, i) => {
    const tr = $("d-table").rows[i + 1];
    if (!r.mechanism) tr.classList.add("failed");
    else if ((r.warnings || []).length) tr.classList.add("doubtful");
  });
  $("d-summary").textContent = designSummary(c);
  const ok = c.rows.filter((r) => r.mechanism);
  state.selected = ok.length ? { type: ok[0].mechanism, params: ok[0].params } : null;
  designPictures(ok, obj, u);
}

// One sentence over the rows: how many types have a design, and how many of those are doubtful.
function designSummary(c) {
  const ok = c.rows.filter((r) => r.mechanism), doubt = ok.filter((r) => (r.warnings || []).length);
  const task = `TR ${num(c.time_ratio)} and stroke ${num(c.stroke)} ${c.units.length}`;
  if (!ok.length) return `No type has a design for ${task}: each row says why.`;
  let out = `${ok.length} of ${c.rows.length} types ${ok.length === 1 ? "has" : "have"} a design for ${task}, best first.`;
  if (doubt.length === 1 && ok.length === 1) out += " It is doubtful: see the warnings in its row.";
  else if (doubt.length === ok.length) out += " Every one is doubtful: see the warnings in its row.";
  else if (doubt.length) out += ` ${doubt.length} of them doubtful: see the warnings in their rows.`;
  return out;
}

// The reason's first clause (before the solver's counts and ranges), for a reason the server did not word.
function firstClause(reason) {
  const r = String(reason || "no design");
  const cut = r.search(/ \(|; /);
  return cut > 0 ? r.slice(0, cut) : r;
}

// Every design drawn at one scale (the frame that holds the largest), each card its type and objective.
async function designPictures(rows, obj, u) {
  const box = $("d-pictures");
  box.innerHTML = "";
  const cards = rows.map((r) => {
    const card = document.createElement("div");
    card.className = "card" + ((r.warnings || []).length ? " doubtful" : "");
    card.innerHTML = `<strong></strong><br><span></span>`;
    card.querySelector("strong").textContent = r.type;
    const deg = obj.unit === "rad";
    card.querySelector("span").textContent = `${obj.label} ${fmt(deg ? r[obj.criterion] / DEG : r[obj.criterion], 4)}`
      + `${deg ? " deg" : " " + unitText(u[obj.criterion] || obj.unit)}, ${r.status}` + ((r.warnings || []).length ? ", doubtful" : "");
    const svg = el("svg", { role: "img" }, card);
    card.addEventListener("click", () => openDesign(r.mechanism, r.params));
    box.appendChild(card);
    return { svg, card, r };
  });
  const drawn = await Promise.all(cards.map(({ card, r }) =>
    call("POST", "/api/analyze", { type: r.mechanism, params: r.params, theta2: 0, omega2: 1, polygons: false })
      .then((a) => a.drawing).catch((e) => { card.title = e.message; return null; })));
  const views = drawn.filter(Boolean).map((d) => d.view);
  if (!views.length) return;
  const W = Math.max(...views.map((v) => v[2])), H = Math.max(...views.map((v) => v[3]));
  cards.forEach(({ svg }, i) => {
    const d = drawn[i];
    if (!d) return;
    const [x, y, w, h] = d.view;
    drawMechanism(svg, { ...d, view: [x + w / 2 - W / 2, y + h / 2 - H / 2, W, H] }, d.shapes);
  });
  const scale = document.createElement("p");
  scale.className = "legend";
  scale.id = "d-scale";
  scale.textContent = `Every design drawn at one scale: the largest, ${num(W, 3)} x ${num(H, 3)} ${u.length} over its `
    + "turn, fills its picture.";
  box.prepend(scale);
}

// Synthesis: one problem shown two ways, a form and its JSON (Problem.to_json's form), kept in step: an edit of
// either rewrites the other, and Solve sends the JSON. The form shows the type, each parameter fixed or free
// between bounds, each branch sign, the targets and the objective; what else the JSON sets (conditions, masses,
// ...) stays in it and is named under the form.
const FORM_KEYS = ["mechanism", "fixed", "free", "branches", "targets", "objective", "size"];

function synthesisForm(type, problem) {
  const t = state.types[type], box = $("s-params"), p = problem || {};
  const fixed = p.fixed || {}, free = p.free || {}, branches = p.branches || {};
  box.innerHTML = "";
  const head = document.createElement("div");
  head.className = "s-head";
  for (const [h, help] of [["", ""], [`value [${state.units}; deg]`, ""], ["free", HELP.free], ["low", ""], ["high", ""]]) {
    const sp = document.createElement("span");
    sp.textContent = h;
    if (help) sp.title = help;
    head.appendChild(sp);
  }
  box.appendChild(head);
  const tiny = tinyOf({ ...t.params, ...fixed }, t.kinds);
  for (const [k, kind] of Object.entries(t.kinds)) {
    const label = document.createElement("label");
    label.innerHTML = `<span class="name" title="${k}"></span>`;
    label.firstChild.textContent = k;
    label.className = "s-row";
    if (kind === "branch") {
      const sel = document.createElement("select");
      sel.id = `s-b-${k}`;
      sel.title = HELP.sigma;
      for (const [v, text] of [["1", "+1"], ["-1", "-1"], ["both", "both"]]) sel.add(new Option(text, v));
      const given = branches[k] || (k in fixed ? [fixed[k]] : [t.params[k] ?? 1]);
      sel.value = given.length > 1 ? "both" : String(Math.sign(given[0]) || 1);
      label.appendChild(sel);
      label.classList.add("s-branch");
      box.appendChild(label);
      continue;
    }
    const shownValue = (v) => (kind === "angle" ? num(v / DEG, 12) : num(v, 12, tiny));
    const v = k in fixed ? fixed[k] : t.params[k] ?? 0;
    const val = document.createElement("input");
    Object.assign(val, { type: "number", step: "any", value: shownValue(v), id: `s-v-${k}` });
    const isFree = document.createElement("input");
    Object.assign(isFree, { type: "checkbox", id: `s-f-${k}`, title: HELP.free, checked: k in free });
    const lo = document.createElement("input"), hi = document.createElement("input");
    const span = Math.max(Math.abs(v), 0.05);
    const plain = { length: [span / 5, 3 * span], angle: [-Math.PI, Math.PI] }[kind] || [-3 * span, 3 * span];
    const [l, h] = free[k] || plain.map((x) => +x.toPrecision(kind === "angle" ? 12 : 3));
    Object.assign(lo, { type: "number", step: "any", value: shownValue(l), id: `s-lo-${k}` });
    Object.assign(hi, { type: "number", step: "any", value: shownValue(h), id: `s-hi-${k}` });
    label.append(val, isFree, lo, hi);
    box.appendChild(label);
  }
}

// The form's problem merged into `base` (the JSON's other fields kept): angles in the form are degrees.
function formProblem(base = {}) {
  const type = $("s-type").value, t = state.types[type];
  const out = {};
  for (const [k, v] of Object.entries(base)) if (!FORM_KEYS.includes(k)) out[k] = v;
  const fixed = {}, free = {}, branches = {};
  for (const [k, kind] of Object.entries(t.kinds)) {
    const rad = (x) => (kind === "angle" ? Number(x) * DEG : Number(x));
    if (kind === "branch") {
      const v = $(`s-b-${k}`).value;
      branches[k] = v === "both" ? [1, -1] : [Number(v)];
    } else if ($(`s-f-${k}`).checked) free[k] = [rad($(`s-lo-${k}`).value), rad($(`s-hi-${k}`).value)];
    else if ($(`s-v-${k}`).value !== "") fixed[k] = rad($(`s-v-${k}`).value);
  }
  const o = chosenObjective($("s-objective"));
  const size = o.size || (base.objective === o.objective ? base.size : undefined);
  return { mechanism: type, fixed, free, branches, targets: { ...(base.targets || {}), time_ratio: Number($("s-tr").value),
    stroke: Number($("s-stroke").value) }, objective: o.objective, ...(size ? { size } : {}), ...out };
}

// The criterion (an option of the objective list) of a problem's objective and size; one the list lacks is added.
function objectiveOf(p) {
  if (p.objective === null || p.objective === undefined || p.objective === "none") return "";
  const all = Object.values(state.objectives).filter((o) => o.objective === p.objective);
  const o = all.find((x) => !x.size || x.size === (p.size || "footprint")) || all[0];
  if (!o) return null;
  if (![...$("s-objective").options].some((opt) => opt.value === o.criterion)) objectiveOptions($("s-objective"), [o], false);
  return o.criterion;
}

// The JSON's problem shown in the form; false (and why, under the form) where the form cannot show it.
function problemToForm(p) {
  const why = (text) => { $("s-form-note").textContent = text; $("s-form").classList.toggle("stale", !!text); return !text; };
  if (!p || typeof p !== "object" || Array.isArray(p)) return why("The form is not in step: the JSON is not a problem (an object).");
  if (!state.types[p.mechanism]) {
    return why(`The form is not in step: the app serves no type ${JSON.stringify(p.mechanism)} (it serves ${Object.keys(state.types).join(", ")}).`);
  }
  const objective = objectiveOf(p);
  if (objective === null) return why(`The form is not in step: no objective ${JSON.stringify(p.objective)}.`);
  $("s-type").value = p.mechanism;
  synthesisForm(p.mechanism, p);
  const tg = p.targets || {};
  $("s-tr").value = tg.time_ratio ?? "";
  $("s-stroke").value = tg.stroke ?? "";
  $("s-objective").value = objective;
  const plain = { omega2: 1, accel_over: "cycle", units: state.units };  // the defaults, not named
  const extra = Object.entries(p).filter(([k, v]) => !FORM_KEYS.includes(k) && k !== "name" && v !== null && v !== ""
    && plain[k] !== v && !(typeof v === "object" && !Object.keys(v).length))
    .map(([k, v]) => (typeof v === "object" ? `${k} (${Object.keys(v).join(", ")})` : `${k} ${v}`));
  const others = Object.keys(tg).filter((k) => !["time_ratio", "stroke"].includes(k));
  if (others.length) extra.unshift(`targets ${others.join(", ")}`);
  why("");
  $("s-extra").textContent = extra.length ? `Also in the JSON (edit it there): ${extra.join("; ")}.` : "";
  return true;
}

// The JSON box set to a problem, the form following it; the results marked as the old problem's.
function problemSet(problem) {
  $("s-json").value = JSON.stringify(problem, null, 2);
  problemToForm(problem);
  inputsChanged("solve");
  inputsChanged("front");
}

// The form edited: the JSON rewritten from it, its other fields kept.
function formChanged() {
  let base = {};
  try { base = JSON.parse($("s-json").value); } catch (e) { base = {}; }
  if (!base || typeof base !== "object" || Array.isArray(base)) base = {};
  $("s-json").value = JSON.stringify(formProblem(base), null, 2);
  $("s-form-note").textContent = "";
  $("s-form").classList.remove("stale");
  say("s-file-msg", "");  // (the problem is no longer the file's)
  inputsChanged("solve");
  inputsChanged("front");
}

// Another type chosen: its own parameters (its default design), the task and objective kept; the old type's
// conditions, branches and name dropped.
function typeChanged() {
  const type = $("s-type").value;
  synthesisForm(type);
  let base = {};
  try { base = JSON.parse($("s-json").value); } catch (e) { base = {}; }
  for (const k of ["conditions", "name"]) delete base[k];
  $("s-json").value = JSON.stringify(formProblem(base), null, 2);
  problemToForm(JSON.parse($("s-json").value));
  inputsChanged("solve");
  inputsChanged("front");
}

// A problem file picked: its text read by the server (qropt's .json and .toml; a .py is refused, with why).
async function loadProblemFile() {
  const f = $("s-file").files[0];
  if (!f) return;
  say("s-file-msg", `reading ${f.name}...`);
  try {
    const text = await f.text();
    $("s-file").value = "";  // the same file picked again loads again
    const p = await call("POST", "/api/problem/read", { name: f.name, text });
    problemSet(p);
    say("s-file-msg", `loaded ${f.name}: the form and the JSON show it`);
  } catch (e) {
    say("s-file-msg", `${f.name} not loaded: ${e.message}`, true);
  }
}

// The Synthesis page's inputs: the problem's JSON, flattened (targets.time_ratio = 1.5).
function synthesisInputs() {
  let p;
  try { p = JSON.parse($("s-json").value); } catch (e) { return { problem: "not JSON" }; }
  const out = {};
  const walk = (v, path) => {
    if (v && typeof v === "object" && !Array.isArray(v)) {
      for (const [k, x] of Object.entries(v)) walk(x, path ? `${path}.${k}` : k);
    } else out[path || "problem"] = Array.isArray(v) ? JSON.stringify(v) : shownNumber(v);
  };
  walk(p, "");
  return out;
}

function problemText() {
  try { return JSON.parse($("s-json").value); } catch (e) { throw new Error(`the problem is not JSON: ${e.message}`); }
}

// A criterion's value as shown: angles in degrees, the unit with the problem's length unit ("" if none).
function criterionShown(criterion, units) {
  const o = state.objectives[criterion];
  if (!o) return { label: criterion, unit: "", value: (v) => v };
  if (o.unit === "rad") return { label: o.label, unit: "deg", value: (v) => v / DEG };
  return { label: o.label, unit: unitText(o.unit.replace(/length/g, units || state.units)), value: (v) => v };
}

async function runSolve() {
  $("s-solve").disabled = true;
  const asked = synthesisInputs();
  try {
    const problem = problemText();
    const r = await runJob("solve", problem, $("s-progress"), $("s-cancel"));
    state.result = { problem, result: r };
    const div = $("s-result");
    div.innerHTML = "";
    const h = document.createElement("p");
    h.innerHTML = `<span class="status-${r.status}"></span> <span></span>`;
    h.children[0].textContent = r.status;
    h.children[0].title = HELP.status;
    h.children[1].textContent = r.message;
    div.appendChild(h);
    if (r.certificate) {
      const c = document.createElement("p");
      c.textContent = `certificate: ${r.certificate.global_claim || "local only"}`;
      c.id = "s-claim";
      div.appendChild(c);
    }
    const type = problem.mechanism, kinds = (state.types[type] || {}).kinds || {};
    const free = Object.keys(problem.free || {}), length = (r.units && r.units.length) || problem.units || state.units;
    const opt = r.local_optima && r.local_optima.length ? r.local_optima : (r.params && Object.keys(r.params).length ? [r] : []);
    const criterion = objectiveOf(problem) || "", crit = criterionShown(criterion, length);
    const objective = criterion && criterion !== "gamma_min";  // (gamma_min has its own column)
    const head = ["#", "status", ...free.map((k) => (kinds[k] === "angle" ? `${k} [deg]` : `${k} [${length}]`)),
      "gamma_min [deg]", ...(objective ? [`${crit.label}${crit.unit ? ` [${crit.unit}]` : ""}`] : [])];
    table($("s-optima"), head,
      opt.map((o, i) => [i + 1, o.status, ...free.map((k) => fmt(kinds[k] === "angle" ? o.params[k] / DEG : o.params[k], 6)),
        o.quantities && o.quantities.gamma_min !== undefined ? fmt(o.quantities.gamma_min / DEG, 5) : "-",
        ...(objective ? [o.objective === null || o.objective === undefined ? "-" : fmt(crit.value(o.objective), 6)] : [])]),
      (i) => openDesign(type, opt[i].params));
    $("s-optima").rows[0].cells[2 + free.length].title = HELP.gamma_min;
    const solved = r.success && r.params && Object.keys(r.params).length;
    state.selected = solved ? { type, params: r.params } : null;
    await drawSolved(solved ? type : null, r.params);
    fresh("solve", asked);
  } catch (e) {
    $("s-progress").textContent = "";
    stale("solve", e.message);
  } finally {
    $("s-solve").disabled = false;
  }
}

// The solved design drawn as the Mechanism page draws it (at theta2 = 0, its joints named); nothing without one.
async function drawSolved(type, params) {
  const svg = $("s-svg");
  clear(svg);
  svg.classList.toggle("none", !type);
  state.solved = null;
  if (!type) return;
  try {
    const a = await call("POST", "/api/analyze", { type, params, theta2: 0, omega2: 1, polygons: false });
    state.solved = [a.drawing, `the solved design at theta2 = 0 deg: TR ${fmt(a.time_ratio, 5)}, `
      + `stroke ${fmt(a.stroke, 5)} ${a.units}`];
    drawMechanism(svg, state.solved[0], state.solved[0].shapes, state.solved[1]);
  } catch (e) {
    note(svg, `No picture: ${e.message}`);
  }
}

async function runFront() {
  $("s-front").disabled = true;
  const asked = synthesisInputs();
  try {
    const problem = problemText();
    const f = await runJob("pareto", { problem, objectives: ["max_gamma_min", "min_peak_accel"], n: 7 },
      $("s-progress"), $("s-cancel"));
    $("s-front-svg").classList.remove("none");
    const [ca, cb] = f.criteria.map((c) => criterionShown(c, f.units));
    const xy = f.values.map((v) => [ca.value(v[0]), cb.value(v[1])]);
    const xlabel = `${ca.label} [${ca.unit}]`, ylabel = `${cb.label} [${cb.unit}]`;
    const spread = (k) => Math.max(...xy.map((p) => p[k])) - Math.min(...xy.map((p) => p[k]));
    const one = xy.length > 0 && spread(0) <= 1e-9 * Math.abs(xy[0][0]) + 1e-12 && spread(1) <= 1e-9 * Math.abs(xy[0][1]) + 1e-12;
    if (!xy.length || one) {
      clear($("s-front-svg"));
      const nfree = Object.keys(problem.free || {}).length, ntargets = Object.keys(problem.targets || {}).length;
      const why = !xy.length ? "The front has no point: no design meets the task."
        : `The front is one design (${xlabel} ${fmt(xy[0][0], 5)}, ${ylabel} ${fmt(xy[0][1], 5)}): with ${nfree} free `
          + `parameter${nfree === 1 ? "" : "s"} and ${ntargets} target${ntargets === 1 ? "" : "s"}, meeting the targets leaves no `
          + "freedom to trade one criterion against the other. Free another parameter (tick its box) for a front.";
      $("s-front-note").textContent = why;
      $("s-front-svg").classList.add("none");
    } else {
      $("s-front-note").textContent = `The front of ${xy.length} designs: a point opens its design on the Mechanism page.`;
      scatter($("s-front-svg"), xy, xlabel, ylabel, (i) => openDesign(problem.mechanism, f.points[i].params));
    }
    fresh("front", asked);
  } catch (e) {
    $("s-progress").textContent = "";
    stale("front", e.message);
  } finally {
    $("s-front").disabled = false;
  }
}

// Export from any page: the page's design as DXF, SVG or JSON, its HTML report; the page's result as JSON.
function current(page) {
  if (page === "mechanism") return { type: state.type, params: state.params, units: state.units };
  return state.selected && { ...state.selected, units: state.units };
}
function download(name, data, mime) {
  const a = document.createElement("a");
  a.href = URL.createObjectURL(new Blob([data], { type: mime }));
  a.download = name;
  document.body.appendChild(a);
  a.click();
  setTimeout(() => { URL.revokeObjectURL(a.href); a.remove(); }, 1000);
}
function exportBar(div) {
  const page = div.dataset.from, msg = document.createElement("span");
  msg.id = `export-${page}-msg`;
  msg.className = "msg";
  msg.setAttribute("role", "status");
  for (const fmt2 of ["dxf", "svg", "json", "report"]) {
    const b = document.createElement("button");
    b.type = "button";
    b.textContent = fmt2 === "report" ? "HTML report" : fmt2.toUpperCase();
    b.id = `export-${page}-${fmt2}`;
    b.addEventListener("click", async () => {
      const d = current(page);
      if (!d) { say(msg.id, "no design on this page yet: run it first", true); return; }
      if (page === "mechanism" && state.results.mechanism.stale) {
        say(msg.id, "no export: the inputs give no design that turns (the reason is above the numbers)", true);
        return;
      }
      const name = `${d.type.replace(/[^\w.-]+/g, "_")}.${fmt2 === "report" ? "html" : fmt2}`;
      try {
        const theta2 = Number($("m-theta").value) * DEG;
        if (fmt2 === "report") {
          say(msg.id, "the report is being written...");
          const r = await runJob("report", { ...d, theta2, omega2: Number($("m-omega").value) });
          download(name, r.html, "text/html");
        } else {
          const r = await fetch(`/api/export/${fmt2}`, { method: "POST", headers: { "Content-Type": "application/json" },
            body: JSON.stringify({ ...d, theta2 }) });
          if (!r.ok) throw new Error((await r.json()).error);
          download(name, await r.blob(), r.headers.get("Content-Type"));
        }
        say(msg.id, `downloaded ${name} (${d.type}${page === "mechanism" ? "" : ", the page's design"})`);
      } catch (e) { say(msg.id, `no ${fmt2 === "report" ? "report" : fmt2.toUpperCase()}: ${e.message}`, true); }
    });
    div.appendChild(b);
  }
  div.appendChild(msg);
}

async function start() {
  window.addEventListener("hashchange", route);
  route();
  document.querySelectorAll(".mass-model").forEach(massPanel);
  const [info, options] = await Promise.all([call("GET", "/api/types"), call("GET", "/api/design/options")]);
  for (const o of options.objectives) state.objectives[o.criterion] = o;
  objectiveOptions($("d-objective"), options.objectives);
  $("s-objective").add(new Option("none — any design meeting the task", ""));
  objectiveOptions($("s-objective"), options.objectives.filter((o) => !o.dynamic));  // (a file's dynamic one is added)
  designTypes(options.types);
  state.designTypes = options.types;
  $("d-types").addEventListener("change", () => refreshTargets("d"));
  $("d-budget").max = options.time_limit;
  $("d-objective").addEventListener("change", designObjectiveChanged);
  $("d-budget").addEventListener("input", () => { $("d-budget").dataset.typed = "1"; });
  resultGroup("mechanism", { panels: ["m-numbers", "m-svg", "m-plot", "m-vpoly", "m-apoly", "m-torque", "m-forces"],
    inputs: mechanismInputs, note: "m-error", live: true });
  resultGroup("design", { panels: ["d-table", "d-pictures"], inputs: designInputs, watch: ["design-form"] });
  resultGroup("solve", { panels: ["s-result", "s-svg", "s-optima"], inputs: synthesisInputs, watch: ["s-json"] });
  resultGroup("front", { panels: ["s-front-note", "s-front-svg"], inputs: synthesisInputs, watch: ["s-json"] });
  for (const t of info) {
    state.types[t.type] = t;
    $("m-type").add(new Option(`${t.class} (${t.type})`, t.type));
    $("s-type").add(new Option(`${t.class} (${t.type})`, t.type));
  }
  $("m-type").addEventListener("change", () => showParams($("m-type").value, state.types[$("m-type").value].params));
  $("m-theta").addEventListener("input", () => { $("m-theta-n").value = $("m-theta").value; analyze(); });
  $("m-theta-n").addEventListener("change", () => { $("m-theta").value = $("m-theta-n").value; analyze(); });
  $("m-omega").addEventListener("change", analyze);
  document.querySelector(".mass-model[data-prefix='m']").addEventListener("change", analyze);  // every input of the panel
  $("m-play").addEventListener("click", play);
  $("design-form").addEventListener("submit", runDesign);
  $("s-type").addEventListener("change", typeChanged);
  for (const ev of ["input", "change"]) {
    $("s-form").addEventListener(ev, (e) => { if (e.target.id !== "s-type") formChanged(); });
  }
  $("s-json").addEventListener("input", () => {
    say("s-file-msg", "");  // (the problem is no longer the file's)
    let p;
    try { p = JSON.parse($("s-json").value); } catch (e) {
      $("s-form-note").textContent = `The form is not in step: the JSON does not read (${e.message}).`;
      $("s-form").classList.add("stale");
      return;
    }
    problemToForm(p);
  });
  $("s-solve").addEventListener("click", runSolve);
  $("s-front").addEventListener("click", runFront);
  $("s-file").addEventListener("change", loadProblemFile);
  document.querySelectorAll(".export").forEach(exportBar);
  const first = info.find((t) => t.type === "drag-link-slider") || info[0];
  const files = await call("GET", "/api/problems");
  problemSet(files.length ? files[0].problem : {
    mechanism: "drag-link-slider", fixed: { r1: 0.1, r2: 0.225, r4: 0.275, r6: 0.3 },
    free: { r3: [0.05, 1.0], r5: [0.01, 0.5] }, targets: { time_ratio: 1.5, stroke: 0.3 },
    conditions: { grashof: "drag-link" }, objective: "max_gamma_min" });
  const open = files.length ? state.types[files[0].problem.mechanism] : null;
  if (!applyURL()) {
    state.restoring = true;
    showParams((open || first).type, (open || first).params);
  }
  window.addEventListener("popstate", () => { route(); applyURL(); });
  document.body.dataset.ready = "1";
}

start().catch((e) => { $("status").textContent = `the app could not start: ${e.message}`; });
