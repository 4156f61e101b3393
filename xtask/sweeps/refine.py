"""Random `refine` problems through the binary, each answer checked from its output alone.

    cargo build --release -p curvefit
    python xtask/sweeps/refine.py SEED COUNT      # numpy needed; writes problems to $SWEEP_OUT

Problems: n = 2 ... 5000, d = 1/2/3, open and closed; even, jittered, clustered, noisy and nearly
straight points at scales 1e-3 ... 1e4 and offsets up to 1e6; interpolation, balls, smoothing and
half-space sets; random tangent sets (ball, wedge, tension, half-space) on 40 %, clamped or
near-clamped ends, further levels, the "average" derivative, other parametrizations, given knots
(spans 1e-3 ... 10), the paper's solver on small ones; with FAR=1 also bounds far beyond the data ("no bound" as a
huge radius or offset) and balls at data scales of 1e+-90 and 1e+-120. Checks, independent of the solver: the exit
code is 0 or 2 (never a panic or a timeout), nothing is written on a refusal, nothing in the
result is null (non-finite), an exact answer has kkt_residual <= 1e-9, and its data vertices keep to their constraint
(interpolated, inside their balls, inside their half-spaces) to 1e-7 of the data's extent.
ROBUSTNESS.md section 4, item 18, reports a run.
"""
import json, subprocess, sys, os, time
import numpy as np
ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
BIN = os.environ.get("BIN", os.path.join(ROOT, "target", "release", "curvefit"))
rng = np.random.default_rng(int(sys.argv[1]) if len(sys.argv) > 1 else 1)
COUNT = int(sys.argv[2]) if len(sys.argv) > 2 else 200
OUT = os.environ.get("SWEEP_OUT", "/tmp/curvefit-sweep/refine"); os.makedirs(OUT, exist_ok=True)
FAR = os.environ.get("FAR") == "1"
far_rng = np.random.default_rng(1000 + (int(sys.argv[1]) if len(sys.argv) > 1 else 1))
# (Tangent half-spaces' far offsets draw from a stream of their own, added later: the problems of
# far_rng are those of the runs before it.)
far_tangent_rng = np.random.default_rng(2000 + (int(sys.argv[1]) if len(sys.argv) > 1 else 1))

