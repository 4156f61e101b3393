"""Random `scheme`, `surface` and `natural` problems through the binary, checked against exact
properties of the seeds rather than against our own numbers.

    cargo build --release -p curvefit
    python xtask/sweeps/subdivision.py SEED COUNT   # numpy needed; writes to $SWEEP_OUT

- scheme (P = 2 ... 16 even, N = 2 ... 16, 2 ... 200 points, d = 1 ... 3, open and closed, 0 ... 3
  levels, coordinates 1e-5 ... 1e5): every rule's weights sum to exactly 1 (as fractions); the
  output interpolates the input exactly (every N^L-th point); on open polygons sampled from a
  polynomial of degree <= min(P - 1, points - 1) the output lies on that polynomial at i / N^L
  (Khan et al.: the schemes reproduce degree 2m + 1), to 1e-8 of its size.
- surface (2 ... 11 rows and columns, wrapped or not): on open grids of a product of polynomials
  of degree <= 3 the refined grid lies on that surface, and interpolates the input exactly.
- natural (L = 1 ... 300, d = 1 ... 3, up to 12 levels, coordinates 1e-100 ... 1e100): finite, the
  point count 2^K L + 1, and from 8 levels on the last level's energy within 1e-3 of the exact
  limit energy (Warren-Weimer Theorem 6.4), up to rounding of the data's scale.
"""
import json, subprocess, sys, os
import numpy as np
from fractions import Fraction
ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
BIN = os.environ.get("BIN", os.path.join(ROOT, "target", "release", "curvefit"))
rng = np.random.default_rng(int(sys.argv[1])); COUNT = int(sys.argv[2])
OUT = os.environ.get("SWEEP_OUT", "/tmp/curvefit-sweep/subdivision"); os.makedirs(OUT, exist_ok=True)
stats = {}
def run(args, timeout=60):
    try:
        r = subprocess.run([BIN] + args, capture_output=True, text=True, timeout=timeout); return r.returncode, r
    except subprocess.TimeoutExpired: return "TIMEOUT", None
