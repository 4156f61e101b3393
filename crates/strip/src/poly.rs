//! Dense univariate polynomials in the monomial basis, and isolation of their real roots.
//!
//! Used for the candidate equations of the per-interval problem: the touching-pair system is
//! reduced, by a Sylvester resultant, to one univariate polynomial whose real roots in the
//! (normalized) interval are isolated by a derivative cascade.

/// p(x) = Σ c\[k\] x^k.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct Poly(pub Vec<f64>);

impl Poly {
    pub fn constant(c: f64) -> Self {
        Poly(vec![c])
    }
    pub fn new(c: &[f64]) -> Self {
        Poly(c.to_vec())
    }
    pub fn eval(&self, x: f64) -> f64 {
        self.0.iter().rev().fold(0.0, |acc, &c| acc * x + c)
    }
    pub fn derivative(&self) -> Poly {
        if self.0.len() <= 1 {
            return Poly(vec![0.0]);
        }
        Poly(
            self.0
                .iter()
                .enumerate()
                .skip(1)
                .map(|(k, &c)| k as f64 * c)
                .collect(),
        )
    }
    pub fn add(&self, o: &Poly) -> Poly {
        let n = self.0.len().max(o.0.len());
        Poly(
            (0..n)
                .map(|k| self.0.get(k).copied().unwrap_or(0.0) + o.0.get(k).copied().unwrap_or(0.0))
                .collect(),
        )
    }
    pub fn sub(&self, o: &Poly) -> Poly {
        self.add(&o.scale(-1.0))
    }
    pub fn scale(&self, s: f64) -> Poly {
        Poly(self.0.iter().map(|c| c * s).collect())
    }
    pub fn mul(&self, o: &Poly) -> Poly {
        if self.0.is_empty() || o.0.is_empty() {
            return Poly(vec![0.0]);
        }
        let mut r = vec![0.0; self.0.len() + o.0.len() - 1];
        for (i, a) in self.0.iter().enumerate() {
            if *a == 0.0 {
                continue;
            }
            for (j, b) in o.0.iter().enumerate() {
                r[i + j] += a * b;
            }
        }
        Poly(r)
    }
    /// Largest coefficient magnitude.
    pub fn norm(&self) -> f64 {
        self.0.iter().fold(0.0, |m, c| m.max(c.abs()))
    }
    /// Drops trailing coefficients below `rel` times the largest one.
    pub fn trimmed(&self, rel: f64) -> Poly {
        let n = self.norm();
        let mut c = self.0.clone();
        while c.len() > 1 && c.last().is_some_and(|x| x.abs() <= rel * n) {
            c.pop();
        }
        Poly(c)
    }
}

/// Determinant of a small square matrix of polynomials (Laplace expansion along the first row,
/// skipping zero entries; only used for the 5×5 Sylvester matrix).
pub(crate) fn det(m: &[Vec<Poly>]) -> Poly {
    let n = m.len();
    if n == 1 {
        return m[0][0].clone();
    }
    let mut acc = Poly(vec![0.0]);
    for j in 0..n {
        if m[0][j].norm() == 0.0 {
            continue;
        }
        let minor: Vec<Vec<Poly>> = m[1..]
            .iter()
            .map(|row| {
                row.iter()
                    .enumerate()
                    .filter(|(k, _)| *k != j)
                    .map(|(_, p)| p.clone())
                    .collect()
            })
            .collect();
        let term = m[0][j].mul(&det(&minor));
        acc = if j % 2 == 0 {
            acc.add(&term)
        } else {
            acc.sub(&term)
        };
    }
    acc
}

/// Bisection steps when refining a bracketed root (2^-80 of the bracket: below f64 resolution).
const BISECTION_STEPS: usize = 80;

