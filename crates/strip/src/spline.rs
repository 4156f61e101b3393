//! Cubic splines through given points, in the moment (second-derivative) formulation, and the
//! piecewise cubics the solver passes between its stages.
//!
//! With knots x_0 < … < x_K, values v_k and moments m_k = f''(x_k), the C² cubic spline solves
//! the tridiagonal system (h_{k−1}/6) m_{k−1} + ((h_{k−1} + h_k)/3) m_k + (h_k/6) m_{k+1} =
//! Δ_k − Δ_{k−1} (Δ_k = (v_{k+1} − v_k)/h_k) with natural ends m_0 = m_K = 0 or clamped ends
//! (h_0/3) m_0 + (h_0/6) m_1 = Δ_0 − s_0 and (h/6) m_{K−1} + (h/3) m_K = s_1 − Δ_{K−1}. The
//! matrix is strictly diagonally dominant whatever the spacing, so the solve is stable without
//! pivoting (its condition number is at most 3). By Holladay's theorem this spline has the least
//! ∫f''² among all functions through the points (with the given end slopes).

use banded::TridiagonalLu;

/// A piecewise cubic: `coeffs[j]` = \[c0, c1, c2, c3\] on \[breaks\[j\], breaks\[j+1\]\] in
/// s = t − breaks\[j\].
#[derive(Clone, Debug, Default)]
pub(crate) struct Curve {
    pub breaks: Vec<f64>,
    pub coeffs: Vec<[f64; 4]>,
}

impl Curve {
    /// Value and slope at t (the piece containing t; the right one at a break).
    pub fn eval(&self, t: f64) -> (f64, f64) {
        let n = self.coeffs.len();
        let j = self.breaks.partition_point(|b| *b <= t).clamp(1, n) - 1;
        let c = &self.coeffs[j];
        let s = t - self.breaks[j];
        (
            c[0] + s * (c[1] + s * (c[2] + s * c[3])),
            c[1] + s * (2.0 * c[2] + 3.0 * s * c[3]),
        )
    }
}

/// Scratch space of [`moments`]: the rows [sub, diagonal, super] and their LU factor (storage
/// reused from solve to solve).
#[derive(Default)]
pub(crate) struct Work {
    rows: Vec<[f64; 3]>,
    lu: TridiagonalLu,
}

/// The moments m of the spline through (x, v) with natural ends or the given end slopes, into
/// `m` (the tridiagonal system of the module docs).
pub(crate) fn moments(
    x: &[f64],
    v: &[f64],
    ends: [Option<f64>; 2],
    m: &mut Vec<f64>,
    w: &mut Work,
) {
    moments_with(x, v, None, ends, m, w);
}

/// [`moments`]; with `low` (the values' low parts, v_k + low_k), the right-hand sides
/// Δ_k − Δ_{k−1} from slopes carried with their roundings ([`crate::compensated::slope`]), so
/// that they keep the relative accuracy of their own size where the slopes nearly cancel (steep
/// data of small curvature: values 1e7 with slopes 3e4 and moments 10⁴ times smaller lose four
/// digits in the plain differences).
fn moments_with(
    x: &[f64],
    v: &[f64],
    low: Option<&[f64]>,
    ends: [Option<f64>; 2],
    m: &mut Vec<f64>,
    w: &mut Work,
) {
    let k = x.len();
    m.clear();
    m.resize(k, 0.0);
    w.rows.clear();
    w.rows.resize(k, [0.0, 1.0, 0.0]);
    let (rows, r) = (&mut w.rows, m);
    let (mut d_prev, mut c_prev) = (0.0, 0.0);
    let mut h_prev = 0.0;
    for i in 0..k - 1 {
        let h = x[i + 1] - x[i];
        let (d, c) = if let Some(l) = low {
            crate::compensated::slope(x[i], x[i + 1], v[i], v[i + 1], l[i], l[i + 1])
        } else {
            ((v[i + 1] - v[i]) / h, 0.0)
        };
        if i > 0 {
            rows[i] = [h_prev / 6.0, (h_prev + h) / 3.0, h / 6.0];
            r[i] = (d - d_prev) + (c - c_prev);
        } else if let Some(s) = ends[0] {
            rows[0] = [0.0, h / 3.0, h / 6.0];
            r[0] = (d - s) + c;
        }
        (d_prev, c_prev) = (d, c);
        h_prev = h;
    }
    if let Some(s) = ends[1] {
        rows[k - 1] = [h_prev / 6.0, h_prev / 3.0, 0.0];
        r[k - 1] = (s - d_prev) - c_prev;
    }
    // Diagonally dominant (module docs): only a non-finite input makes a pivot fail, and then
    // the moments are NaN, as the elimination itself would leave them.
    if w.lu.refactor(rows, 0.0).is_err() || w.lu.solve_in_place(r, 1).is_err() {
        r.fill(f64::NAN);
    }
}

/// A cubic spline through (x_k, v_k) with moments m_k; `low`, when not empty, the values' low
/// parts (through v_k + low_k: [`Spline::through_exactly`]).
#[derive(Clone, Debug)]
pub(crate) struct Spline {
    pub x: Vec<f64>,
    pub v: Vec<f64>,
    pub m: Vec<f64>,
    pub low: Vec<f64>,
}

