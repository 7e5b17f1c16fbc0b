// qropt app: the pages over the JSON API (no external resources; SVG drawn here from the API's shapes).
"use strict";

const $ = (id) => document.getElementById(id);
const SVGNS = "http://www.w3.org/2000/svg";
const DEG = Math.PI / 180;
const COLOURS = { absolute: "#000", relative: "#1565c0", normal: "#2e7d32", tangential: "#ef6c00",
  sliding: "#6a1b9a", coriolis: "#c62828" };
const WORK = "#2e7d32", RET = "#e65100";

// The app's state; window.qropt lets a test read what the page shows and how fast it updates.
const state = {
  types: {}, type: null, params: {}, units: "m", analysis: null, frames: null, playing: false,
  inflight: false, pending: false, updates: 0, answers: 0, designRows: [], selected: null, result: null, job: null,
  objectives: {}, results: {},
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
  if (!r.ok) throw new Error((data && data.error) || `${r.status} ${r.statusText}`);
  return data === null ? text : data;
}

function say(text) { $("status").textContent = text || ""; }

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
function unitsPerPixel(svg, w, h, px) {
  const r = svg.getBoundingClientRect();
  const scale = Math.min((r.width || 400) / w, (r.height || 300) / h);
  return px / scale;
}
const fmt = (v, d = 4) => (v === null || v === undefined || Number.isNaN(v) ? "-" : Number(v).toPrecision(d));
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
  svg.setAttribute("viewBox", `${x - pad} ${-(y + h) - pad} ${w + 2 * pad} ${h + 2 * pad}`);
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
    const fs = unitsPerPixel(svg, w + 2 * pad, h + 2 * pad, 13);
    el("text", { x: x - pad + fs * 0.5, y: -(y + h) - pad + fs * 1.2, "font-size": fs, fill: "#333" }, svg, label);
    const js = unitsPerPixel(svg, w + 2 * pad, h + 2 * pad, 13);  // each joint's name, as the tables name it
    for (const s of shapes) {
      if (s.part !== "pivot" && s.part !== "joint") continue;
      const [jx, jy] = s.points[0];
      el("text", { x: jx + 0.5 * js, y: -jy - 0.5 * js, "font-size": js, fill: "#1a237e", stroke: "#fff",
        "stroke-width": 0.25 * js, "paint-order": "stroke", "font-weight": "bold", class: "joint-name" }, svg, s.name);
    }
  }
}

// Panels of curves over the crank angle in one svg: each its own y axis and label with units.
function plotCycle(svg, th, panels, working, mark) {
  clear(svg);
  const W = 640, H = 90 * panels.length + 40, L = 70, R = 15, T = 10;
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
  svg.setAttribute("viewBox", `${x0 - pad} ${-y1 - pad} ${x1 - x0 + 2 * pad} ${y1 - y0 + 2 * pad}`);
  const defs = el("defs", {}, svg);
  for (const [k, c] of Object.entries(COLOURS)) {
    const mk = el("marker", { id: `arrow-${quantity}-${k}`, viewBox: "0 0 10 10", refX: 10, refY: 5,
      markerWidth: 7, markerHeight: 7, orient: "auto-start-reverse" }, defs);
    el("path", { d: "M 0 0 L 10 5 L 0 10 z", fill: c }, mk);
  }
  const fs = unitsPerPixel(svg, x1 - x0 + 2 * pad, y1 - y0 + 2 * pad, 11);
  const g = el("g", { transform: "scale(1,-1)" }, svg);
  const drawn = new Set();
  for (const s of segs) {
    const key = s.from.concat(s.to).map((v) => Math.round(v / (1e-6 * span))).join(",");
    if (drawn.has(key) || Math.hypot(s.term.vector[0], s.term.vector[1]) < 1e-12 * span) continue;
    drawn.add(key);
    el("line", { x1: s.from[0], y1: s.from[1], x2: s.to[0], y2: s.to[1], stroke: COLOURS[s.term.kind],
      "stroke-width": 1.8, "vector-effect": "non-scaling-stroke",
      "marker-end": `url(#arrow-${quantity}-${s.term.kind})` }, g);
    if (Math.hypot(s.term.vector[0], s.term.vector[1]) < 0.15 * span) continue;  // short terms: no room to name
    el("text", { x: (s.from[0] + s.to[0]) / 2, y: -(s.from[1] + s.to[1]) / 2, "font-size": fs, fill: COLOURS[s.term.kind],
      transform: "scale(1,-1)" }, g, s.term.name);
  }
  for (const e of eqs) {
    el("line", { x1: 0, y1: 0, x2: e.exact[0], y2: e.exact[1], stroke: "#777", "stroke-dasharray": "4 3",
      "vector-effect": "non-scaling-stroke" }, g);
  }
  el("circle", { cx: 0, cy: 0, r: 0.012 * span, fill: "#000" }, g);
  el("text", { x: x0 - pad + fs * 0.4, y: -y1 - pad + fs * 1.3, "font-size": fs * 1.2 }, svg,
    `${quantity} polygon [${unit}]`);
}

