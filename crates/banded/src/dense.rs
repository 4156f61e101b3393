//! Small dense kernels on row-major d×d blocks stored in slices, for the block factorization.
//!
//! Sums of products start from their first product, not from 0.0 (0.0 + x is not x for
//! x = −0.0, so the compiler keeps such an addition). Every kernel takes the block size `d` (≥ 1)
//! at run time and is `#[inline(always)]`: the block
//! factorization calls them with a compile-time constant (d = 1..4) or a run-time value (the
//! general path), so the constant ones unroll completely. Triangular factors store their
//! diagonal *inverted* (1/l_cc): every use of it is a division, and the solves' recurrences are
//! latency-bound, so they multiply instead.

// Index loops over several blocks at once read more clearly than iterator chains here.
#![allow(clippy::needless_range_loop)]

/// s ← s − a bᵀ.
#[inline(always)]
pub(crate) fn sub_mul_t(s: &mut [f64], a: &[f64], b: &[f64], d: usize) {
    let (s, a, b) = (&mut s[..d * d], &a[..d * d], &b[..d * d]);
    for r in 0..d {
        for c in 0..d {
            let mut t = a[r * d] * b[c * d];
            for q in 1..d {
                t += a[r * d + q] * b[c * d + q];
            }
            s[r * d + c] -= t;
        }
    }
}

/// The lower triangle (with the diagonal) of s ← s − a aᵀ.
#[inline(always)]
pub(crate) fn sub_gram_lower(s: &mut [f64], a: &[f64], d: usize) {
    let (s, a) = (&mut s[..d * d], &a[..d * d]);
    for r in 0..d {
        for c in 0..=r {
            let mut t = a[r * d] * a[c * d];
            for q in 1..d {
                t += a[r * d + q] * a[c * d + q];
            }
            s[r * d + c] -= t;
        }
    }
}

/// s ← s L⁻ᵀ for lower triangular L with inverted diagonal: each row x of the result solves
/// L xᵀ = (row of s)ᵀ.
#[inline(always)]
pub(crate) fn right_solve_lt(s: &mut [f64], l: &[f64], d: usize) {
    let (s, l) = (&mut s[..d * d], &l[..d * d]);
    for r in 0..d {
        for c in 0..d {
            let mut t = s[r * d + c];
            for q in 0..c {
                t -= s[r * d + q] * l[c * d + q];
            }
            s[r * d + c] = t * l[c * d + c];
        }
    }
}

/// In-place lower Cholesky factor (diagonal inverted, strict upper triangle zeroed) of the
/// symmetric `s`, of which only the lower triangle is read. Row c's pivot is accepted if it is
/// finite and above `rtol · kref[c]`; otherwise `Err(c)`.
#[inline(always)]
pub(crate) fn cholesky(s: &mut [f64], kref: &[f64], rtol: f64, d: usize) -> Result<(), usize> {
    let (s, kref) = (&mut s[..d * d], &kref[..d]);
    for c in 0..d {
        let mut p = s[c * d + c];
        for q in 0..c {
            p -= s[c * d + q] * s[c * d + q];
        }
        if !(p.is_finite() && p > rtol * kref[c]) {
            return Err(c);
        }
        let inv = 1.0 / p.sqrt();
        s[c * d + c] = inv;
        for r in c + 1..d {
            let mut t = s[r * d + c];
            for q in 0..c {
                t -= s[r * d + q] * s[c * d + q];
            }
            s[r * d + c] = t * inv;
        }
        for r in 0..c {
            s[r * d + c] = 0.0;
        }
    }
    Ok(())
}

/// The d-vector at offset `o` and stride `st` of `x` is x[o], x[o + st], …, x[o + (d − 1) st].
///
/// v ← v − a u for the vectors v at `vo` and u at `uo` of `x` (distinct rows).
#[inline(always)]
pub(crate) fn sub_mul_vec(x: &mut [f64], vo: usize, a: &[f64], uo: usize, st: usize, d: usize) {
    let a = &a[..d * d];
    for r in 0..d {
        let mut t = a[r * d] * x[uo];
        for c in 1..d {
            t += a[r * d + c] * x[uo + c * st];
        }
        x[vo + r * st] -= t;
    }
}

/// v ← v − aᵀ u for the vectors v at `vo` and u at `uo` of `x` (distinct rows).
#[inline(always)]
pub(crate) fn sub_mul_t_vec(x: &mut [f64], vo: usize, a: &[f64], uo: usize, st: usize, d: usize) {
    let a = &a[..d * d];
    for c in 0..d {
        let mut t = a[c] * x[uo];
        for r in 1..d {
            t += a[r * d + c] * x[uo + r * st];
        }
        x[vo + c * st] -= t;
    }
}

/// v ← L⁻¹ v for the vector v at `vo` of `x` (L lower triangular, n×n, inverted diagonal).
#[inline(always)]
pub(crate) fn lower_solve(l: &[f64], x: &mut [f64], vo: usize, st: usize, n: usize) {
    let l = &l[..n * n];
    for r in 0..n {
        let mut t = x[vo + r * st];
        for c in 0..r {
            t -= l[r * n + c] * x[vo + c * st];
        }
        x[vo + r * st] = t * l[r * n + r];
    }
}

/// v ← L⁻ᵀ v for the vector v at `vo` of `x` (L lower triangular, n×n, inverted diagonal).
#[inline(always)]
pub(crate) fn lower_t_solve(l: &[f64], x: &mut [f64], vo: usize, st: usize, n: usize) {
    let l = &l[..n * n];
    for r in (0..n).rev() {
        let mut t = x[vo + r * st];
        for c in r + 1..n {
            t -= l[c * n + r] * x[vo + c * st];
        }
        x[vo + r * st] = t * l[r * n + r];
    }
}
