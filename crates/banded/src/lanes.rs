//! Reductions in independent lanes: sums and maxima over long arrays whose running value,
//! carried in one register, made each step wait for the one before (a chain of dependent adds or
//! compares: refine's certificate sums and maximizes over 8·10⁵ vertices, [`crate::vector::max_dist`]
//! over every data point). Sums take four lanes, combined at the end ([`total`]): a sum is the
//! same up to the order of its additions, so the number of lanes is part of its bits. Maxima do
//! not round, so any number of lanes gives the one a running fold gives ([`raise_all`]);
//! [`raise_abs`] takes sixteen.
//!
//! ```
//! use banded::lanes::{max_abs, sum_over};
//! assert_eq!(max_abs(&[1.0, -7.0, 3.0, 2.0, -5.0]), 7.0);
//! assert_eq!(sum_over(5, |i| i as f64), 10.0);
//! ```

/// Calls `f(lane, i)` for i in 0 .. n: i in whole groups of four in lanes 0, 1, 2, 3 (i mod 4),
/// the rest in lane 0.
#[inline(always)]
pub fn by_lanes(n: usize, mut f: impl FnMut(usize, usize)) {
    let whole = n - n % 4;
    for i in (0..whole).step_by(4) {
        for l in 0..4 {
            f(l, i + l);
        }
    }
    for i in whole..n {
        f(0, i);
    }
}

/// m ← max(m, v) for m not NaN: what `f64::max` gives (a NaN v leaves m), as one compare and
/// select instead of `max`'s NaN handling.
#[inline(always)]
pub fn raise(m: &mut f64, v: f64) {
    if v > *m {
        *m = v;
    }
}

/// max(m, max_k |x_k − mid|) for m ≥ 0 (a NaN m stays NaN; the lanes start at 0), a NaN
/// |x_k − mid| passed over as [`raise`] does; sixteen independent maxima (four vectors of four),
/// so that the compares of consecutive elements do not wait for each other. (Over arrays of
/// sixteen, `as_chunks`: `chunks_exact` re-split the slice at every step, a fifth of the
/// certificate's samples at N = 8·10⁵.)
#[inline(always)]
pub fn raise_abs(m: &mut f64, x: &[f64], mid: f64) {
    let mut lanes = [0.0f64; MAXIMA_LANES];
    let (groups, rest) = x.as_chunks::<MAXIMA_LANES>();
    for q in groups {
        for l in 0..MAXIMA_LANES {
            raise(&mut lanes[l], (q[l] - mid).abs());
        }
    }
    for v in rest {
        raise(&mut lanes[0], (v - mid).abs());
    }
    raise_all(m, lanes);
}

/// The independent maxima of [`raise_abs`]: four vectors of four doubles. A maximum does not
/// round, so any number of lanes gives the same result; with four (one vector) each compare
/// waited for the one before, and the certificate's maxima over its blocks' coordinates were
/// ~9 % of a certified 10⁵-point interpolation's samples.
const MAXIMA_LANES: usize = 16;

/// max_k |x_k|, 0 for no elements ([`raise_abs`] from 0).
#[inline(always)]
pub fn max_abs(x: &[f64]) -> f64 {
    let mut m = 0.0;
    raise_abs(&mut m, x, 0.0);
    m
}

/// The four lanes' sums added, pairwise: (s₀ + s₁) + (s₂ + s₃).
#[inline(always)]
pub fn total(lanes: [f64; 4]) -> f64 {
    (lanes[0] + lanes[1]) + (lanes[2] + lanes[3])
}

/// m ← max(m, the lanes' maxima), NaNs passed over as [`raise`] does.
#[inline(always)]
pub fn raise_all<const L: usize>(m: &mut f64, lanes: [f64; L]) {
    for l in lanes {
        raise(m, l);
    }
}

/// Σ_i f(i) over i in 0 .. n in four independent sums (i mod 4), so that the additions do not
/// wait for each other (one running sum of |Hp| over the free vertices was a sixth of the pass's
/// samples at N = 8·10⁵).
#[inline(always)]
pub fn sum_over(n: usize, f: impl Fn(usize) -> f64) -> f64 {
    let mut lanes = [0.0f64; 4];
    by_lanes(n, |l, i| lanes[l] += f(i));
    total(lanes)
}

/// max(m, max_i f(i)) over i in 0 .. n, a NaN passed over as [`raise`] does, in four independent
/// lanes (i mod 4), so that the compares do not wait for each other. The maximum does not
/// round, so it is the one a running fold gives.
#[inline(always)]
pub fn raise_over(m: &mut f64, n: usize, f: impl Fn(usize) -> f64) {
    let mut lanes = [*m; 4];
    by_lanes(n, |l, i| raise(&mut lanes[l], f(i)));
    raise_all(m, lanes);
}

/// Σ_i |x_i| in four independent sums, as [`sum_over`] takes them (i mod 4, the rest in lane 0;
/// the same bits), from arrays of four (`as_chunks`), which the compiler vectorizes: through
/// `sum_over`'s closure, each element's bounds check kept the loop scalar.
///
/// ```
/// use banded::lanes::{sum_abs, sum_over};
/// let x = [1.0, -2.5, 3.0, -4.0, 0.5, -1e-3];
/// assert_eq!(sum_abs(&x).to_bits(), sum_over(x.len(), |i| x[i].abs()).to_bits());
/// ```
#[inline(always)]
pub fn sum_abs(x: &[f64]) -> f64 {
    let mut lanes = [0.0f64; 4];
    let (quads, rest) = x.as_chunks::<4>();
    for q in quads {
        for l in 0..4 {
            lanes[l] += q[l].abs();
        }
    }
    for v in rest {
        lanes[0] += v.abs();
    }
    total(lanes)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// What [`raise_abs`] must equal: one running maximum, element by element.
    fn fold(m: f64, x: &[f64], mid: f64) -> f64 {
        let mut m = m;
        for &v in x {
            raise(&mut m, (v - mid).abs());
        }
        m
    }

    #[test]
    fn raise_abs_is_the_running_maximum_whatever_the_length() {
        // A deterministic stream with NaNs, infinities, signed zeros and both signs, over every
        // length through two whole groups of lanes and the tail after them.
        let mut s = 0x9E37_79B9_7F4A_7C15u64;
        let mut next = move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            s
        };
        for len in 0..=2 * MAXIMA_LANES + 5 {
            for _ in 0..20 {
                let x: Vec<f64> = (0..len)
                    .map(|_| match next() % 16 {
                        0 => f64::NAN,
                        1 => f64::INFINITY,
                        2 => -0.0,
                        _ => (next() % 2001) as f64 - 1000.0,
                    })
                    .collect();
                for (m, mid) in [(0.0, 0.0), (500.0, 3.0), (f64::NAN, 0.0), (0.25, -7.5)] {
                    let mut got = m;
                    raise_abs(&mut got, &x, mid);
                    let want = fold(m, &x, mid);
                    assert!(
                        got.to_bits() == want.to_bits(),
                        "len {len}, m {m}, mid {mid}: {got} against {want}"
                    );
                }
            }
        }
    }
}
