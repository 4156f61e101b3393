//! The bounds of a normalized cell, and a candidate of the per-interval problem: knots, values and slopes (Hermite data at every
//! knot), one Hermite cubic per piece.

use crate::piece::cubic3;
use crate::types::{Shape, Side};

/// A candidate: knots, values and slopes (Hermite data at every knot), at most four knots.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Pw {
    pub n: usize,
    pub x: [f64; 4],
    pub v: [f64; 4],
    pub m: [f64; 4],
    /// The magnitude of the terms each value was computed from (0 for the data at the cell's
    /// ends; Σ|g_k|τ^k for a bound's value at a contact τ): its rounding is u times this.
    pub vm: [f64; 4],
}

/// f'' at the left and right end of the Hermite cubic on a piece of length `l`.
#[inline]
pub(crate) fn ends(l: f64, v0: f64, v1: f64, m0: f64, m1: f64) -> (f64, f64) {
    let d = (v1 - v0) / l;
    (
        (6.0 * d - 4.0 * m0 - 2.0 * m1) / l,
        (-6.0 * d + 2.0 * m0 + 4.0 * m1) / l,
    )
}

/// The magnitudes of the terms that make up f'' at the left and right end of the Hermite cubic on
/// a piece of length `l` (see [`ends`]): (6(|v1 − v0| + e0 + e1)/l + 4|m0| + 2|m1|)/l and its
/// mirror, e0 and e1 the magnitudes the values were computed from (a bound's value at a contact
/// carries the rounding of its polynomial's terms; the difference v1 − v0 is exact or rounded
/// relative to itself). The computed f'' at that end is off by a few u times this (u = 2⁻⁵³): the
/// rounding level of an f'' jump at a break is measured against it ([`crate::types::C2_ROUNDING`]).
#[inline]
pub(crate) fn end_terms(l: f64, v: [f64; 2], e: [f64; 2], m0: f64, m1: f64) -> (f64, f64) {
    let v = 6.0 * ((v[1] - v[0]).abs() + e[0] + e[1]) / l;
    (
        (v + 4.0 * m0.abs() + 2.0 * m1.abs()) / l,
        (v + 2.0 * m0.abs() + 4.0 * m1.abs()) / l,
    )
}

impl Pw {
    pub(crate) fn piece(&self, j: usize) -> (f64, f64, f64) {
        let l = self.x[j + 1] - self.x[j];
        let (a, b) = ends(l, self.v[j], self.v[j + 1], self.m[j], self.m[j + 1]);
        (l, a, b)
    }
    /// ∫ f''² over [0, 1] (f'' is linear on each piece).
    pub fn energy(&self) -> f64 {
        (0..self.n - 1)
            .map(|j| {
                let (l, a, b) = self.piece(j);
                l / 3.0 * (a * a + a * b + b * b)
            })
            .sum()
    }
    /// Jumps f''(x_j−) − f''(x_j+) at the interior knots.
    pub fn jumps2(&self) -> [f64; 2] {
        let mut r = [0.0; 2];
        for j in 1..self.n - 1 {
            let (_, _, b) = self.piece(j - 1);
            let (_, a, _) = self.piece(j);
            r[j - 1] = b - a;
        }
        r
    }
    /// [`end_terms`] of piece j.
    pub(crate) fn terms(&self, j: usize) -> (f64, f64) {
        let l = self.x[j + 1] - self.x[j];
        end_terms(
            l,
            [self.v[j], self.v[j + 1]],
            [self.vm[j], self.vm[j + 1]],
            self.m[j],
            self.m[j + 1],
        )
    }
    /// The largest |f''| at a piece end.
    pub(crate) fn f2_max(&self) -> f64 {
        (0..self.n - 1).fold(0.0f64, |s, j| {
            let (_, a, b) = self.piece(j);
            s.max(a.abs()).max(b.abs())
        })
    }
    /// The rounding level of the jumps [`Pw::jumps2`] at the interior knots, given the largest
    /// |f''| `f2` of the whole solution (cell units): [`crate::types::C2_ROUNDING`] times f2 plus
    /// the [`end_terms`] of the two pieces meeting there.
    pub(crate) fn jumps2_floor(&self, f2: f64) -> [f64; 2] {
        let mut r = [0.0; 2];
        for j in 1..self.n - 1 {
            let (_, left) = self.terms(j - 1);
            let (right, _) = self.terms(j);
            r[j - 1] = crate::types::C2_ROUNDING * (f2 + left + right);
        }
        r
    }
    /// Jumps f'''(x_j+) − f'''(x_j−) at the interior knots.
    pub fn jumps3(&self) -> [f64; 2] {
        let mut r = [0.0; 2];
        for j in 1..self.n - 1 {
            let (l0, a0, b0) = self.piece(j - 1);
            let (l1, a1, b1) = self.piece(j);
            r[j - 1] = (b1 - a1) / l1 - (b0 - a0) / l0;
        }
        r
    }
    /// Gradient of the energy with respect to (y0, z0, y1, z1):
    /// (2f'''(0+), −2f''(0+), −2f'''(1−), 2f''(1−)).
    pub fn grad(&self) -> [f64; 4] {
        let (l0, a0, b0) = self.piece(0);
        let (l1, a1, b1) = self.piece(self.n - 2);
        [
            2.0 * (b0 - a0) / l0,
            -2.0 * a0,
            -2.0 * (b1 - a1) / l1,
            2.0 * b1,
        ]
    }
    /// Monomial coefficients of piece j in s = x − x_j.
    pub fn coeffs(&self, j: usize) -> [f64; 4] {
        let l = self.x[j + 1] - self.x[j];
        let (v0, v1, m0, m1) = (self.v[j], self.v[j + 1], self.m[j], self.m[j + 1]);
        let d = (v1 - v0) / l;
        [
            v0,
            m0,
            (3.0 * d - 2.0 * m0 - m1) / l,
            (m0 + m1 - 2.0 * d) / (l * l),
        ]
    }
}

