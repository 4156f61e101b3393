"""Optimality of the binary's exact answers against an independent solver (Clarabel).

    python xtask/sweeps/refine.py SEED COUNT        # writes p*.json / r*.json to $SWEEP_OUT
    SWEEP_OUT=... python xtask/sweeps/optimality.py # numpy, scipy and clarabel needed

`refine.py` checks that an answer keeps to its constraints and claims a certificate ≤ 1e-9; it
cannot tell a feasible curve that is *not* the smoothest one from the optimum, because the
certificate is the code under test. This script can. For every answered problem of a refine sweep
whose program it can pose (fixed knots: `knot_iterations` 0, or the result's final knots, which the
certificate is for; interpolation, balls, half-spaces or smoothing, with any tangents and ends
(the derivative rules of docs/input.md written out here); no further levels; the exact solver;
no bound beyond 1e100), it builds the conic program of docs/math.md §2 from the result's knots
alone — its own A of E = ½‖Ap‖² (Kersey (2.1)), not the library's — solves it with Clarabel, and
compares objectives:
- the answer's energy E recomputed here must agree with the result's `energy` (the objective is
  E, plus ½ Σ w_i |p_i − q_i|² for smoothing), and
- Clarabel must not find a feasible point (violation ≤ 1e-9 of the data's extent, derivatives
  relative to the data's slopes) whose objective is lower by more than 1e-7 relative, plus what
  its violation and the coordinates' rounding explain: that would make the certified answer not
  optimal. Any status counts: a feasible point need not be optimal to show that ours is not.
Points are centred and scaled to unit extent and the spans to unit total length before Clarabel
sees them (the objective scales by a known factor), so data at 1e-3 or offset by 1e6 is posed
well.
"""
import glob, json, os, re, sys
import numpy as np
import scipy.sparse as sp
import clarabel

from derivatives import derivative_rows

OUT = os.environ.get("SWEEP_OUT", "/tmp/curvefit-sweep/refine")
MAX_VERTICES = int(os.environ.get("MAX_VERTICES", "20000"))
REL = 1e-7


def energy_rows(h, closed):
    """A with E = ½‖A p‖² for the spans h = diff(t) of knots t_1..t_N (open) or t_1..t_{N+1}
    (closed): math.md §1. (The Python bench, crates/curvefit-py/bench/bench.py, builds the same
    rows from the knots for its Clarabel peer; this one takes the spans, whose digits survive
    where knots of 1e6 hold spans of 1e-10, and the sweep does not import the package's bench,
    which imports the package.)"""
    nv = len(h) if closed else len(h) + 1
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
    # (Bounds far beyond the data, "no bound" written as 1e300, do not scale to a posed program.)
    huge = max((abs(x) for x in numbers(prob.get("tangents"), prob.get("boundary"))), default=0.0)
    return (c in ("interpolate", "balls", "halfspaces", "smoothing")
            and prob.get("levels", 0) == 0 and prob.get("solver", "exact") == "exact"
            and len(res["points"]) <= MAX_VERTICES and huge < 1e100)


