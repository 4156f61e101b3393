// Scheme mode: the (2m+2)-point n-ary interpolating scheme of Khan et al. (`curvefit scheme`
// with a polygon) level by level, and Warren–Weimer's natural cubic subdivision
// (`curvefit natural`) of the same open polygon for comparison. The state is the `scheme`
// problem object.

import { round, fmt, badIndex } from "./view.js";

export function defaultProblem() {
  return {
    points: 4,
    arity: 3,
    levels: 3,
    polygon: { points: [[1, 1.5], [2.4, 4.6], [4.2, 3.2], [5.6, 5.0], [7.2, 1.4], [8.8, 3.6]], closed: false },
  };
}

export function check(p) {
  if (!p.polygon || !Array.isArray(p.polygon.points) || p.polygon.points.some((q) => q.length !== 2)) {
    return "the page draws a plane polygon: polygon.points must be [[x, y], …]";
  }
  return null;
}

const LEVEL_COLORS = ["#c7d2fe", "#93a5f5", "#6078e8", "#1f3fbf", "#0b1f80"];

export class SchemeMode {
  constructor() {
    this.sub = "scheme";
    this.natural = true;
    this.load(defaultProblem());
  }

  load(p) { this.problem = p; }
  get points() { return this.problem.polygon.points; }

  handles() { return this.points.map((q, i) => ({ id: i, x: q[0], y: q[1] })); }
  move(id, x, y) { this.points[id] = [round(x), round(y)]; }
  add(x, y) { this.points.push([round(x), round(y)]); return this.points.length - 1; }
  remove(id) { if (this.points.length > 2) this.points.splice(id, 1); }
  wheel() { return false; }

  bindControls(form, changed) {
    this.form = form;
    form.addEventListener("input", () => {
      const f = form.elements;
      this.problem.points = Number(f.points.value);
      this.problem.arity = Number(f.arity.value);
      this.problem.levels = Number(f.levels.value);
      this.problem.polygon.closed = f.closed.checked;
      this.natural = f.natural.checked;
      changed();
    });
  }

  syncControls() {
    const f = this.form.elements;
    f.points.value = String(this.problem.points);
    f.arity.value = this.problem.arity;
    f.levels.value = this.problem.levels ?? 1;
    f.closed.checked = !!this.problem.polygon.closed;
    f.natural.checked = this.natural;
  }

  help() {
    return "Drag the control polygon's vertices; click to add one, right-click to remove one. Lighter lines are the coarser levels.";
  }

  compute(solve) {
    const out = { levels: [] };
    const L = this.problem.levels ?? 1;
    // The coarser levels, each the same problem with fewer levels (the last is the problem).
    for (let l = 1; l <= L; l++) {
      const r = solve("scheme", { ...this.problem, levels: l });
      if (r.error) { out.error = r.error; return out; }
      out.levels.push(r.result.polygon.output);
      if (l === L) out.result = r.result;
    }
    if (this.natural && !this.problem.polygon.closed) {
      const r = solve("natural", { points: this.points, levels: L });
      if (r.error) out.error = r.error;
      else out.natural = r.result;
    }
    return out;
  }

  draw(v, out) {
    const closed = !!this.problem.polygon.closed;
    v.polyline(this.points, { color: "#9aa3af", width: 1, closed, dash: [4, 4] });
    if (out && out.natural) {
      const lv = out.natural.levels;
      v.polyline(lv[lv.length - 1].points, { color: "#d97706", width: 2, alpha: 0.8 });
    }
    if (out && out.levels) {
      const n = out.levels.length;
      out.levels.forEach((pts, l) => {
        const last = l === n - 1;
        v.polyline(pts, { color: last ? "#1d2330" : LEVEL_COLORS[Math.min(l, LEVEL_COLORS.length - 1)], width: last ? 2.2 : 1, closed, alpha: last ? 1 : 0.8 });
      });
    }
    const bad = badIndex(out, ["polygon.points", "points"]);
    this.points.forEach((q, i) => v.dot(q, { r: 5, fill: i === bad ? "#c62828" : "#fff", stroke: i === bad ? "#c62828" : "#1d2330" }));
  }

  stats(out) {
    const r = out.result;
    const rule = r.rules.map((x) => `a=${x.residue}: ${x.weights.join(", ")}`).join("\n");
    const rows = [
      ["scheme", `${r.points}-point ${r.arity}-ary`],
      ["refined points", String(r.polygon.output.length)],
      ["rules", rule],
    ];
    if (out.natural) {
      const lv = out.natural.levels;
      rows.push(["natural energy", `level ${lv.length - 1}: ${fmt(lv[lv.length - 1].energy, 6)}, limit ${fmt(out.natural.limit_energy, 6)}`]);
    }
    return rows;
  }
}
