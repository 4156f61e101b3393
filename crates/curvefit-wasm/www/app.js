// The playground: the library (curvefit::spec in WebAssembly) solves the command line's JSON
// problem on every change; the page draws the problem and the answer. A change schedules one
// frame (solve + redraw) on the next animation frame, so a fast drag never queues solves.

import init, { solve as wasmSolve, last_panic, version } from "./pkg/curvefit_wasm.js";
import { View } from "./view.js";
import * as refine from "./refine.js";
import * as strip from "./strip.js";
import * as scheme from "./scheme.js";

const MODULES = { refine, strip, scheme };
const HIT_RADIUS = 10; // CSS pixels

const $ = (id) => document.getElementById(id);

// The last replies by problem text: a frame whose problem did not change (the drag's last
// pointerup, a resize, a mode switched back, strip's natural spline while a bound moves) reuses
// the reply instead of solving again. Replies are only read, never changed, by the modes.
const REPLIES = new Map();
const REPLIES_KEPT = 8;

// Where a frame's solving time goes (ms, summed over the frame's solves): the problem to JSON,
// the module (parse, solve, write the reply), the reply from JSON.
const spent = { stringify: 0, wasm: 0, parse: 0, solves: 0, reused: 0 };

// The library's reply for `problem`: {result} or {error: {field, index, message, text}}. A trap
// (a bug: the libraries never panic on input) is reported with the panic's message.
function solve(sub, problem) {
  const t0 = performance.now();
  const text = JSON.stringify(problem);
  const key = `${sub} ${text}`;
  const t1 = performance.now();
  spent.stringify += t1 - t0;
  const kept = REPLIES.get(key);
  if (kept) {
    spent.reused++;
    return kept;
  }
  let reply;
  try {
    const answer = wasmSolve(sub, text);
    const t2 = performance.now();
    reply = JSON.parse(answer);
    spent.wasm += t2 - t1;
    spent.parse += performance.now() - t2;
    spent.solves++;
  } catch (e) {
    const msg = last_panic() || String(e);
    // Not kept: after a trap the module's state is not to be trusted, so the next frame solves.
    return { error: { field: "", index: null, message: `internal error: ${msg}`, text: `internal error: ${msg}` } };
  }
  if (REPLIES.size >= REPLIES_KEPT) REPLIES.delete(REPLIES.keys().next().value);
  REPLIES.set(key, reply);
  return reply;
}

const state = {
  modes: { refine: new refine.RefineMode(), strip: new strip.StripMode(), scheme: new scheme.SchemeMode() },
  mode: "refine",
  out: null,
  drag: null,
  pending: false,
  frames: [],
  solves: 0,
};

function mode() { return state.modes[state.mode]; }

function schedule() {
  if (state.pending) return;
  state.pending = true;
  requestAnimationFrame(frame);
}

// One frame: solve, then redraw; both timed for the test (performance.now(), synchronous work),
// the solving split as in `spent`.
function frame() {
  state.pending = false;
  for (const k of Object.keys(spent)) spent[k] = 0;
  const t0 = performance.now();
  state.out = mode().compute(solve);
  const t1 = performance.now();
  draw();
  const t2 = performance.now();
  state.solves += spent.solves;
  state.frames.push({ solve: t1 - t0, draw: t2 - t1, total: t2 - t0, ...spent, dragging: !!state.drag });
  if (state.frames.length > 2000) state.frames.splice(0, 1000);
  showStats();
  if (!state.drag) showProblem();
}

function draw() {
  view.resize();
  view.clear();
  mode().draw(view, state.out);
}

function showStats() {
  const out = state.out;
  const err = $("error");
  if (out.error) {
    err.hidden = false;
    err.textContent = out.error.text;
    err.dataset.field = out.error.field;
  } else {
    err.hidden = true;
    err.textContent = "";
  }
  const dl = $("stats");
  dl.textContent = "";
  const rows = out.result ? mode().stats(out) : [];
  const last = state.frames[state.frames.length - 1];
  const ms = (x) => x.toFixed(1);
  rows.push(["frame", last.solves > 0
    ? `${ms(last.total)} ms (solve ${ms(last.solve)}: wasm ${ms(last.wasm)}, JSON ${ms(last.stringify + last.parse)}; draw ${ms(last.draw)})`
    : `${ms(last.total)} ms (problem unchanged: reply reused; draw ${ms(last.draw)})`, null, "frame"]);
  for (const [k, v, cls, id] of rows) {
    const dt = document.createElement("dt");
    dt.textContent = k;
    const dd = document.createElement("dd");
    dd.textContent = v;
    if (cls) dd.className = cls;
    if (id) dd.id = id;
    dl.append(dt, dd);
  }
}

// The problem as readable JSON: one line per point (`[x, y]`), nested objects indented.
function pretty(p) {
  return JSON.stringify(p, null, 1).replace(/\[\s*(-?[\d.e+-]+(?:,\s*-?[\d.e+-]+)*)\s*\]/g, (_, xs) => `[${xs.split(/,\s*/).join(", ")}]`);
}