/// Σ|g_k| x^k: the magnitude of the terms of the cubic g at x ≥ 0.
fn magnitude(g: &[f64; 4], x: f64) -> f64 {
    g[0].abs() + x * (g[1].abs() + x * (g[2].abs() + x * g[3].abs()))
}

/// Builds the candidate of `shape` with extra knots `tau` (None if the knots are out of order).
pub(crate) fn build(cell: &Cell, th: &[f64; 4], shape: Shape, tau: &[f64; 2]) -> Option<Pw> {
    let [y0, z0, y1, z1] = *th;
    let mut pw = Pw {
        n: 2,
        x: [0.0, 1.0, 0.0, 0.0],
        v: [y0, y1, 0.0, 0.0],
        m: [z0, z1, 0.0, 0.0],
        vm: [0.0; 4],
    };
    let (g1, g2, x1, x2) = match shape {
        Shape::Free => return Some(pw),
        Shape::Touch(s) => {
            let g = cell.bound(s)?;
            let t = tau[0];
            if !(t > 0.0 && t < 1.0) {
                return None;
            }
            let (gv, gd, _) = cubic3(g, t);
            pw.n = 3;
            pw.x = [0.0, t, 1.0, 0.0];
            pw.v = [y0, gv, y1, 0.0];
            pw.m = [z0, gd, z1, 0.0];
            pw.vm = [0.0, magnitude(g, t), 0.0, 0.0];
            return Some(pw);
        }
        Shape::Subarc(s) => {
            let g = cell.bound(s)?;
            (g, g, tau[0], tau[1])
        }
        Shape::Pair(s) => (cell.bound(s)?, cell.bound(s.other())?, tau[0], tau[1]),
    };
    if !(x1 > 0.0 && x1 < x2 && x2 < 1.0) {
        return None;
    }
    let (a, ad, _) = cubic3(g1, x1);
    let (b, bd, _) = cubic3(g2, x2);
    pw.n = 4;
    pw.x = [0.0, x1, x2, 1.0];
    pw.v = [y0, a, b, y1];
    pw.m = [z0, ad, bd, z1];
    pw.vm = [0.0, magnitude(g1, x1), magnitude(g2, x2), 0.0];
    Some(pw)
}

/// Bounds of one normalized cell: cubic coefficients in σ ∈ [0, 1].
#[derive(Clone, Copy, Debug)]
pub(crate) struct Cell {
    pub lower: Option<[f64; 4]>,
    pub upper: Option<[f64; 4]>,
}

impl Cell {
    pub(crate) fn bound(&self, s: Side) -> Option<&[f64; 4]> {
        match s {
            Side::Lower => self.lower.as_ref(),
            Side::Upper => self.upper.as_ref(),
        }
    }
}

/// The solution of one normalized cell.
#[derive(Clone, Copy, Debug)]
pub(crate) struct CellSolution {
    pub shape: Shape,
    pub tau: [f64; 2],
    pub pw: Pw,
    pub energy: f64,
    /// Whether the optimality certificate held.
    pub certified: bool,
}
