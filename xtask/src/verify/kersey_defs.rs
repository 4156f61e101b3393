//! Kersey's definitions (seed 000, §2, §3.6) evaluated from scratch, with no library code: the
//! oracle of the identity cases of `energy.rs` and of the free-knot and derivative cases of
//! `refine/`. Everything here follows the seed's formulas literally (0-based indices):
//!
//! - divided differences by the explicit formula 25.1.4 of Abramowitz–Stegun that the proof of
//!   Theorem 2.1 quotes, Δ_{i,k} f = Σ_j p_{i+j} / π'_{i,k}(t_{i+j});
//! - E(f) = Σ_i |Δ_{i−1,2} f|² h_{i−1,2} over every vertex of a closed curve (knots and points
//!   extended periodically) and the interior vertices of an open one (§3.6);
//! - the rows α_i of A (§2.1) with the periodic extension of the spans;
//! - jmp_i(D³f) = (h_{i−1,3}/h_i) Δ_{i−1,3} f − (h_{i−2,3}/h_{i−1}) Δ_{i−2,3} f (§2.2), i.e.
//!   (c_{i+1} − c_i)/h_i − (c_i − c_{i−1})/h_{i−1} with c_i = Δ_{i−1,2} f; on an open curve the
//!   second differences that do not exist (c_0, c_{N−1}) are 0 and a term whose span does not
//!   exist is dropped;
//! - Df(t_i) by (2.2) (average) and by the Bessel quadratic (what (2.3) intends), with the §3.6
//!   end rules of an open curve.

/// A polygon with knots: `t` has N values (open) or N + 1 (closed, the last closing the curve).
#[derive(Clone, Debug)]
pub struct Curve {
    pub t: Vec<f64>,
    pub p: Vec<Vec<f64>>,
    pub closed: bool,
}

/// Which approximate derivative Df(t_i).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Df {
    /// (2.2): ½(s_{i−1} + s_i); open ends: the one-sided slope.
    Average,
    /// The derivative at t_i of the quadratic through p_{i−1}, p_i, p_{i+1}; open ends: of the
    /// end quadratic at the end knot (§3.6).
    Bessel,
}

pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

pub fn norm2(a: &[f64]) -> f64 {
    dot(a, a)
}

pub fn sub(a: &[f64], b: &[f64]) -> Vec<f64> {
    a.iter().zip(b).map(|(x, y)| x - y).collect()
}

/// The Euclidean distance |a − b|.
pub fn dist(a: &[f64], b: &[f64]) -> f64 {
    norm2(&sub(a, b)).sqrt()
}

fn axpy(y: &mut [f64], a: f64, x: &[f64]) {
    for (u, v) in y.iter_mut().zip(x) {
        *u += a * v;
    }
}

impl Curve {
    /// From the library's knots and points (values copied; nothing else is used).
    pub fn from_lib(k: &divdiff::Knots, p: &divdiff::Points) -> Curve {
        Curve {
            t: k.values().to_vec(),
            p: p.to_rows(),
            closed: k.is_closed(),
        }
    }

    pub fn n(&self) -> usize {
        self.p.len()
    }

    pub fn dim(&self) -> usize {
        self.p[0].len()
    }

    /// The total parameter length T.
    pub fn length(&self) -> f64 {
        self.t[self.t.len() - 1] - self.t[0]
    }

    /// t_i, extended periodically for a closed curve (t_{i+N} = t_i + T).
    pub fn t(&self, i: isize) -> f64 {
        if self.closed {
            let n = self.n() as isize;
            let (q, r) = (i.div_euclid(n), i.rem_euclid(n));
            self.t[r as usize] + q as f64 * self.length()
        } else {
            self.t[i as usize]
        }
    }

    pub fn p(&self, i: isize) -> &[f64] {
        &self.p[i.rem_euclid(self.n() as isize) as usize]
    }

    pub fn h(&self, i: isize) -> f64 {
        self.t(i + 1) - self.t(i)
    }

    /// Whether span i exists (all spans of a closed curve; 0..N−2 of an open one).
    fn has_span(&self, i: isize) -> bool {
        self.closed || (0..self.n() as isize - 1).contains(&i)
    }

    /// Δ_{i,k} f = Σ_j p_{i+j} / π'(t_{i+j}) (explicit formula 25.1.4 of \[1\]).
    pub fn dd(&self, i: isize, k: usize) -> Vec<f64> {
        let mut out = vec![0.0; self.dim()];
        for j in 0..=k as isize {
            let tj = self.t(i + j);
            let dpi: f64 = (0..=k as isize)
                .filter(|&m| m != j)
                .map(|m| tj - self.t(i + m))
                .product();
            axpy(&mut out, 1.0 / dpi, self.p(i + j));
        }
        out
    }

    /// Slope of span i, [t_i, t_{i+1}] f.
    pub fn s(&self, i: isize) -> Vec<f64> {
        self.dd(i, 1)
    }

    /// c_i = Δ_{i−1,2} f, the second difference centred at vertex i; 0 at the ends of an open
    /// curve, where it does not exist.
    pub fn c(&self, i: isize) -> Vec<f64> {
        if !self.closed && (i <= 0 || i >= self.n() as isize - 1) {
            return vec![0.0; self.dim()];
        }
        self.dd(i - 1, 2)
    }

    /// The vertices whose term is in E: all (closed), 1..N−2 (open).
    pub fn energy_vertices(&self) -> std::ops::Range<usize> {
        if self.closed {
            0..self.n()
        } else {
            1..self.n() - 1
        }
    }

    /// The vertices whose parameter is free with T fixed: all (closed; vertex 0 moves t_0 and
    /// t_N together), the interior ones (open).
    pub fn free_vertices(&self) -> std::ops::Range<usize> {
        self.energy_vertices()
    }