// A scatter of two criteria whose points open their designs.
function scatter(svg, pts2, xlabel, ylabel, onPick) {
  clear(svg);
  const W = 640, H = 300, L = 70, B = 40, T = 10, R = 15;
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

function table(tbl, head, rows, onPick) {
  tbl.innerHTML = "";
  const tr = tbl.insertRow();
  for (const h of head) { const th = document.createElement("th"); th.textContent = h; tr.appendChild(th); }
  rows.forEach((r, i) => {
    const row = tbl.insertRow();
    for (const c of r) row.insertCell().textContent = c;
    if (onPick) { row.className = "pick"; row.addEventListener("click", () => onPick(i)); }
  });
}

// ---- pages ----------------------------------------------------------------------------------------------
function route() {
  const page = (location.hash || "#mechanism").slice(1);
  for (const p of ["design", "mechanism", "synthesis"]) {
    $(`page-${p}`).classList.toggle("shown", p === page);
    $(`tab-${p}`).classList.toggle("active", p === page);
  }
}

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
  const kinds = state.types[type].kinds;
  for (const [k, kind] of Object.entries(kinds)) {
    if (!(k in state.params)) continue;
    const label = document.createElement("label");
    label.innerHTML = `<span>${k} <span class="unit">${{ angle: "deg", branch: "" }[kind] ?? state.units}</span></span>`;
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
      Object.assign(n, { type: "number", step: "any", value: +shown.toPrecision(6), id: `n-${k}` });
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
// and Design pages), its inputs P-dyn (ticked: used), P-density, P-ram, P-force and P-gravity.
const MASS_FIELDS = [["density", "links [kg/m]", 1.57, 0.1], ["ram", "ram [kg]", 20, 1],
  ["force", "cutting force [N]", 1000, 100], ["gravity", "gravity [m/s²]", 9.81, 0.1]];
function massPanel(div) {
  const p = div.dataset.prefix, fs = document.createElement("fieldset");
  fs.innerHTML = `<legend><label><input id="${p}-dyn" type="checkbox"> mass model and load</label></legend>`;
  for (const [k, text, value, step] of MASS_FIELDS) {
    const label = document.createElement("label"), input = document.createElement("input");
    Object.assign(input, { id: `${p}-${k}`, type: "number", value, step, className: "num" });
    label.append(`${text} `, input);
    fs.appendChild(label);
  }
  div.appendChild(fs);
}
// The panel's masses and loads (Masses.to_dict and Loads.to_dict forms), or null when not ticked.
function massModel(p) {
  if (!$(`${p}-dyn`).checked) return null;
  const v = (k) => Number($(`${p}-${k}`).value);
  return { masses: { density: v("density"), ram: v("ram"), block: 0, bodies: {} },
    loads: { cutting_force: v("force"), friction: 0, gravity: v("gravity"), follower_torque: 0 } };
}
function massInputs(p) {
  if (!$(`${p}-dyn`).checked) return {};
  return Object.fromEntries(MASS_FIELDS.map(([k, text]) => [text.split(" [")[0], $(`${p}-${k}`).value]));
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

let framesTimer = null;
async function analyze() {
  if (state.inflight) { state.pending = true; return; }
  state.inflight = true;
  state.pending = false;
  stopAnimation();
  const asked = mechanismInputs();
  try {
    const a = await call("POST", "/api/analyze", request(0));
    state.analysis = a;
    state.updates += 1;
    state.answers += 1;
    showAnalysis(a);
    fresh("mechanism", asked);
  } catch (e) {
    state.answers += 1;
    stale("mechanism", e.message);
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
    if (a.dynamics) showForces(a.dynamics, Number($("m-theta").value), a.cycle.working);
  } catch (e) { state.frames = null; }
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
    $("m-forces").innerHTML = "";
  }
}

function showForces(dy, th, working) {
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
  } else {
    rows.push(["peak torque [N m]", "(when the inputs rest)"]);
  }
  table($("m-forces"), ["at theta2", "value"], rows);
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
  if (!state.frames || !state.frames.frames.length) { say("the turn is still being computed"); return; }
  state.playing = true;
  $("m-play").textContent = "Stop";
  const f = state.frames.frames, t0 = performance.now();
  const step = (now) => {
    const i = Math.floor((Math.max(0, now - t0) / 1000) * 24) % f.length;  // (a frame's time may precede t0)
    drawMechanism($("m-svg"), state.frames, f[i].shapes,
      `theta2 = ${f[i].theta2_deg.toFixed(0)} deg, ${f[i].working ? "working" : "return"} stroke`);
    if (state.playing) animation = requestAnimationFrame(step);
  };
  animation = requestAnimationFrame(step);
}

function openDesign(type, params) {
  location.hash = "#mechanism";
  route();
  showParams(type, params);
}

// Design: the task solved for every chosen type in a worker (a dynamic objective with the mass model and load,
// within a time budget), the rows ranked, each with its picture.
function objectiveOptions(select, entries) {
  for (const o of entries) {
    const text = o.objective + (o.size ? ` (${o.size})` : "") + ` — ${o.label}` + (o.dynamic ? ", mass model" : "");
    const opt = new Option(text, o.criterion);
    opt.dataset.dynamic = o.dynamic ? "1" : "";
    select.add(opt);
  }
  select.value = "gamma_min";
}

function chosenObjective(select) {
  const o = state.objectives[select.value];
  return o.size ? { objective: o.objective, size: o.size } : { objective: o.objective };
}

// A dynamic objective needs the mass model and gets a time budget (30 s) unless one was typed; a kinematic one none.
function designObjectiveChanged() {
  const o = state.objectives[$("d-objective").value], b = $("d-budget");
  if (o.dynamic) $("d-dyn").checked = true;
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
  } catch (e) {
    $("d-progress").textContent = "";
    stale("design", e.message);
  } finally {
    $("d-run").disabled = false;
  }
}

