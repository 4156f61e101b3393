"""Optimality of the binary's exact answers against an independent solver (Clarabel).

    python xtask/sweeps/refine.py SEED COUNT        # writes p*.json / r*.json to $SWEEP_OUT
    SWEEP_OUT=... python xtask/sweeps/optimality.py # numpy, scipy and clarabel needed

`refine.py` checks that an answer keeps to its constraints and claims a certificate ≤ 1e-9; it
cannot tell a feasible curve that is *not* the smoothest one from the optimum, because the
certificate is the code under test. This script can. For every answered problem of a refine sweep
whose program it can pose (fixed knots: `knot_iterations` 0, or the result's final knots, which the
certificate is for; interpolation, balls, half-spaces or smoothing; no tangents, ends or further
levels; the exact solver), it builds the conic program of docs/math.md §2 from the result's knots
alone — its own A of E = ½‖Ap‖² (Kersey (2.1)), not the library's — solves it with Clarabel, and
compares objectives:
- the answer's objective recomputed here must agree with the result's `energy` (smoothing adds
  ½ Σ w_i |p_i − q_i|²), and
- Clarabel must not find a feasible point (violation ≤ 1e-9 of the data's extent) whose objective
  is lower by more than 1e-7 relative: that would make the certified answer not optimal.
Points are centred and scaled to unit extent and the knots to unit length before Clarabel sees
them (the objective scales by a known factor), so data at 1e-3 or offset by 1e6 is posed well.
"""
import glob, json, os, re, sys
import numpy as np
import scipy.sparse as sp
import clarabel

OUT = os.environ.get("SWEEP_OUT", "/tmp/curvefit-sweep/refine")
MAX_VERTICES = int(os.environ.get("MAX_VERTICES", "20000"))
REL = 1e-7


def energy_rows(t, closed):
    """A with E = ½‖A p‖² for knots t_1..t_N (open) or t_1..t_{N+1} (closed): math.md §1."""
    h = np.diff(t)
    nv = len(h) if closed else len(t)
    if closed:
        i = np.arange(nv)
        hm, hp = h[i - 1], h[i]
        cols = np.stack([(i - 1) % nv, i, (i + 1) % nv], axis=1)
    else:
        i = np.arange(1, nv - 1)
        hm, hp = h[i - 1], h[i]
        cols = np.stack([i - 1, i, i + 1], axis=1)
    root = np.sqrt(hm + hp)
    a1 = np.sqrt(2) / (hm * root)
    a3 = np.sqrt(2) / (hp * root)
    vals = np.stack([a1, -a1 - a3, a3], axis=1)
    rows = np.repeat(np.arange(len(i)), 3)
    return sp.csr_matrix((vals.ravel(), (rows, cols.ravel())), shape=(len(i), nv))


def poseable(prob, res):
    c = prob.get("constraint", {"type": "interpolate"})["type"]
    return (c in ("interpolate", "balls", "halfspaces", "smoothing")
            and "tangents" not in prob and "boundary" not in prob
            and prob.get("levels", 0) == 0 and prob.get("solver", "exact") == "exact"
            and len(res["points"]) <= MAX_VERTICES)


