"""The package's curves against scipy, an independent implementation of the same splines.

* natural: Warren–Weimer's limit curve is the natural cubic spline through its values on Z,
  N p_0 (N: end rows unit vectors, interior rows (1/6, 2/3, 1/6); Warren–Weimer §6.3, restated
  in the project's docs/math.md §5). With scipy's ``CubicSpline(bc_type="natural")`` through
  those values as f, every level's points are f's B-spline control points: for a uniform cubic
  spline on the grid h = 2^-k, control point c_j = f(jh) − h² f''(jh)/6 (f(jh) = (c_{j−1} +
  4c_j + c_{j+1})/6 and f''(jh) = (c_{j−1} − 2c_j + c_{j+1})/h²; at the natural ends f'' = 0 and
  c_0 = f(0)). The limit energy is ∫‖f''‖², computed from scipy's coefficients in closed form.
* strip: with no bounds, or bounds the natural spline stays inside, the best interpolant in
  the strip is the natural cubic spline through the data: scipy's ``CubicSpline(bc_type=
  "natural")``; with end slopes, ``bc_type=((1, a), (1, b))``. The result, called like a PPoly,
  equals its own ``to_ppoly()``.
"""

import numpy as np
import pytest
from scipy.interpolate import CubicSpline, PPoly

import curvefit


def energy_of(pp: PPoly) -> float:
    """∫ f''² of a piecewise cubic, exactly: f'' = 2c2 + 6c3 s on each piece of length h."""
    c = pp.c  # (4, m, ...) descending powers
    h = np.diff(pp.x)
    h = h.reshape(h.shape + (1,) * (c.ndim - 2))
    a, b = 2.0 * c[1], 6.0 * c[0]  # f'' = a + b s
    return float(np.sum(a * a * h + a * b * h**2 + b * b * h**3 / 3.0))


def limit_values(p0):
    """N p_0: the natural scheme's limit on Z (end rows unit vectors, interior (1, 4, 1)/6)."""
    v = p0.copy()
    v[1:-1] = (p0[:-2] + 4.0 * p0[1:-1] + p0[2:]) / 6.0
    return v


@pytest.mark.parametrize("d", [1, 2, 3])
def test_natural_limit_is_scipys_natural_spline(d):
    rng = np.random.default_rng(7 + d)
    p0 = rng.normal(size=(9, d)) * np.array([1.0, 5.0, 0.1][:d])
    levels = 6
    r = curvefit.natural(p0, levels=levels)
    L = len(p0) - 1
    f = CubicSpline(np.arange(L + 1.0), limit_values(p0), bc_type="natural")
    scale = np.abs(p0).max()
    for lv in r.levels:
        h = 2.0 ** -lv.level
        x = np.arange(2**lv.level * L + 1) * h
        control = f(x) - h * h * f(x, 2) / 6.0
        assert lv.points.shape == control.shape
        assert np.abs(lv.points - control).max() <= 1e-12 * scale, lv.level
    assert r.limit_energy == pytest.approx(energy_of(f), rel=1e-11)
    # The level energies decrease to the limit's (Theorem 6.4).
    e = [lv.energy for lv in r.levels]
    assert all(a > b for a, b in zip(e, e[1:])) and e[-1] > r.limit_energy


def jittered(n, seed):
    rng = np.random.default_rng(seed)
    t = np.cumsum(rng.uniform(0.05, 2.0, n))  # very unequal spans
    y = np.sin(t) + 0.3 * rng.normal(size=n)
    return t, y


@pytest.mark.parametrize("n", [2, 3, 7, 40])
def test_inactive_strip_is_scipys_natural_spline(n):
    t, y = jittered(n, n)
    x = np.linspace(t[0] - 0.5, t[-1] + 0.5, 2001)
    f = CubicSpline(t, y, bc_type="natural")
    scale = np.abs(y).max()
    s = curvefit.strip(t, y)
    assert s.extra_knots == []
    for nu in range(4):
        assert np.abs(s(x, nu) - f(x, nu)).max() <= 1e-9 * scale * (1 + np.ptp(t)) ** nu, nu
    assert s.energy == pytest.approx(energy_of(f), rel=1e-9)
    assert s.norm == pytest.approx(np.sqrt(s.energy), rel=1e-15)
    # Bounds that the natural spline stays well inside are inactive: the same spline.
    lo = f(x).min() - 1.0
    hi = f(x).max() + 1.0
    b = curvefit.strip(
        t,
        y,
        lower={"polyline": [[t[0], lo], [t[-1], lo]]},
        upper={"pieces": np.tile([hi, 0.0, 0.0, 0.0], (n - 1, 1))},
    )
    assert b.extra_knots == []
    assert np.abs(b(x) - f(x)).max() <= 1e-9 * scale


def test_clamped_strip_is_scipys_clamped_spline():
    t, y = jittered(12, 3)
    f = CubicSpline(t, y, bc_type=((1, 0.5), (1, -2.0)))
    x = np.linspace(t[0], t[-1], 999)
    for s in (
        curvefit.strip(t, y, end_slopes=[0.5, -2.0]),
        curvefit.strip(t, y, bc_type=((1, 0.5), (1, -2.0))),
    ):
        assert np.abs(s(x) - f(x)).max() <= 1e-9 * np.abs(y).max()
        assert s.slopes[0] == pytest.approx(0.5, abs=1e-9)
    mixed = curvefit.strip(t, y, bc_type=((1, 0.5), (2, 0.0)))
    g = CubicSpline(t, y, bc_type=((1, 0.5), (2, 0.0)))
    assert np.abs(mixed(x) - g(x)).max() <= 1e-9 * np.abs(y).max()


def test_strip_result_is_a_ppoly():
    t = np.array([0.0, 1.0, 2.0, 3.0, 4.0])
    y = np.array([0.0, 1.0, 0.0, 0.0, 1.0])
    s = curvefit.strip(t, y, lower={"pieces": np.tile([-0.05, 0, 0, 0], (4, 1))})
    assert s.extra_knots, "the bound is active"
    assert {k.kind for k in s.extra_knots} <= {"touch_lower", "subarc_start_lower", "subarc_end_lower"}
    pp = s.to_ppoly()
    assert isinstance(pp, PPoly)
    x = np.linspace(-1, 5, 1203).reshape(3, 401)
    for nu in range(5):
        np.testing.assert_allclose(s(x, nu), pp(x, nu), rtol=1e-13, atol=1e-13)
    assert s(x).shape == x.shape
    assert np.ndim(s(2.5)) == 0
    inside = s(x, extrapolate=False)
    assert np.isnan(inside[x < 0]).all() and np.isnan(inside[x > 4]).all()
    np.testing.assert_allclose(inside[(x >= 0) & (x <= 4)], pp(x[(x >= 0) & (x <= 4)]), rtol=1e-13)
    # The bound holds on a fine grid, and the data are interpolated.
    fine = np.linspace(0, 4, 4001)
    assert s(fine).min() >= -0.05 - 1e-9
    np.testing.assert_allclose(s(t), y, atol=1e-12)
    assert energy_of(pp) == pytest.approx(s.energy, rel=1e-9)
    with pytest.raises(ValueError):
        s(x, -1)
