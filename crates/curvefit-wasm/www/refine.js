// Refine mode: Kersey's variational refinement (`curvefit refine`). The mode's state is the
// command line's problem object itself, edited in place, so what the page shares is exactly
// what it solved.

import { round, fmt, badIndex } from "./view.js";

// Tangent handles are drawn at q + TANGENT_SCALE · Df (Df in units of the curve's parameter).
const TANGENT_SCALE = 1 / 3;
const DEFAULT_RADIUS = 0.35;
const DEFAULT_WEIGHT = 4;
const DEFAULT_HALFPLANE = 0.15;

export function defaultProblem() {
  return {
    points: [[1, 1.2], [2.6, 4.4], [4.4, 1.6], [6, 4.6], [7.6, 1.4], [9, 3.8]],
    closed: false,
    k: 3,
    levels: 2,
    parametrization: "centripetal",
    constraint: { type: "balls", radii: [0, 0.5, 0.3, 0.6, 0.3, 0] },
    boundary: { type: "natural" },
  };
}

// What the page can draw and edit: 2-D points and the constraint kinds and ends of its controls.
export function check(p) {
  if (!Array.isArray(p.points) || p.points.some((q) => !Array.isArray(q) || q.length !== 2)) {
    return "the page draws plane curves: points must be [[x, y], …]";
  }
  return null;
}

export class RefineMode {
  constructor() {
    this.sub = "refine";
    this.load(defaultProblem());
  }

  load(p) {
    this.problem = p;
    this.cache = {};
  }

  get points() { return this.problem.points; }
  get kind() { return (this.problem.constraint && this.problem.constraint.type) || "interpolate"; }
  get clamped() { return !this.problem.closed && this.problem.boundary && this.problem.boundary.type === "clamped"; }

  handles() {
    const h = this.points.map((q, i) => ({ id: i, x: q[0], y: q[1] }));
    if (this.clamped) {
      const b = this.problem.boundary;
      const n = this.points.length;
      const a = this.points[0], z = this.points[n - 1];
      h.unshift({ id: "start", x: a[0] + TANGENT_SCALE * b.start[0], y: a[1] + TANGENT_SCALE * b.start[1] });
      h.unshift({ id: "end", x: z[0] + TANGENT_SCALE * b.end[0], y: z[1] + TANGENT_SCALE * b.end[1] });
    }
    return h;
  }

  move(id, x, y) {
    if (id === "start" || id === "end") {
      const q = id === "start" ? this.points[0] : this.points[this.points.length - 1];
      this.problem.boundary[id] = [round((x - q[0]) / TANGENT_SCALE), round((y - q[1]) / TANGENT_SCALE)];
      return;
    }
    const q = this.points[id];
    const dx = round(x) - q[0], dy = round(y) - q[1];
    q[0] = round(x);
    q[1] = round(y);
    // A half-plane travels with its point (its offset is relative to the point).
    const c = this.problem.constraint;
    if (c && c.type === "halfspaces" && c.sets[id]) {
      for (const h of c.sets[id]) h.offset = round(h.offset + h.normal[0] * dx + h.normal[1] * dy);
    }
  }

  // Per-point arrays follow the points (a new point gets the kind's default).
  perPoint(f) {
    const c = this.problem.constraint;
    if (c && c.radii) f(c.radii, () => DEFAULT_RADIUS);
    if (c && c.weights) f(c.weights, () => DEFAULT_WEIGHT);
    if (c && c.sets) f(c.sets, (q) => [halfplane(q, Math.PI / 2, DEFAULT_HALFPLANE)]);
    if (Array.isArray(this.problem.tangents)) f(this.problem.tangents, () => null);
  }

  add(x, y) {
    const q = [round(x), round(y)];
    this.points.push(q);
    this.perPoint((a, make) => a.push(make(q)));
    return this.points.length - 1;
  }

  remove(id) {
    if (typeof id !== "number") return;
    this.points.splice(id, 1);
    this.perPoint((a) => a.splice(id, 1));
  }

  wheel(id, dy, shift) {
    if (typeof id !== "number") return false;
    const c = this.problem.constraint;
    const f = Math.exp(-dy * 0.0015);
    if (c.type === "balls") {
      c.radii[id] = round(c.radii[id] > 0 ? c.radii[id] * f : dy < 0 ? 0.05 : 0);
      if (c.radii[id] < 0.01) c.radii[id] = 0;
    } else if (c.type === "smoothing") {
      c.weights[id] = round(Math.max(0.01, c.weights[id] * f));
    } else if (c.type === "halfspaces") {
      const q = this.points[id];
      const h = c.sets[id][0];
      if (!h) return false;
      let angle = Math.atan2(h.normal[1], h.normal[0]);
      let d = h.offset - (h.normal[0] * q[0] + h.normal[1] * q[1]);
      if (shift) angle += dy * 0.002;
      else d -= dy * 0.001;
      c.sets[id][0] = halfplane(q, angle, d);
    } else {
      return false;
    }
    return true;
  }

  setKind(kind) {
    const c = this.problem.constraint || { type: "interpolate" };
    this.cache[c.type] = c;
    const n = this.points.length;
    const old = this.cache[kind];
    if (kind === "balls") {
      this.problem.constraint = old && old.radii.length === n ? old : { type: "balls", radii: this.points.map(() => DEFAULT_RADIUS) };
    } else if (kind === "smoothing") {
      this.problem.constraint = old && old.weights.length === n ? old : { type: "smoothing", weights: this.points.map(() => DEFAULT_WEIGHT) };
    } else if (kind === "halfspaces") {
      this.problem.constraint = old && old.sets.length === n ? old : { type: "halfspaces", sets: this.points.map((q) => [halfplane(q, Math.PI / 2, DEFAULT_HALFPLANE)]) };
    } else {
      this.problem.constraint = { type: "interpolate" };
    }
  }

