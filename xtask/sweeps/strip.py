"""Random `strip` problems through the binary, each answer checked from its output alone.

    cargo build --release -p curvefit
    python xtask/sweeps/strip.py SEED COUNT       # numpy and scipy needed; problems to $SWEEP_OUT

Problems: n = 2 ... 5000 sites, even, jittered, very unequal (log-normal spans over up to eight
decades) or clustered, at scales 1e-3 ... 1e4 and offsets up to 10⁶ ranges; values smooth, noisy, a
random walk or steps, at scales 1e-3 ... 1e4 and offsets up to 10³ of their scale; bounds as cubic
pieces (a band about the data polygon, constants jumping at the sites, one side only) or
polylines with their own breakpoints (the band sampled off the sites, a steep narrow wiggle),
half-widths from 1e-6 to 1 of the value range, end slopes on 30 %; 8 % move one value outside
its bound (a refusal is due).

Checks, none of which uses the solver's code: the exit code is 0 or 2 (never a panic or a
timeout) and nothing is written on a refusal; an answer's breaks contain the sites, its pieces
interpolate the data (1e-9 of the value range), join in value and slope (1e-9 of their scales)
and in f'' to its rounding (the strip crate's C2_ROUNDING model at 16ε, plus |f'''| times the
rounding of the break's abscissa), keep inside both bounds on 16 points per piece and at every
polyline vertex (1e-9 of the value range plus the abscissa's rounding), put every reported
contact (touch, subarc end) on its bound, and report their own energy ∫f''² and slopes; the
energy is at least the unconstrained spline's (scipy CubicSpline, same ends), and equals it
(1e-9) where that spline keeps inside the bounds with room (1e-6 of the range) to spare.
ROBUSTNESS.md item 25 reports runs.
"""
import json, os, re, subprocess, sys, time
import numpy as np
from scipy.interpolate import CubicSpline

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
BIN = os.environ.get("BIN", os.path.join(ROOT, "target", "release", "curvefit"))
SEED = int(sys.argv[1]) if len(sys.argv) > 1 else 1
rng = np.random.default_rng(SEED)
COUNT = int(sys.argv[2]) if len(sys.argv) > 2 else 200
OUT = os.environ.get("SWEEP_OUT", "/tmp/curvefit-sweep/strip"); os.makedirs(OUT, exist_ok=True)
TIMEOUT = 120
EPS = np.finfo(float).eps


def sites(n):
    kind = rng.choice(["even", "jitter", "unequal", "cluster"])
    if kind == "even":
        h = np.ones(n - 1)
    elif kind == "jitter":
        h = 1 + rng.uniform(-0.45, 0.45, n - 1)
    elif kind == "unequal":
        h = np.exp(rng.normal(0, rng.choice([1.0, 2.0, 3.0]), n - 1))
    else:
        h = np.where(rng.uniform(size=n - 1) < 0.5, 1e-3, 1.0) * (1 + rng.uniform(0, 0.2, n - 1))
    t = np.concatenate([[0.0], np.cumsum(h)])
    scale = 10.0 ** rng.choice([-3, 0, 0, 0, 2, 4]) / t[-1] * max(1, n / 10)
    off = rng.choice([0.0, 0.0, 1.0, 1e3, 1e6]) * scale * t[-1]
    t = off + scale * t
    # A span below one ulp of the offset rounds to 0: such sites do not increase, and the bounds
    # built on them divide by 0 (`Infinity`, which is no JSON number), so the problem tested the
    # parser instead of the solver (seed 311, case 134). Each such site moves up to the next
    # double; the other problems are as before.
    for i in range(1, n):
        if t[i] <= t[i - 1]:
            t[i] = np.nextafter(t[i - 1], np.inf)
    return t, kind


def values(t):
    n = len(t)
    kind = rng.choice(["smooth", "noisy", "walk", "steps"])
    x = (t - t[0]) / max(t[-1] - t[0], 1e-300)
    if kind == "smooth":
        y = np.sin(2 * np.pi * rng.uniform(0.5, 4) * x)
    elif kind == "noisy":
        y = np.sin(2 * np.pi * x) + 0.3 * rng.normal(size=n)
    elif kind == "walk":
        y = np.cumsum(rng.normal(size=n)) / np.sqrt(max(n, 1))
    else:
        y = np.floor(4 * rng.uniform(size=n)) / 4 + 0.01 * rng.normal(size=n)
    scale = 10.0 ** rng.choice([-3, 0, 0, 0, 2, 4])
    off = rng.choice([0.0, 0.0, 1.0, 1e3]) * scale
    return off + scale * y, kind


def band_pieces(t, y, w, side):
    """The data polygon ± w as one linear piece per interval (c0, c1, 0, 0) in s = t − t_i."""
    slope = np.diff(y) / np.diff(t)
    return [[float(y[i] + side * w), float(slope[i]), 0.0, 0.0] for i in range(len(t) - 1)]


