#!/usr/bin/env python3
"""curvefit from Python against scipy, Clarabel and csaps, all in this one process.

Usage: python bench.py [--quick] [--reps R]

Every case times the call a Python user makes, numpy in and numpy out (curvefit: the
``curvefit.refine`` call including reading the arrays and building the result object), as the
median of R repetitions after one warm-up call. Where the peer is fast enough (interpolation,
smoothing) the peer and curvefit are called in alternation and the ratio printed is the median
of the R pairs' ratios, so that the machine's drift during a run does not fall on one side of
it. Data: a noisy star with jittered angles
(r_i = 1 + 0.35·(i mod 2) + 0.05·N(0,1), θ_i = 2π(i + U(−0.4, 0.4))/n, sorted; seed fixed).

1. interpolation, closed, n = 10⁵, k = 7: ``curvefit.refine(q, closed=True, k=7,
   knot_iterations=0)`` (one solve on the centripetal data parameters, its KKT certificate
   included) against scipy ``CubicSpline(u, q, bc_type="periodic")`` fit + evaluation at the
   same (k + 1)·n parameters (every span cut into k + 1 equal sub-spans; u centripetal, the
   same data parameters). The same pairs again with every call after 50 ms asleep: a user's
   single call, not one right after the same call. Also the default three knot updates (four
   solves).
2. balls, closed, n = 10⁴, k = 3, knot_iterations = 0, radii in [0.2, 0.7] × the mean data
   spacing, on the noisy star (most balls active at the optimum) and on xtask's smooth wavy
   circle (most inactive): ``curvefit.refine(q, ..., radii=r)`` against Clarabel (Python) on the same
   second-order cone program, posed here from the formulas of docs/math.md §1–2 on the
   knots curvefit solved with: minimize ½‖z‖² s.t. z = (A ⊗ I_d) p (E = ½‖Ap‖², A's rows
   α_{i,1}, α_{i,2}, α_{i,3}), ‖p_{i_k} − q_i‖ ≤ r_i (the factored form: Clarabel stalls on
   P = H ⊗ I_d itself from n = 10⁴ on, H's condition number growing like N⁴; see
   xtask/src/bench/refine.rs). Clarabel's time is its setup (DefaultSolver: equilibration,
   symbolic factorization) plus solve(), and solve() alone; its answer is checked by the energy
   of its vertices against curvefit's and by its ball violations.
3. smoothing, open, n = 10⁵, k = 7: ``curvefit.refine(q, k=7, knot_iterations=0,
   weights=w)`` (minimize E + ½ Σ w_i‖p_{i_k} − q_i‖², E ≈ ½∫‖f''‖²) against csaps
   ``CubicSmoothingSpline(u, q.T, weights=w, smooth=0.5)`` (minimizes ½Σ w_i‖f(u_i) − q_i‖²
   + ½∫‖f''‖² — the continuous problem the discrete one approximates) fit + evaluation at the
   same parameters; the largest distance between the two curves is printed as a sanity check.
4. clamped interpolation, open, n = 10⁵, k = 7: ``curvefit.refine(q, closed=False, k=7,
   knot_iterations=0, boundary={"type": "clamped", "start": v0, "end": v1})`` (the end
   derivatives v0, v1 = the end chords over their parameter spans) against scipy
   ``CubicSpline(u, q, bc_type=((1, v0), (1, v1)))`` fit + evaluation at the same parameters
   (curvefit's ends hold the discrete derivative, scipy's the spline's; the largest distance
   between the two curves is printed as a sanity check).

Nothing is asserted: the printed ratios are what the README's table reports.
"""

import argparse
import os
import platform
import statistics
import sys
import time

import numpy as np

import curvefit


def star(n, seed=20261124, closed=True):
    rng = np.random.default_rng(seed)
    th = np.sort(2 * np.pi * (np.arange(n) + rng.uniform(-0.4, 0.4, n)) / n)
    if not closed:
        th = th * 0.9  # an open arc of the star
    r = 1 + 0.35 * (np.arange(n) % 2) + 0.05 * rng.normal(size=n)
    return np.column_stack([r * np.cos(th), r * np.sin(th)])


