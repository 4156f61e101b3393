"""Mapping curvefit.refine over 10⁴ curves with Dask on a local cluster of two worker processes
(the pattern for a cluster of machines): the results equal the serial run's, field for field.
Problems and results travel between processes by pickle."""

import numpy as np
import pytest

import curvefit

dask = pytest.importorskip("dask")
distributed = pytest.importorskip("distributed")
import dask.bag as db  # noqa: E402
from dask.distributed import Client, LocalCluster  # noqa: E402

COUNT = 10_000


def curve(i):
    """Curve i: a noisy star of 6–13 points with jittered angles (deterministic in i)."""
    rng = np.random.default_rng(i)
    n = 6 + i % 8
    th = np.sort(2 * np.pi * (np.arange(n) + 0.35 * rng.uniform(-1, 1, n)) / n)
    r = 1 + 0.4 * (np.arange(n) % 2) + 0.05 * rng.normal(size=n)
    return np.column_stack([r * np.cos(th), r * np.sin(th)])


def solve(i):
    q = curve(i)
    kw = {"closed": True, "k": 3}
    if i % 2:
        kw["radii"] = np.full(len(q), 0.03)
    return curvefit.refine(q, **kw)


def test_dask_map_equals_the_serial_run():
    serial = [solve(i) for i in range(COUNT)]
    with LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    ) as cluster, Client(cluster) as client:
        bag = db.from_sequence(range(COUNT), npartitions=16).map(solve)
        distributed_results = bag.compute()
        # client.map over single tasks too: the results come back by pickle.
        futures = client.map(solve, range(50))
        some = client.gather(futures)
    assert len(distributed_results) == COUNT
    for i, (a, b) in enumerate(zip(serial, distributed_results)):
        assert type(b) is curvefit.RefineResult
        assert a.to_dict() == b.to_dict(), i
    assert [r.to_dict() for r in some] == [r.to_dict() for r in serial[:50]]
