"""The large arrays (points, knots, radii, weights, t, y, a scheme's polygon) given as
C-contiguous float64 arrays are copied in bulk (crates/curvefit-py/src/bulk.rs), not walked
through serde: the results must equal those from the same values given as lists (which take the
element-by-element reader), the caller's dicts must stay as they were, and every array the bulk
path must not take (NaN, ±inf, wrong shape, empty) must fail exactly as the list does."""

import numpy as np
import pytest

import curvefit


def star(n, seed=3):
    rng = np.random.default_rng(seed)
    th = np.sort(2 * np.pi * (np.arange(n) + rng.uniform(-0.4, 0.4, n)) / n)
    r = 1 + 0.35 * (np.arange(n) % 2) + 0.05 * rng.normal(size=n)
    return np.column_stack([r * np.cos(th), r * np.sin(th)])


def as_lists(problem):
    """The problem with every numpy array, at any depth, as nested lists."""
    if isinstance(problem, dict):
        return {k: as_lists(v) for k, v in problem.items()}
    if isinstance(problem, np.ndarray):
        return problem.tolist()
    return problem


def refine_problems():
    q = star(40)
    n = len(q)
    yield {"points": q, "closed": True, "k": 4}
    yield {"points": q, "k": 3, "constraint": {"type": "balls", "radii": np.linspace(0.01, 0.2, n)}}
    yield {"points": q, "k": 3, "constraint": {"type": "smoothing", "weights": np.linspace(5, 50, n)}}
    yield {"points": q, "k": 3, "knot_iterations": 0, "knots": np.cumsum(np.linspace(0.5, 1.5, n)) - 0.5}
    yield {"points": np.column_stack([star(30), np.linspace(0, 1, 30)]), "closed": True, "k": 2}


@pytest.mark.parametrize("problem", list(refine_problems()))
def test_bulk_arrays_give_the_results_lists_give(problem):
    assert curvefit.refine(**problem).to_dict() == curvefit.refine(**as_lists(problem)).to_dict()


def test_bulk_arrays_of_the_other_subcommands():
    t = np.linspace(0.0, 6.0, 25)
    y = 0.9 * np.sin(t)
    upper = {"polyline": [[0.0, 0.95], [6.0, 0.95]]}
    a = curvefit.strip(t=t, y=y, upper=upper)
    b = curvefit.strip(t=t.tolist(), y=y.tolist(), upper=upper)
    assert a.to_dict() == b.to_dict()
    q = star(12)
    assert curvefit.natural(q, levels=2).to_dict() == curvefit.natural(q.tolist(), levels=2).to_dict()
    poly = {"points": q, "closed": True}
    a = curvefit.scheme(points=4, arity=3, polygon=poly, levels=2)
    b = curvefit.scheme(points=4, arity=3, polygon=as_lists(poly), levels=2)
    assert a.to_dict() == b.to_dict()
    g = np.random.default_rng(0).normal(size=(12, 3))
    assert curvefit.surface(g, rows=4, cols=3).to_dict() == curvefit.surface(g.tolist(), rows=4, cols=3).to_dict()


def test_the_callers_dicts_are_not_changed():
    q = star(20)
    radii = np.full(20, 0.05)
    constraint = {"type": "balls", "radii": radii}
    problem = {"points": q, "constraint": constraint, "k": 3}
    curvefit.refine(**problem)
    assert problem["points"] is q and problem["constraint"] is constraint
    assert constraint == {"type": "balls", "radii": radii} and constraint["radii"] is radii
    # refine_many reads every problem the same way.
    [r] = curvefit.refine_many([problem])
    assert constraint["radii"] is radii and r.to_dict() == curvefit.refine(**as_lists(problem)).to_dict()


@pytest.mark.parametrize(
    "problem",
    [
        {"points": np.array([[0.0, 0.0], [1.0, np.nan], [0.0, 1.0]])},
        {"points": np.array([[0.0, 0.0], [1.0, 0.0], [0.0, -np.inf]]), "closed": True},
        {"points": np.zeros((0, 2))},
        {"points": np.zeros((3, 0))},
        {"points": np.array([0.0, 1.0, 2.0])},
        {"points": np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 0.0]])},
        {"points": star(5), "constraint": {"type": "balls", "radii": np.array([0.1, 0.1, np.nan, 0.1, 0.1])}},
        {"points": star(5), "constraint": {"type": "balls", "radii": np.full((5, 1), 0.1)}},
        {"points": star(5), "constraint": {"type": "balls", "radii": np.full(4, 0.1)}},
        {"points": star(5), "constraint": {"type": "smoothing", "weights": np.array([1.0, -1.0, 1.0, 1.0, 1.0])}},
        {"points": star(5), "knots": np.array([0.0, 1.0, 1.0, 2.0, 3.0])},
        {"points": star(5), "constraint": {"type": "balls", "radii": np.full(5, 0.1)}, "unknown": 1},
    ],
)
def test_arrays_the_bulk_path_refuses_fail_as_lists_do(problem):
    with pytest.raises(curvefit.InputError) as a:
        curvefit.refine(**problem)
    with pytest.raises(curvefit.InputError) as b:
        curvefit.refine(**as_lists(problem))
    assert (a.value.field, a.value.index, str(a.value)) == (b.value.field, b.value.index, str(b.value))
