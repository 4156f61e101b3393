// The drawing surface: a canvas showing the world box [0, W] × [0, H] (y up), kept to its
// aspect ratio and sharp on high-DPI screens.

export const W = 10;
export const H = 6;

export class View {
  constructor(canvas) {
    this.canvas = canvas;
    this.ctx = canvas.getContext("2d");
    this.resize();
  }

  // Matches the backing store to the CSS size; called on every frame (cheap when unchanged).
  resize() {
    const r = this.canvas.getBoundingClientRect();
    const dpr = window.devicePixelRatio || 1;
    const w = Math.max(1, Math.round(r.width * dpr));
    const h = Math.max(1, Math.round(r.height * dpr));
    if (this.canvas.width !== w || this.canvas.height !== h) {
      this.canvas.width = w;
      this.canvas.height = h;
    }
    this.dpr = dpr;
    this.scale = Math.min(r.width / W, r.height / H);
    this.ox = (r.width - this.scale * W) / 2;
    this.oy = (r.height - this.scale * H) / 2;
    this.rect = r;
  }

  sx(x) { return this.ox + this.scale * x; }
  sy(y) { return this.oy + this.scale * (H - y); }
  // Client (mouse) coordinates to the world.
  world(clientX, clientY) {
    const x = clientX - this.rect.left;
    const y = clientY - this.rect.top;
    return [(x - this.ox) / this.scale, H - (y - this.oy) / this.scale];
  }
  // A distance on screen (CSS pixels) in world units.
  px(d) { return d / this.scale; }

  clear() {
    const c = this.ctx;
    c.setTransform(this.dpr, 0, 0, this.dpr, 0, 0);
    c.clearRect(0, 0, this.rect.width, this.rect.height);
    c.strokeStyle = "#eef0f3";
    c.lineWidth = 1;
    c.beginPath();
    for (let x = 0; x <= W; x++) { c.moveTo(this.sx(x), this.sy(0)); c.lineTo(this.sx(x), this.sy(H)); }
    for (let y = 0; y <= H; y++) { c.moveTo(this.sx(0), this.sy(y)); c.lineTo(this.sx(W), this.sy(y)); }
    c.stroke();
  }

  polyline(pts, { color = "#1d2330", width = 2, closed = false, dash = null, alpha = 1 } = {}) {
    if (pts.length === 0) return;
    const c = this.ctx;
    c.save();
    c.globalAlpha = alpha;
    c.strokeStyle = color;
    c.lineWidth = width;
    c.lineJoin = "round";
    if (dash) c.setLineDash(dash);
    c.beginPath();
    c.moveTo(this.sx(pts[0][0]), this.sy(pts[0][1]));
    for (let i = 1; i < pts.length; i++) c.lineTo(this.sx(pts[i][0]), this.sy(pts[i][1]));
    if (closed) c.closePath();
    c.stroke();
    c.restore();
  }

  dot(p, { r = 5, fill = "#1d2330", stroke = null, width = 1.5 } = {}) {
    const c = this.ctx;
    c.beginPath();
    c.arc(this.sx(p[0]), this.sy(p[1]), r, 0, 2 * Math.PI);
    if (fill) { c.fillStyle = fill; c.fill(); }
    if (stroke) { c.strokeStyle = stroke; c.lineWidth = width; c.stroke(); }
  }

  // A circle of world radius `radius`.
  circle(p, radius, { fill = null, stroke = "#1f6feb", width = 1, dash = null } = {}) {
    const c = this.ctx;
    c.save();
    if (dash) c.setLineDash(dash);
    c.beginPath();
    c.arc(this.sx(p[0]), this.sy(p[1]), Math.max(0, radius * this.scale), 0, 2 * Math.PI);
    if (fill) { c.fillStyle = fill; c.fill(); }
    if (stroke) { c.strokeStyle = stroke; c.lineWidth = width; c.stroke(); }
    c.restore();
  }

  text(p, s, { color = "#6b7280", dx = 8, dy = -8, font = "12px system-ui" } = {}) {
    const c = this.ctx;
    c.fillStyle = color;
    c.font = font;
    c.fillText(s, this.sx(p[0]) + dx, this.sy(p[1]) + dy);
  }
}

// Rounds a world coordinate for the problem's JSON (what the page shares stays readable; a
// thousandth of a unit is below a pixel at any size the page draws).
export function round(x) {
  return Math.round(x * 1000) / 1000;
}

export function fmt(x, digits = 4) {
  if (typeof x !== "number" || !Number.isFinite(x)) return String(x);
  const a = Math.abs(x);
  return a !== 0 && (a < 1e-3 || a >= 1e5) ? x.toExponential(2) : x.toPrecision(digits);
}

// The index of the point an error names, when its field is one of `fields` (`points[3]`,
// `constraint.radii[3]` → 3); null otherwise (the error is about something else).
export function badIndex(out, fields) {
  const e = out && out.error;
  if (!e || e.index === null || e.index === undefined) return null;
  return fields.some((f) => e.field.startsWith(`${f}[`)) ? e.index : null;
}
