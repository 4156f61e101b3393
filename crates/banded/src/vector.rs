//! Small dense vector helpers on `f64` slices: [`dot`], [`norm`], [`dist`],
//! [`consecutive_dists`], [`max_dist`], [`axpy`].
//!
//! One home for the helpers the workspace otherwise writes again and again. [`dot`] and
//! [`axpy`] are the plain loops (summed left to right, so switching a local copy to them
//! changes no result). [`norm`] and [`dist`] do not overflow or underflow where the result is
//! representable: they accumulate squares in three ranges, Blue's algorithm as in LAPACK's
//! `dnrm2` since 3.10 (E. Anderson, *Algorithm 978: Safe Scaling in the Level 1 BLAS*, ACM TOMS
//! 44(1), 2017; J. L. Blue, ACM TOMS 4(1), 1978): squares of entries in the middle range are
//! summed as they are, tiny ones scaled up by 2^537 and huge ones scaled down by 2^−538, and
//! the three sums are combined at the end. On data in the middle range (|x| between 2^−511 and
//! 2^486) the result equals the naive √(Σ x²) bit for bit. A NaN entry gives NaN.
//!
//! ```
//! use banded::vector::{axpy, dist, dot, norm};
//! assert_eq!(dot(&[1.0, 2.0], &[3.0, 4.0]), 11.0);
//! assert_eq!(norm(&[3.0, 4.0]), 5.0);
//! // No overflow where the naive formula gives infinity, no underflow where it gives 0.
//! assert_eq!(norm(&[3e300, 4e300]), 5e300);
//! assert!((norm(&[3e-300, 4e-300]) - 5e-300).abs() < 1e-315);
//! assert_eq!(dist(&[1.0, 1.0], &[4.0, 5.0]), 5.0);
//! let mut y = vec![1.0, 1.0];
//! axpy(2.0, &[1.0, 2.0], &mut y);
//! assert_eq!(y, [3.0, 5.0]);
//! ```

/// Entries below this magnitude are summed scaled by [`SCALE_SMALL`] (2^⌈(e_min − 1)/2⌉ with
/// e_min = −1021: LAPACK's `tsml`).
const SMALL: f64 = 1.4916681462400413e-154; // 2^-511
/// Entries above this magnitude are summed scaled by [`SCALE_BIG`] (2^⌊(e_max − t + 1)/2⌋ with
/// e_max = 1024, t = 53: LAPACK's `tbig`).
const BIG: f64 = 1.997_919_072_202_235e146; // 2^486
/// Scale for tiny entries (LAPACK's `ssml`, 2^537).
const SCALE_SMALL: f64 = 4.4989137945431964e161; // 2^537
/// Scale for huge entries (LAPACK's `sbig`, 2^−538).
const SCALE_BIG: f64 = 1.1113793747425387e-162; // 2^-538

/// Σ a_i b_i over the common length, summed left to right.
#[inline]
pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// y ← y + α x over the common length.
#[inline]
pub fn axpy(alpha: f64, x: &[f64], y: &mut [f64]) {
    for (yi, xi) in y.iter_mut().zip(x) {
        *yi += alpha * xi;
    }
}

/// The Euclidean norm √(Σ x_i²), without overflow or underflow (see the module docs).
pub fn norm(x: &[f64]) -> f64 {
    scaled_norm(x.iter().copied())
}

/// The Euclidean distance |a − b| over the common length, without overflow or underflow of
/// the squares (see the module docs; the differences a_i − b_i themselves are rounded as
/// usual and overflow only if they exceed `f64::MAX`).
#[inline]
pub fn dist(a: &[f64], b: &[f64]) -> f64 {
    dist_of(a.len().min(b.len()), |c| a[c] - b[c])
}

/// [`dist`] of the `d` differences `diff(c)`.
#[inline(always)]
fn dist_of(d: usize, diff: impl Fn(usize) -> f64) -> f64 {
    // The common case first, without the three-range branches: when every difference is 0 or
    // in the middle range, Blue's sum is the naive one bit for bit (module docs). NaN fails the
    // range test and goes the long way, which propagates it.
    let (mut sum, mut middle) = (0.0, true);
    for c in 0..d {
        let v = diff(c).abs();
        middle &= v == 0.0 || (SMALL..=BIG).contains(&v);
        sum += v * v;
    }
    if middle {
        sum.sqrt()
    } else {
        scaled_norm((0..d).map(diff))
    }
}