impl Spline {
    /// The spline through the points with natural ends, or the given end slopes.
    pub fn through(x: Vec<f64>, v: Vec<f64>, ends: [Option<f64>; 2]) -> Spline {
        let mut m = Vec::new();
        moments(&x, &v, ends, &mut m, &mut Work::default());
        Spline {
            x,
            v,
            m,
            low: Vec::new(),
        }
    }

    /// The spline through (x_k, v_k + low_k) — values given with low parts, 0 for doubles taken
    /// as they are — with its moments' right-hand sides compensated (`moments_with`): to the
    /// accuracy the moment system allows (condition ≤ 3), not to its inputs' roundings. Its
    /// values stay the doubles v.
    pub fn through_exactly(
        x: Vec<f64>,
        v: Vec<f64>,
        low: &[f64],
        ends: [Option<f64>; 2],
    ) -> Spline {
        let mut m = Vec::new();
        moments_with(&x, &v, Some(low), ends, &mut m, &mut Work::default());
        Spline {
            x,
            v,
            m,
            low: low.to_vec(),
        }
    }

    /// f''' on piece k.
    pub(crate) fn third(&self, k: usize) -> f64 {
        (self.m[k + 1] - self.m[k]) / (self.x[k + 1] - self.x[k])
    }

    /// The jump f'''(x_k+) − f'''(x_k−) at interior knot k, and |f'''| on both sides (its
    /// scale).
    pub fn jump(&self, k: usize) -> (f64, f64) {
        let (l, r) = (self.third(k - 1), self.third(k));
        (r - l, l.abs() + r.abs())
    }

    /// ∫f''² (f'' is linear on each piece).
    pub fn energy(&self) -> f64 {
        (0..self.x.len() - 1)
            .map(|k| {
                let (a, b) = (self.m[k], self.m[k + 1]);
                (self.x[k + 1] - self.x[k]) / 3.0 * (a * a + a * b + b * b)
            })
            .sum()
    }

    /// The value and the second derivative at x (x within \[x_0, x_K\]).
    pub fn at(&self, x: f64) -> (f64, f64) {
        let n = self.x.len();
        let k = self.x.partition_point(|u| *u <= x).clamp(1, n - 1) - 1;
        let h = self.x[k + 1] - self.x[k];
        let (a, b) = ((self.x[k + 1] - x) / h, (x - self.x[k]) / h);
        (
            a * self.v[k]
                + b * self.v[k + 1]
                + ((a * a * a - a) * self.m[k] + (b * b * b - b) * self.m[k + 1]) * h * h / 6.0,
            a * self.m[k] + b * self.m[k + 1],
        )
    }

    /// The same function as a [`Curve`] (with low parts, each piece's slope from the values'
    /// compensated slope, as its moments are; its value the double v_k).
    pub fn to_curve(&self) -> Curve {
        let k = self.x.len();
        let coeffs = (0..k - 1)
            .map(|i| {
                let (h, m0, m1) = (self.x[i + 1] - self.x[i], self.m[i], self.m[i + 1]);
                [self.v[i], self.slope(i), 0.5 * m0, (m1 - m0) / (6.0 * h)]
            })
            .collect();
        Curve {
            breaks: self.x.clone(),
            coeffs,
        }
    }

    /// f' at the start of piece i, as [`Spline::to_curve`] writes it: the values' chord (with
    /// their low parts, compensated) less h(2m_i + m_{i+1})/6.
    pub fn slope(&self, i: usize) -> f64 {
        let (x, v) = (&self.x, &self.v);
        let h = x[i + 1] - x[i];
        let chord = match self.low.as_slice() {
            [] => (v[i + 1] - v[i]) / h,
            l => {
                let (d, c) =
                    crate::compensated::slope(x[i], x[i + 1], v[i], v[i + 1], l[i], l[i + 1]);
                d + c
            }
        };
        chord - h * (2.0 * self.m[i] + self.m[i + 1]) / 6.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn natural_and_clamped_splines_reproduce_cubics_and_lines() {
        // A cubic through 6 uneven points with its own end slopes is reproduced exactly by the
        // clamped spline; a line by the natural one.
        let x = vec![0.0, 0.3, 1.1, 1.2, 2.5, 3.0];
        let f = |t: f64| 1.0 - 2.0 * t + 0.5 * t * t - 0.25 * t * t * t;
        let df = |t: f64| -2.0 + t - 0.75 * t * t;
        let v: Vec<f64> = x.iter().map(|t| f(*t)).collect();
        let s = Spline::through(x.clone(), v, [Some(df(0.0)), Some(df(3.0))]);
        let c = s.to_curve();
        for k in 0..=60 {
            let t = 3.0 * k as f64 / 60.0;
            let (val, d) = c.eval(t);
            assert!(
                (val - f(t)).abs() < 1e-13 && (d - df(t)).abs() < 1e-12,
                "{t}"
            );
        }
        for k in 1..x.len() - 1 {
            assert!(s.jump(k).0.abs() < 1e-12);
        }
        let line: Vec<f64> = x.iter().map(|t| 2.0 - 0.5 * t).collect();
        let s = Spline::through(x.clone(), line, [None, None]);
        assert!(s.m.iter().all(|m| m.abs() < 1e-14) && s.energy() < 1e-26);
        for t in [0.0, 0.5, 2.9, 3.0] {
            assert!((s.at(t).0 - (2.0 - 0.5 * t)).abs() < 1e-14);
        }
    }
}
