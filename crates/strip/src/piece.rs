//! Cubic polynomials c0 + c1 s + c2 s² + c3 s³ on an interval: values, Taylor shifts and exact
//! minima (the feasibility tests of the per-interval problem and of the returned pieces).

/// Value, first and second derivative of a cubic.
pub(crate) fn cubic3(c: &[f64; 4], x: f64) -> (f64, f64, f64) {
    (
        c[0] + x * (c[1] + x * (c[2] + x * c[3])),
        c[1] + x * (2.0 * c[2] + 3.0 * x * c[3]),
        2.0 * c[2] + 6.0 * x * c[3],
    )
}

/// Taylor coefficients of the cubic g about x0 (the same cubic in s' = s − x0).
pub(crate) fn shift(g: &[f64; 4], x0: f64) -> [f64; 4] {
    let (v, d1, d2) = cubic3(g, x0);
    [v, d1, 0.5 * d2, g[3]]
}

/// min over [0, l] of the cubic c (in s ∈ [0, l]).
pub(crate) fn cubic_min(c: &[f64; 4], l: f64) -> f64 {
    let mut m = c[0].min(cubic3(c, l).0);
    // critical points: c1 + 2 c2 s + 3 c3 s² = 0
    for s in roots::find_roots_quadratic(3.0 * c[3], 2.0 * c[2], c[1]).as_ref() {
        if *s > 0.0 && *s < l {
            m = m.min(cubic3(c, *s).0);
        }
    }
    m
}

/// min over \[0, l\] of the cubic c and where it is taken (ends, and the real roots of the
/// derivative 3c3 s² + 2c2 s + c1 by the cancellation-free quadratic formula).
pub(crate) fn cubic_argmin(c: &[f64; 4], l: f64) -> (f64, f64) {
    let at = |s: f64| c[0] + s * (c[1] + s * (c[2] + s * c[3]));
    let mut best = (c[0], 0.0);
    let mut consider = |s: f64| {
        if s > 0.0 && s <= l {
            let v = at(s);
            if v < best.0 || v.is_nan() {
                best = (v, s);
            }
        }
    };
    consider(l);
    let (a, b, k) = (3.0 * c[3], 2.0 * c[2], c[1]);
    if a == 0.0 {
        if b != 0.0 {
            consider(-k / b);
        }
    } else {
        let disc = b * b - 4.0 * a * k;
        if disc >= 0.0 {
            let q = -0.5 * (b + b.signum() * disc.sqrt());
            if q != 0.0 {
                consider(q / a);
                consider(k / q);
            }
        }
    }
    best
}