def centripetal(q, closed):
    pts = np.vstack([q, q[:1]]) if closed else q
    return np.concatenate([[0.0], np.cumsum(np.sqrt(np.linalg.norm(np.diff(pts, axis=0), axis=1)))])


def split(u, k):
    """The (k+1)·spans parameters of the k-level split (every span cut into k + 1 equal parts)."""
    m = k + 1
    s = np.arange(m) / m
    return (u[:-1, None] * (1.0 - s) + u[1:, None] * s).ravel()


# The pause before each call of the "after idle" pairs (interpolation): a user's single call
# finds the machine after other work or none, not right after the same call.
IDLE_S = 0.05


def timed(f, idle=0.0):
    if idle:
        time.sleep(idle)
    t0 = time.perf_counter()
    out = f()
    return time.perf_counter() - t0, out


def median_time(f, reps):
    f()
    times = []
    out = None
    for _ in range(reps):
        t, out = timed(f)
        times.append(t)
    return statistics.median(times), out


def paired_times(peer, ours, reps, idle=0.0):
    """Medians of `peer` and `ours` timed in alternation (one warm-up call each, then `reps`
    pairs, the pair's order swapped every other pair), and the median of the pairs' ratios
    peer/ours: a drift of the machine's speed during the run (this 2-core machine's speed moves
    by tens of per cent within seconds) falls on both sides of a pair instead of on one side of
    the ratio, and neither side always runs right after the other. With `idle`, every call
    comes after that many seconds asleep (not timed)."""
    peer()
    ours()
    tp, to, ratios = [], [], []
    out_p = out_o = None
    for i in range(reps):
        if i % 2 == 0:
            a, out_p = timed(peer, idle)
            b, out_o = timed(ours, idle)
        else:
            b, out_o = timed(ours, idle)
            a, out_p = timed(peer, idle)
        tp.append(a)
        to.append(b)
        ratios.append(a / b)
    return statistics.median(tp), statistics.median(to), statistics.median(ratios), out_p, out_o


def ms(t):
    return f"{t * 1e3:9.2f}"


