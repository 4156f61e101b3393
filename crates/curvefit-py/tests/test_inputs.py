"""Inputs in any form numpy users have: float32, integer arrays, lists, tuples, non-contiguous
and negatively strided views, Fortran order, numpy scalars, d = 1, 2, 3 — each read once into
the problem and solved exactly as the float64 contiguous array of the same values."""

import numpy as np
import pytest

import curvefit


def star(n, d, seed=1):
    rng = np.random.default_rng(seed)
    th = np.sort(2 * np.pi * (np.arange(n) + 0.4 * rng.uniform(-1, 1, n)) / n)
    r = 1 + 0.35 * (np.arange(n) % 2) + 0.05 * rng.normal(size=n)
    cols = [r * np.cos(th), r * np.sin(th), 0.3 * np.sin(3 * th)]
    if d == 1:
        return np.cumsum(rng.uniform(0.1, 1.0, n))[:, None] * np.where(np.arange(n) % 3 == 0, 1, 0.97)[:, None]
    return np.column_stack(cols[:d])


def same(a, b):
    da, db = a.to_dict(), b.to_dict()
    assert da == db


@pytest.mark.parametrize("d", [1, 2, 3])
@pytest.mark.parametrize("closed", [False, True])
def test_forms_of_points_give_the_same_result(d, closed):
    q = star(11, d)
    kw = dict(closed=closed, k=3, radii=np.full(len(q), 0.02))
    ref = curvefit.refine(np.ascontiguousarray(q, dtype=np.float64), **kw)
    assert ref.points.shape[1] == d and ref.points.dtype == np.float64
    forms = {
        "list": q.tolist(),
        "tuple": tuple(tuple(p) for p in q.tolist()),
        "fortran": np.asfortranarray(q),
        "reversed twice": q[::-1][::-1],
        "strided": np.repeat(q, 2, axis=0)[::2],
        "column view": np.column_stack([q, np.zeros(len(q))])[:, :d],
        "list of arrays": [np.array(p) for p in q],
        "numpy scalars": [[np.float64(x) for x in p] for p in q],
    }
    for name, form in forms.items():
        got = curvefit.refine(form, **kw)
        assert got.to_dict() == ref.to_dict(), name
    # The radii in any form too.
    for radii in (np.full(len(q), 0.02, dtype=np.float64)[::-1], [0.02] * len(q), tuple([0.02] * len(q))):
        assert curvefit.refine(q, closed=closed, k=3, radii=radii).to_dict() == ref.to_dict()


def test_float32_and_integer_arrays_read_their_values():
    q32 = star(9, 2).astype(np.float32)
    a = curvefit.refine(q32, closed=True)
    b = curvefit.refine(q32.astype(np.float64), closed=True)
    assert a.to_dict() == b.to_dict()
    qi = np.array([[0, 0], [3, 1], [5, 4], [2, 6], [-1, 3]], dtype=np.int32)
    for dtype in (np.int8, np.int16, np.int32, np.int64, np.uint8, np.float16):
        q = qi.astype(dtype) if dtype not in (np.uint8,) else (qi + 1).astype(dtype)
        ref = curvefit.refine(q.astype(np.float64), closed=True)
        assert curvefit.refine(q, closed=True).to_dict() == ref.to_dict(), dtype
    # Integers where the JSON has integers: numpy integers, 0-d arrays.
    r = curvefit.refine(qi, closed=True, k=np.int64(4), knot_iterations=np.array(2))
    assert r.points.shape == (25, 2) and r.iterations.knot_updates == 2


def test_results_are_float64_arrays_of_the_json_shapes():
    q = star(10, 3)
    r = curvefit.refine(q, k=5)
    assert r.points.shape == (9 * 6 + 1, 3) and r.points.dtype == np.float64
    assert r.points.flags.c_contiguous
    assert r.knots.shape == (55,) and r.data_vertex.dtype == np.int64
    assert r.active.dtype == np.bool_ and r.active.shape == (10,)
    assert r.multipliers.shape == (10, 3)  # interpolation: the reaction, d values per point
    assert list(r.data_vertex) == list(range(0, 55, 6))
    # The data vertices interpolate (to rounding: the exact solver's polish step moves them by ulps).
    np.testing.assert_allclose(r.points[r.data_vertex], q, rtol=0, atol=1e-14)
    c = curvefit.refine(q, closed=True, k=5)
    assert c.points.shape == (60, 3) and c.knots.shape == (61,)
    s = curvefit.strip(np.arange(5.0), np.array([0, 1, 0, 1, 0.0]))
    assert s.coefficients.shape == (4, 4) and s.breaks.shape == (5,)
    g = curvefit.surface(np.random.default_rng(0).normal(size=(3, 4, 3)))
    assert g.points.shape == (5 * 7, 3) and g.quads.shape == (4 * 6, 4) and g.grid.shape == (5, 7, 3)
    n = curvefit.natural(np.arange(8.0).reshape(4, 2), levels=3)
    assert [lv.points.shape for lv in n.levels] == [(4, 2), (7, 2), (13, 2), (25, 2)]


def test_surface_grid_shape_equals_rows_cols():
    g = np.random.default_rng(1).normal(size=(4, 3, 3))
    a = curvefit.surface(g, closed=(True, False), levels=2)
    b = curvefit.surface(g.reshape(12, 3), rows=4, cols=3, closed=[True, False], levels=2)
    assert a.to_dict() == b.to_dict()


def test_inputs_are_not_modified():
    q = star(8, 2)
    before = q.copy()
    r = curvefit.refine(q, closed=True, k=2)
    np.testing.assert_array_equal(q, before)
    r.points[0, 0] = 99.0  # the result owns its arrays
    np.testing.assert_array_equal(q, before)


def test_array_likes_and_refused_python_types():
    class ArrayLike:
        """An object numpy converts through __array__ (like pandas' and xarray's)."""

        def __init__(self, a):
            self.a = a

        def __array__(self, dtype=None, copy=None):
            return self.a

    q = star(7, 2)
    assert curvefit.refine(ArrayLike(q), closed=True).to_dict() == curvefit.refine(q, closed=True).to_dict()
    for bad in (b"\x00\x01", bytearray(b"ab"), {1, 2}, object()):
        with pytest.raises(curvefit.InputError) as e:
            curvefit.refine(bad)
        assert e.value.field == "points", bad