  setEnds(ends) {
    if (ends === "clamped") {
      const p = this.points, n = p.length;
      const tan = (a, b) => [round(b[0] - a[0]), round(b[1] - a[1])];
      this.problem.boundary = { type: "clamped", start: tan(p[0], p[1] || p[0]), end: tan(p[n - 2] || p[n - 1], p[n - 1]) };
    } else {
      this.problem.boundary = { type: "natural" };
    }
  }

  bindControls(form, changed) {
    this.form = form;
    form.addEventListener("input", () => {
      const f = form.elements;
      if (f.kind.value !== this.kind) this.setKind(f.kind.value);
      this.problem.closed = f.closed.checked;
      // End conditions belong to open curves (the library refuses them on closed ones).
      if (this.problem.closed) f.ends.value = "natural";
      const ends = this.problem.boundary && this.problem.boundary.type === "clamped" ? "clamped" : "natural";
      if (f.ends.value !== ends) this.setEnds(f.ends.value);
      f.ends.disabled = this.problem.closed;
      this.problem.k = Number(f.k.value);
      this.problem.levels = Number(f.levels.value);
      this.problem.parametrization = f.parametrization.value;
      changed();
    });
  }

  syncControls() {
    const f = this.form.elements;
    f.kind.value = this.kind;
    f.closed.checked = !!this.problem.closed;
    f.ends.value = this.problem.boundary && this.problem.boundary.type === "clamped" ? "clamped" : "natural";
    f.ends.disabled = !!this.problem.closed;
    f.k.value = this.problem.k ?? 3;
    f.levels.value = this.problem.levels ?? 0;
    const par = this.problem.parametrization ?? "centripetal";
    f.parametrization.value = typeof par === "string" ? par : "centripetal";
  }

  help() {
    return "Click to add a point, drag to move it, right-click to remove it; the wheel over a point resizes its ball (or weight, or half-plane offset; shift+wheel turns the half-plane).";
  }

  compute(solve) {
    const r = solve("refine", this.problem);
    return r.error ? { error: r.error } : { result: r.result };
  }

  draw(v, out) {
    const p = this.problem;
    const c = p.constraint || { type: "interpolate" };
    const r = out && out.result;
    // Constraint sets first, under the curve.
    this.points.forEach((q, i) => {
      const active = r && r.active && r.active[i];
      if (c.type === "balls") {
        v.circle(q, c.radii[i], { fill: active ? "rgba(31,111,235,0.16)" : "rgba(31,111,235,0.04)", stroke: active ? "#1f6feb" : "#9db8e8", width: active ? 1.5 : 1 });
      } else if (c.type === "smoothing") {
        v.circle(q, v.px(4 + 3 * Math.log1p(c.weights[i])), { stroke: "#9aa3af", dash: [3, 3] });
      } else if (c.type === "halfspaces") {
        for (const h of c.sets[i] || []) drawHalfplane(v, q, h, active);
      }
    });
    if (r) {
      v.polyline(r.points, { color: "#1d2330", width: 2.2, closed: !!p.closed });
      for (const j of r.data_vertex) v.dot(r.points[j], { r: 2.5, fill: "#1f6feb" });
    }
    const bad = badIndex(out, ["points", "constraint.radii", "constraint.weights", "constraint.sets", "tangents"]);
    this.points.forEach((q, i) => v.dot(q, { r: 5, fill: i === bad ? "#c62828" : "#fff", stroke: i === bad ? "#c62828" : "#1d2330" }));
    if (this.clamped) {
      for (const h of this.handles().filter((h) => typeof h.id === "string")) {
        const q = h.id === "start" ? this.points[0] : this.points[this.points.length - 1];
        v.polyline([q, [h.x, h.y]], { color: "#d97706", width: 1.5 });
        v.dot([h.x, h.y], { r: 4.5, fill: "#d97706" });
      }
    }
  }

  stats(out) {
    const r = out.result;
    const nActive = r.active.filter((a) => a).length;
    return [
      ["points", `${this.points.length} data, ${r.points.length} refined`],
      ["energy E", fmt(r.energy, 8)],
      ["KKT certificate", fmt(r.kkt_residual), r.kkt_residual <= 1e-9 ? "ok" : "bad", "kkt"],
      ["active", `${nActive} of ${r.active.length}`],
      ["iterations", `${r.iterations.knot_updates} knot updates, ${r.iterations.solves} solves`],
    ];
  }
}

function halfplane(q, angle, d) {
  const n = [round(Math.cos(angle)), round(Math.sin(angle))];
  return { normal: n, offset: round(n[0] * q[0] + n[1] * q[1] + d) };
}

// The line normal · x = offset near q, hatched on the infeasible side (normal · x > offset).
function drawHalfplane(v, q, h, active) {
  const [nx, ny] = h.normal;
  const nn = Math.hypot(nx, ny) || 1;
  const ux = nx / nn, uy = ny / nn;
  const d = (h.offset - (nx * q[0] + ny * q[1])) / nn;
  const foot = [q[0] + d * ux, q[1] + d * uy];
  const L = 0.7;
  const a = [foot[0] - L * uy, foot[1] + L * ux];
  const b = [foot[0] + L * uy, foot[1] - L * ux];
  const color = active ? "#7c3aed" : "#b8a6e6";
  v.polyline([a, b], { color, width: active ? 2 : 1.3 });
  for (let s = -0.6; s <= 0.61; s += 0.2) {
    const m = [foot[0] - s * uy, foot[1] + s * ux];
    v.polyline([m, [m[0] + 0.12 * ux + 0.08 * uy, m[1] + 0.12 * uy - 0.08 * ux]], { color, width: 1 });
  }
}