function showDesign(c, input) {
  const u = c.units, length = u.length, obj = state.objectives[$("d-objective").value];
  const cols = [["gamma_min", "gamma_min [deg]", (v) => fmt(v / DEG, 4)], ["footprint", `footprint [${length}²]`],
    ["peak_accel", `peak accel [${length}/s²]`]];
  if (!cols.some((col) => col[0] === obj.criterion)) cols.push([obj.criterion, `${obj.label} [${u[obj.criterion]}]`]);
  if (input.masses && obj.criterion !== "peak_torque") cols.push(["peak_torque", `peak torque [${u.peak_torque}]`]);
  table($("d-table"), ["#", "type", "status", ...cols.map((col) => col[1]), "certificate or reason"],
    c.rows.map((r, i) => [i + 1, r.type, r.status,
      ...cols.map(([k, , f]) => (r[k] === null || r[k] === undefined ? "-" : (f || fmt)(r[k]))),
      r.reason || r.claim || ""]),
    (i) => c.rows[i].mechanism && openDesign(c.rows[i].mechanism, c.rows[i].params));
  const ok = c.rows.filter((r) => r.mechanism);
  state.selected = ok.length ? { type: ok[0].mechanism, params: ok[0].params } : null;
  $("d-pictures").innerHTML = "";
  for (const r of ok) {
    const card = document.createElement("div");
    card.className = "card";
    card.innerHTML = `<strong></strong><br><span></span>`;
    card.querySelector("strong").textContent = r.type;
    card.querySelector("span").textContent = `${obj.label} ${fmt(obj.unit === "rad" ? r[obj.criterion] / DEG : r[obj.criterion], 4)}`
      + `${obj.unit === "rad" ? " deg" : " " + u[obj.criterion]}, ${r.status}`;
    const svg = el("svg", { role: "img" }, card);
    card.addEventListener("click", () => openDesign(r.mechanism, r.params));
    $("d-pictures").appendChild(card);
    call("POST", "/api/analyze", { type: r.mechanism, params: r.params, theta2: 0, omega2: 1, polygons: false })
      .then((a) => drawMechanism(svg, a.drawing, a.drawing.shapes)).catch((e) => { card.title = e.message; });
  }
}

