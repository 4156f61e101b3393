//! Exact rational helpers: Lagrange basis weights and correct rounding to `f64`.

use num_bigint::BigInt;
use num_rational::BigRational;
use num_traits::{One, ToPrimitive, Zero};

/// The Lagrange basis on the integer nodes `lo, lo + 1, …, lo + count − 1`, evaluated exactly at
/// `x`: entry j is L_j(x) = Π_{l ≠ j} (x − l) / (j − l) (node j = `lo + j`).
///
/// For `count == 0` the result is empty. When `x` is a node the result is the unit vector of
/// that node.
///
/// ```
/// use subdivision::{lagrange_weights, BigRational};
/// // The 4-point binary rule: nodes −1..2 at x = 1/2 give (−1, 9, 9, −1)/16.
/// let w = lagrange_weights(-1, 4, &BigRational::new(1.into(), 2.into()));
/// let expect: Vec<BigRational> = [-1, 9, 9, -1]
///     .iter()
///     .map(|&v| BigRational::new(v.into(), 16.into()))
///     .collect();
/// assert_eq!(w, expect);
/// ```
pub fn lagrange_weights(lo: isize, count: usize, x: &BigRational) -> Vec<BigRational> {
    let node = |j: usize| BigRational::from_integer(BigInt::from(lo + j as isize));
    // If x is a node the basis is a unit vector; otherwise use the barycentric form
    // L_j(x) = ℓ(x) w_j / (x − x_j), ℓ(x) = Π (x − x_l), w_j = 1 / Π_{l≠j} (x_j − x_l),
    // which needs O(count) products per weight instead of O(count²).
    if let Some(k) = (0..count).find(|&j| node(j) == *x) {
        return (0..count)
            .map(|j| {
                if j == k {
                    BigRational::one()
                } else {
                    BigRational::zero()
                }
            })
            .collect();
    }
    let ell = (0..count).fold(BigRational::one(), |acc, l| acc * (x - node(l)));
    (0..count)
        .map(|j| {
            // Π_{l≠j} (j − l) over consecutive integers = (−1)^{count−1−j} j! (count−1−j)!.
            let denom = (0..count)
                .filter(|&l| l != j)
                .fold(BigInt::one(), |acc, l| {
                    acc * BigInt::from(j as isize - l as isize)
                });
            &ell / (BigRational::from_integer(denom) * (x - node(j)))
        })
        .collect()
}

/// The `f64` nearest to the exact rational `q` (round half to even), as computed by
/// `num-rational`'s correctly rounded conversion; ±∞ or 0 outside the `f64` range.
pub fn rational_to_f64(q: &BigRational) -> f64 {
    // `Ratio<BigInt>::to_f64` scales the quotient to 55–56 bits and rounds with the remainder as
    // sticky bit; it returns None only for NaN, which a rational cannot be.
    q.to_f64().unwrap_or(f64::NAN)
}
