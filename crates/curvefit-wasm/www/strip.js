// Strip mode: best interpolation in a strip (`curvefit strip`): the C² cubic spline through
// (t_i, y_i) of least ∫f''² between a lower and an upper polyline. The state is the command
// line's problem object; the natural spline (no bounds) is solved alongside for comparison.

import { round, fmt, badIndex, W } from "./view.js";

const KIND_COLOR = {
  touch_lower: "#d97706",
  touch_upper: "#7c3aed",
  subarc_start_lower: "#059669",
  subarc_end_lower: "#059669",
  subarc_start_upper: "#db2777",
  subarc_end_upper: "#db2777",
};

export function defaultProblem() {
  const t = [0.6, 1.6, 2.4, 3.5, 4.4, 5.2, 6.3, 7.2, 8.2, 9.3];
  const y = [2.2, 3.4, 3.1, 1.6, 1.9, 3.5, 3.9, 2.0, 2.6, 3.3];
  return {
    t,
    y,
    lower: { polyline: [[0, 1.8], [2.5, 2.7], [3.6, 1.35], [5, 1.5], [7.4, 1.9], [10, 2.2]] },
    upper: { polyline: [[0, 3.0], [1.6, 3.5], [2.4, 3.2], [4.0, 2.3], [5.6, 4.0], [7.5, 4.3], [10, 3.6]] },
  };
}

export function check(p) {
  if (!Array.isArray(p.t) || !Array.isArray(p.y)) return "a strip problem has t and y";
  for (const b of [p.lower, p.upper]) {
    if (b && !b.polyline) return "the page draws polyline bounds ({\"polyline\": [[t, v], …]})";
  }
  return null;
}

export class StripMode {
  constructor() {
    this.sub = "strip";
    this.show = { natural: true, lower: true, upper: true };
    this.load(defaultProblem());
  }

  load(p) {
    this.problem = p;
    this.saved = { lower: p.lower || defaultProblem().lower, upper: p.upper || defaultProblem().upper };
    this.show.lower = !!p.lower;
    this.show.upper = !!p.upper;
  }

  handles() {
    const h = this.problem.t.map((t, i) => ({ id: `s${i}`, x: t, y: this.problem.y[i] }));
    for (const side of ["lower", "upper"]) {
      const b = this.problem[side];
      if (b) b.polyline.forEach((q, i) => h.push({ id: `${side}${i}`, x: q[0], y: q[1] }));
    }
    return h;
  }

  move(id, x, y) {
    if (id[0] === "s") {
      const i = Number(id.slice(1));
      this.problem.t[i] = round(x);
      this.problem.y[i] = round(y);
    } else {
      const side = id.startsWith("lower") ? "lower" : "upper";
      const q = this.problem[side].polyline[Number(id.slice(side.length))];
      q[0] = round(x);
      q[1] = round(y);
    }
  }

  // A click adds a data point at its place among the sites.
  add(x, y) {
    const { t, y: ys } = this.problem;
    let i = 0;
    while (i < t.length && t[i] < x) i++;
    t.splice(i, 0, round(x));
    ys.splice(i, 0, round(y));
    return `s${i}`;
  }

  remove(id) {
    if (id[0] === "s" && this.problem.t.length > 2) {
      const i = Number(id.slice(1));
      this.problem.t.splice(i, 1);
      this.problem.y.splice(i, 1);
    }
  }

  wheel() { return false; }

  bindControls(form, changed) {
    this.form = form;
    form.addEventListener("input", () => {
      const f = form.elements;
      this.show.natural = f.natural.checked;
      for (const side of ["lower", "upper"]) {
        if (f[side].checked && !this.problem[side]) this.problem[side] = this.saved[side];
        if (!f[side].checked && this.problem[side]) {
          this.saved[side] = this.problem[side];
          delete this.problem[side];
        }
      }
      changed();
    });
  }

  syncControls() {
    const f = this.form.elements;
    f.natural.checked = this.show.natural;
    f.lower.checked = !!this.problem.lower;
    f.upper.checked = !!this.problem.upper;
  }

  help() {
    return "Drag the data points and the vertices of the lower and upper polylines; click to add a data point, right-click to remove one.";
  }