// Synthesis: a problem as a form or JSON, solved in a worker: every local optimum and the certificate; a front.
function synthesisForm(type) {
  const t = state.types[type], box = $("s-params");
  box.innerHTML = "";
  const head = document.createElement("div");
  head.className = "s-head";
  for (const h of ["", `value [${state.units}]`, "free", "low", "high"]) {
    const sp = document.createElement("span");
    sp.textContent = h;
    head.appendChild(sp);
  }
  box.appendChild(head);
  for (const [k, kind] of Object.entries(t.kinds)) {
    if (kind === "branch" || !(k in t.params)) continue;
    const v = t.params[k], label = document.createElement("label");
    label.innerHTML = `<span>${k}</span>`;
    const val = document.createElement("input");
    Object.assign(val, { type: "number", step: "any", value: +v.toPrecision(5), id: `s-v-${k}` });
    const free = document.createElement("input");
    Object.assign(free, { type: "checkbox", id: `s-f-${k}`, title: "free, between the two bounds" });
    const lo = document.createElement("input"), hi = document.createElement("input");
    const span = Math.max(Math.abs(v), 0.05);
    Object.assign(lo, { type: "number", step: "any", value: kind === "length" ? +(span / 5).toPrecision(3) : -+(3 * span).toPrecision(3), id: `s-lo-${k}` });
    Object.assign(hi, { type: "number", step: "any", value: +(3 * span).toPrecision(3), id: `s-hi-${k}` });
    label.append(val, free, lo, hi);
    label.className = "s-row";
    box.appendChild(label);
  }
}

function formProblem() {
  const type = $("s-type").value, t = state.types[type];
  const fixed = {}, free = {};
  for (const [k, kind] of Object.entries(t.kinds)) {
    if (!(k in t.params)) continue;
    if (kind === "branch") { fixed[k] = t.params[k]; continue; }
    if ($(`s-f-${k}`).checked) free[k] = [Number($(`s-lo-${k}`).value), Number($(`s-hi-${k}`).value)];
    else fixed[k] = Number($(`s-v-${k}`).value);
  }
  return { mechanism: type, fixed, free, targets: { time_ratio: Number($("s-tr").value), stroke: Number($("s-stroke").value) },
    ...chosenObjective($("s-objective")) };
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
    h.children[1].textContent = r.message;
    div.appendChild(h);
    if (r.certificate) {
      const c = document.createElement("p");
      c.textContent = `certificate: ${r.certificate.global_claim || "local only"}`;
      c.id = "s-claim";
      div.appendChild(c);
    }
    const type = problem.mechanism;
    const free = Object.keys(problem.free || {});
    const opt = r.local_optima && r.local_optima.length ? r.local_optima : (r.params && Object.keys(r.params).length ? [r] : []);
    table($("s-optima"), ["#", "status", ...free, "gamma_min [deg]", "objective"],
      opt.map((o, i) => [i + 1, o.status, ...free.map((k) => fmt(o.params[k], 6)),
        o.quantities && o.quantities.gamma_min !== undefined ? fmt(o.quantities.gamma_min / DEG, 5) : "-", fmt(o.objective, 6)]),
      (i) => openDesign(type, opt[i].params));
    if (r.params && Object.keys(r.params).length) state.selected = { type, params: r.params };
    fresh("solve", asked);
  } catch (e) {
    $("s-progress").textContent = "";
    stale("solve", e.message);
  } finally {
    $("s-solve").disabled = false;
  }
}

