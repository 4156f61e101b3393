#!/usr/bin/env python3
"""Peer baselines for `cargo xtask bench refine`.

Usage: refine_peer.py interp N K REPS
  scipy's periodic cubic spline. Builds the same closed test curve as xtask/src/bench/refine.rs
  (data q_i on a wavy circle, centripetal parameters u_1 = 0, u_{i+1} = u_i + |q_{i+1} - q_i|^(1/2),
  closing span included), then times CubicSpline(u, q, bc_type='periodic') fit + evaluation at the
  (K+1)N parameters of the K-level split (every span cut into K+1 equal sub-spans).

Usage: refine_peer.py balls FILE REPS [TIME_LIMIT_S]
  Clarabel (Python package) on the conic program FILE written by the bench (the one builder
  `clarabel_problem` in crates/refine/tests/kersey_support/mod.rs):
      minimize 1/2 x'Px + q'x + constant  s.t.  A x + s = b, s in K.
  FILE: one JSON header line (n_vars, m, p_nnz, a_nnz, n_cones, constant; padded with spaces so
  the binary part starts at a multiple of 8 bytes), then little-endian arrays in this order:
  P rows, P cols (int64), P values (float64) -- the upper triangle, repeated entries add --;
  q (float64, n_vars); A rows, A cols (int64), A values (float64); b (float64, m);
  cone kinds (int64: 0 zero, 1 second-order, 2 non-negative), cone dimensions (int64).
  Two settings: Clarabel's defaults (verbose off) and the defaults with tol_gap_abs, tol_gap_rel
  and tol_feas tightened to 1e-10. Each repetition constructs a fresh solver (timed as setup:
  DefaultSolver(...), which equilibrates and assembles/factors symbolically) and times
  solver.solve() alone; medians over REPS. TIME_LIMIT_S (optional) is Clarabel's time_limit.
  For each run: status, solve_s, setup_s, iterations, energy (obj_val + constant),
  energy_x (1/2 x'Px + q'x + constant recomputed here from x; loses digits to cancellation when
  P is large and E small), max_cone_violation of s = b - Ax, and x_file: the last solve's x,
  written as little-endian float64 to FILE.x.<settings> for the bench to evaluate and delete,
  and hit_time_limit (stopped by TIME_LIMIT_S short of Solved). When the default run hits the
  limit the tight run is skipped.

Each mode prints one JSON line. Exit code 3 when numpy/scipy (or, for balls, clarabel) is not
importable (the bench then skips the comparison with a message).
"""
import json
import sys
import time

try:
    import numpy as np
    import scipy.sparse as sp
    from scipy.interpolate import CubicSpline
except ImportError as e:  # pragma: no cover
    print(json.dumps({"skipped": str(e)}))
    sys.exit(3)


def curve(n):
    th = 2.0 * np.pi * np.arange(n) / n
    r = 1.0 + 0.3 * np.sin(5.0 * th) + 0.1 * np.cos(17.0 * th)
    return np.column_stack([r * np.cos(th), r * np.sin(th)])


