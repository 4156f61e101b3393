"""refine_many: results in order, equal to one refine call per problem; errors in place; and
the GIL is released while Rust solves (other Python threads keep running)."""

import pickle
import threading
import time

import numpy as np
import pytest

import curvefit


def problems(count, seed=0):
    rng = np.random.default_rng(seed)
    out = []
    for i in range(count):
        n = 5 + i % 7
        th = np.sort(2 * np.pi * (np.arange(n) + 0.3 * rng.uniform(-1, 1, n)) / n)
        r = 1 + 0.4 * rng.uniform(size=n)
        q = np.column_stack([r * np.cos(th), r * np.sin(th)])
        p = {"points": q, "closed": bool(i % 2), "k": 1 + i % 4}
        if i % 3 == 1:
            p["radii"] = rng.uniform(0, 0.1, n)
        elif i % 5 == 2:
            p["constraint"] = {"type": "smoothing", "weights": rng.uniform(1, 100, n)}
        out.append(p)
    return out


def test_many_equals_one_at_a_time():
    ps = problems(60)
    serial = [curvefit.refine(**p).to_dict() for p in ps]
    for threads in (None, 1, 2, 3):
        many = curvefit.refine_many(ps, threads=threads)
        assert len(many) == len(ps)
        assert [r.to_dict() for r in many] == serial, threads


def test_many_returns_errors_in_place():
    ps = problems(6)
    ps[1] = dict(ps[1], k=0)
    ps[3] = {"points": [[0, 0], [1, 0], [1, 0]]}
    ps[4] = dict(ps[4], radii=[-1.0] * len(ps[4]["points"]))
    ps.append("not a problem")
    out = curvefit.refine_many(ps)
    kinds = [type(r).__name__ for r in out]
    assert kinds == ["RefineResult", "InputError", "RefineResult", "InputError", "InputError", "RefineResult", "InputError"]
    for i in (1, 3, 4):
        with pytest.raises(curvefit.InputError) as e:
            curvefit.refine(**ps[i])
        assert (out[i].field, out[i].index, out[i].message) == (e.value.field, e.value.index, e.value.message)
    assert out[4].field == "radii[0]"
    assert out[6].field == "problem"
    assert curvefit.refine_many([]) == []


def test_results_pickle():
    r = curvefit.refine(**problems(2)[1])
    r2 = pickle.loads(pickle.dumps(r))
    assert r2.to_dict() == r.to_dict() and repr(r2) == repr(r)
    s = curvefit.strip([0, 1, 2, 3], [0, 1, 0, 1])
    s2 = pickle.loads(pickle.dumps(s))
    assert s2.to_dict() == s.to_dict() and float(s2(1.5)) == float(s(1.5))
    for obj in (
        curvefit.natural([[0], [1], [3]], levels=2),
        curvefit.scheme(4, 3, surface=True, polygon={"points": [[0, 0], [1, 0], [1, 1]]}),
        curvefit.surface(np.zeros((2, 2, 3)) + np.arange(4.0).reshape(2, 2, 1)),
    ):
        assert pickle.loads(pickle.dumps(obj)).to_dict() == obj.to_dict()


def test_the_gil_is_released_during_a_solve():
    """A Python thread keeps ticking while another thread is inside a long solve: the longest
    pause between its ticks is a small part of the solve (with the GIL held it would be all
    of it). The problem is sized for a solve of ~0.1 s on a 2-core machine (at n = 6·10⁴
    it took 39–46 ms once mimalloc stopped requesting huge pages, under the 50 ms asserted)."""
    n = 200_000
    th = 2 * np.pi * np.arange(n) / n
    q = np.column_stack([np.cos(th), np.sin(th)]) * (1 + 0.2 * np.cos(7 * th))[:, None]
    ticks = []
    done = threading.Event()
    span = {}

    def solve():
        t0 = time.perf_counter()
        curvefit.refine(q, closed=True, k=7, knot_iterations=3)
        span["solve"] = (t0, time.perf_counter())
        done.set()

    worker = threading.Thread(target=solve)
    worker.start()
    while not done.is_set():
        ticks.append(time.perf_counter())
        time.sleep(0.001)
    worker.join()
    t0, t1 = span["solve"]
    inside = [t for t in ticks if t0 <= t <= t1]
    assert t1 - t0 > 0.05, "the solve is long enough to observe"
    gaps = np.diff([t0] + inside + [t1])
    assert gaps.max() < 0.5 * (t1 - t0), (gaps.max(), t1 - t0)
    assert len(inside) >= 10