async function runFront() {
  $("s-front").disabled = true;
  const asked = synthesisInputs();
  try {
    const problem = problemText();
    const f = await runJob("pareto", { problem, objectives: ["max_gamma_min", "min_peak_accel"], n: 7 },
      $("s-progress"), $("s-cancel"));
    const [a, b] = f.criteria;
    scatter($("s-front-svg"), f.values.map((v) => [a === "gamma_min" ? v[0] / DEG : v[0], v[1]]),
      a === "gamma_min" ? "gamma_min [deg]" : a, `${b} [${f.units}/s²]`,
      (i) => openDesign(problem.mechanism, f.points[i].params));
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
  const page = div.dataset.from;
  for (const fmt2 of ["dxf", "svg", "json", "report"]) {
    const b = document.createElement("button");
    b.type = "button";
    b.textContent = fmt2 === "report" ? "HTML report" : fmt2.toUpperCase();
    b.id = `export-${page}-${fmt2}`;
    b.addEventListener("click", async () => {
      const d = current(page);
      if (!d) { say("no design on this page yet"); return; }
      try {
        const theta2 = Number($("m-theta").value) * DEG;
        if (fmt2 === "report") {
          say("writing the report...");
          const r = await runJob("report", { ...d, theta2, omega2: Number($("m-omega").value) });
          download(`${d.type}.html`, r.html, "text/html");
          say("");
        } else {
          const r = await fetch(`/api/export/${fmt2}`, { method: "POST", headers: { "Content-Type": "application/json" },
            body: JSON.stringify({ ...d, theta2 }) });
          if (!r.ok) throw new Error((await r.json()).error);
          download(`${d.type}.${fmt2}`, await r.blob(), r.headers.get("Content-Type"));
        }
      } catch (e) { say(e.message); }
    });
    div.appendChild(b);
  }
}

async function start() {
  window.addEventListener("hashchange", route);
  route();
  document.querySelectorAll(".mass-model").forEach(massPanel);
  const [info, options] = await Promise.all([call("GET", "/api/types"), call("GET", "/api/design/options")]);
  for (const o of options.objectives) state.objectives[o.criterion] = o;
  objectiveOptions($("d-objective"), options.objectives);
  objectiveOptions($("s-objective"), options.objectives.filter((o) => !o.dynamic));  // the form has no masses
  designTypes(options.types);
  $("d-budget").max = options.time_limit;
  $("d-objective").addEventListener("change", designObjectiveChanged);
  $("d-budget").addEventListener("input", () => { $("d-budget").dataset.typed = "1"; });
  resultGroup("mechanism", { panels: ["m-numbers", "m-svg", "m-plot", "m-vpoly", "m-apoly", "m-torque", "m-forces"],
    inputs: mechanismInputs, note: "m-error", live: true });
  resultGroup("design", { panels: ["d-table", "d-pictures"], inputs: designInputs, watch: ["design-form"] });
  resultGroup("solve", { panels: ["s-result", "s-optima"], inputs: synthesisInputs, watch: ["s-json"] });
  resultGroup("front", { panels: ["s-front-svg"], inputs: synthesisInputs, watch: ["s-json"] });
  for (const t of info) {
    state.types[t.type] = t;
    $("m-type").add(new Option(`${t.class} (${t.type})`, t.type));
    $("s-type").add(new Option(`${t.class} (${t.type})`, t.type));
  }
  $("m-type").addEventListener("change", () => showParams($("m-type").value, state.types[$("m-type").value].params));
  $("m-theta").addEventListener("input", () => { $("m-theta-n").value = $("m-theta").value; analyze(); });
  $("m-theta-n").addEventListener("change", () => { $("m-theta").value = $("m-theta-n").value; analyze(); });
  for (const id of ["m-omega", "m-dyn", "m-density", "m-ram", "m-force", "m-gravity"]) $(id).addEventListener("change", analyze);
  $("m-play").addEventListener("click", play);
  $("design-form").addEventListener("submit", runDesign);
  $("s-type").addEventListener("change", () => synthesisForm($("s-type").value));
  const problemSet = (text) => { $("s-json").value = text; inputsChanged("solve"); inputsChanged("front"); };
  $("s-to-json").addEventListener("click", () => problemSet(JSON.stringify(formProblem(), null, 2)));
  $("s-solve").addEventListener("click", runSolve);
  $("s-front").addEventListener("click", runFront);
  $("s-file").addEventListener("change", async () => {
    const f = $("s-file").files[0];
    if (f) problemSet(await f.text());
  });
  document.querySelectorAll(".export").forEach(exportBar);
  const first = info.find((t) => t.type === "drag-link-slider") || info[0];
  $("s-type").value = first.type;
  synthesisForm(first.type);
  const files = await call("GET", "/api/problems");
  $("s-json").value = JSON.stringify(files.length ? files[0].problem : {
    mechanism: "drag-link-slider", fixed: { r1: 0.1, r2: 0.225, r4: 0.275, r6: 0.3 },
    free: { r3: [0.05, 1.0], r5: [0.01, 0.5] }, targets: { time_ratio: 1.5, stroke: 0.3 },
    conditions: { grashof: "drag-link" }, objective: "max_gamma_min" }, null, 2);
  const open = files.length ? state.types[files[0].problem.mechanism] : null;
  showParams((open || first).type, (open || first).params);
  document.body.dataset.ready = "1";
}

start().catch((e) => say(e.message));