def numbers(*xs):
    for x in xs:
        if isinstance(x, (int, float)) and not isinstance(x, bool):
            yield float(x)
        elif isinstance(x, dict):
            yield from numbers(*x.values())
        elif isinstance(x, list):
            yield from numbers(*x)


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
    # Normalize: points about the data's centroid to unit extent, spans to unit total length.
    c0 = q.mean(axis=0)
    L = max(np.abs(q - c0).max(), 1e-300)
    tau = t[-1] - t[0]
    # (The spans scaled, not the knots shifted: spans of 1e-10 beside knots of 1e6 keep their
    # digits.)
    qn, pn, hn = (q - c0) / L, (p - c0) / L, np.diff(t) / tau
    # E(p/L, t/τ) = τ³ E(p, t) / L²; smoothing weights follow so the objective scales alike.
    A = energy_rows(hn, closed)
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
    # (The result's `energy` is E of (2.1) alone, the smoothing penalty not included.)
    agree = abs(reported - 0.5 * float(np.sum((A @ pn) ** 2)))
    # The energy one rounding of the coordinates can carry (normalized units: a coordinate of
    # size |q|/L rounds by ε|q|/L): to first order the forces Σ_j |(Hp)_j| times it, to second
    # ‖A‖_F² times its square. Below it two energies cannot be told apart. (The solvers work about
    # the data's centroid; the points written out are rounded at their own size, which at 1e6 ± 0.02
    # moved E by 5.7e-7 of itself — and that size is the answer's where it lies farther out than
    # the data: a line through a point left free and one bounded on one side has E = 0 wherever
    # it lies, and seed 47 case 120 put it 1.8e4 from data 3e-4 apart, E = 1.7e-20 written.)
    g = np.asarray(A.T @ (A @ pn))
    reactions = float(np.linalg.norm(g, axis=1).sum())
    rounding = np.finfo(float).eps * (max(np.abs(q).max(), np.abs(p).max()) / L + 1)
    floor = 4 * reactions * rounding + 100 * rounding**2 * float(A.multiply(A).sum()) * d
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

    # The data constraints in normalized units, one entry per set: (i, "point", q_i),
    # (i, "ball", q_i, r_i) or (i, "half", n, c) for n·p_{i_k} ≤ c.
    data_sets = []
    if kind == "interpolate":
        data_sets = [(i, "point", qn[i]) for i in range(n)]
    elif kind == "balls":
        r = np.array(con["radii"], float) / L
        data_sets = [(i, "point", qn[i]) if r[i] == 0 else (i, "ball", qn[i], r[i]) for i in range(n)]
    elif kind == "halfspaces":
        for i, hs in enumerate(con["sets"]):
            for h in hs:
                nvec = np.array(h["normal"], float)
                data_sets.append((i, "half", nvec, (h["offset"] - nvec @ c0) / L))
    for i, ty, *par in data_sets:
        if ty == "point":
            rows.append(pick(i)); bs.append(par[0]); cones.append(clarabel.ZeroConeT(d))
        elif ty == "ball":
            rows.append(sp.vstack([sp.csr_matrix((1, nx + nz)), pick(i)]))
            bs.append(np.concatenate([[par[1]], par[0]]))
            cones.append(clarabel.SecondOrderConeT(d + 1))
        else:
            rows.append(sp.csr_matrix(par[0][None, :]) @ pick(i))
            bs.append(np.array([par[1]])); cones.append(clarabel.NonnegativeConeT(1))
    # Derivative constraints (tangents at data vertices, the ends of an open curve): Df' of the
    # normalized curve is τ/L times Df, so their vectors and radii scale by τ/L.
    rule = prob.get("derivative", "bessel")
    dscale = tau / L
    derivs = []  # (vertex, set)
    for i, tg in enumerate(prob.get("tangents") or []):
        if tg is not None:
            derivs.append((int(dv[i]), tg))
    bd = prob.get("boundary") or {"type": "natural"}
    if bd["type"] == "clamped":
        derivs += [(0, {"type": "equal", "value": bd["start"]}), (nv - 1, {"type": "equal", "value": bd["end"]})]
    elif bd["type"] == "near_clamped":
        derivs += [(0, {"type": "ball", "center": bd["start"], "radius": bd["radius"]}),
                   (nv - 1, {"type": "ball", "center": bd["end"], "radius": bd["radius"]})]
    dcheck = []  # (D as a d × (nx + nz) matrix, the set) for the violation of Clarabel's point
    for j, st in derivs:
        wts = derivative_rows(hn, closed, j, rule)
        cols = np.array([v * d + c for v in wts for c in range(d)])
        vals = np.array([wts[v] for v in wts for c in range(d)], float)
        rws = np.array([c for v in wts for c in range(d)])
        D = sp.csr_matrix((vals, (rws, cols)), shape=(d, nx + nz))
        dcheck.append((D, st))
        ty = st["type"]
        if ty == "equal":
            rows.append(D); bs.append(np.array(st["value"], float) * dscale); cones.append(clarabel.ZeroConeT(d))
        elif ty in ("ball", "tension"):
            v = np.array(st.get("center", [0.0] * d), float) * dscale
            rows.append(sp.vstack([sp.csr_matrix((1, nx + nz)), D]))
            bs.append(np.concatenate([[st["radius"] * dscale], v]))
            cones.append(clarabel.SecondOrderConeT(d + 1))
        elif ty == "wedge":
            a = np.array(st["direction"], float); a /= np.linalg.norm(a)
            ad = sp.csr_matrix(a[None, :]) @ D
            perp = D - sp.csr_matrix(a[:, None]) @ ad
            rows.append(-sp.vstack([np.tan(st["half_angle"]) * ad, perp]))
            bs.append(np.zeros(d + 1)); cones.append(clarabel.SecondOrderConeT(d + 1))
        elif ty == "halfspaces":
            for h in st["halfspaces"]:
                nvec = np.array(h["normal"], float)
                rows.append(sp.csr_matrix(nvec[None, :]) @ D)
                bs.append(np.array([h["offset"] * dscale])); cones.append(clarabel.NonnegativeConeT(1))
    Amat = sp.vstack(rows, format="csc")
    b = np.concatenate(bs)
    settings = clarabel.DefaultSettings()
    settings.verbose = False
    settings.time_limit = 120.0
    sol = clarabel.DefaultSolver(P, cvec, Amat, b, cones, settings).solve()
    x = np.asarray(sol.x)[:nx].reshape(nv, d).copy()
    # Clarabel's point put back onto the data constraints it grazes (its data vertices into their
    # balls, onto their points; half-spaces one by one), so that its remaining violation, which
    # the allowance below charges at ‖A‖_F² v² where spans are tiny, is that of the derivatives.
    def violation(i, ty, *par):
        if ty == "point":
            return float(np.abs(x[dv[i]] - par[0]).max())
        if ty == "ball":
            return float(np.linalg.norm(x[dv[i]] - par[0]) - par[1])
        return float(par[0] @ x[dv[i]] - par[1]) / np.linalg.norm(par[0])

    for i, ty, *par in data_sets:
        over = violation(i, ty, *par)
        if over <= 0:
            continue
        if ty == "point":
            x[dv[i]] = par[0]
        elif ty == "ball":
            gap_i = x[dv[i]] - par[0]
            x[dv[i]] = par[0] + gap_i * (par[1] / np.linalg.norm(gap_i))
        else:
            x[dv[i]] -= over * par[0] / np.linalg.norm(par[0])
    theirs = objective(x)
    # Clarabel's violation of the data constraints (normalized units: relative to the extent).
    viol = max([0.0] + [violation(i, ty, *par) for i, ty, *par in data_sets])
    # ... and of the derivative constraints, relative to the data's slopes (1 in normalized units).
    xz = np.concatenate([x.ravel(), np.zeros(nz)])
    for D, st in dcheck:
        df = D @ xz
        ty = st["type"]
        if ty == "equal":
            v = np.abs(df - np.array(st["value"], float) * dscale).max()
        elif ty in ("ball", "tension"):
            v = np.linalg.norm(df - np.array(st.get("center", [0.0] * d), float) * dscale) - st["radius"] * dscale
        elif ty == "wedge":
            a = np.array(st["direction"], float); a /= np.linalg.norm(a)
            v = np.linalg.norm(df - (a @ df) * a) - np.tan(st["half_angle"]) * (a @ df)
        else:
            v = max((np.array(h["normal"]) @ df - h["offset"] * dscale) / np.linalg.norm(h["normal"]) for h in st["halfspaces"])
        viol = max(viol, float(v))
    gap = (ours - theirs) / max(abs(ours), abs(theirs), 1e-300)
    status = str(sol.status)
    # A point that violates the constraints by v can lower the energy by about v times the
    # reactions the constraints exert (Σ_j |(Hp)_j|, from the answer's own points), and by up to
    # ‖A‖_F² v² more (spans of 1e-8 make that term 1e3 at v = 5e-11).
    # (Over every vertex: a derivative constraint's force acts on the vertices of its stencil, as
    # its multiplier over a span of at most 1 in normalized units.)
    allowance = 10 * (viol * reactions + viol**2 * float(A.multiply(A).sum()) * d) + floor
    # (Any feasible point of Clarabel's counts, whatever its status: it need not be optimal to
    # show that ours is not.)
    if viol <= 1e-9 and ours - theirs > REL * max(abs(ours), abs(theirs)) + allowance:
        bad.append(f"Clarabel found a feasible point {gap:.2e} lower ({theirs / scale:.9e} against {ours / scale:.9e}, its violation {viol:.1e})")
    resolution = allowance / max(abs(ours), abs(theirs), 1e-300)
    return bad, gap, status, viol, c0 + L * x, resolution


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
        bad, gap, status, viol, _, resolution = check(prob, res)
        if status != "Solved" or viol > 1e-9:
            counts["clarabel unsolved"] += 1
        elif resolution < REL and gap > worst[0]:
            worst = (gap, case)
        if bad:
            counts["flagged"] += 1
            c = prob.get("constraint", {"type": "interpolate"})["type"]
            print(f"BAD case {case} n={len(prob['points'])} d={len(prob['points'][0])} closed={prob['closed']} k={prob['k']} c={c}: {bad}", flush=True)
    print(counts, f"largest (ours − Clarabel)/|ours| where Clarabel solved feasibly and the energies resolve 1e-7: {worst[0]:.1e} (case {worst[1]})")
    return 1 if counts["flagged"] else 0


if __name__ == "__main__":
    sys.exit(main())
