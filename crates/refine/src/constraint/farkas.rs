//! Proofs that a set of half-spaces {x : n_j · x ≤ c_j} in R^d has no common point, checked in
//! exact integer arithmetic before any solve.
//!
//! **Farkas' lemma.** The half-spaces have no common point iff some y ≥ 0 has Σ y_j n_j = 0 and
//! Σ y_j c_j < 0. One direction is all a proof needs: for x in all of them,
//! 0 = (Σ y_j n_j)·x = Σ y_j (n_j·x) ≤ Σ y_j c_j < 0, a contradiction.
//!
//! **Where y is found.** By Helly's theorem some s ≤ d + 1 of the half-spaces already have no
//! common point, and a minimal such subset S has normals of rank s − 1 and a one-dimensional
//! space of Farkas vectors, strictly positive on S (a minimal infeasible system). On any s − 1
//! coordinates R where the normals restricted to R have rank s − 1, the null space of that
//! (s − 1) × s matrix is the same line, spanned by its signed maximal minors (cofactors):
//! y_j = (−1)^j det(N[R, S ∖ j]). So [`search`] tries every subset of size 2 … d + 1 with every
//! choice of coordinates, screens the cofactors in floating point (signs, Σ y_j c_j) and checks
//! the survivors exactly: each half-space scaled by a power of two (which leaves it the same
//! set) to integers, the cofactors as big integers, Σ y_j n_j = 0 in every coordinate, y ≥ 0
//! and Σ y_j c_j < 0. A reported subset is a proof; none reported proves nothing.
//!
//! **Cost.** First a witness, O(m) per round: a few rounds of projections onto the half-spaces
//! from a reference point (the data point, for a polytope the data point must lie in); a point
//! in all of them (floating-point test) ends the search with no claim. The subsets are tried
//! only for sets of dimension d ≤ [`MAX_DIM`] with at most [`MAX_CANDIDATES`] candidates
//! (Σ_s C(m, s) C(d, s − 1): m = 22 half-planes, m = 12 half-spaces in R³), and for at most
//! [`PROBLEM_CANDIDATES`] in one problem; the rest are left to the solver's own diagnosis.
//!
//! Complete for sets within the limits, in exact arithmetic on the given doubles.

use banded::vector::{axpy, dot, norm};
use num_bigint::BigInt;
use num_traits::{Num, Signed, Zero};

/// Dimensions searched (cofactors of at most d × d by Laplace expansion).
pub(crate) const MAX_DIM: usize = 3;

/// Candidate (subset, coordinates) pairs searched per set.
pub(crate) const MAX_CANDIDATES: usize = 2_000;

/// Candidates searched per problem (all its sets together): about 20 ms of screening (190 ns
/// each, measured at 22 half-planes), whatever the number of sets.
pub(crate) const PROBLEM_CANDIDATES: usize = 100_000;

/// Projection rounds of the witness search.
const WITNESS_ROUNDS: usize = 32;

/// Screening slack of the floating-point cofactors (relative): only what is clearly no proof is
/// skipped; the exact check decides.
const SCREEN: f64 = 1e-6;

/// The indices (increasing) of at most d + 1 of the `m` half-spaces `row(j)` = (normal, offset)
/// that have no common point, proved by Farkas' lemma in exact arithmetic (module docs); `None` when
/// no proof is found (the set may be nonempty, or beyond the search's limits). `start` is where
/// the witness search starts (the origin if `None`); `budget` the candidates the problem has
/// left ([`PROBLEM_CANDIDATES`] at first), reduced by this set's. The normals are finite,
/// non-zero and of dimension `d`; the offsets finite.
pub(crate) fn search<'a>(
    m: usize,
    row: impl Fn(usize) -> (&'a [f64], f64),
    d: usize,
    start: Option<&[f64]>,
    budget: &mut usize,
) -> Option<Vec<usize>> {
    if m < 2 || d == 0 || d > MAX_DIM || has_witness(m, &row, d, start) {
        return None;
    }
    let top = m.min(d + 1);
    let candidates: usize = (2..=top)
        .map(|s| binomial(m, s).saturating_mul(binomial(d, s - 1)))
        .fold(0, usize::saturating_add);
    if candidates > MAX_CANDIDATES.min(*budget) {
        return None;
    }
    *budget -= candidates;
    // Unit normals and offsets for the screen (no overflow in the cofactors).
    let unit: Vec<(Vec<f64>, f64)> = (0..m)
        .map(|j| {
            let (n, c) = row(j);
            let l = norm(n);
            (n.iter().map(|x| x / l).collect(), c / l)
        })
        .collect();
    let exact: Vec<Vec<BigInt>> = (0..m)
        .map(|j| {
            let (n, c) = row(j);
            integer_row(n, c)
        })
        .collect();
    for s in 2..=top {
        for subset in combinations(m, s) {
            for coords in combinations(d, s - 1) {
                let y = cofactors(s, &block(&subset, &coords, |j, r| unit[j].0[r]));
                let offset = |j: usize| unit[subset[j]].1;
                if screened(&y[..s], offset) && proves(&exact, &subset, &coords, d) {
                    return Some(subset);
                }
            }
        }
    }
    None
}