/// [`dist`] of consecutive rows, bit for bit: `out[j]` = dist(row j + 1, row j) of `coords`
/// (rows of `d` values, row after row; it must hold `out.len() + 1` rows).
///
/// Four rows at a time, without branches, when every difference of the four is 0 or in the
/// middle range (the naive sums, `dist`'s common case); row by row through [`dist`] otherwise.
/// Inlined always, so that under a caller's wider vector instructions (refine's knot updates,
/// 8·10⁵ rows each) the four sums and square roots run in one vector.
///
/// ```
/// use banded::vector::{consecutive_dists, dist};
/// let rows = [0.0, 0.0, 3.0, 4.0, 3.0, 4.0, 1e300, 0.0, 0.0, 1.0, 1.0, 1.0];
/// let mut out = [0.0; 5];
/// consecutive_dists(&rows, 2, &mut out);
/// assert_eq!(out[..2], [5.0, 0.0]);
/// for (j, o) in out.iter().enumerate() {
///     assert_eq!(*o, dist(&rows[2 * j + 2..2 * j + 4], &rows[2 * j..2 * j + 2]));
/// }
/// ```
///
/// # Panics
/// If `coords` holds fewer than `out.len() + 1` rows.
#[inline(always)]
pub fn consecutive_dists(coords: &[f64], d: usize, out: &mut [f64]) {
    let rows = out.len();
    assert!(
        rows == 0 || coords.len() >= (rows + 1) * d,
        "consecutive_dists: {} values hold fewer than {} rows of {d}",
        coords.len(),
        rows + 1
    );
    // (Literal d = 1, 2, 3: the inlined body is specialized, its indexing and loops fixed.)
    match d {
        1 => dist_blocks(coords, 1, out),
        2 => dist_blocks(coords, 2, out),
        3 => dist_blocks(coords, 3, out),
        _ => dist_blocks(coords, d, out),
    }
}

/// The body of [`consecutive_dists`]: blocks of four rows, each read as one window, so the
/// differences and sums are straight vector arithmetic when `d` is a constant.
#[inline(always)]
fn dist_blocks(coords: &[f64], d: usize, out: &mut [f64]) {
    const LANES: usize = 4;
    let row = |j: usize| &coords[j * d..(j + 1) * d];
    let blocks = out.len() / LANES;
    let (head, tail) = out.split_at_mut(blocks * LANES);
    for (b, o) in head.chunks_exact_mut(LANES).enumerate() {
        let w = &coords[b * LANES * d..][..(LANES + 1) * d];
        let (mut sum, mut middle) = ([0.0; LANES], true);
        for c in 0..d {
            for (lane, s) in sum.iter_mut().enumerate() {
                let v = (w[(lane + 1) * d + c] - w[lane * d + c]).abs();
                middle &= v == 0.0 || (SMALL..=BIG).contains(&v);
                *s += v * v;
            }
        }
        if middle {
            for (o, s) in o.iter_mut().zip(sum) {
                *o = s.sqrt();
            }
        } else {
            for (lane, o) in o.iter_mut().enumerate() {
                let j = b * LANES + lane;
                *o = dist(row(j + 1), row(j));
            }
        }
    }
    for (jj, o) in tail.iter_mut().enumerate() {
        let j = blocks * LANES + jj;
        *o = dist(row(j + 1), row(j));
    }
}

/// The largest [`dist`] between row i of `a` and row i of `b` (rows of `d` values, row after
/// row; over the rows both have), as `rows.map(dist).fold(0.0, f64::max)` gives it bit for bit —
/// a NaN distance is passed over, as `f64::max` passes it over; 0 without rows or with d = 0.
///
/// One branch-free pass when every difference is 0 or in the middle range (the maximum of the
/// naive squared sums, whose square root is the largest distance: √ is monotonic and correctly
/// rounded); row by row through [`dist`] otherwise. Why: the certificate and validation take
/// this maximum over every data point, and row-by-row calls with their range branches were
/// ~20 ns a row.
///
/// ```
/// use banded::vector::max_dist;
/// assert_eq!(max_dist(&[0.0, 0.0, 1.0, 1.0], &[3.0, 4.0, 1.0, 2.0], 2), 5.0);
/// assert_eq!(max_dist(&[3e300, 4e300], &[0.0, 0.0], 2), 5e300);
/// ```
pub fn max_dist(a: &[f64], b: &[f64], d: usize) -> f64 {
    if d == 0 {
        return 0.0;
    }
    let rows = (a.len() / d).min(b.len() / d);
    let (a, b) = (&a[..rows * d], &b[..rows * d]);
    // (Literal d = 1, 2, 3: the inlined body is specialized, its indexing and loops fixed.)
    match d {
        1 => max_row_dist(rows, 1, |i, c| a[i + c] - b[i + c]),
        2 => max_row_dist(rows, 2, |i, c| a[i * 2 + c] - b[i * 2 + c]),
        3 => max_row_dist(rows, 3, |i, c| a[i * 3 + c] - b[i * 3 + c]),
        _ => max_row_dist(rows, d, |i, c| a[i * d + c] - b[i * d + c]),
    }
}

