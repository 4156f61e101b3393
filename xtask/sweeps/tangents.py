"""Tangent sets over balls on hard data, through the binary: which classes are certified and which
refused, each answer checked from its output alone.

    cargo build --release -p curvefit
    python xtask/sweeps/tangents.py [SEEDS]     # numpy needed; default 2 seeds; problems to $SWEEP_OUT

Problems: a closed noisy star (r_i = 1 + 0.35 (i mod 2) + 0.05 N(0, 1), jittered angles),
n = 2000, 5000, 10000, k = 3 and 7, the default three knot updates, balls of radius 0.2 … 0.7 of
the mean data spacing (most active), and on every fifth point one tangent set of one kind: a
wedge of half-angle 0.6 about the circle's tangent, a ball about the tangent, a tension bound, or
a half-plane (the derivative not pointing backwards).

Checks, independent of the solver: exit code 0 or 2 (never a panic or a timeout), an answer has
kkt_residual <= 1e-9, its data vertices lie in their balls (to 1e-9 of the extent), and its
derivatives at the constrained vertices — recomputed from the output points and knots with the
"bessel" rule (the derivative at t_i of the quadratic through p_{i-1}, p_i, p_{i+1}) — lie in
their sets (to 1e-7 of the set's size, or of the curve's median speed for the cones: a wedge
holds Df = 0). Exits 1 when a check fails; refusals are counted, not
failures (ROBUSTNESS.md §4, item 37 reports a run).
"""
import json, os, subprocess, sys, time
import numpy as np

from derivatives import derivative_rows

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
BIN = os.environ.get("BIN", os.path.join(ROOT, "target", "release", "curvefit"))
OUT = os.environ.get("SWEEP_OUT", "/tmp/curvefit-sweep/tangents")
os.makedirs(OUT, exist_ok=True)
SEEDS = int(sys.argv[1]) if len(sys.argv) > 1 else 2


def problem(n, k, kind, seed):
    rng = np.random.default_rng(seed * 100 + n + k)
    th = np.sort(2 * np.pi * (np.arange(n) + rng.uniform(-0.4, 0.4, n)) / n)
    r = 1 + 0.35 * (np.arange(n) % 2) + 0.05 * rng.normal(size=n)
    q = np.c_[r * np.cos(th), r * np.sin(th)]
    sp = np.linalg.norm(np.diff(q, axis=0), axis=1).mean()
    ang = np.arctan2(q[:, 1], q[:, 0])
    tangent = np.c_[-np.sin(ang), np.cos(ang)]
    # |Df| on centripetal data parameters: the smoothed curve's length (the balls let it cut the
    # zigzag, about the circle of radius 1.175) over the parameters' span (n spans of about
    # |chord|^(1/2)).
    speed = 2 * np.pi * 1.175 / (n * np.sqrt(sp))
    sets = []
    for i in range(n):
        if i % 5:
            sets.append(None)
        elif kind == "wedge":
            sets.append({"type": "wedge", "direction": tangent[i].tolist(), "half_angle": 0.6})
        elif kind == "ball":
            sets.append({"type": "ball", "center": (tangent[i] * speed).tolist(), "radius": 0.5 * speed})
        elif kind == "tension":
            sets.append({"type": "tension", "radius": 1.2 * speed})
        else:
            sets.append({"type": "halfspaces", "halfspaces": [{"normal": (-tangent[i]).tolist(), "offset": 0.0}]})
    radii = sp * rng.uniform(0.2, 0.7, n)
    return {
        "points": q.tolist(),
        "closed": True,
        "k": k,
        "constraint": {"type": "balls", "radii": radii.tolist()},
        "tangents": sets,
    }


def derivative(p, t, j):
    """Df(t_j) of the closed curve p on knots t by the "bessel" rule (`derivatives.py`)."""
    return sum(w * p[v] for v, w in derivative_rows(np.diff(t), True, j, "bessel").items())


def check(prob, res):
    bad = []
    if not res["kkt_residual"] <= 1e-9:
        bad.append(f"kkt {res['kkt_residual']}")
    q = np.array(prob["points"])
    p = np.array(res["points"])
    dv = np.array(res["data_vertex"])
    extent = np.abs(p - p.mean(0)).max()
    radii = np.array(prob["constraint"]["radii"])
    e = (np.linalg.norm(p[dv] - q, axis=1) - radii).max()
    if e > 1e-9 * extent:
        bad.append(f"ball {e:.3g}")
    t = np.array(res["knots"])
    # (A wedge is a cone: Df = 0, the curve stopping at its apex, is in it; its violation is
    # measured against the curve's typical speed, not its own |Df|.)
    speed = np.median([np.linalg.norm(derivative(p, t, j)) for j in range(len(p))])
    for i, s in enumerate(prob["tangents"]):
        if s is None:
            continue
        v = derivative(p, t, dv[i])
        if s["type"] == "wedge":
            a = np.array(s["direction"])
            # v·a ≥ |v| cos θ.
            e = np.linalg.norm(v) * np.cos(s["half_angle"]) - v @ a
            scale = speed
        elif s["type"] == "ball":
            e = np.linalg.norm(v - np.array(s["center"])) - s["radius"]
            scale = np.linalg.norm(s["center"]) + s["radius"]
        elif s["type"] == "tension":
            e = np.linalg.norm(v) - s["radius"]
            scale = s["radius"]
        else:
            h = s["halfspaces"][0]
            e = np.array(h["normal"]) @ v - h["offset"]
            scale = speed
        if e > 1e-7 * scale:
            bad.append(f"tangent {i} {s['type']} {e:.3g}")
            break
    return bad


def main():
    counts, failures = {}, 0
    t0 = time.time()
    for n in (2000, 5000, 10000):
        for k in (3, 7):
            for kind in ("wedge", "ball", "tension", "halfspaces"):
                for seed in range(1, SEEDS + 1):
                    prob = problem(n, k, kind, seed)
                    name = f"{kind}-{n}-{k}-{seed}"
                    path = os.path.join(OUT, f"{name}.json")
                    out = os.path.join(OUT, f"{name}.out.json")
                    with open(path, "w") as f:
                        json.dump(prob, f)
                    if os.path.exists(out):
                        os.remove(out)
                    start = time.time()
                    try:
                        r = subprocess.run([BIN, "refine", path, "-o", out, "-q"], capture_output=True, text=True, timeout=600)
                        code = r.returncode
                    except subprocess.TimeoutExpired:
                        code, r = "timeout", None
                    dt = time.time() - start
                    c = counts.setdefault(kind, {"certified": 0, "refused": 0})
                    if code == 0:
                        with open(out) as f:
                            bad = check(prob, json.load(f))
                        c["certified"] += 1
                        if bad:
                            failures += 1
                            print(f"BAD {name}: {bad}", flush=True)
                    elif code == 2 and not os.path.exists(out):
                        c["refused"] += 1
                        print(f"refused {name} ({dt:.1f} s): {r.stderr.strip()[:160]}", flush=True)
                    else:
                        failures += 1
                        print(f"BAD {name}: exit {code}", flush=True)
    print(json.dumps(counts), f"{time.time() - t0:.0f} s", flush=True)
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