def check(prob, res):
    closed = prob["closed"]
    q = np.array(prob["points"], float)
    n, d = q.shape
    p = np.array(res["points"], float)
    nv = len(p)
    t = np.array(res["knots"], float)
    dv = np.array(res["data_vertex"])
    con = prob.get("constraint", {"type": "interpolate"})
    kind = con["type"]
    # Normalize: points about the data's centroid to unit extent, knots to unit length.
    c0 = q.mean(axis=0)
    L = max(np.abs(q - c0).max(), 1e-300)
    tau = t[-1] - t[0]
    qn, pn, tn = (q - c0) / L, (p - c0) / L, (t - t[0]) / tau
    # E(p/L, t/τ) = τ³ E(p, t) / L²; smoothing weights follow so the objective scales alike.
    A = energy_rows(tn, closed)
    w = None
    if kind == "smoothing":
        w = np.array(con["weights"], float) * tau**3

    def objective(x):
        e = 0.5 * float(np.sum((A @ x) ** 2))
        if w is not None:
            e += 0.5 * float(np.sum(w * np.sum((x[dv] - qn) ** 2, axis=1)))
        return e

    ours = objective(pn)
    scale = tau**3 / L**2
    reported = res["energy"] * scale
    if kind == "smoothing":
        # (The result's energy is E alone or E plus the penalty: accept either, say which.)
        e_only = 0.5 * float(np.sum((A @ pn) ** 2))
        agree = min(abs(reported - ours), abs(reported - e_only))
    else:
        agree = abs(reported - ours)
    # The energy one rounding of the coordinates can carry (normalized units): below it two
    # energies cannot be told apart.
    floor = 100 * (np.finfo(float).eps * (np.abs(q).max() / L + 1)) ** 2 * float(A.multiply(A).sum()) * d
    bad = []
    if agree > 1e-8 * max(abs(ours), 1e-300) and agree > floor:
        bad.append(f"energy {res['energy']:.6e} disagrees with the recomputed {ours / scale:.6e}")

    # Clarabel: x = [p (nv·d), z (rows·d)], minimize ½‖z‖² (+ smoothing), (A ⊗ I) p = z.
    nz = A.shape[0] * d
    nx = nv * d
    Ad = sp.kron(A, sp.identity(d), format="csc")
    pdiag = np.concatenate([np.zeros(nx), np.ones(nz)])
    cvec = np.zeros(nx + nz)
    if w is not None:
        for i in range(n):
            for j in range(d):
                pdiag[dv[i] * d + j] += w[i]
                cvec[dv[i] * d + j] -= w[i] * qn[i, j]
    P = sp.diags(pdiag, format="csc")
    rows, bs, cones = [sp.hstack([Ad, -sp.identity(nz)], format="csc")], [np.zeros(nz)], [clarabel.ZeroConeT(nz)]

    def pick(i):
        return sp.csr_matrix((np.ones(d), (np.arange(d), dv[i] * d + np.arange(d))), shape=(d, nx + nz))

    if kind == "interpolate":
        rows += [pick(i) for i in range(n)]
        bs += [qn[i] for i in range(n)]
        cones.append(clarabel.ZeroConeT(n * d))
    elif kind == "balls":
        r = np.array(con["radii"], float) / L
        for i in range(n):
            if r[i] == 0:
                rows.append(pick(i)); bs.append(qn[i]); cones.append(clarabel.ZeroConeT(d))
            else:
                rows.append(sp.vstack([sp.csr_matrix((1, nx + nz)), pick(i)]))
                bs.append(np.concatenate([[r[i]], qn[i]]))
                cones.append(clarabel.SecondOrderConeT(d + 1))
    elif kind == "halfspaces":
        for i, hs in enumerate(con["sets"]):
            for h in hs:
                nvec = np.array(h["normal"], float)
                off = (h["offset"] - nvec @ c0) / L
                rows.append(sp.csr_matrix((nvec, (np.zeros(d, int), dv[i] * d + np.arange(d))), shape=(1, nx + nz)))
                bs.append(np.array([off]))
                cones.append(clarabel.NonnegativeConeT(1))
    Amat = sp.vstack(rows, format="csc")
    b = np.concatenate(bs)
    settings = clarabel.DefaultSettings()
    settings.verbose = False
    settings.time_limit = 120.0
    sol = clarabel.DefaultSolver(P, cvec, Amat, b, cones, settings).solve()
    x = np.asarray(sol.x)[:nx].reshape(nv, d)
    theirs = objective(x)
    # Clarabel's violation of the data constraints (normalized units: relative to the extent).
    viol = 0.0
    if kind == "interpolate":
        viol = np.abs(x[dv] - qn).max()
    elif kind == "balls":
        viol = max(0.0, float((np.linalg.norm(x[dv] - qn, axis=1) - np.array(con["radii"]) / L).max()))
    elif kind == "halfspaces":
        for i, hs in enumerate(con["sets"]):
            for h in hs:
                nvec = np.array(h["normal"], float)
                viol = max(viol, float(nvec @ x[dv[i]] - (h["offset"] - nvec @ c0) / L) / np.linalg.norm(nvec))
    gap = (ours - theirs) / max(abs(ours), abs(theirs), 1e-300)
    status = str(sol.status)
    # A point that violates the constraints by v can lower the energy by about v times the
    # reactions the constraints exert (Σ_i |(Hp)_{i_k}|, from the answer's own points).
    g = np.asarray(A.T @ (A @ pn))
    reactions = float(np.linalg.norm(g[dv], axis=1).sum())
    allowance = 10 * viol * reactions + floor
    # (Any feasible point of Clarabel's counts, whatever its status: it need not be optimal to
    # show that ours is not.)
    if viol <= 1e-9 and ours - theirs > REL * max(abs(ours), abs(theirs)) + allowance:
        bad.append(f"Clarabel found a feasible point {gap:.2e} lower ({theirs / scale:.9e} against {ours / scale:.9e}, its violation {viol:.1e})")
    return bad, gap, status, viol, c0 + L * x


def main():
    files = sorted(glob.glob(f"{OUT}/r*.json"), key=lambda f: int(re.findall(r"r(\d+)\.json", f)[0]))
    counts = {"posed": 0, "skipped": 0, "flagged": 0, "clarabel unsolved": 0}
    worst = (-np.inf, None)
    for f in files:
        case = int(re.findall(r"r(\d+)\.json", f)[0])
        try:
            res = json.load(open(f))
        except (json.JSONDecodeError, OSError):
            continue
        prob = json.load(open(f"{OUT}/p{case}.json"))
        if not poseable(prob, res):
            counts["skipped"] += 1
            continue
        counts["posed"] += 1
        bad, gap, status, viol, _ = check(prob, res)
        if status != "Solved" or viol > 1e-9:
            counts["clarabel unsolved"] += 1
        elif gap > worst[0]:
            worst = (gap, case)
        if bad:
            counts["flagged"] += 1
            c = prob.get("constraint", {"type": "interpolate"})["type"]
            print(f"BAD case {case} n={len(prob['points'])} d={len(prob['points'][0])} closed={prob['closed']} k={prob['k']} c={c}: {bad}", flush=True)
    print(counts, f"largest (ours − Clarabel)/|ours| where Clarabel solved feasibly: {worst[0]:.1e} (case {worst[1]})")
    return 1 if counts["flagged"] else 0


if __name__ == "__main__":
    sys.exit(main())
