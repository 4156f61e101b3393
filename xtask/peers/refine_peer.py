#!/usr/bin/env python3
"""Peer baseline for `cargo xtask bench refine`: scipy's periodic cubic spline.

Usage: refine_peer.py interp N K REPS
  Builds the same closed test curve as xtask/src/bench/refine.rs (data q_i on a wavy circle,
  centripetal parameters u_1 = 0, u_{i+1} = u_i + |q_{i+1} - q_i|^(1/2), closing span included),
  then times CubicSpline(u, q, bc_type='periodic') fit + evaluation at the (K+1)N parameters of
  the K-level split (every span cut into K+1 equal sub-spans). Prints one JSON line.
Exit code 3 when scipy is not importable (the bench then skips the comparison).
"""
import json
import sys
import time

try:
    import numpy as np
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


def main():
    if len(sys.argv) != 5 or sys.argv[1] != "interp":
        print(__doc__, file=sys.stderr)
        sys.exit(2)
    n, k, reps = int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4])
    print(json.dumps(interp(n, k, reps)))


if __name__ == "__main__":
    main()