def interpolation(n, k, reps):
    from scipy.interpolate import CubicSpline

    q = star(n)
    u = centripetal(q, closed=True)
    t = split(u, k)
    qc = np.vstack([q, q[:1]])

    def scipy_fit():
        return CubicSpline(u, qc, bc_type="periodic")(t)

    def ours():
        return curvefit.refine(q, closed=True, k=k, knot_iterations=0)

    ts, tc, ratio, ys, r = paired_times(scipy_fit, ours, reps)
    tsi, tci, ratio_idle, _, _ = paired_times(scipy_fit, ours, reps, IDLE_S)
    td, rd = median_time(lambda: curvefit.refine(q, closed=True, k=k), max(1, reps // 2))
    assert r.points.shape == ys.shape, (r.points.shape, ys.shape)
    print(f"1. interpolation, closed, n = {n}, k = {k}: {(k + 1) * n} points out")
    print(f"   scipy CubicSpline(periodic) fit + eval      {ms(ts)} ms")
    print(f"   curvefit.refine, knot_iterations = 0        {ms(tc)} ms   ratio {ratio:5.2f}x  (kkt {r.kkt_residual:.1e})")
    print(f"   the same pairs, each call after {IDLE_S * 1e3:.0f} ms idle: scipy {ms(tsi).strip()} ms, curvefit {ms(tci).strip()} ms, ratio {ratio_idle:5.2f}x")
    print(f"   curvefit.refine, default knot_iterations 3  {ms(td)} ms   ratio {ts / td:5.2f}x  (kkt {rd.kkt_residual:.1e})")
    return {"scipy": ts, "curvefit": tc, "ratio": ratio, "curvefit_default": td,
            "scipy_idle": tsi, "curvefit_idle": tci, "ratio_idle": ratio_idle}


def radii_for(q, seed=7):
    spacing = np.linalg.norm(np.diff(np.vstack([q, q[:1]]), axis=0), axis=1).mean()
    return (0.2 + 0.5 * np.random.default_rng(seed).uniform(size=len(q))) * spacing


def energy_rows(knots, closed):
    """A of E = ½‖Ap‖² (docs/math.md §1) as scipy.sparse, for knots t_1..t_N (open) or
    t_1..t_{N+1} (closed)."""
    import scipy.sparse as sp

    h = np.diff(knots)
    nv = len(h) if closed else len(knots)
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


def wavy_circle(n):
    """xtask's balls data (xtask/src/bench/refine.rs): r(θ) = 1 + 0.3 sin 5θ + 0.1 cos 17θ at
    θ_i = 2πi/n — smooth, so most balls are inactive at the optimum."""
    th = 2 * np.pi * np.arange(n) / n
    r = 1 + 0.3 * np.sin(5 * th) + 0.1 * np.cos(17 * th)
    return np.column_stack([r * np.cos(th), r * np.sin(th)])


def balls(n, reps, data="star"):
    import clarabel
    import scipy.sparse as sp

    q = star(n) if data == "star" else wavy_circle(n)
    rad = radii_for(q)
    k = 3
    tc, r = median_time(
        lambda: curvefit.refine(q, closed=True, k=k, knot_iterations=0, radii=rad), reps
    )
    d = q.shape[1]
    A = energy_rows(r.knots, closed=True)
    nv = len(r.points)
    Ad = sp.kron(A, sp.identity(d), format="csc")
    nz = Ad.shape[0]
    nx = nv * d
    # Variables x = [p (nv·d), z (nz)]; objective ½‖z‖².
    P = sp.block_diag([sp.csc_matrix((nx, nx)), sp.identity(nz)], format="csc")
    c = np.zeros(nx + nz)
    # Zero cone: (A ⊗ I) p − z = 0, written A x + s = b with b = 0.
    eq = sp.hstack([Ad, -sp.identity(nz)], format="csc")
    # Second-order cones: s = (r_i, q_i − p_{v_i}) = b − A x with A's rows picking p_{v_i}.
    dv = r.data_vertex
    soc_rows = []
    for j in range(d):
        soc_rows.append(sp.csr_matrix((np.ones(n), (np.arange(n), dv * d + j)), shape=(n, nx + nz)))
    # Interleave: per ball, one zero row (the radius) then d rows.
    blocks = [sp.csr_matrix((n, nx + nz))] + soc_rows
    order = np.arange((d + 1) * n).reshape(d + 1, n).T.ravel()
    soc = sp.vstack(blocks, format="csr")[order]
    b_soc = np.column_stack([rad, q]).ravel()
    Amat = sp.vstack([eq, soc], format="csc")
    b = np.concatenate([np.zeros(nz), b_soc])
    cones = [clarabel.ZeroConeT(nz)] + [clarabel.SecondOrderConeT(d + 1)] * n
    settings = clarabel.DefaultSettings()
    settings.verbose = False
    setup, solve, total, sol = [], [], [], None
    for _ in range(max(1, reps)):
        t0 = time.perf_counter()
        solver = clarabel.DefaultSolver(P, c, Amat, b, cones, settings)
        t1 = time.perf_counter()
        sol = solver.solve()
        t2 = time.perf_counter()
        setup.append(t1 - t0)
        solve.append(t2 - t1)
        total.append(t2 - t0)
    p = np.asarray(sol.x)[:nx].reshape(nv, d)
    e_clarabel = 0.5 * np.sum((A @ p) ** 2)
    viol = max(0.0, float((np.linalg.norm(p[dv] - q, axis=1) - rad).max()))
    tt, ts = statistics.median(total), statistics.median(solve)
    print(f"2. balls, closed, n = {n}, k = {k}, knot_iterations = 0, {data}: {nv} vertices, {int(r.active.sum())} of {n} balls active")
    print(f"   Clarabel (Python) setup + solve              {ms(tt)} ms   status {sol.status}, {sol.iterations} iterations")
    print(f"   Clarabel solve() alone                       {ms(ts)} ms")
    print(f"   curvefit.refine(radii=...)                   {ms(tc)} ms   ratio {tt / tc:6.1f}x (solve alone {ts / tc:6.1f}x)")
    print(f"   energy: curvefit {r.energy:.12e} (kkt {r.kkt_residual:.1e}); Clarabel's vertices {e_clarabel:.12e} "
          f"(rel. diff {(e_clarabel - r.energy) / r.energy:+.1e}, ball violation {viol:.1e})")
    return {"clarabel": tt, "clarabel_solve": ts, "curvefit": tc}


def smoothing(n, k, reps):
    import csaps

    q = star(n, closed=False)
    u = centripetal(q, closed=False)
    t = np.concatenate([split(u, k), u[-1:]])
    w = np.random.default_rng(3).uniform(50.0, 500.0, n)

    def peer():
        return csaps.CubicSmoothingSpline(u, q.T, weights=w, smooth=0.5)(t).T

    return against_a_curve(
        f"3. smoothing, open, n = {n}, k = {k}, weights in [50, 500]: {len(t)} points out",
        ("csaps", "csaps CubicSmoothingSpline fit + eval", peer),
        ("curvefit.refine(weights=...)", lambda: curvefit.refine(q, k=k, knot_iterations=0, weights=w)),
        reps,
    )


def against_a_curve(title, peer, ours, reps):
    """Times a peer that returns points and curvefit in pairs (`paired_times`), prints the two
    medians, the ratio and the largest distance between the two curves at the same parameters
    (a sanity check: the peer solves the continuous problem the discrete one approximates), and
    returns them. `peer` = (its key, its label, its call); `ours` = (label, call)."""
    key, peer_label, peer_call = peer
    ours_label, ours_call = ours
    ts, tc, ratio, ys, r = paired_times(peer_call, ours_call, reps)
    gap = np.linalg.norm(r.points - ys, axis=1).max()
    print(title)
    print(f"   {peer_label:<45}{ms(ts)} ms")
    print(f"   {ours_label:<45}{ms(tc)} ms   ratio {ratio:5.2f}x  (kkt {r.kkt_residual:.1e})")
    print(f"   largest distance between the two curves at the same parameters: {gap:.1e} (data spread ~1)")
    return {key: ts, "curvefit": tc, "ratio": ratio}


def clamped(n, k, reps):
    from scipy.interpolate import CubicSpline

    q = star(n, closed=False)
    u = centripetal(q, closed=False)
    t = np.concatenate([split(u, k), u[-1:]])
    v0 = (q[1] - q[0]) / (u[1] - u[0])
    v1 = (q[-1] - q[-2]) / (u[-1] - u[-2])
    ends = {"type": "clamped", "start": v0, "end": v1}

    def peer():
        return CubicSpline(u, q, bc_type=((1, v0), (1, v1)))(t)

    def ours():
        return curvefit.refine(q, closed=False, k=k, knot_iterations=0, boundary=ends)

    return against_a_curve(
        f"4. clamped interpolation, open, n = {n}, k = {k}: {len(t)} points out",
        ("scipy", "scipy CubicSpline(clamped) fit + eval", peer),
        ("curvefit.refine(boundary=clamped)", ours),
        reps,
    )


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="smaller sizes, fewer repetitions")
    ap.add_argument("--reps", type=int, default=None)
    a = ap.parse_args()
    reps = a.reps or (3 if a.quick else 7)
    print(f"curvefit {curvefit.__version__}, Python {platform.python_version()}, numpy {np.__version__}, "
          f"{os.cpu_count()} cores, load average {os.getloadavg()[0]:.2f} at start")
    interpolation(10_000 if a.quick else 100_000, 7, reps)
    balls(1_000 if a.quick else 10_000, max(1, min(reps, 3)), "star")
    balls(1_000 if a.quick else 10_000, max(1, min(reps, 3)), "wavy circle")
    smoothing(10_000 if a.quick else 100_000, 7, reps)
    clamped(10_000 if a.quick else 100_000, 7, reps)
    print(f"load average {os.getloadavg()[0]:.2f} at end")


if __name__ == "__main__":
    sys.exit(main())