    /// E(f) = Σ |Δ_{i−1,2} f|² h_{i−1,2} (Kersey §2, §3.6).
    pub fn energy(&self) -> f64 {
        self.energy_vertices()
            .map(|i| {
                let i = i as isize;
                norm2(&self.dd(i - 1, 2)) * (self.t(i + 1) - self.t(i - 1))
            })
            .sum()
    }

    /// Row i of A (§2.1): (α_{i,1}, α_{i,2}, α_{i,3}) on columns i − 1, i, i + 1.
    pub fn alpha(&self, i: usize) -> [f64; 3] {
        let i = i as isize;
        let (a, b) = (self.h(i - 1), self.h(i));
        let a1 = 2f64.sqrt() / (a * (a + b).sqrt());
        let a3 = 2f64.sqrt() / (b * (a + b).sqrt());
        [a1, -a1 - a3, a3]
    }

    /// jmp_i(D³f) (§2.2) with the open-curve conventions of the module docs.
    pub fn jmp(&self, i: usize) -> Vec<f64> {
        let i = i as isize;
        let mut out = vec![0.0; self.dim()];
        if self.has_span(i) {
            let (c1, c0) = (self.c(i + 1), self.c(i));
            for (o, (x, y)) in out.iter_mut().zip(c1.iter().zip(&c0)) {
                *o += (x - y) / self.h(i);
            }
        }
        if self.has_span(i - 1) {
            let (c1, c0) = (self.c(i), self.c(i - 1));
            for (o, (x, y)) in out.iter_mut().zip(c1.iter().zip(&c0)) {
                *o -= (x - y) / self.h(i - 1);
            }
        }
        out
    }

    /// jmp_i by the printed third-difference form, where Δ_{i−2,3} and Δ_{i−1,3} exist (every
    /// vertex of a closed curve, 2..N−3 of an open one); `None` elsewhere.
    pub fn jmp_third(&self, i: usize) -> Option<Vec<f64>> {
        let n = self.n();
        if !self.closed && !(2..n.saturating_sub(2)).contains(&i) {
            return None;
        }
        let i = i as isize;
        let (d1, d0) = (self.dd(i - 1, 3), self.dd(i - 2, 3));
        let (r, l) = (
            (self.t(i + 2) - self.t(i - 1)) / self.h(i),
            (self.t(i + 1) - self.t(i - 2)) / self.h(i - 1),
        );
        Some(d1.iter().zip(&d0).map(|(a, b)| r * a - l * b).collect())
    }

    /// Df(t_i) by `rule`.
    pub fn df(&self, i: usize, rule: Df) -> Vec<f64> {
        let n = self.n();
        let ii = i as isize;
        if self.closed || (1..n - 1).contains(&i) {
            return match rule {
                Df::Average => {
                    let (l, r) = (self.s(ii - 1), self.s(ii));
                    l.iter().zip(&r).map(|(a, b)| 0.5 * (a + b)).collect()
                }
                // p'(t_i) = s_{i−1} + h_{i−1} Δ_{i−1,2} for the Newton form from t_{i−1}.
                Df::Bessel => {
                    let mut v = self.s(ii - 1);
                    axpy(&mut v, self.h(ii - 1), &self.dd(ii - 1, 2));
                    v
                }
            };
        }
        if n == 2 {
            return self.s(0);
        }
        match (rule, i == 0) {
            (Df::Average, true) => self.s(0),
            (Df::Average, false) => self.s(n as isize - 2),
            // p'(t_0) = s_0 − h_0 Δ_{0,2}; p'(t_{N−1}) = s_{N−2} + h_{N−2} Δ_{N−3,2}.
            (Df::Bessel, true) => {
                let mut v = self.s(0);
                axpy(&mut v, -self.h(0), &self.dd(0, 2));
                v
            }
            (Df::Bessel, false) => {
                let m = n as isize;
                let mut v = self.s(m - 2);
                axpy(&mut v, self.h(m - 2), &self.dd(m - 3, 2));
                v
            }
        }
    }

    /// A copy with vertex i's parameter moved by `dt` (closed, i = 0: t_0 and t_N together).
    pub fn moved(&self, i: usize, dt: f64) -> Curve {
        let mut c = self.clone();
        c.t[i] += dt;
        if self.closed && i == 0 {
            let last = c.t.len() - 1;
            c.t[last] += dt;
        }
        c
    }

    /// Central differences of E in each vertex's parameter (points fixed), step `rel` times the
    /// shortest span.
    pub fn fd_knot_gradient(&self, rel: f64) -> Vec<f64> {
        let hmin = self
            .t
            .windows(2)
            .map(|w| w[1] - w[0])
            .fold(f64::INFINITY, f64::min);
        let d = rel * hmin;
        (0..self.n())
            .map(|i| (self.moved(i, d).energy() - self.moved(i, -d).energy()) / (2.0 * d))
            .collect()
    }

    /// The third-difference terms of the exact free-knot condition at vertex i:
    /// |h_{i−1,3} Δ_{i−1,3} f|² − |h_{i−2,3} Δ_{i−2,3} f|² = |c_{i+1} − c_i|² − |c_i − c_{i−1}|²
    /// (each term present when its span exists).
    pub fn third_difference_terms(&self, i: usize) -> f64 {
        let i = i as isize;
        let sq = |a: Vec<f64>, b: Vec<f64>| {
            a.iter()
                .zip(&b)
                .map(|(x, y)| (x - y) * (x - y))
                .sum::<f64>()
        };
        let mut v = 0.0;
        if self.has_span(i) {
            v += sq(self.c(i + 1), self.c(i));
        }
        if self.has_span(i - 1) {
            v -= sq(self.c(i), self.c(i - 1));
        }
        v
    }
}