def const_pieces(y, w, side):
    """Constants jumping at the sites: the larger (upper) or smaller (lower) neighbour ± w."""
    pick = np.maximum if side > 0 else np.minimum
    return [[float(pick(y[i], y[i + 1]) + side * w), 0.0, 0.0, 0.0] for i in range(len(y) - 1)]


def band_polyline(t, y, w, side, wiggle):
    """The data polygon ± w (± a narrow wiggle) at its own breakpoints: the sites and points
    between them, so the bound bends off the sites."""
    mids = t[:-1] + np.diff(t) * rng.uniform(0.2, 0.8, len(t) - 1)
    tt = np.sort(np.concatenate([t, mids]))
    yy = np.interp(tt, t, y)
    extra = wiggle * w * np.abs(np.sin(np.arange(len(tt)) * 2.3)) if wiggle else 0.0
    vv = yy + side * (w + extra)
    return [[float(a), float(b)] for a, b in zip(tt, vv)]


def problem():
    n = int(rng.choice([2, 3, 5, 10, 30, 100, 300, 1000, 5000], p=[.05, .05, .1, .15, .2, .2, .1, .1, .05]))
    t, tkind = sites(n)
    y, ykind = values(t)
    spread = float(np.ptp(y)) or 1.0
    w = spread * 10.0 ** rng.uniform(-6, 0)
    bkind = rng.choice(["band", "const", "polyline", "wiggle", "lower-only", "upper-only"])
    p = {"t": t.tolist(), "y": y.tolist()}
    if bkind in ("band", "lower-only", "upper-only"):
        if bkind != "upper-only":
            p["lower"] = {"pieces": band_pieces(t, y, w, -1)}
        if bkind != "lower-only":
            p["upper"] = {"pieces": band_pieces(t, y, w, +1)}
    elif bkind == "const":
        p["lower"] = {"pieces": const_pieces(y, w, -1)}
        p["upper"] = {"pieces": const_pieces(y, w, +1)}
    else:
        wig = 3.0 if bkind == "wiggle" else 0.0
        p["lower"] = {"polyline": band_polyline(t, y, w, -1, wig)}
        p["upper"] = {"polyline": band_polyline(t, y, w, +1, wig)}
    if rng.uniform() < 0.3:
        s = float(rng.normal() * spread / (t[-1] - t[0]))
        p["end_slopes"] = [s if rng.uniform() < 0.7 else None, -s if rng.uniform() < 0.7 else None]
    outside = rng.uniform() < 0.08
    if outside:
        i = int(rng.integers(n))
        p["y"][i] = float(y[i] + (-1 if bkind == "lower-only" else 1) * (3 * w + spread))
    return p, dict(n=n, t=str(tkind), y=str(ykind), bounds=str(bkind), w=float(w / spread), outside=bool(outside))


def bound_at(spec, t, x, side="right"):
    """Independent evaluation of a bound at x (None: no bound). Cubic pieces are read in the
    data interval starting at x where x is a site (`side="right"`) or in the one ending there
    (`side="left"`, the left limit of a bound that jumps at a site)."""
    if spec is None:
        return None
    if "polyline" in spec:
        pl = np.array(spec["polyline"])
        return np.interp(x, pl[:, 0], pl[:, 1])
    c = np.array(spec["pieces"])
    i = np.clip(np.searchsorted(t, x, side=side) - 1, 0, len(t) - 2)
    s = x - t[i]
    return c[i, 0] + s * (c[i, 1] + s * (c[i, 2] + s * c[i, 3]))


def energy(c2, c3, h):
    """∫ f''² over pieces c0 + c1 s + c2 s² + c3 s³ of lengths h: f'' = 2c2 + 6c3 s."""
    b, a = 2 * c2, 6 * c3
    return float(np.sum(b * b * h + a * b * h * h + a * a * h ** 3 / 3))


def natural_energy(t, y, ends):
    bc = []
    for s in ends:
        bc.append((1, s) if s is not None else (2, 0.0))
    cs = CubicSpline(t, y, bc_type=(bc[0], bc[1]))
    # scipy's c[0] s³ + c[1] s² + c[2] s + c[3]
    return energy(cs.c[1], cs.c[0], np.diff(t)), cs