/// All real roots of `p` in `[lo, hi]`, ascending.
///
/// Derivative cascade: the real roots of p' split `[lo, hi]` into pieces on which p is monotone;
/// each piece holds at most one root, found by bisection when p changes sign on it. A critical
/// point where |p| is below `touch_tol · ‖p‖` (a double root that does not change sign) is
/// reported as a root as well, so tangential solutions are not lost; callers polish and validate.
pub(crate) fn real_roots(p: &Poly, lo: f64, hi: f64, touch_tol: f64) -> Vec<f64> {
    let p = p.trimmed(1e-300);
    let deg = p.0.len() - 1;
    if deg == 0 {
        return Vec::new();
    }
    let scale = p.norm() * (1.0 + lo.abs().max(hi.abs())).powi(deg as i32);
    let crit = if deg >= 2 {
        real_roots(&p.derivative(), lo, hi, 0.0)
    } else {
        Vec::new()
    };
    let mut pts = Vec::with_capacity(crit.len() + 2);
    pts.push(lo);
    pts.extend(crit.iter().copied().filter(|&c| c > lo && c < hi));
    pts.push(hi);
    let mut out: Vec<f64> = Vec::new();
    for w in pts.windows(2) {
        let (mut a, mut b) = (w[0], w[1]);
        let (mut fa, fb) = (p.eval(a), p.eval(b));
        if fa == 0.0 {
            out.push(a);
            continue;
        }
        if fa.signum() == fb.signum() {
            continue;
        }
        for _ in 0..BISECTION_STEPS {
            let m = 0.5 * (a + b);
            if m <= a || m >= b {
                break;
            }
            let fm = p.eval(m);
            if fm == 0.0 {
                a = m;
                b = m;
                break;
            }
            if fm.signum() == fa.signum() {
                a = m;
                fa = fm;
            } else {
                b = m;
            }
        }
        out.push(0.5 * (a + b));
    }
    if p.eval(hi) == 0.0 {
        out.push(hi);
    }
    if touch_tol > 0.0 {
        for &c in &crit {
            if c > lo && c < hi && p.eval(c).abs() <= touch_tol * scale {
                out.push(c);
            }
        }
    }
    out.sort_by(f64::total_cmp);
    out.dedup_by(|a, b| (*a - *b).abs() <= 1e-14 * (1.0 + b.abs()));
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn roots_of_a_product_of_linear_factors() {
        // (x - 0.1)(x - 0.35)(x - 0.6)(x - 0.95)(x + 2): four roots in [0, 1], one outside.
        let mut p = Poly::constant(1.0);
        for r in [0.1, 0.35, 0.6, 0.95, -2.0] {
            p = p.mul(&Poly::new(&[-r, 1.0]));
        }
        let r = real_roots(&p, 0.0, 1.0, 0.0);
        assert_eq!(r.len(), 4);
        for (a, b) in r.iter().zip([0.1, 0.35, 0.6, 0.95]) {
            assert!((a - b).abs() < 1e-12, "{a} vs {b}");
        }
    }

    #[test]
    fn double_root_is_reported_with_touch_tolerance() {
        // (x - 0.5)^2 (x + 1): no sign change at 0.5.
        let p = Poly::new(&[-0.5, 1.0])
            .mul(&Poly::new(&[-0.5, 1.0]))
            .mul(&Poly::new(&[1.0, 1.0]));
        // without the tolerance, rounding decides whether a sign change is seen; with it the
        // root is always reported
        for r in real_roots(&p, 0.0, 1.0, 0.0) {
            assert!((r - 0.5).abs() < 1e-6);
        }
        let r = real_roots(&p, 0.0, 1.0, 1e-12);
        assert_eq!(r.len(), 1);
        assert!((r[0] - 0.5).abs() < 1e-9);
    }

    #[test]
    fn sylvester_determinant_is_the_resultant() {
        // Res(x - a, x - b) = b - a for constant (degree-0 in y) coefficients: 2x2 Sylvester.
        let m = vec![
            vec![Poly::constant(1.0), Poly::constant(-0.25)],
            vec![Poly::constant(1.0), Poly::constant(-0.75)],
        ];
        assert!((det(&m).eval(0.0) - (-0.75 + 0.25)).abs() < 1e-15);
    }
}