// The share box, the command line and the URL show the current problem.
function showProblem() {
  const text = JSON.stringify(mode().problem);
  if (document.activeElement !== $("json")) $("json").value = pretty(mode().problem);
  $("command").textContent = `curvefit ${mode().sub} ${mode().sub}.json`;
  history.replaceState(null, "", `#${state.mode}=${encodeURIComponent(text)}`);
}

function setMode(name) {
  state.mode = name;
  for (const b of document.querySelectorAll("#modes button")) b.classList.toggle("active", b.dataset.mode === name);
  for (const m of Object.keys(MODULES)) $(`controls-${m}`).hidden = m !== name;
  mode().syncControls();
  $("help").textContent = mode().help();
  schedule();
}

// Loads a problem (the command line's JSON) into a mode; the library checks it when solving,
// the page only that it can draw it.
function load(name, problem) {
  if (!MODULES[name]) throw new Error(`unknown mode ${name}`);
  if (typeof problem !== "object" || problem === null || Array.isArray(problem)) throw new Error("the problem must be a JSON object");
  const why = MODULES[name].check(problem);
  if (why) throw new Error(why);
  state.modes[name].load(problem);
  setMode(name);
}

// A pasted problem's subcommand, from its fields.
function guessMode(p) {
  if (p && "t" in p) return "strip";
  if (p && "arity" in p) return "scheme";
  return "refine";
}

function hit(clientX, clientY) {
  let best = null, bestD = HIT_RADIUS;
  const [x, y] = [clientX - view.rect.left, clientY - view.rect.top];
  for (const h of mode().handles()) {
    const d = Math.hypot(view.sx(h.x) - x, view.sy(h.y) - y);
    if (d <= bestD) { best = h; bestD = d; }
  }
  return best;
}

let view;

async function main() {
  await init();
  view = new View($("canvas"));
  $("version").textContent = `curvefit ${version()} · WebAssembly`;
  for (const [name, m] of Object.entries(state.modes)) m.bindControls($(`controls-${name}`), schedule);
  for (const b of document.querySelectorAll("#modes button")) b.addEventListener("click", () => setMode(b.dataset.mode));

  const canvas = $("canvas");
  canvas.addEventListener("pointerdown", (e) => {
    if (e.button !== 0) return;
    view.resize();
    const h = hit(e.clientX, e.clientY);
    if (h) {
      state.drag = { id: h.id };
    } else {
      const [x, y] = view.world(e.clientX, e.clientY);
      state.drag = { id: mode().add(x, y) };
    }
    canvas.setPointerCapture(e.pointerId);
    schedule();
  });
  canvas.addEventListener("pointermove", (e) => {
    if (!state.drag) return;
    const [x, y] = view.world(e.clientX, e.clientY);
    mode().move(state.drag.id, x, y);
    schedule();
  });
  const end = () => { if (state.drag) { state.drag = null; schedule(); } };
  canvas.addEventListener("pointerup", end);
  canvas.addEventListener("pointercancel", end);
  canvas.addEventListener("contextmenu", (e) => {
    e.preventDefault();
    view.resize();
    const h = hit(e.clientX, e.clientY);
    if (h) { mode().remove(h.id); schedule(); }
  });
  canvas.addEventListener("wheel", (e) => {
    view.resize();
    const h = hit(e.clientX, e.clientY);
    if (h && mode().wheel(h.id, e.deltaY, e.shiftKey)) {
      e.preventDefault();
      schedule();
    }
  }, { passive: false });
  window.addEventListener("resize", schedule);

  $("load").addEventListener("click", () => {
    try {
      const p = JSON.parse($("json").value);
      load(guessMode(p), p);
    } catch (e) {
      state.out = { error: { field: "", index: null, message: e.message, text: `pasted JSON: ${e.message}` } };
      showStats();
    }
  });
  $("download").addEventListener("click", () => {
    const blob = new Blob([pretty(mode().problem) + "\n"], { type: "application/json" });
    const a = document.createElement("a");
    a.href = URL.createObjectURL(blob);
    a.download = `${mode().sub}.json`;
    a.click();
    URL.revokeObjectURL(a.href);
  });
  $("link").addEventListener("click", () => navigator.clipboard && navigator.clipboard.writeText(location.href));
  $("reset").addEventListener("click", () => load(state.mode, MODULES[state.mode].defaultProblem()));

  // A shared link: #MODE=<the problem's JSON, URI-encoded>.
  const m = /^#(refine|strip|scheme)=(.*)$/.exec(location.hash);
  let start = "refine";
  if (m) {
    try {
      load(m[1], JSON.parse(decodeURIComponent(m[2])));
      start = m[1];
    } catch (e) {
      console.warn(`the link's problem could not be read: ${e.message}`);
    }
  }
  setMode(start);
}

// What the browser test reads and drives (the same calls the controls make).
window.playground = {
  state,
  solve,
  load,
  setMode,
  problem: () => JSON.parse(JSON.stringify(mode().problem)),
  // Client (mouse) coordinates of a world point, for driving the page with the real mouse.
  toClient: (x, y) => { view.resize(); return [view.rect.left + view.sx(x), view.rect.top + view.sy(y)]; },
  ready: main(),
};