def check(p, r):
    t = np.array(p["t"]); y = np.array(p["y"])
    br = np.array(r["breaks"]); co = np.array(r["coefficients"])
    vscale = max(np.abs(y).max(), 1e-300)
    vrange = max(float(np.ptp(y)), 1e-14 * vscale, 1e-300)
    flags = []
    if not np.all(np.diff(br) > 0):
        flags.append("breaks not increasing")
    if len(co) != len(br) - 1:
        return ["coefficients/breaks length"]
    idx = np.searchsorted(br, t)
    if np.any(idx >= len(br)) or not np.all(br[np.minimum(idx, len(br) - 1)] == t):
        flags.append("a site is not a break")
    h = np.diff(br)
    val = lambda j, s: co[j, 0] + s * (co[j, 1] + s * (co[j, 2] + s * co[j, 3]))
    d1 = lambda j, s: co[j, 1] + s * (2 * co[j, 2] + 3 * s * co[j, 3])
    d2 = lambda j, s: 2 * co[j, 2] + 6 * s * co[j, 3]
    # interpolation
    j = np.clip(np.searchsorted(br, t, side="right") - 1, 0, len(h) - 1)
    fi = val(j, t - br[j])
    err = np.abs(fi - y).max() / (vrange + 1e-5 * vscale)
    if err > 1e-9:
        flags.append(f"interpolation {err:.1e}")
    # C² joins. f''(b±) is computed from a piece's end values v₀, v₁ and slopes m₀, m₁ over its
    # length L, so it is known to ~u·R with R = (6(|v₀| + |v₁|)/L + 4|m₀| + 2|m₁|)/L (the strip
    # crate's documented C2_ROUNDING model, with 16ε in place of its 4ε for the map back from
    # the normalized frame), plus |f'''| times the rounding of a break's abscissa; value and
    # slope joins to 1e-9 of their scales.
    J = np.arange(len(h) - 1)
    scale1 = max(np.abs(co[:, 1]).max(), 1e-300)
    f2max = max(np.abs(2 * co[:, 2]).max(), np.abs(d2(np.arange(len(h)), h)).max(), 1e-300)
    v0, v1 = np.abs(co[:, 0]), np.abs(val(np.arange(len(h)), h))
    m0, m1 = np.abs(co[:, 1]), np.abs(d1(np.arange(len(h)), h))
    R = (6 * (v0 + v1) / h + 4 * np.maximum(m0, m1) + 2 * np.minimum(m0, m1)) / h
    jv = np.abs(val(J, h[J]) - co[J + 1, 0]).max(initial=0) / vscale
    j1 = np.abs(d1(J, h[J]) - co[J + 1, 1]).max(initial=0) / scale1
    jump2 = np.abs(d2(J, h[J]) - 2 * co[J + 1, 2])
    # and f'' at a break moves by |f'''| times the rounding of the break's abscissa
    allow2 = 16 * EPS * (f2max + R[J] + R[J + 1]) + 4 * EPS * np.abs(br[J + 1]) * 6 * (
        np.abs(co[J, 3]) + np.abs(co[J + 1, 3]))
    # a join also moves by the next derivative times the rounding of the break's abscissa
    xr = 4 * EPS * np.abs(br[J + 1])
    jv_allow = 1e-9 + (xr * np.abs(d1(J, h[J]))).max(initial=0) / vscale
    j1_allow = 1e-9 + (xr * np.abs(d2(J, h[J]))).max(initial=0) / scale1
    if jv > jv_allow or j1 > j1_allow:
        flags.append(f"C1 join {max(jv, j1):.1e}")
    if len(J) and np.any(jump2 > allow2):
        k = int(np.argmax(jump2 / allow2))
        flags.append(f"C2 join {jump2[k] / f2max:.1e} of max|f''| ({jump2[k] / allow2[k]:.1f}x its rounding)")
    # bounds: 16 points per piece, plus each bound's polyline breakpoints
    s = np.linspace(0, 1, 16)
    jj = np.repeat(np.arange(len(h)), len(s)); ss = np.tile(s, len(h)) * h[jj]
    x = br[jj] + ss
    f = val(jj, ss)
    # (a break that is a site starts a new data interval: piece bounds are read on its side)
    viol = 0.0
    for spec, side in ((p.get("lower"), -1), (p.get("upper"), +1)):
        if spec is None:
            continue
        b = bound_at(spec, t, x)
        if "polyline" in spec:
            pl = np.array(spec["polyline"])
            jb = np.clip(np.searchsorted(br, pl[:, 0], side="right") - 1, 0, len(h) - 1)
            fb = val(jb, pl[:, 0] - br[jb])
            viol = max(viol, float(np.max(side * (fb - pl[:, 1]))))
        viol = max(viol, float(np.max(side * (f - b))))
    # 1e-9 of the value scale plus what moving the abscissa by its rounding moves f
    allow = 1e-9 * vrange + 1e-14 * vscale + 4 * EPS * np.abs(x).max() * np.abs(m0).max()
    if viol > allow:
        flags.append(f"bound violated {viol / vrange:.1e} of the value range ({viol / allow:.1f}x allowed)")
    # every reported contact is one: f on its bound there (to the value allowance)
    for k in r["extra_knots"]:
        side = -1 if k["kind"].endswith("lower") else +1
        spec = p.get("lower" if side < 0 else "upper")
        if spec is None:
            flags.append(f"{k['kind']} at {k['t']} without that bound")
            continue
        x0 = k["t"]
        jk = int(np.clip(np.searchsorted(br, x0, side="right") - 1, 0, len(h) - 1))
        gap = abs(val(jk, x0 - br[jk]) - bound_at(spec, t, x0))
        if gap > allow:
            flags.append(f"{k['kind']} at {x0}: f is {gap / vrange:.1e} of the range off the bound")
    e = energy(co[:, 2], co[:, 3], h)
    # (each break's rounding moves ∫f''² by up to f''² there times that rounding)
    f2at = np.maximum(np.abs(d2(np.arange(len(h)), 0)), np.abs(d2(np.arange(len(h)), h))) ** 2
    e_allow = 1e-9 * max(abs(e), 1e-300) + float(np.sum(f2at * 8 * EPS * np.maximum(np.abs(br[:-1]), np.abs(br[1:]))))
    if abs(e - r["energy"]) > e_allow:
        flags.append(f"energy {r['energy']:.6e} vs {e:.6e}")
    sl = d1(j, t - br[j])
    if np.abs(sl - np.array(r["slopes"])).max() > 1e-9 * scale1:
        flags.append("slopes")
    # against the unconstrained spline
    ends = p.get("end_slopes") or [None, None]
    try:
        en, cs = natural_energy(t, y, ends)
    except Exception:
        return flags
    floor = 1e-12 * vrange ** 2 / (t[-1] - t[0]) ** 3
    if e < en * (1 - 1e-9) - floor:
        flags.append(f"energy {e:.9e} below the unconstrained spline's {en:.9e}")
    xs = np.concatenate([x, t])
    fn = cs(xs)
    room = np.inf
    for spec, side in ((p.get("lower"), -1), (p.get("upper"), +1)):
        if spec is None:
            continue
        # both limits at the sites (a bound that jumps there)
        for at in ("right", "left"):
            room = min(room, float(np.min(-side * (fn - bound_at(spec, t, xs, at)))))
    if room > 1e-6 * vrange and abs(e - en) > 1e-9 * en + floor:
        flags.append(f"inside-spline energy {e:.12e} vs scipy {en:.12e}")
    return flags