/// The (s − 1) × s matrix of the normals of `subset` on the coordinates `coords`
/// (`normal(j, r)`: coordinate r of half-space j), in a fixed-size block (s ≤ 4).
fn block<T: Num + Clone>(
    subset: &[usize],
    coords: &[usize],
    normal: impl Fn(usize, usize) -> T,
) -> [[T; 4]; 3] {
    std::array::from_fn(|r| {
        std::array::from_fn(|j| match (coords.get(r), subset.get(j)) {
            (Some(&c), Some(&h)) => normal(h, c),
            _ => T::zero(),
        })
    })
}

/// Whether a few rounds of projections from `start` reach a point of every half-space
/// (floating-point test: a witness only ends the search, it claims nothing).
/// (d ≤ [`MAX_DIM`]: the point lives on the stack, no allocation per set on the validation path.)
fn has_witness<'a>(
    m: usize,
    row: &impl Fn(usize) -> (&'a [f64], f64),
    d: usize,
    start: Option<&[f64]>,
) -> bool {
    let mut buf = [0.0; MAX_DIM];
    let x = &mut buf[..d];
    if let Some(s) = start {
        x.copy_from_slice(s);
    }
    let inside = |x: &[f64]| {
        (0..m).all(|j| {
            let (n, c) = row(j);
            dot(n, x) <= c
        })
    };
    for _ in 0..WITNESS_ROUNDS {
        if inside(x) {
            return true;
        }
        for j in 0..m {
            let (n, c) = row(j);
            let g = dot(n, x) - c;
            if g > 0.0 {
                // Slightly past the boundary, so that a point of a thin set lands inside it.
                axpy(-g * (1.0 + 1e-9) / dot(n, n), n, x);
            }
        }
    }
    inside(x)
}

/// Whether the floating-point cofactors `y` may be a Farkas vector: nonzero, of one sign (up
/// to [`SCREEN`]), and Σ y_j c_j not clearly positive once y ≥ 0.
fn screened(y: &[f64], offset: impl Fn(usize) -> f64) -> bool {
    let big = y.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    // (The cofactors are finite: unit normals.)
    if big == 0.0 {
        return false;
    }
    let sign = if y.iter().all(|&v| v >= -SCREEN * big) {
        1.0
    } else if y.iter().all(|&v| v <= SCREEN * big) {
        -1.0
    } else {
        return false;
    };
    let (mut sum, mut size) = (0.0, 0.0);
    for (j, &v) in y.iter().enumerate() {
        sum += sign * v * offset(j);
        size += (v * offset(j)).abs();
    }
    sum <= SCREEN * size
}

/// The exact check of one candidate: the cofactors y of the integer normals of `subset` on
/// `coords`, then Σ y_j n_j = 0 in all `d` coordinates, y ≥ 0 (after one sign) and
/// Σ y_j c_j < 0.
fn proves(exact: &[Vec<BigInt>], subset: &[usize], coords: &[usize], d: usize) -> bool {
    let s = subset.len();
    let all = cofactors(s, &block(subset, coords, |j, r| exact[j][r].clone()));
    let mut y = all[..s].to_vec();
    if y.iter().all(Zero::is_zero) {
        return false;
    }
    if y.iter().any(Signed::is_negative) {
        if y.iter().any(Signed::is_positive) {
            return false;
        }
        y.iter_mut().for_each(|v| *v = -v.clone());
    }
    let weighted =
        |k: usize| -> BigInt { y.iter().zip(subset).map(|(v, &j)| v * &exact[j][k]).sum() };
    (0..d).all(|k| weighted(k).is_zero()) && weighted(d).is_negative()
}