for case in range(COUNT):
    what = rng.choice(["scheme", "surface", "natural"])
    P = int(rng.choice(range(2, 17, 2))); N = int(rng.integers(2, 17))
    o = f"{OUT}/r{case}.json"
    if os.path.exists(o): os.remove(o)
    if what == "scheme":
        closed = bool(rng.random() < 0.3)
        npts = int(rng.choice([2, 3, 5, 8, 17, 40, 200]))
        d = int(rng.integers(1, 4))
        levels = int(rng.choice([0, 1, 2, 3]))
        while npts * N ** levels > 2e5 and levels > 0: levels -= 1
        deg = min(P - 1, npts - 1, int(rng.integers(0, 8)))
        sc = 10.0 ** rng.choice([-5, 0, 0, 5])
        coef = rng.normal(size=(d, deg + 1)) * sc
        x = np.arange(npts, dtype=float)
        pts = np.stack([np.polyval(c, x) for c in coef], 1)
        json.dump({"points": pts.tolist(), "closed": closed}, open(f"{OUT}/poly{case}.json", "w"))
        args = ["scheme", "--stencil", str(P), "--arity", str(N), "--apply", f"{OUT}/poly{case}.json", "--levels", str(levels), "-o", o]
        if rng.random() < 0.3: args.append("--surface")
        rc, r = run(args)
        desc = f"scheme P={P} N={N} npts={npts} d={d} L={levels} closed={closed} deg={deg}"
        if rc == 0:
            res = json.load(open(o)); out = np.array(res["polygon"]["output"], float)
            bad = []
            step = N ** levels
            if not np.all(np.isfinite(out)): bad.append("nonfinite")
            if np.abs(out[::step][:npts] - pts).max() > 0: bad.append(f"not interpolating {np.abs(out[::step][:npts] - pts).max()}")
            for rule in res["rules"]:
                s = sum(Fraction(w) for w in rule["weights"])
                if s != 1: bad.append(f"weights sum {s}")
            if not closed:
                xs = np.arange(len(out)) / step
                ref = np.stack([np.polyval(c, xs) for c in coef], 1)
                err = np.abs(out - ref).max() / max(np.abs(ref).max(), 1e-300)
                if err > 1e-8: bad.append(f"poly reproduction {err:.2e}")
            if bad: print("BAD", case, desc, bad, flush=True)
    elif what == "surface":
        rows, cols = int(rng.integers(2, 12)), int(rng.integers(2, 12))
        closed = [bool(rng.random() < 0.3), bool(rng.random() < 0.3)]
        levels = int(rng.choice([0, 1, 2]))
        while rows * cols * N ** (2 * levels) > 2e5 and levels > 0: levels -= 1
        dr, dc = min(P - 1, rows - 1, 3), min(P - 1, cols - 1, 3)
        cr, cc = rng.normal(size=dr + 1), rng.normal(size=dc + 1)
        I, J = np.meshgrid(np.arange(rows, dtype=float), np.arange(cols, dtype=float), indexing="ij")
        Z = np.polyval(cr, I) * np.polyval(cc, J)
        pts = np.stack([I.ravel(), J.ravel(), Z.ravel()], 1)
        prob = {"rows": rows, "cols": cols, "points": pts.tolist(), "closed": closed, "scheme": {"points": P, "arity": N}, "levels": levels}
        json.dump(prob, open(f"{OUT}/surf{case}.json", "w"))
        rc, r = run(["surface", f"{OUT}/surf{case}.json", "-o", o])
        desc = f"surface P={P} N={N} {rows}x{cols} L={levels} closed={closed}"
        if rc == 0:
            res = json.load(open(o)); out = np.array(res["points"], float); bad = []
            if not np.all(np.isfinite(out)): bad.append("nonfinite")
            if not any(closed):
                ref = np.polyval(cr, out[:, 0]) * np.polyval(cc, out[:, 1])
                err = np.abs(out[:, 2] - ref).max() / max(np.abs(ref).max(), 1e-300)
                if err > 1e-8: bad.append(f"poly reproduction {err:.2e}")
                R, C = res["rows"], res["cols"]; step = N ** levels
                g = out.reshape(R, C, 3)[::step, ::step]
                if np.abs(g.reshape(-1, 3) - pts).max() > 0: bad.append("not interpolating")
            if bad: print("BAD", case, desc, bad, flush=True)
    else:
        L = int(rng.choice([1, 2, 3, 5, 20, 300])); d = int(rng.integers(1, 4))
        levels = int(rng.choice([0, 1, 4, 8, 12]))
        while (L * 2 ** levels + 1) * d * 2 > 1e7 and levels > 0: levels -= 1
        pts = rng.normal(size=(L + 1, d)) * 10.0 ** rng.choice([-100, -3, 0, 3, 100])
        json.dump({"points": pts.tolist(), "levels": levels}, open(f"{OUT}/nat{case}.json", "w"))
        rc, r = run(["natural", f"{OUT}/nat{case}.json", "-o", o])
        desc = f"natural L={L} d={d} levels={levels} scale={np.abs(pts).max():.0e}"
        if rc == 0:
            res = json.load(open(o)); bad = []
            E = [lv["energy"] for lv in res["levels"]]; lim = res["limit_energy"]
            if not all(np.isfinite(E)) or not np.isfinite(lim): bad.append("nonfinite")
            elif levels >= 8 and abs(E[-1] - lim) > 1e-3 * abs(lim) + 1e-12 * float(np.abs(pts).max())**2 * L: bad.append(f"energy {E[-1]} vs limit {lim}")
            last = np.array(res["levels"][-1]["points"], float)
            if len(last) != L * 2 ** levels + 1: bad.append("count")
            if bad: print("BAD", case, desc, bad, flush=True)
    stats[str(rc)] = stats.get(str(rc), 0) + 1
    if rc == 2: print("refused", case, desc, r.stderr.strip()[:200], flush=True)
    elif rc != 0: print("CRASH", rc, case, desc, (r.stderr[-500:] if r else ""), flush=True)
print(stats)