def main():
    tally = {"ok": 0, "refused": 0}
    flagged, refusals = [], {}
    slow = []
    for case in range(COUNT):
        p, meta = problem()
        f = os.path.join(OUT, f"strip-{SEED}-{case}.json")
        o = os.path.join(OUT, f"strip-{SEED}-{case}.out.json")
        with open(f, "w") as fh:
            json.dump(p, fh)
        if os.path.exists(o):
            os.remove(o)
        t0 = time.time()
        try:
            cp = subprocess.run([BIN, "strip", f, "-o", o], capture_output=True, text=True, timeout=TIMEOUT)
        except subprocess.TimeoutExpired:
            flagged.append((case, meta, ["timeout"]))
            continue
        dt = time.time() - t0
        if dt > 5:
            slow.append((case, meta["n"], round(dt, 1)))
        if cp.returncode == 2:
            tally["refused"] += 1
            last = cp.stderr.strip().splitlines()[-1] if cp.stderr.strip() else "?"
            # the message without its field and numbers, to group refusals of one kind
            key = re.sub(r"[-+]?\d[\d.e+-]*", "#", re.sub(r"^error: (\w+\[\d+\]: )?", "", last))[:70]
            refusals.setdefault(key, []).append((case, meta))
            if os.path.exists(o):
                flagged.append((case, meta, ["output written on a refusal"]))
            continue
        if cp.returncode != 0:
            flagged.append((case, meta, [f"exit {cp.returncode}: {cp.stderr[-300:]}"]))
            continue
        r = json.load(open(o))
        fl = check(p, r)
        if meta["outside"]:
            fl.append("answered with a value outside its bound")
        if fl:
            flagged.append((case, meta, fl))
        else:
            tally["ok"] += 1
    print(f"seed {SEED}: {COUNT} problems, {tally['ok']} answered and checked, {tally['refused']} refused, {len(flagged)} flagged")
    for k, v in sorted(refusals.items(), key=lambda kv: -len(kv[1])):
        outside = sum(m["outside"] for _, m in v)
        print(f"  refused {len(v):4d} ({outside} with a value moved outside): {k}")
        for c, m in v:
            if not m["outside"]:
                print(f"      case {c}: n = {m['n']}, sites {m['t']}, values {m['y']}, bounds {m['bounds']}, half-width {m['w']:.1e} of the range")
    for c, m, fl in flagged:
        print(f"  FLAG case {c} {m}: {'; '.join(fl)}")
    if slow:
        print("  slow (> 5 s):", slow)


if __name__ == "__main__":
    main()