/// The signed maximal minors of the (s − 1) × s matrix `a` (2 ≤ s ≤ 4): y_j = (−1)^j det of
/// the matrix without column j, so that Σ_j a_rj y_j = 0 for every row r (entries past s are 0).
fn cofactors<T: Num + Clone>(s: usize, a: &[[T; 4]; 3]) -> [T; 4] {
    std::array::from_fn(|j| {
        if j >= s {
            return T::zero();
        }
        let mut cols = [0; 3];
        for (slot, c) in cols.iter_mut().zip((0..s).filter(|&c| c != j)) {
            *slot = c;
        }
        let minor = det(a, s - 1, &cols);
        if j % 2 == 0 {
            minor
        } else {
            T::zero() - minor
        }
    })
}

/// The determinant of the first `k` ≤ 3 rows of `a` on the columns `cols[..k]`.
fn det<T: Num + Clone>(a: &[[T; 4]; 3], k: usize, cols: &[usize; 3]) -> T {
    let e = |r: usize, i: usize| a[r][cols[i]].clone();
    match k {
        0 => T::one(),
        1 => e(0, 0),
        2 => e(0, 0) * e(1, 1) - e(0, 1) * e(1, 0),
        _ => {
            e(0, 0) * (e(1, 1) * e(2, 2) - e(1, 2) * e(2, 1))
                - e(0, 1) * (e(1, 0) * e(2, 2) - e(1, 2) * e(2, 0))
                + e(0, 2) * (e(1, 0) * e(2, 1) - e(1, 1) * e(2, 0))
        }
    }
}

/// (normal, offset) scaled by one power of two to integers: the same half-space.
fn integer_row(normal: &[f64], offset: f64) -> Vec<BigInt> {
    let parts: Vec<(i64, i32)> = normal.iter().chain([&offset]).map(|&x| decode(x)).collect();
    let low = parts
        .iter()
        .filter(|(m, _)| *m != 0)
        .map(|&(_, e)| e)
        .min()
        .unwrap_or(0);
    parts
        .iter()
        .map(|&(m, e)| BigInt::from(m) << ((e - low) as usize))
        .collect()
}

/// A finite double as m · 2^e, m an integer (|m| < 2^53).
fn decode(x: f64) -> (i64, i32) {
    let bits = x.to_bits();
    let sign = if bits >> 63 == 0 { 1 } else { -1 };
    let exp = ((bits >> 52) & 0x7ff) as i32;
    let frac = (bits & ((1u64 << 52) - 1)) as i64;
    if exp == 0 {
        (sign * frac, -1074)
    } else {
        (sign * (frac | (1i64 << 52)), exp - 1075)
    }
}

fn binomial(n: usize, k: usize) -> usize {
    if k > n {
        return 0;
    }
    (0..k).fold(1usize, |acc, i| acc.saturating_mul(n - i) / (i + 1))
}

/// The k-subsets of 0 .. n in lexicographic order.
fn combinations(n: usize, k: usize) -> impl Iterator<Item = Vec<usize>> {
    let mut next = (k <= n).then(|| (0..k).collect::<Vec<usize>>());
    std::iter::from_fn(move || {
        let out = next.take()?;
        let mut c = out.clone();
        let mut i = k;
        while i > 0 {
            i -= 1;
            if c[i] < n - k + i {
                c[i] += 1;
                for j in i + 1..k {
                    c[j] = c[j - 1] + 1;
                }
                next = Some(c);
                break;
            }
        }
        Some(out)
    })
}

#[cfg(test)]
mod tests {
    use super::{decode, search};

    fn run(rows: &[(&[f64], f64)]) -> Option<Vec<usize>> {
        search(
            rows.len(),
            |j| rows[j],
            rows[0].0.len(),
            None,
            &mut super::PROBLEM_CANDIDATES.clone(),
        )
    }

    #[test]
    fn decode_is_exact() {
        for x in [1.0, -0.1, 3e-310, 1.7e308, 0.0, -2.5] {
            let (m, e) = decode(x);
            // (2^e in two factors: 2^−1074 alone is below the smallest power powi reaches.)
            let back = m as f64 * 2f64.powi(e / 2) * 2f64.powi(e - e / 2);
            assert_eq!(back.to_bits(), x.to_bits(), "{x}");
        }
    }