  compute(solve) {
    const out = {};
    const r = solve("strip", this.problem);
    if (r.error) out.error = r.error;
    else out.result = r.result;
    if (this.show.natural) {
      const n = solve("strip", { t: this.problem.t, y: this.problem.y });
      if (n.result) out.natural = n.result;
    }
    return out;
  }

  draw(v, out) {
    const p = this.problem;
    // The strip: the band between the polylines, then its edges.
    for (const side of ["lower", "upper"]) {
      const b = p[side];
      if (!b) continue;
      const pts = b.polyline;
      const edge = side === "lower" ? 0 : 6;
      const c = v.ctx;
      c.beginPath();
      c.moveTo(v.sx(pts[0][0]), v.sy(edge));
      for (const q of pts) c.lineTo(v.sx(q[0]), v.sy(q[1]));
      c.lineTo(v.sx(pts[pts.length - 1][0]), v.sy(edge));
      c.closePath();
      c.fillStyle = "rgba(107,114,128,0.10)";
      c.fill();
      v.polyline(pts, { color: "#6b7280", width: 1.5 });
      for (const q of pts) v.dot(q, { r: 4, fill: "#fff", stroke: "#6b7280" });
    }
    if (out && out.natural) v.polyline(sample(out.natural), { color: "#1f6feb", width: 1.5, alpha: 0.35, dash: [6, 4] });
    if (out && out.result) {
      const r = out.result;
      v.polyline(sample(r), { color: "#1d2330", width: 2.2 });
      for (const k of r.extra_knots) {
        v.dot([k.t, evaluate(r, k.t)], { r: 4.5, fill: KIND_COLOR[k.kind] || "#000" });
      }
    }
    const bad = badIndex(out, ["t", "y"]);
    p.t.forEach((t, i) => v.dot([t, p.y[i]], { r: 5, fill: i === bad ? "#c62828" : "#1d2330" }));
  }

  stats(out) {
    const r = out.result;
    const rows = [
      ["‖f''‖", fmt(r.norm, 8), null, "norm"],
      ["∫f''²", fmt(r.energy, 8)],
      ["extra knots", r.extra_knots.length ? count(r.extra_knots) : "none"],
      ["gradient norm", fmt(r.gradient_norm)],
    ];
    if (out.natural) rows.splice(1, 0, ["natural ‖f''‖", fmt(out.natural.norm, 8)]);
    return rows;
  }
}

function count(knots) {
  const c = {};
  for (const k of knots) {
    const kind = k.kind.replace(/_(start|end)/, "");
    c[kind] = (c[kind] || 0) + 1;
  }
  return Object.entries(c).map(([k, n]) => `${n} ${k.replace("_", " ")}`).join(", ");
}

// The piecewise cubic of a strip result at t (the piece whose break is the last ≤ t).
function evaluate(r, t) {
  const b = r.breaks;
  let lo = 0, hi = b.length - 2;
  while (lo < hi) {
    const mid = (lo + hi + 1) >> 1;
    if (b[mid] <= t) lo = mid; else hi = mid - 1;
  }
  const [c0, c1, c2, c3] = r.coefficients[lo];
  const s = t - b[lo];
  return c0 + s * (c1 + s * (c2 + s * c3));
}

// Points along every piece, dense enough to look smooth at any width the page is drawn.
function sample(r) {
  const pts = [];
  const b = r.breaks;
  const span = Math.max(1e-9, b[b.length - 1] - b[0]);
  for (let j = 0; j + 1 < b.length; j++) {
    const h = b[j + 1] - b[j];
    const m = Math.max(2, Math.ceil((160 * h) / span) + 2);
    const [c0, c1, c2, c3] = r.coefficients[j];
    for (let i = 0; i < m; i++) {
      const s = (h * i) / m;
      pts.push([b[j] + s, c0 + s * (c1 + s * (c2 + s * c3))]);
    }
  }
  const j = b.length - 2;
  const [c0, c1, c2, c3] = r.coefficients[j];
  const s = b[j + 1] - b[j];
  pts.push([b[j + 1], c0 + s * (c1 + s * (c2 + s * c3))]);
  return pts.filter((q) => q[0] >= -1 && q[0] <= W + 1);
}