def interp(n, k, reps):
    q = curve(n)
    qc = np.vstack([q, q[:1]])
    u = np.concatenate([[0.0], np.cumsum(np.sqrt(np.linalg.norm(np.diff(qc, axis=0), axis=1)))])
    m = k + 1
    s = np.arange(m) / m
    t = (u[:-1, None] * (1.0 - s) + u[1:, None] * s).ravel()

    def run():
        cs = CubicSpline(u, qc, bc_type="periodic")
        return cs(t)

    run()
    times = []
    for _ in range(reps):
        t0 = time.perf_counter()
        out = run()
        times.append(time.perf_counter() - t0)
    times.sort()
    return {"n": n, "k": k, "evaluations": int(out.shape[0]), "median_s": times[len(times) // 2]}


def load_socp(path):
    """Reads the bench's conic program (format in the module docstring)."""
    with open(path, "rb") as f:
        raw = f.read()
    nl = raw.index(b"\n")
    hdr = json.loads(raw[:nl])
    off = nl + 1

    def take(dtype, count):
        nonlocal off
        arr = np.frombuffer(raw, dtype=dtype, count=count, offset=off)
        off += 8 * count
        return arr

    n, m = hdr["n_vars"], hdr["m"]
    p_rows, p_cols, p_vals = take("<i8", hdr["p_nnz"]), take("<i8", hdr["p_nnz"]), take("<f8", hdr["p_nnz"])
    q = take("<f8", n).copy()
    a_rows, a_cols, a_vals = take("<i8", hdr["a_nnz"]), take("<i8", hdr["a_nnz"]), take("<f8", hdr["a_nnz"])
    b = take("<f8", m).copy()
    kinds, dims = take("<i8", hdr["n_cones"]), take("<i8", hdr["n_cones"])
    if off != len(raw):
        raise ValueError(f"{path}: {len(raw) - off} trailing bytes")
    # COO -> CSC sums repeated entries (as Clarabel's Rust new_from_triplets does).
    P = sp.coo_matrix((p_vals, (p_rows, p_cols)), shape=(n, n)).tocsc()
    A = sp.coo_matrix((a_vals, (a_rows, a_cols)), shape=(m, n)).tocsc()
    P.sort_indices()
    A.sort_indices()
    if sp.tril(P, k=-1).nnz:
        raise ValueError("P has entries below the diagonal")
    if int(dims.sum()) != m:
        raise ValueError("cone dimensions do not add up to the rows of A")
    return P, q, A, b, list(zip(kinds.tolist(), dims.tolist())), hdr["constant"]


def cone_objects(cones, clarabel):
    make = {0: clarabel.ZeroConeT, 1: clarabel.SecondOrderConeT, 2: clarabel.NonnegativeConeT}
    return [make[k](d) for k, d in cones]


def cone_violation(cones, s):
    """Largest violation of s in the product cone (0 when s is in it)."""
    worst = 0.0
    row = 0
    # Group equal (kind, dim) blocks that are consecutive, so 10^5 balls are one numpy call.
    i = 0
    while i < len(cones):
        j = i
        while j < len(cones) and cones[j] == cones[i]:
            j += 1
        kind, dim = cones[i]
        block = s[row:row + (j - i) * dim].reshape(j - i, dim)
        if kind == 0:
            v = np.abs(block).max()
        elif kind == 1:
            v = max(0.0, (np.linalg.norm(block[:, 1:], axis=1) - block[:, 0]).max())
        else:
            v = max(0.0, (-block).max())
        worst = max(worst, float(v))
        row += (j - i) * dim
        i = j
    return worst


def balls(path, reps, time_limit):
    try:
        import clarabel
    except ImportError as e:  # pragma: no cover
        print(json.dumps({"skipped": f"clarabel: {e}"}))
        sys.exit(3)
    P, q, A, b, cones, constant = load_socp(path)
    cone_list = cone_objects(cones, clarabel)

    def settings(tol):
        s = clarabel.DefaultSettings()
        s.verbose = False
        if time_limit is not None:
            s.time_limit = time_limit
        if tol is not None:
            s.tol_gap_abs = tol
            s.tol_gap_rel = tol
            s.tol_feas = tol
        return s

    def run(tol, label):
        setups, solves = [], []
        for _ in range(reps):
            st = settings(tol)
            t0 = time.perf_counter()
            solver = clarabel.DefaultSolver(P, q, A, b, cone_list, st)
            t1 = time.perf_counter()
            sol = solver.solve()
            t2 = time.perf_counter()
            setups.append(t1 - t0)
            solves.append(t2 - t1)
        x = np.asarray(sol.x)
        s = b - A @ x
        energy_x = 0.5 * (x @ (P @ x) + x @ (P.T @ x) - x @ (P.diagonal() * x)) + q @ x + constant
        setups.sort()
        solves.sort()
        x_file = f"{path}.x.{label}"
        x.astype("<f8").tofile(x_file)
        return {
            "status": str(sol.status),
            "solve_s": solves[len(solves) // 2],
            "setup_s": setups[len(setups) // 2],
            "clarabel_solve_time_s": sol.solve_time,
            "iterations": int(sol.iterations),
            "energy": sol.obj_val + constant,
            "energy_x": float(energy_x),
            "max_cone_violation": cone_violation(cones, s),
            "x_file": x_file,
            # Clarabel reports a run stopped by time_limit as MaxTime, or as AlmostSolved when
            # the reduced tolerances hold at that point: only the clock tells them apart. A run
            # that reaches Solved in the iteration that crosses the limit did finish.
            "hit_time_limit": time_limit is not None
            and str(sol.status) != "Solved"
            and sol.solve_time >= 0.99 * time_limit,
        }

    default = run(None, "default")
    if default["hit_time_limit"]:
        # Tighter tolerances would only run into the same limit.
        tight = {"skipped": "the default-settings run hit the time limit"}
    else:
        tight = run(1e-10, "tol_1e-10")
    return {
        "n_vars": P.shape[0],
        "m": A.shape[0],
        "clarabel": getattr(clarabel, "__version__", "?"),
        "default": default,
        "tol_1e-10": tight,
    }


def main():
    if len(sys.argv) == 5 and sys.argv[1] == "interp":
        n, k, reps = int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4])
        print(json.dumps(interp(n, k, reps)))
    elif len(sys.argv) in (4, 5) and sys.argv[1] == "balls":
        limit = float(sys.argv[4]) if len(sys.argv) == 5 else None
        print(json.dumps(balls(sys.argv[2], int(sys.argv[3]), limit)))
    else:
        print(__doc__, file=sys.stderr)
        sys.exit(2)


if __name__ == "__main__":
    main()