    #[test]
    fn opposed_half_spaces_without_room_are_a_proof() {
        // x ≤ 0 and x ≥ 1 (scaled normals): empty.
        assert_eq!(
            run(&[(&[2.0, 0.0], 0.0), (&[-0.5, 0.0], -0.5)]),
            Some(vec![0, 1])
        );
        // 0 ≤ x ≤ 1: not empty; touching (x = 0 only): not empty.
        assert_eq!(run(&[(&[1.0, 0.0], 1.0), (&[-1.0, 0.0], 0.0)]), None);
        assert_eq!(run(&[(&[1.0, 0.0], 0.0), (&[-1.0, 0.0], 0.0)]), None);
        // Nearly opposite normals meet far away (x = 1e9): not empty, no proof.
        assert_eq!(run(&[(&[1.0, 0.0], 0.0), (&[-1.0, 1e-9], -1.0)]), None);
        // Normals 0.1, which is not exactly representable: 5 ≤ x ≤ 10 is not empty, x ≤ −10
        // with x ≥ −5 is, and 0.3/0.1 ≤ x ≤ 0.3/0.1 (the same doubles) touches, exactly.
        assert_eq!(run(&[(&[0.1], 1.0), (&[-0.1], -0.5)]), None);
        assert_eq!(run(&[(&[0.1], -1.0), (&[-0.1], 0.5)]), Some(vec![0, 1]));
        assert_eq!(run(&[(&[0.1], 0.3), (&[-0.1], -0.3)]), None);
    }

    #[test]
    fn three_half_planes_without_two_that_show_it() {
        // x ≤ 0, y ≤ 0, x + y ≥ 1: every two meet, the three do not.
        let empty: [(&[f64], f64); 3] = [
            (&[1.0, 0.0], 0.0),
            (&[0.0, 1.0], 0.0),
            (&[-1.0, -1.0], -1.0),
        ];
        assert_eq!(run(&empty), Some(vec![0, 1, 2]));
        // x + y ≥ 0 instead: the origin is common.
        let touching: [(&[f64], f64); 3] =
            [(&[1.0, 0.0], 0.0), (&[0.0, 1.0], 0.0), (&[-1.0, -1.0], 0.0)];
        assert_eq!(run(&touching), None);
    }

    #[test]
    fn a_triangle_with_inward_normals_is_empty() {
        // The triangle (0,0), (1,0), (0,1) with its normals flipped: outside all three edges.
        let flipped: [(&[f64], f64); 3] = [
            (&[0.0, 1.0], 0.0),
            (&[1.0, 0.0], 0.0),
            (&[-1.0, -1.0], -1.0),
        ];
        assert!(run(&flipped).is_some());
        let right: [(&[f64], f64); 3] =
            [(&[0.0, -1.0], 0.0), (&[-1.0, 0.0], 0.0), (&[1.0, 1.0], 1.0)];
        assert_eq!(run(&right), None);
    }

    #[test]
    fn four_half_spaces_in_space_and_a_degenerate_triple() {
        // x, y, z ≥ 0 and x + y + z ≤ −1e-3: the four are needed.
        let simplex: [(&[f64], f64); 4] = [
            (&[-1.0, 0.0, 0.0], 0.0),
            (&[0.0, -1.0, 0.0], 0.0),
            (&[0.0, 0.0, -1.0], 0.0),
            (&[1.0, 1.0, 1.0], -1e-3),
        ];
        assert_eq!(run(&simplex), Some(vec![0, 1, 2, 3]));
        // In R³, three half-spaces whose normals lie in the plane z = 0 (x ≤ 0, y ≤ 0,
        // x + y ≥ 1) plus an unrelated z ≤ 5: a minimal subset of size 3 < d + 1.
        let planar: [(&[f64], f64); 4] = [
            (&[0.0, 0.0, 1.0], 5.0),
            (&[1.0, 0.0, 0.0], 0.0),
            (&[0.0, 1.0, 0.0], 0.0),
            (&[-1.0, -1.0, 0.0], -1.0),
        ];
        assert_eq!(run(&planar), Some(vec![1, 2, 3]));
    }

    #[test]
    fn a_box_far_from_the_start_is_found_nonempty() {
        let b: [(&[f64], f64); 4] = [
            (&[1.0, 0.0], 1e6 + 1.0),
            (&[-1.0, 0.0], -1e6),
            (&[0.0, 1.0], -1e6 + 1.0),
            (&[0.0, -1.0], 1e6),
        ];
        assert_eq!(run(&b), None);
    }
}