def points(n, d, closed):
    kind = rng.choice(["even", "jitter", "cluster", "noisy", "line"])
    if kind == "line":
        t = np.sort(rng.uniform(0, 10, n)); t += np.arange(n) * 1e-3
        P = np.zeros((n, d)); P[:, 0] = t
        if d > 1: P[:, 1] = rng.normal(0, 1e-6, n)
        return P, kind
    a = np.linspace(0, 2 * np.pi, n, endpoint=not closed)
    if kind == "jitter": a = np.sort(a + rng.uniform(-0.4, 0.4, n) * (a[1] - a[0]))
    if kind == "cluster":
        a = np.sort(np.concatenate([rng.uniform(0, 0.05, n // 2), rng.uniform(0, 2 * np.pi, n - n // 2)]))
    r = 1 + (0.3 * rng.normal(size=n) if kind == "noisy" else 0.2 * np.sin(5 * a))
    P = np.zeros((n, d)); P[:, 0] = r * np.cos(a)
    if d > 1: P[:, 1] = r * np.sin(a)
    if d > 2: P[:, 2] = 0.3 * np.sin(3 * a) + (0.1 * rng.normal(size=n) if kind == "noisy" else 0)
    if d == 1: P[:, 0] = np.sin(a) + 0.1 * rng.normal(size=n)
    scale = 10.0 ** rng.choice([-3, 0, 0, 0, 4]); off = 10.0 ** rng.choice([0, 0, 3, 6])
    return P * scale + off, kind

def make():
    d = int(rng.choice([1, 2, 2, 3]))
    closed = bool(rng.random() < 0.4)
    n = int(rng.choice([2, 3, 4, 5, 8, 20, 100, 1000, 5000]))
    if closed: n = max(n, 3)
    P, kind = points(n, d, closed)
    # drop consecutive duplicates
    prob = {"points": P.tolist(), "closed": closed, "k": int(rng.choice([1, 2, 3, 7])),
            "knot_iterations": int(rng.choice([0, 1, 3])), }
    sp = np.linalg.norm(np.diff(P, axis=0), axis=1); h = float(np.median(sp)) if len(sp) else 1.0
    c = rng.choice(["interpolate", "balls", "halfspaces", "smoothing", "halfspaces"])
    if c == "balls":
        prob["constraint"] = {"type": "balls", "radii": (h * rng.uniform(0, 1.5, n) * (rng.random(n) < 0.8)).tolist()}
    elif c == "smoothing":
        prob["constraint"] = {"type": "smoothing", "weights": (10.0 ** rng.uniform(-1, 5, n)).tolist()}
    elif c == "halfspaces":
        sets = []
        for i in range(n):
            m = int(rng.choice([0, 1, 2, 3, 4]))
            hs = []
            for _ in range(m):
                nv = rng.normal(size=d); nv /= np.linalg.norm(nv)
                hs.append({"normal": nv.tolist(), "offset": float(nv @ P[i] + h * rng.uniform(0, 0.5))})
            sets.append(hs)
        prob["constraint"] = {"type": "halfspaces", "sets": sets}
    if rng.random() < 0.4:
        tg = []
        for i in range(n):
            u = rng.random()
            if u < 0.6: tg.append(None); continue
            f = rng.choice(["ball", "wedge", "tension", "halfspaces"])
            if f == "ball": tg.append({"type": "ball", "center": (rng.normal(size=d)).tolist(), "radius": float(rng.uniform(0, 2))})
            elif f == "wedge":
                a = rng.normal(size=d)
                tg.append({"type": "wedge", "direction": a.tolist(), "half_angle": float(rng.uniform(0, 1.5))})
            elif f == "tension": tg.append({"type": "tension", "radius": float(rng.uniform(0, 3))})
            else:
                nv = rng.normal(size=d)
                tg.append({"type": "halfspaces", "halfspaces": [{"normal": nv.tolist(), "offset": float(rng.uniform(-0.5, 2))}]})
        prob["tangents"] = tg
    if not closed and rng.random() < 0.3:
        v1, v2 = rng.normal(size=d).tolist(), rng.normal(size=d).tolist()
        if rng.random() < 0.5: prob["boundary"] = {"type": "clamped", "start": v1, "end": v2}
        else: prob["boundary"] = {"type": "near_clamped", "start": v1, "end": v2, "radius": float(rng.uniform(0, 1))}
    if rng.random() < 0.2: prob["levels"] = int(rng.choice([1, 2])); prob["level_k"] = int(rng.choice([1, 2]))
    if rng.random() < 0.2: prob["derivative"] = "average"
    if rng.random() < 0.2:
        # (The exponent is drawn before the choice, as in the runs ROBUSTNESS.md reports.)
        choice = rng.choice(["uniform", "chordal", {"exponent": float(rng.uniform(0, 2))}])
        prob["parametrization"] = str(choice) if isinstance(choice, str) else choice
    if rng.random() < 0.15 and n <= 1000:
        kn = np.cumsum(np.concatenate([[0], 10.0 ** rng.uniform(-3, 1, n - (0 if closed else 1))]))
        prob["knots"] = kn.tolist()
    if rng.random() < 0.1 and n <= 100: prob["solver"] = "paper"
    if FAR: far(prob)
    return prob, kind

def far(prob):
    """FAR=1: "no bound" spelled as a huge number on some of the bounds (ROBUSTNESS.md section 4,
    item 29), and balls at the ends of the scale range, drawn from their own stream so that the
    problems are otherwise those of the same seed without FAR."""
    huge = lambda: float(10.0 ** far_rng.uniform(8, 300))
    c = prob.get("constraint", {"type": "interpolate"})
    if c["type"] == "balls":
        r = c["radii"]
        for i in range(len(r)):
            if far_rng.random() < 0.2: r[i] = huge()
        if far_rng.random() < 0.2 and "knots" not in prob and "tangents" not in prob and "boundary" not in prob:
            s = 10.0 ** far_rng.choice([-120, -90, 90, 120])
            prob["points"] = (np.array(prob["points"]) * s).tolist(); c["radii"] = [min(x * s, 1e300) for x in r]
    if c["type"] == "halfspaces":
        for hs in c["sets"]:
            for h in hs:
                if far_rng.random() < 0.3: h["offset"] = huge()
    for t in prob.get("tangents") or []:
        if t and "radius" in t and far_rng.random() < 0.5: t["radius"] = huge()
        if t and t["type"] == "halfspaces" and far_tangent_rng.random() < 0.5:
            for h in t["halfspaces"]: h["offset"] = float(10.0 ** far_tangent_rng.uniform(8, 300))
    b = prob.get("boundary")
    if b and b["type"] == "near_clamped" and far_rng.random() < 0.5: b["radius"] = huge()

def check(prob, res):
    bad = []
    P = np.array(prob["points"], float); n, d = P.shape
    p = np.array(res["points"], float)
    if not np.all(np.isfinite(p)): bad.append("nonfinite points")
    # (JSON has no inf or NaN: a non-finite number anywhere in the result is written as null.)
    if "null" in json.dumps(res): bad.append("null in the result")
    scale = max(np.abs(P - P.mean(0)).max(), 1e-300) if n > 1 else 1
    if prob.get("solver", "exact") == "exact" and not res["kkt_residual"] <= 1e-9: bad.append(f"kkt {res['kkt_residual']}")
    if prob.get("levels", 0) == 0:
        dv = np.array(res["data_vertex"]); c = prob.get("constraint", {"type": "interpolate"})
        tol = 1e-7 * scale + 1e-9 * np.abs(P).max()
        if c["type"] == "interpolate":
            e = np.abs(p[dv] - P).max()
            if e > tol: bad.append(f"interp err {e}")
        if c["type"] == "balls":
            r = np.array(c["radii"]); dist = np.linalg.norm(p[dv] - P, axis=1)
            e = (dist - r).max()
            if e > tol: bad.append(f"ball viol {e}")
        if c["type"] == "halfspaces":
            for i, hs in enumerate(c["sets"]):
                for hh in hs:
                    v = np.dot(hh["normal"], p[dv[i]]) - hh["offset"]
                    if v > tol: bad.append(f"hs viol {i} {v}"); break
    return bad

t0 = time.time(); stats = {}
for case in range(COUNT):
    prob, kind = make()
    f = f"{OUT}/p{case}.json"; o = f"{OUT}/r{case}.json"
    json.dump(prob, open(f, "w"))
    if os.path.exists(o): os.remove(o)
    ts = time.time()
    try:
        r = subprocess.run([BIN, "refine", f, "-o", o], capture_output=True, text=True, timeout=120)
        rc = r.returncode
    except subprocess.TimeoutExpired:
        rc = "TIMEOUT"; r = None
    el = time.time() - ts
    desc = f"n={len(prob['points'])} d={len(prob['points'][0])} closed={prob['closed']} c={prob.get('constraint',{}).get('type','interp')} tg={'tangents' in prob} bd={prob.get('boundary',{}).get('type')} lv={prob.get('levels',0)} ki={prob['knot_iterations']} k={prob['k']} kind={kind} solver={prob.get('solver','exact')} knots={'knots' in prob}"
    if rc == 0:
        bad = check(prob, json.load(open(o)))
        stats["ok"] = stats.get("ok", 0) + 1
        if bad: print(f"BAD case {case} {desc}: {bad}", flush=True)
        if el > 10: print(f"SLOW {el:.1f}s case {case} {desc}", flush=True)
    elif rc == 2:
        stats["refused"] = stats.get("refused", 0) + 1
        if os.path.exists(o) and os.path.getsize(o) > 0: print(f"PARTIAL OUTPUT case {case}")
        print(f"refused case {case} {desc}: {r.stderr.strip()[:300]}", flush=True)
    else:
        stats[str(rc)] = stats.get(str(rc), 0) + 1
        print(f"CRASH rc={rc} case {case} {desc}: {(r.stderr[-800:] if r else '')}", flush=True)
print(stats, f"{time.time()-t0:.0f}s")