/// The largest [`dist`] from `point` to the rows of `a` (rows of `point.len()` values), as
/// [`max_dist`] computes it.
///
/// ```
/// use banded::vector::max_dist_from;
/// assert_eq!(max_dist_from(&[1.0, 1.0, 4.0, 5.0, 1.0, 2.0], &[1.0, 1.0]), 5.0);
/// ```
pub fn max_dist_from(a: &[f64], point: &[f64]) -> f64 {
    let d = point.len();
    if d == 0 {
        return 0.0;
    }
    let rows = a.len() / d;
    let a = &a[..rows * d];
    match *point {
        [x] => max_row_dist(rows, 1, |i, _| a[i] - x),
        [x, y] => max_row_dist(rows, 2, |i, c| a[i * 2 + c] - [x, y][c]),
        [x, y, z] => max_row_dist(rows, 3, |i, c| a[i * 3 + c] - [x, y, z][c]),
        _ => max_row_dist(rows, d, |i, c| a[i * d + c] - point[c]),
    }
}

/// [`max_dist`] over `rows` pairs of rows of `d` values, `diff(i, c)` the difference of pair i
/// in coordinate c. The branch-free pass takes four rows at a time into four running maxima
/// ([`crate::lanes`]), so that the compares do not wait for each other (one running maximum was
/// ~2 ns a row, three times per solve over the data points).
#[inline(always)]
fn max_row_dist(rows: usize, d: usize, diff: impl Fn(usize, usize) -> f64) -> f64 {
    use crate::lanes::{raise, raise_all};
    let (mut largest, mut middle) = ([0.0f64; 4], true);
    let whole = rows - rows % 4;
    for i in (0..whole).step_by(4) {
        let mut sum = [0.0f64; 4];
        for c in 0..d {
            for (lane, s) in sum.iter_mut().enumerate() {
                let v = diff(i + lane, c).abs();
                middle &= (v == 0.0) | (SMALL..=BIG).contains(&v);
                *s += v * v;
            }
        }
        // (a NaN sum is passed over, as `f64::max` passes it over; it also clears `middle`)
        for (m, s) in largest.iter_mut().zip(sum) {
            raise(m, s);
        }
    }
    for i in whole..rows {
        let mut sum = 0.0;
        for c in 0..d {
            let v = diff(i, c).abs();
            middle &= (v == 0.0) | (SMALL..=BIG).contains(&v);
            sum += v * v;
        }
        raise(&mut largest[0], sum);
    }
    if middle {
        let mut m = 0.0;
        raise_all(&mut m, largest);
        m.sqrt()
    } else {
        (0..rows).fold(0.0, |m, i| m.max(dist_of(d, |c| diff(i, c))))
    }
}

/// Blue's three-accumulator sum of squares (LAPACK `dnrm2`, Anderson 2017).
#[inline]
fn scaled_norm(values: impl Iterator<Item = f64>) -> f64 {
    let (mut big, mut mid, mut small) = (0.0f64, 0.0f64, 0.0f64);
    let mut no_big = true;
    for v in values {
        let a = v.abs();
        if a > BIG {
            big += (a * SCALE_BIG) * (a * SCALE_BIG);
            no_big = false;
        } else if a < SMALL {
            // Once a huge entry is seen the tiny ones cannot matter.
            if no_big {
                small += (a * SCALE_SMALL) * (a * SCALE_SMALL);
            }
        } else {
            // Also takes NaN (every comparison above is false), which then propagates.
            mid += a * a;
        }
    }
    if big > 0.0 {
        // mid > 0 or NaN: fold it into the big sum (its scaled square cannot overflow).
        if mid > 0.0 || mid.is_nan() {
            big += (mid * SCALE_BIG) * SCALE_BIG;
        }
        big.sqrt() / SCALE_BIG
    } else if small > 0.0 {
        if mid > 0.0 || mid.is_nan() {
            let m = mid.sqrt();
            let s = small.sqrt() / SCALE_SMALL;
            let (lo, hi) = if s > m { (m, s) } else { (s, m) };
            hi * (1.0 + (lo / hi) * (lo / hi)).sqrt()
        } else {
            small.sqrt() / SCALE_SMALL
        }
    } else {
        mid.sqrt()
    }
}

