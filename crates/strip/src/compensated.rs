//! Numbers carried as a rounded value and its error (error-free transformations): the slopes and
//! bound values [`crate::resolve`] forms a spline from, so that it is the spline of the caller's
//! doubles — and of its bounds' exact values at the contacts — to the accuracy the moment system
//! allows, not to the roundings of its inputs.
//!
//! `two_diff` is Knuth's TwoSum (exact: a − b = s + e), a product's error comes exactly from a
//! fused multiply-add, and [`cubic`] is the compensated Horner scheme of Graillat, Langlois and
//! Louvet (*Compensated Horner scheme*, 2005), its error term accumulated to first order. The
//! corrections are first order in the roundings: they leave ε² of the terms.

/// a − b as the rounded difference and its rounding error, exactly (a − b = s + e).
pub(crate) fn two_diff(a: f64, b: f64) -> (f64, f64) {
    let s = a - b;
    let bb = s - a;
    (s, (a - (s - bb)) - (b + bb))
}

/// a + b as the rounded sum and its rounding error, exactly.
fn two_sum(a: f64, b: f64) -> (f64, f64) {
    two_diff(a, -b)
}

/// The slope (v₁ + l₁ − v₀ − l₀)/(x₁ − x₀) of values with low parts `l` (0 for doubles taken as
/// they are): the rounded quotient of the rounded differences and a correction for the errors
/// of both differences, the low parts, and the division's exact remainder.
pub(crate) fn slope(x0: f64, x1: f64, v0: f64, v1: f64, l0: f64, l1: f64) -> (f64, f64) {
    let (h, eh) = two_diff(x1, x0);
    let (dv, ev) = two_diff(v1, v0);
    let d = dv / h;
    let remainder = (-d).mul_add(h, dv);
    (d, (remainder + ev + (l1 - l0) - d * eh) / h)
}

/// The cubic c0 + c1 s + c2 s² + c3 s³ at s = x − x0, as its rounded value and the error of the
/// compensated Horner scheme (the roundings of s, of every product and every sum).
pub(crate) fn cubic(c: &[f64; 4], x0: f64, x: f64) -> (f64, f64) {
    let (s, es) = two_diff(x, x0);
    let (mut r, mut err) = (c[3], 0.0);
    for &k in [c[2], c[1], c[0]].iter() {
        let p = r * s;
        let ep = r.mul_add(s, -p);
        let (sum, e) = two_sum(p, k);
        err = err * s + (ep + e);
        r = sum;
    }
    let slope = c[1] + s * (2.0 * c[2] + 3.0 * s * c[3]);
    (r, err + es * slope)
}

/// The line through (a₀, a₁) and (b₀, b₁) at x, as its value rounded as
/// [`crate::types::line_at`] rounds it, a₁ + ((b₁ − a₁)(x − a₀))/(b₀ − a₀), and the error of
/// that rounding.
pub(crate) fn line(a: [f64; 2], b: [f64; 2], x: f64) -> (f64, f64) {
    let (dy, edy) = two_diff(b[1], a[1]);
    let (dt, edt) = two_diff(x, a[0]);
    let (dx, edx) = two_diff(b[0], a[0]);
    let p = dy * dt;
    let ep = dy.mul_add(dt, -p);
    let q = p / dx;
    let remainder = (-q).mul_add(dx, p);
    let (v, e) = two_sum(a[1], q);
    (v, e + (remainder + ep + edy * dt + dy * edt - q * edx) / dx)
}

#[cfg(test)]
mod tests {
    use super::*;
    use num_rational::BigRational;
    use num_traits::ToPrimitive;

    fn q(x: f64) -> BigRational {
        BigRational::from_float(x).expect("finite")
    }

    /// hi + lo against the exact rational value: within a few ε² of the terms' size.
    fn assert_close(hi: f64, lo: f64, exact: &BigRational, size: f64) {
        let err = ((q(hi) + q(lo)) - exact).to_f64().unwrap().abs();
        assert!(
            err <= 8.0 * f64::EPSILON * f64::EPSILON * size,
            "{hi} + {lo}: {err:e} off (size {size})"
        );
        let plain = (q(hi) - exact).to_f64().unwrap().abs();
        assert!(
            err <= plain,
            "the correction made it worse: {err:e} > {plain:e}"
        );
    }

    #[test]
    fn differences_are_exact() {
        for (a, b) in [(1e7 + 0.1, 3.3e-3), (0.1, 0.2), (1e16, 1.0), (-3.7, 1e-30)] {
            let (s, e) = two_diff(a, b);
            assert_eq!(q(s) + q(e), q(a) - q(b));
        }
    }

    #[test]
    fn slopes_cubics_and_lines_carry_their_roundings() {
        // steep values far from the origin, and sites whose difference rounds
        let (x0, x1, v0, v1) = (
            1e6 + 0.057_392_303_8,
            1e6 + 0.354_337_665_8,
            1.000_403_9e7,
            9.990_922e6,
        );
        let (d, c) = slope(x0, x1, v0, v1, 0.0, 0.0);
        let exact = (q(v1) - q(v0)) / (q(x1) - q(x0));
        assert_close(d, c, &exact, d.abs());
        let (x0, x1) = (0.1, 3e5 + 0.7);
        let (d, c) = slope(x0, x1, v0, v1, 2e-10, -1e-10);
        let exact = (q(v1) + q(-1e-10) - q(v0) - q(2e-10)) / (q(x1) - q(x0));
        assert_close(d, c, &exact, d.abs() + 1e-15);
        let k = [
            1.000_403_950_283_804_5e7,
            -33_054.932_428_902_43,
            17.3,
            -2.9,
        ];
        let (t0, x) = (1e6, 1e6 + 0.057_392_303_8);
        let (v, e) = cubic(&k, t0, x);
        let s = q(x) - q(t0);
        let exact = q(k[0]) + s.clone() * (q(k[1]) + s.clone() * (q(k[2]) + s * q(k[3])));
        assert_close(v, e, &exact, v.abs());
        let (a, b) = ([5e5 + 0.25, 1.000_3e7], [5e5 + 0.95, 1.000_41e7]);
        let x = 5e5 + 0.333_3;
        let (v, e) = line(a, b, x);
        let exact = q(a[1]) + (q(b[1]) - q(a[1])) * (q(x) - q(a[0])) / (q(b[0]) - q(a[0]));
        assert_close(v, e, &exact, v.abs());
        // the rounded values are the plain formulas' (the exchange's bound values)
        let plain = a[1] + (b[1] - a[1]) * (x - a[0]) / (b[0] - a[0]);
        assert_eq!(v.to_bits(), plain.to_bits());
        let s = 1e6 + 0.057_392_303_8 - 1e6;
        let plain = k[0] + s * (k[1] + s * (k[2] + s * k[3]));
        assert_eq!(
            cubic(&k, 1e6, 1e6 + 0.057_392_303_8).0.to_bits(),
            plain.to_bits()
        );
    }
}