#[cfg(test)]
// Exact comparisons on purpose: the scale constants are powers of two and the middle-range
// claim is bit for bit.
#[allow(clippy::float_cmp)]
mod tests {
    use super::*;

    #[test]
    fn scale_constants_are_the_lapack_powers_of_two() {
        // 2^−511, 2^486, 2^537, 2^−538 exactly (LAPACK la_constants for binary64).
        assert_eq!(SMALL, 2f64.powi(-511));
        assert_eq!(BIG, 2f64.powi(486));
        assert_eq!(SCALE_SMALL, 2f64.powi(537));
        assert_eq!(SCALE_BIG, 2f64.powi(-538));
    }

    #[test]
    fn norm_matches_the_naive_formula_in_the_middle_range() {
        let x: Vec<f64> = (0..37)
            .map(|i| ((i * 7919) % 101) as f64 / 13.0 - 3.0)
            .collect();
        let naive = x.iter().map(|v| v * v).sum::<f64>().sqrt();
        assert_eq!(norm(&x), naive);
    }

    #[test]
    fn norm_survives_extreme_magnitudes() {
        // Reference: the exact norm of a scaled 3-4-5 (or 1-1-√2) vector, by homogeneity.
        for s in [1e-320, 1e-300, 1e-160, 1e-150, 1e150, 1e160, 1e300] {
            let r = norm(&[3.0 * s, 4.0 * s]);
            assert!((r / (5.0 * s) - 1.0).abs() < 1e-6, "scale {s}: {r}");
        }
        let r = norm(&[f64::MAX, f64::MAX]) / f64::MAX;
        assert!(r.is_infinite(), "√2·MAX overflows: {r}");
        let r = norm(&[f64::MAX / 2.0, f64::MAX / 2.0]) / (f64::MAX / 2.0);
        assert!((r - 2f64.sqrt()).abs() < 1e-15);
        // Mixed ranges: the tiny entry vanishes next to a huge one, and small + medium combine.
        assert_eq!(norm(&[1e300, 1e-300]), 1e300);
        let r = norm(&[1e-160, 1.0]);
        assert_eq!(r, 1.0);
        let r = norm(&[3e-160, 4e-160, 0.0]);
        assert!((r / 5e-160 - 1.0).abs() < 1e-15);
    }

    /// `consecutive_dists` against `dist` row by row, bit for bit: middle-range rows (the
    /// four-row blocks), blocks holding a tiny, huge, zero or NaN difference (row by row), rows
    /// left after the last block, d = 1 … 5 (the compile-time d = 1, 2, 3 and any d).
    #[test]
    fn consecutive_dists_are_dist_row_by_row() {
        for d in 1..=5 {
            for rows in [0, 1, 3, 4, 9, 23] {
                let mut c: Vec<f64> = (0..(rows + 1) * d)
                    .map(|i| ((i * 7919) % 103) as f64 / 17.0 - 2.5)
                    .collect();
                if rows >= 9 {
                    c[2 * d] = c[d] + 1e-200; // tiny difference in row 1 → 2
                    c[5 * d] = 3e200; // huge differences around row 5
                    c[8 * d] = f64::NAN; // NaN in rows 7 → 8 and 8 → 9
                    c[3 * d..4 * d].fill(0.5);
                    c[4 * d..5 * d].fill(0.5); // a zero-length row 3 → 4
                }
                let mut out = vec![-1.0; rows];
                consecutive_dists(&c, d, &mut out);
                for (j, o) in out.iter().enumerate() {
                    let want = dist(&c[(j + 1) * d..(j + 2) * d], &c[j * d..(j + 1) * d]);
                    assert_eq!(o.to_bits(), want.to_bits(), "d = {d}, row {j}");
                }
            }
        }
    }

    /// `max_dist` against the fold of `dist` it stands for, bit for bit: middle-range rows
    /// (its one-pass path, four rows at a time and the rows after them), rows with a tiny, huge
    /// or NaN difference (the row-by-row path), d = 1, 2, 3, and no rows.
    #[test]
    fn max_dist_is_the_fold_of_dist() {
        let fold = |a: &[f64], b: &[f64], d: usize| {
            a.chunks_exact(d)
                .zip(b.chunks_exact(d))
                .fold(0.0f64, |m, (x, y)| m.max(dist(x, y)))
        };
        for (d, rows) in (1..=3).flat_map(|d| [60, 63].map(|rows| (d, rows))) {
            let a: Vec<f64> = (0..rows * d)
                .map(|i| ((i * 7919) % 211) as f64 / 17.0 - 5.0)
                .collect();
            let b: Vec<f64> = (0..rows * d)
                .map(|i| ((i * 104_729) % 199) as f64 / 23.0 - 4.0)
                .collect();
            assert_eq!(max_dist(&a, &b, d).to_bits(), fold(&a, &b, d).to_bits());
            for odd in [1e-160, 1e-300, 1e200, 1e300, f64::NAN, 0.0] {
                let mut c = b.clone();
                c[7 * d] = a[7 * d] + odd;
                assert_eq!(
                    max_dist(&a, &c, d).to_bits(),
                    fold(&a, &c, d).to_bits(),
                    "d = {d}, difference {odd}"
                );
                let p = &c[7 * d..8 * d];
                let from = a.chunks_exact(d).fold(0.0f64, |m, x| m.max(dist(x, p)));
                assert_eq!(max_dist_from(&a, p).to_bits(), from.to_bits());
            }
        }
        assert_eq!(max_dist(&[], &[], 2), 0.0);
        assert_eq!(max_dist(&[1.0], &[2.0], 0), 0.0);
        assert_eq!(max_dist_from(&[], &[1.0]), 0.0);
    }

    /// Consecutive distances are `dist`'s bits, in the four-row blocks and the rows after them,
    /// also where one row of a block leaves the middle range (tiny, huge, NaN, equal rows).
    #[test]
    fn consecutive_dists_are_dists_bits() {
        for d in 1..=4 {
            for rows in [1, 3, 4, 5, 9, 17] {
                let a: Vec<f64> = (0..(rows + 1) * d)
                    .map(|i| ((i * 7919) % 211) as f64 / 17.0 - 5.0)
                    .collect();
                let each = |a: &[f64]| -> Vec<u64> {
                    (0..rows)
                        .map(|j| {
                            dist(&a[(j + 1) * d..(j + 2) * d], &a[j * d..(j + 1) * d]).to_bits()
                        })
                        .collect()
                };
                let ours = |a: &[f64]| -> Vec<u64> {
                    let mut out = vec![0.0; rows];
                    consecutive_dists(a, d, &mut out);
                    out.iter().map(|x| x.to_bits()).collect()
                };
                assert_eq!(ours(&a), each(&a), "d = {d}, {rows} rows");
                for odd in [1e-160, 1e-300, 1e200, 1e300, f64::NAN, 0.0] {
                    for at in [0, rows / 2, rows] {
                        let mut c = a.clone();
                        c[at * d] += odd;
                        if odd == 0.0 && at > 0 {
                            c[at * d..(at + 1) * d].copy_from_slice(&a[(at - 1) * d..at * d]);
                        }
                        assert_eq!(ours(&c), each(&c), "d = {d}, {rows} rows, {odd} at {at}");
                    }
                }
            }
        }
        consecutive_dists(&[], 2, &mut []);
    }

    #[test]
    fn nan_propagates_and_empty_is_zero() {
        assert!(norm(&[1.0, f64::NAN]).is_nan());
        assert!(norm(&[1e300, f64::NAN]).is_nan());
        assert!(norm(&[1e-300, f64::NAN]).is_nan());
        assert_eq!(norm(&[]), 0.0);
        assert_eq!(dist(&[], &[]), 0.0);
        assert_eq!(dot(&[], &[]), 0.0);
    }

    #[test]
    fn dist_is_the_norm_of_the_difference() {
        let a = [1e200, -2e200, 3.0];
        let b = [-1e200, 2e200, 3.0];
        let r = dist(&a, &b);
        assert!((r / (2e200 * 5f64.sqrt()) - 1.0).abs() < 1e-15);
    }

    #[test]
    fn dists_short_path_is_blues_sum_bit_for_bit() {
        // Middle-range and zero differences take the naive sum; a tiny, huge or NaN difference
        // takes Blue's three ranges. Both must equal the three-range sum of the differences.
        let cases: [[f64; 3]; 6] = [
            [0.3, -7.25, 0.0],
            [1e-150, 2.0, 0.0],
            [1e-160, 1e-155, 0.0],
            [1e-300, 3.0, 4.0],
            [1e200, 3e200, 1.0],
            [0.0, f64::NAN, 1.0],
        ];
        for x in cases {
            let (r, blue) = (dist(&x, &[0.0; 3]), scaled_norm(x.iter().copied()));
            assert!(
                r.to_bits() == blue.to_bits() || (r.is_nan() && blue.is_nan()),
                "{x:?}"
            );
        }
        // The tiny entry below the middle range counts: not lost as the naive square would be.
        assert!(dist(&[1e-160, 0.0], &[0.0, 0.0]) == 1e-160);
    }
}
