//! Smoothness of uniform stationary n-ary subdivision: sum rules, difference schemes, joint
//! spectral radius bounds, Hölder exponent and Cᵏ class of the limit functions.
//!
//! # The method
//!
//! A scheme of arity n in d = 1 or 2 variables refines p^{k+1}_j = Σ_i a_{j − n i} p^k_i
//! (i, j ∈ Z^d); its symbol is A(z) = Σ_r a_r z^r. With σ(z) = 1 + z + ⋯ + z^{n−1}:
//!
//! - **Sum rules.** ℓ_t is the largest power of σ(z_t) dividing A (exact rational division).
//!   Convergence needs ℓ_t ≥ 1 in every direction, and Cᵏ limits need ℓ_t ≥ k + 1.
//! - **Difference schemes.** If σ(z_1) | A, the differences Δ_1 p^k = p^k_{i+e_1} − p^k_i obey
//!   Δ_1 p^{k+1} = S_{A/σ(z_1)} Δ_1 p^k, and the k-th divided differences n^{k·…} Δ^β p^k of
//!   total order |β| = k are subdivided by n^k A/σ^β. The scheme is Cᵏ if and only if every
//!   scheme of k-th divided differences converges, that is, if and only if every difference
//!   scheme n^k A/σ^α with |α| = k + 1 is contractive: its joint spectral radius ρ_k < 1
//!   (Dyn & Levin, *Subdivision schemes in geometric modelling*, Acta Numerica 11 (2002),
//!   Theorems 4.11–4.13 for n = 2; Hassan & Dodgson, *Ternary and three-point univariate
//!   subdivision schemes* (2003) for n = 3 and the same argument for any n; for the tensor
//!   products of two univariate schemes the difference schemes are scalar and decouple).
//! - **Joint spectral radius.** ρ of a scheme S_c is that of its n^d digit matrices
//!   (A_ε)_{J,I} = c_{nI − J + ε} on a window of ⌈N_t/(n−1)⌉ indices per direction (N_t + 1
//!   coefficients of c in direction t; Daubechies & Lagarias, *Two-scale difference equations II*,
//!   SIAM J. Math. Anal. 23 (1992)): bounded below by spectral radii of products and above by
//!   norms of products (see the `jsr` module).
//! - **Hölder exponent.** With ℓ = min_t ℓ_t and K = ℓ − 1, the limit functions have Hölder
//!   exponent α = K − log_n ρ_K (Rioul, *Simple regularity criteria for subdivision schemes*,
//!   SIAM J. Math. Anal. 23 (1992); Daubechies & Lagarias 1992), so the JSR bounds bracket α.
//!
//! Cᵏ is decided from the Hölder bounds where they are conclusive (k < α_lower ⇒ Cᵏ;
//! k > α_upper ⇒ not Cᵏ) and otherwise from ρ_k itself (ρ_k upper < 1 ⇒ Cᵏ, ρ_k lower > 1 ⇒
//! not Cᵏ, each by a margin of 1e−9 over rounding; ρ_k = 1 is certified exactly by a product of
//! digit matrices with the eigenvalue ±1, det(A_π ∓ I) = 0 in rationals): e.g. the 4-point
//! Dubuc–Deslauriers scheme has α = 2 and ρ_2 = 1 exactly, so it is C¹ and not C².
//!
//! Known values the tests reproduce: uniform B-splines of degree p (symbol n (σ/n)^{p+1}):
//! α = p; the binary 4-point Dubuc–Deslauriers scheme: α = 2 (Dubuc 1986; Daubechies &
//! Lagarias 1992); the binary 6-point one: α ≈ 2.830 (Daubechies & Lagarias 1992; Floater &
//! Muntingh, *Exact regularity of pseudo-splines*, 2012).
//!
//! The masks are exact rationals; the digit matrices and the JSR bounds are `f64`.

use num_bigint::BigInt;
use num_rational::BigRational;
use num_traits::{One, Zero};

use crate::jsr::{self, Square};
use crate::matrix::RationalMatrix;
use crate::nary::{check_arity, NaryScheme};
use crate::rational::rational_to_f64;
use crate::Error;

/// A mask of a uniform stationary n-ary subdivision scheme in d = 1 or 2 variables:
/// p^{k+1}_j = Σ_i a_{j − n i} p^k_i. Stored on the smallest box holding its nonzero
/// coefficients, row-major (the last index fastest).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Mask {
    arity: usize,
    first: Vec<isize>,
    shape: Vec<usize>,
    coeffs: Vec<BigRational>,
}

/// Bounds `lower ≤ x ≤ upper` on a computed quantity.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounds {
    /// The lower bound.
    pub lower: f64,
    /// The upper bound.
    pub upper: f64,
}

/// Budgets and tolerance of [`smoothness`]. The work per difference scheme is about
/// dim³ · (45 · `lower_words` + `upper_products`) flops for digit matrices of dimension dim:
/// milliseconds for curve schemes (dim ≤ 30), seconds for the surfaces of the 6-point schemes
/// (dim 40), where smaller budgets give looser but still valid bounds.
#[derive(Clone, Debug, PartialEq)]
pub struct SmoothnessOptions {
    /// Longest product whose spectral radius enters the lower JSR bound. Default 8.
    pub max_length: usize,
    /// Most products (primitive words up to rotation) evaluated for the lower bound per
    /// difference scheme. Default 2 000.
    pub lower_words: usize,
    /// Most matrix products formed by the upper-bound search per difference scheme.
    /// Default 20 000.
    pub upper_products: usize,
    /// The upper-bound search stops when every word's normalized norm is within this relative
    /// distance of the lower bound. Default 1e−4.
    pub tolerance: f64,
    /// Largest digit-matrix dimension accepted (the product of the window widths).
    /// Default 256.
    pub max_matrix: usize,
}

impl Default for SmoothnessOptions {
    fn default() -> Self {
        SmoothnessOptions {
            max_length: 8,
            lower_words: 2_000,
            upper_products: 20_000,
            tolerance: 1e-4,
            max_matrix: 256,
        }
    }
}

/// What [`smoothness`] finds about a scheme.
#[derive(Clone, Debug, PartialEq)]
pub struct Smoothness {
    /// Per direction t: ℓ_t, the largest power of σ(z_t) = 1 + z_t + ⋯ + z_t^{n−1} dividing the
    /// symbol.
    pub sum_rules: Vec<usize>,
    /// Bounds on the Hölder exponent α of the limit functions (`None` if some ℓ_t = 0: the
    /// scheme does not converge).
    pub holder: Option<Bounds>,
    /// (k, bounds on ρ_k) for each order k whose difference schemes were analysed: ρ_k is the
    /// largest JSR of the difference schemes n^k A/σ^α, |α| = k + 1. Cᵏ ⇔ ρ_k < 1.
    pub difference_jsr: Vec<(usize, Bounds)>,
    /// The largest k for which the limits are proven Cᵏ (`None`: not even C⁰ proven).
    pub smooth: Option<usize>,
    /// The smallest k for which the limits are proven not Cᵏ (`None`: none proven).
    pub not_smooth: Option<usize>,
}

/// Floating-point JSR bounds decide ρ_k < 1 or ρ_k ≥ 1 only when they clear 1 by this
/// relative margin (they are exact up to rounding, ≪ 1e−9); at 1 within the margin, ρ_k ≥ 1 is
/// certified exactly by a product with eigenvalue ±1, or the order stays undecided.
const DECISION_MARGIN: f64 = 1e-9;

fn q(v: i64) -> BigRational {
    BigRational::from_integer(BigInt::from(v))
}

fn pow(base: usize, exp: usize) -> BigRational {
    (0..exp).fold(BigRational::one(), |acc, _| acc * q(base as i64))
}

impl Mask {
    /// A univariate mask: `coeffs[r]` is a_{first + r}.
    ///
    /// # Errors
    /// [`Error::TooFew`] (`arity`) below 2 or (`coeffs`) for no coefficient,
    /// [`Error::TooLarge`] (`arity`) above [`crate::MAX_ARITY`], [`Error::InvalidValue`] (`coeffs`)
    /// unless the coefficients sum to n (each of the n rules reproducing constants).
    pub fn new(arity: usize, first: isize, coeffs: Vec<BigRational>) -> Result<Mask, Error> {
        let len = coeffs.len();
        Mask::build(arity, vec![first], vec![len], coeffs)
    }

    /// A bivariate mask on the box `first + [0, shape[0]) × [0, shape[1])`, row-major:
    /// `coeffs[r * shape[1] + s]` is a_{(first\[0\] + r, first\[1\] + s)}.
    ///
    /// # Errors
    /// As [`Mask::new`] (the coefficients must sum to n²), and [`Error::WrongLength`]
    /// (`coeffs`) if `coeffs.len() != shape[0] * shape[1]`.
    pub fn bivariate(
        arity: usize,
        first: [isize; 2],
        shape: [usize; 2],
        coeffs: Vec<BigRational>,
    ) -> Result<Mask, Error> {
        let expected = shape[0].checked_mul(shape[1]).ok_or(Error::TooLarge {
            field: "shape",
            limit: usize::MAX,
            got: usize::MAX,
        })?;
        if coeffs.len() != expected {
            return Err(Error::WrongLength {
                field: "coeffs",
                expected,
                got: coeffs.len(),
            });
        }
        Mask::build(arity, first.to_vec(), shape.to_vec(), coeffs)
    }

    /// The tensor product a(z_1) b(z_2) of two univariate masks of the same arity.
    ///
    /// # Errors
    /// [`Error::InvalidValue`] (`other`) if a mask is not univariate or the arities differ.
    pub fn tensor(&self, other: &Mask) -> Result<Mask, Error> {
        if self.dimension() != 1 || other.dimension() != 1 || self.arity != other.arity {
            return Err(Error::InvalidValue {
                field: "other",
                index: 0,
                reason: "a tensor product needs two univariate masks of the same arity",
            });
        }
        let mut coeffs = Vec::with_capacity(self.coeffs.len() * other.coeffs.len());
        for x in &self.coeffs {
            for y in &other.coeffs {
                coeffs.push(x * y);
            }
        }
        Mask::bivariate(
            self.arity,
            [self.first[0], other.first[0]],
            [self.shape[0], other.shape[0]],
            coeffs,
        )
    }

    fn build(
        arity: usize,
        first: Vec<isize>,
        shape: Vec<usize>,
        coeffs: Vec<BigRational>,
    ) -> Result<Mask, Error> {
        check_arity(arity)?;
        if coeffs.is_empty() {
            return Err(Error::TooFew {
                field: "coeffs",
                minimum: 1,
                got: 0,
            });
        }
        let sum = coeffs.iter().fold(BigRational::zero(), |a, c| a + c);
        if sum != pow(arity, shape.len()) {
            return Err(Error::InvalidValue {
                field: "coeffs",
                index: 0,
                reason: "the coefficients must sum to n^d (every rule reproduces constants)",
            });
        }
        Ok(Mask {
            arity,
            first,
            shape,
            coeffs,
        }
        .trimmed())
    }

    /// The arity n.
    pub fn arity(&self) -> usize {
        self.arity
    }

    /// The number of variables d (1 or 2).
    pub fn dimension(&self) -> usize {
        self.shape.len()
    }

    /// The smallest index of the box holding the nonzero coefficients, per direction.
    pub fn first(&self) -> &[isize] {
        &self.first
    }

    /// The extent of that box, per direction.
    pub fn shape(&self) -> &[usize] {
        &self.shape
    }

    /// The coefficient a_r (zero outside the box).
    ///
    /// # Panics
    /// If `r.len()` is not the mask's dimension.
    pub fn coefficient(&self, r: &[isize]) -> BigRational {
        assert_eq!(r.len(), self.dimension(), "index of the wrong dimension");
        match self.offset(r) {
            Some(k) => self.coeffs[k].clone(),
            None => BigRational::zero(),
        }
    }

    /// The support of the basic limit function (the limit of the scheme from a single unit
    /// value at the origin), per direction: [first_t/(n−1), last_t/(n−1)], where first_t and
    /// last_t are the extreme indices of nonzero coefficients (the support of a refinable
    /// function with this mask; Daubechies & Lagarias 1992). For a bivariate mask this is the
    /// box spanned by the directions.
    pub fn support(&self) -> Vec<[BigRational; 2]> {
        let den = BigInt::from(self.arity - 1);
        (0..self.dimension())
            .map(|t| {
                let lo = BigInt::from(self.first[t]);
                let hi = BigInt::from(self.first[t] + self.shape[t] as isize - 1);
                [
                    BigRational::new(lo, den.clone()),
                    BigRational::new(hi, den.clone()),
                ]
            })
            .collect()
    }

    /// Per direction t, the largest ℓ_t such that σ(z_t)^{ℓ_t} divides the symbol.
    pub fn sum_rules(&self) -> Vec<usize> {
        (0..self.dimension())
            .map(|t| {
                let mut m = self.clone();
                let mut l = 0;
                while let Some(next) = m.divided(t) {
                    m = next;
                    l += 1;
                }
                l
            })
            .collect()
    }

    fn offset(&self, r: &[isize]) -> Option<usize> {
        let mut k = 0usize;
        for ((&rt, &first), &len) in r.iter().zip(&self.first).zip(&self.shape) {
            let i = rt - first;
            if i < 0 || i >= len as isize {
                return None;
            }
            k = k * len + i as usize;
        }
        Some(k)
    }

    /// The same mask on the smallest box holding its nonzero coefficients (a zero mask keeps
    /// one zero coefficient).
    fn trimmed(self) -> Mask {
        let d = self.dimension();
        let mut lo = self.shape.clone();
        let mut hi = vec![0usize; d];
        let mut any = false;
        for (k, c) in self.coeffs.iter().enumerate() {
            if c.is_zero() {
                continue;
            }
            any = true;
            let idx = self.unflatten(k);
            for t in 0..d {
                lo[t] = lo[t].min(idx[t]);
                hi[t] = hi[t].max(idx[t]);
            }
        }
        if !any {
            return Mask {
                arity: self.arity,
                first: vec![0; d],
                shape: vec![1; d],
                coeffs: vec![BigRational::zero()],
            };
        }
        let shape: Vec<usize> = (0..d).map(|t| hi[t] - lo[t] + 1).collect();
        let first: Vec<isize> = (0..d).map(|t| self.first[t] + lo[t] as isize).collect();
        let total: usize = shape.iter().product();
        let mut coeffs = Vec::with_capacity(total);
        for k in 0..total {
            let mut idx = vec![0usize; d];
            let mut rest = k;
            for t in (0..d).rev() {
                idx[t] = rest % shape[t] + lo[t];
                rest /= shape[t];
            }
            let old = idx
                .iter()
                .zip(&self.shape)
                .fold(0usize, |acc, (&i, &len)| acc * len + i);
            coeffs.push(self.coeffs[old].clone());
        }
        Mask {
            arity: self.arity,
            first,
            shape,
            coeffs,
        }
    }

    fn unflatten(&self, mut k: usize) -> Vec<usize> {
        let d = self.dimension();
        let mut idx = vec![0usize; d];
        for t in (0..d).rev() {
            idx[t] = k % self.shape[t];
            k /= self.shape[t];
        }
        idx
    }

    /// A / σ(z_t) if σ(z_t) divides A exactly, else `None`. Along every line in direction t,
    /// c(z) = σ(z) q(z) gives q_i = c_i − (q_{i−1} + ⋯ + q_{i−n+1}) for the first N − n + 2
    /// coefficients; the division is exact iff the top n − 1 coefficients then match too.
    fn divided(&self, t: usize) -> Option<Mask> {
        let n = self.arity;
        let len = self.shape[t];
        if len < n {
            return None;
        }
        let qlen = len - (n - 1);
        let mut shape = self.shape.clone();
        shape[t] = qlen;
        let stride: usize = self.shape[t + 1..].iter().product();
        let lines = self.coeffs.len() / len;
        let mut out = vec![BigRational::zero(); lines * qlen];
        let new_stride: usize = shape[t + 1..].iter().product();
        for line in 0..lines {
            // Index of the line's first coefficient: split `line` into (outer, inner) around t.
            let (outer, inner) = (line / stride, line % stride);
            let at = |i: usize| outer * len * stride + i * stride + inner;
            let at_q = |i: usize| outer * qlen * new_stride + i * new_stride + inner;
            let mut qv: Vec<BigRational> = Vec::with_capacity(qlen);
            for i in 0..len {
                // c_i = Σ_{s=0}^{n−1} q_{i−s} (q outside 0..qlen is zero).
                let known: BigRational = (1..n)
                    .filter(|&s| s <= i && i - s < qlen)
                    .map(|s| qv[i - s].clone())
                    .fold(BigRational::zero(), |a, b| a + b);
                let rest = &self.coeffs[at(i)] - known;
                if i < qlen {
                    qv.push(rest);
                } else if !rest.is_zero() {
                    return None;
                }
            }
            for (i, v) in qv.into_iter().enumerate() {
                out[at_q(i)] = v;
            }
        }
        Some(
            Mask {
                arity: n,
                first: self.first.clone(),
                shape,
                coeffs: out,
            }
            .trimmed(),
        )
    }

    /// The digit matrices (A_ε)_{J,I} = c_{nI − J + ε} (indices relative to the box's first
    /// corner), ε ∈ [0, n)^d, on windows of max(1, ⌈N_t/(n−1)⌉) indices per direction: the
    /// matrix dimension and, per digit, the nonzero entries as (row, column, coefficient index).
    #[allow(clippy::type_complexity)]
    fn digit_entries(
        &self,
        max_matrix: usize,
    ) -> Result<(usize, Vec<Vec<(usize, usize, usize)>>), Error> {
        let n = self.arity;
        let d = self.dimension();
        let widths: Vec<usize> = self
            .shape
            .iter()
            .map(|&s| (s - 1).div_ceil(n - 1).max(1))
            .collect();
        let dim = widths
            .iter()
            .try_fold(1usize, |a, &w| a.checked_mul(w))
            .unwrap_or(usize::MAX);
        if dim > max_matrix {
            return Err(Error::TooLarge {
                field: "max_matrix",
                limit: max_matrix,
                got: dim,
            });
        }
        let unflat = |mut k: usize, w: &[usize]| -> Vec<usize> {
            let mut idx = vec![0usize; d];
            for t in (0..d).rev() {
                idx[t] = k % w[t];
                k /= w[t];
            }
            idx
        };
        let digits = n.pow(d as u32);
        let mut out = Vec::with_capacity(digits);
        for e in 0..digits {
            let eps = unflat(e, &vec![n; d]);
            let mut entries = Vec::new();
            for row in 0..dim {
                let jj = unflat(row, &widths);
                'cols: for col in 0..dim {
                    let ii = unflat(col, &widths);
                    let mut k = 0usize;
                    for t in 0..d {
                        let r = (n * ii[t] + eps[t]) as isize - jj[t] as isize;
                        if r < 0 || r >= self.shape[t] as isize {
                            continue 'cols;
                        }
                        k = k * self.shape[t] + r as usize;
                    }
                    if !self.coeffs[k].is_zero() {
                        entries.push((row, col, k));
                    }
                }
            }
            out.push(entries);
        }
        Ok((dim, out))
    }

    /// The digit matrices in `f64`.
    fn digit_matrices(&self, max_matrix: usize) -> Result<Vec<Square>, Error> {
        let (dim, entries) = self.digit_entries(max_matrix)?;
        Ok(entries
            .iter()
            .map(|list| {
                let mut m = Square::zeros(dim);
                for &(r, c, k) in list {
                    m.data[r * dim + c] = rational_to_f64(&self.coeffs[k]);
                }
                m
            })
            .collect())
    }

    /// Whether the product of the digit matrices along `word` has the eigenvalue 1 or −1,
    /// decided exactly: det(A_π ∓ I) = 0 in rational arithmetic. A certificate that ρ ≥ 1 when
    /// the floating-point bound sits at 1 within rounding.
    fn has_unit_eigenvalue(&self, word: &[usize], max_matrix: usize) -> Result<bool, Error> {
        let (dim, entries) = self.digit_entries(max_matrix)?;
        let exact = |e: usize| {
            let mut m = RationalMatrix::zeros(dim, dim);
            for &(r, c, k) in &entries[e] {
                m.set(r, c, self.coeffs[k].clone());
            }
            m
        };
        let mut p = RationalMatrix::zeros(dim, dim);
        for i in 0..dim {
            p.set(i, i, BigRational::one());
        }
        for &e in word {
            p = p.mul(&exact(e)).expect("square matrices of one size");
        }
        Ok([BigRational::one(), -BigRational::one()]
            .iter()
            .any(|shift| {
                let mut m = p.clone();
                for i in 0..dim {
                    let v = m.get(i, i) - shift;
                    m.set(i, i, v);
                }
                m.determinant().is_zero()
            }))
    }

    /// The same coefficients starting at index `first` (univariate; for tests).
    #[cfg(test)]
    fn shifted_to(mut self, first: isize) -> Mask {
        self.first[0] = first;
        self
    }

    fn scaled(&self, s: &BigRational) -> Mask {
        Mask {
            arity: self.arity,
            first: self.first.clone(),
            shape: self.shape.clone(),
            coeffs: self.coeffs.iter().map(|c| c * s).collect(),
        }
    }
}

/// All multi-indices α ∈ N^d with |α| = `order`, α_t ≤ `limit[t]`, the ones with the largest
/// single component first (for tensor products those carry the largest JSR).
fn multi_indices(order: usize, limit: &[usize]) -> Vec<Vec<usize>> {
    let mut out = Vec::new();
    match limit.len() {
        1 => {
            if order <= limit[0] {
                out.push(vec![order]);
            }
        }
        _ => {
            for i in 0..=order {
                let j = order - i;
                if i <= limit[0] && j <= limit[1] {
                    out.push(vec![i, j]);
                }
            }
            out.sort_by_key(|a| std::cmp::Reverse(a.iter().copied().max().unwrap_or(0)));
        }
    }
    out
}

/// The difference schemes of order k: bounds on ρ_k = max_{|α| = k+1} JSR(n^k A/σ^α), and
/// whether ρ_k ≥ 1 is certified exactly (a product with eigenvalue ±1; see
/// [`Mask::has_unit_eigenvalue`]). `None` if some σ^α does not divide A (then the k-th divided
/// differences have no difference scheme and the scheme is not Cᵏ).
struct OrderJsr {
    bounds: Bounds,
    unit_certified: bool,
}

fn order_jsr(
    mask: &Mask,
    k: usize,
    sum_rules: &[usize],
    options: &SmoothnessOptions,
) -> Result<Option<OrderJsr>, Error> {
    let d = mask.dimension();
    let all = multi_indices(k + 1, &vec![k + 1; d]);
    let feasible = multi_indices(k + 1, sum_rules);
    if feasible.len() != all.len() {
        return Ok(None);
    }
    let scale = pow(mask.arity, k);
    let mut best: Option<OrderJsr> = None;
    for alpha in feasible {
        let mut c = mask.clone();
        for (t, &times) in alpha.iter().enumerate() {
            for _ in 0..times {
                c = c.divided(t).expect("divisibility checked by the sum rules");
            }
        }
        let c = c.scaled(&scale);
        let family = c.digit_matrices(options.max_matrix)?;
        // Only the largest JSR over α matters: once one is known, a scheme whose upper bound
        // stays below the largest lower bound so far needs no lower bound of its own.
        let known = best.as_ref().map_or(0.0, |b| b.bounds.lower);
        let b = if known > 0.0 {
            // The upper bound is valid whatever its stopping target; the lower bound is needed
            // only if this scheme might exceed the largest JSR found so far.
            let upper = jsr::upper_bound(&family, options.upper_products, options.tolerance, known);
            let (lower, word) = if upper <= known {
                (0.0, Vec::new())
            } else {
                jsr::lower_bound(&family, options.max_length, options.lower_words)
            };
            jsr::JsrBounds {
                lower,
                upper: upper.max(lower),
                word,
            }
        } else {
            jsr::bounds(
                &family,
                options.max_length,
                options.lower_words,
                options.upper_products,
                options.tolerance,
                0.0,
            )
        };
        // Only a lower bound within rounding of 1 needs the exact certificate.
        let unit = (1.0 - DECISION_MARGIN..=1.0 + DECISION_MARGIN).contains(&b.lower)
            && c.has_unit_eigenvalue(&b.word, options.max_matrix)?;
        best = Some(match best {
            None => OrderJsr {
                bounds: Bounds {
                    lower: b.lower,
                    upper: b.upper,
                },
                unit_certified: unit,
            },
            Some(o) => OrderJsr {
                bounds: Bounds {
                    lower: o.bounds.lower.max(b.lower),
                    upper: o.bounds.upper.max(b.upper),
                },
                unit_certified: o.unit_certified || unit,
            },
        });
    }
    Ok(best)
}

fn check_options(options: &SmoothnessOptions) -> Result<(), Error> {
    if !(options.tolerance.is_finite() && options.tolerance >= 0.0) {
        return Err(Error::InvalidValue {
            field: "tolerance",
            index: 0,
            reason: "the tolerance must be finite and non-negative",
        });
    }
    for (field, v) in [
        ("max_length", options.max_length),
        ("lower_words", options.lower_words),
        ("upper_products", options.upper_products),
        ("max_matrix", options.max_matrix),
    ] {
        if v == 0 {
            return Err(Error::TooFew {
                field,
                minimum: 1,
                got: 0,
            });
        }
    }
    Ok(())
}

/// The smoothness of the scheme with mask `mask` (see the module docs for the method):
/// sum rules, bounds on the Hölder exponent, and the Cᵏ class where the bounds decide it.
///
/// ```
/// use subdivision::{smoothness, NaryScheme, SmoothnessOptions};
/// // The binary 4-point Dubuc–Deslauriers scheme: Hölder exponent exactly 2, C¹ but not C².
/// let s = smoothness(&NaryScheme::new(4, 2)?.mask(), &SmoothnessOptions::default())?;
/// let h = s.holder.unwrap();
/// assert!((h.lower - 2.0).abs() < 1e-9 && (h.upper - 2.0).abs() < 1e-9);
/// assert_eq!((s.smooth, s.not_smooth), (Some(1), Some(2)));
/// # Ok::<(), subdivision::Error>(())
/// ```
///
/// # Errors
/// [`Error::InvalidValue`] (`tolerance`) or [`Error::TooFew`] for an option of 0;
/// [`Error::TooLarge`] (`max_matrix`) if a difference scheme's digit matrices would be larger
/// than `options.max_matrix`.
pub fn smoothness(mask: &Mask, options: &SmoothnessOptions) -> Result<Smoothness, Error> {
    check_options(options)?;
    let sum_rules = mask.sum_rules();
    let ell = sum_rules.iter().copied().min().unwrap_or(0);
    if ell == 0 {
        // Without σ | A in every direction the scheme does not converge (Dyn & Levin 2002).
        return Ok(Smoothness {
            sum_rules,
            holder: None,
            difference_jsr: Vec::new(),
            smooth: None,
            not_smooth: Some(0),
        });
    }
    let n = mask.arity as f64;
    let top = ell - 1;
    let mut computed: Vec<(usize, Bounds)> = Vec::new();
    let top_jsr = order_jsr(mask, top, &sum_rules, options)?
        .expect("orders below the sum rules have difference schemes");
    let rho_top = top_jsr.bounds;
    computed.push((top, rho_top));
    let mut certified = vec![(top, top_jsr.unit_certified)];
    let holder = Bounds {
        lower: top as f64 - rho_top.upper.ln() / n.ln(),
        upper: top as f64 - rho_top.lower.ln() / n.ln(),
    };
    // Decide Cᵏ for k = 0..ell (C^ell would need ell + 1 sum rules). Cᵏ implies C^{k−1}, so
    // the largest k proven and the smallest k refuted say everything that was decided.
    let mut smooth: Option<usize> = None;
    let mut not_smooth = ell;
    for k in 0..ell {
        let verdict = if (k as f64) < holder.lower - DECISION_MARGIN {
            Some(true)
        } else if (k as f64) > holder.upper + DECISION_MARGIN {
            Some(false)
        } else {
            let known = computed.iter().find(|(kk, _)| *kk == k).map(|(_, b)| *b);
            let rho = match known {
                Some(b) => {
                    let unit = certified.iter().any(|&(kk, c)| kk == k && c);
                    Some((b, unit))
                }
                None => match order_jsr(mask, k, &sum_rules, options)? {
                    Some(o) => {
                        computed.push((k, o.bounds));
                        certified.push((k, o.unit_certified));
                        Some((o.bounds, o.unit_certified))
                    }
                    None => None,
                },
            };
            match rho {
                Some((b, _)) if b.upper < 1.0 - DECISION_MARGIN => Some(true),
                Some((b, unit)) if b.lower > 1.0 + DECISION_MARGIN || unit => Some(false),
                Some(_) => None,
                None => Some(false),
            }
        };
        match verdict {
            Some(true) => smooth = Some(k),
            Some(false) => {
                not_smooth = not_smooth.min(k);
                break;
            }
            None => {}
        }
    }
    computed.sort_by_key(|(k, _)| *k);
    Ok(Smoothness {
        sum_rules,
        holder: Some(holder),
        difference_jsr: computed,
        smooth,
        not_smooth: Some(not_smooth),
    })
}

impl NaryScheme {
    /// The mask of the curve scheme (3.13): a_{a − n j} = L_j(a/n), the weight of p^k_{i+j} in
    /// p^{k+1}_{n i + a} (a = 0..n−1, j = −m..m+1); nonzero on |r| ≤ n(m+1) − 1.
    pub fn mask(&self) -> Mask {
        let (n, m) = (self.arity() as isize, self.m() as isize);
        let s = n * (m + 1) - 1;
        let mut coeffs = vec![BigRational::zero(); (2 * s + 1) as usize];
        for a in 0..self.arity() {
            // Residue 0 is the unit rule: its zero weights would fall outside |r| ≤ s.
            for (w, j) in self.exact_rule(a).iter().zip(self.offsets()) {
                if !w.is_zero() {
                    coeffs[(a as isize - n * j + s) as usize] += w;
                }
            }
        }
        Mask::new(self.arity(), -s, coeffs).expect("the rules of (3.13) sum to 1")
    }

    /// The mask of the tensor-product surface scheme (4.2), read off its two-dimensional rules
    /// ([`NaryScheme::surface_rules`]): a_{(a − n r, b − n s)} = L_r(a/n) L_s(b/n).
    pub fn surface_mask(&self) -> Mask {
        let n = self.arity() as isize;
        let s = n * (self.m() as isize + 1) - 1;
        let side = (2 * s + 1) as usize;
        let mut coeffs = vec![BigRational::zero(); side * side];
        for rule in self.surface_rules() {
            let (a, b) = (rule.residue.0 as isize, rule.residue.1 as isize);
            for (&(r, t), w) in rule.offsets.iter().zip(&rule.weights) {
                if !w.is_zero() {
                    let (x, y) = (a - n * r + s, b - n * t + s);
                    coeffs[x as usize * side + y as usize] += w;
                }
            }
        }
        Mask::bivariate(self.arity(), [-s, -s], [side, side], coeffs)
            .expect("the rules of (4.2) sum to 1")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn opts() -> SmoothnessOptions {
        SmoothnessOptions::default()
    }

    /// The n-ary uniform B-spline of degree p: symbol n (σ(z)/n)^{p+1}, limit functions the
    /// B-splines of degree p on the grid Z (C^{p−1}, Hölder exponent exactly p).
    fn bspline(arity: usize, degree: usize) -> Mask {
        let mut c = vec![BigRational::one()];
        for _ in 0..=degree {
            let mut next = vec![BigRational::zero(); c.len() + arity - 1];
            for (i, v) in c.iter().enumerate() {
                for slot in &mut next[i..i + arity] {
                    *slot += v / q(arity as i64);
                }
            }
            c = next;
        }
        let c = c.into_iter().map(|v| v * q(arity as i64)).collect();
        Mask::new(arity, 0, c).unwrap()
    }

    #[test]
    fn bsplines_have_holder_exponent_their_degree() {
        for arity in 2..=4 {
            for degree in 1..=4 {
                let s = smoothness(&bspline(arity, degree), &opts()).unwrap();
                assert_eq!(s.sum_rules, vec![degree + 1]);
                let h = s.holder.unwrap();
                assert!(
                    (h.lower - degree as f64).abs() < 1e-9
                        && (h.upper - degree as f64).abs() < 1e-9,
                    "n = {arity}, p = {degree}: {h:?}"
                );
                assert_eq!(s.smooth, Some(degree - 1), "n = {arity}, p = {degree}");
                assert_eq!(s.not_smooth, Some(degree), "n = {arity}, p = {degree}");
            }
        }
    }

    #[test]
    fn dubuc_deslauriers_four_and_six_point() {
        // 4-point: α = 2 exactly, C¹ not C² (Dubuc 1986; Daubechies & Lagarias 1992).
        let s = smoothness(&NaryScheme::new(4, 2).unwrap().mask(), &opts()).unwrap();
        let h = s.holder.unwrap();
        assert_eq!(s.sum_rules, vec![4]);
        assert!(
            (h.lower - 2.0).abs() < 1e-9 && (h.upper - 2.0).abs() < 1e-9,
            "{h:?}"
        );
        assert_eq!((s.smooth, s.not_smooth), (Some(1), Some(2)));
        // 6-point: α ≈ 2.830 (Daubechies & Lagarias 1992), C² not C³.
        let s = smoothness(&NaryScheme::new(6, 2).unwrap().mask(), &opts()).unwrap();
        let h = s.holder.unwrap();
        assert_eq!(s.sum_rules, vec![6]);
        assert!(h.lower <= 2.830 && 2.830 <= h.upper + 5e-4, "{h:?}");
        assert!(h.upper - h.lower < 0.01, "{h:?}");
        assert_eq!((s.smooth, s.not_smooth), (Some(2), Some(3)));
    }

    #[test]
    fn four_point_scheme_with_tension() {
        // Dyn, Levin & Gregory (1987): mask (−w, 0, ½ + w, 1, ½ + w, 0, −w), C¹ for
        // 0 < w < (√5 − 1)/8 ≈ 0.154. Only w = 1/16 has four sum rules; otherwise two, so it is
        // never C² (a C² scheme needs three).
        for (num, den) in [(1, 32), (1, 10), (1, 8)] {
            let w = BigRational::new(num.into(), den.into());
            let half = BigRational::new(1.into(), 2.into());
            let c = vec![-w.clone(), q(0), &half + &w, q(1), &half + &w, q(0), -w];
            let s = smoothness(&Mask::new(2, -3, c).unwrap(), &opts()).unwrap();
            assert_eq!(s.sum_rules, vec![2], "w = {num}/{den}");
            assert_eq!(
                (s.smooth, s.not_smooth),
                (Some(1), Some(2)),
                "w = {num}/{den}"
            );
        }
    }

    #[test]
    fn two_point_schemes_are_piecewise_linear() {
        // m = 0: linear interpolation, the degree-1 B-spline of any arity: α = 1, C⁰ not C¹.
        for arity in 2..=6 {
            let mask = NaryScheme::new(2, arity).unwrap().mask();
            assert_eq!(mask, bspline(arity, 1).shifted_to(mask.first()[0]));
            let s = smoothness(&mask, &opts()).unwrap();
            let h = s.holder.unwrap();
            assert!((h.lower - 1.0).abs() < 1e-9 && (h.upper - 1.0).abs() < 1e-9);
            assert_eq!((s.smooth, s.not_smooth), (Some(0), Some(1)));
        }
    }

    #[test]
    fn non_convergent_masks_are_reported() {
        // Haar (piecewise constant): one sum rule, ρ_0 = 1: α = 0, not C⁰.
        let haar = Mask::new(2, 0, vec![q(1), q(1)]).unwrap();
        let s = smoothness(&haar, &opts()).unwrap();
        let h = s.holder.unwrap();
        assert!(h.lower.abs() < 1e-9 && h.upper.abs() < 1e-9);
        assert_eq!((s.smooth, s.not_smooth), (None, Some(0)));
        // No sum rule at all: p_{2i} = 2 p_i, p_{2i+1} = 0.
        let s = smoothness(&Mask::new(2, 0, vec![q(2)]).unwrap(), &opts()).unwrap();
        assert_eq!(s.sum_rules, vec![0]);
        assert_eq!((s.holder, s.smooth, s.not_smooth), (None, None, Some(0)));
    }

    #[test]
    fn masks_are_validated_and_trimmed() {
        assert!(matches!(
            Mask::new(2, 0, vec![q(1), q(2)]),
            Err(Error::InvalidValue {
                field: "coeffs",
                ..
            })
        ));
        assert!(matches!(
            Mask::new(1, 0, vec![q(1)]),
            Err(Error::TooFew { field: "arity", .. })
        ));
        assert!(matches!(
            Mask::bivariate(2, [0, 0], [2, 2], vec![q(1); 3]),
            Err(Error::WrongLength {
                field: "coeffs",
                expected: 4,
                got: 3
            })
        ));
        let m = Mask::new(2, -2, vec![q(0), q(1), q(1), q(0)]).unwrap();
        assert_eq!((m.first(), m.shape()), (&[-1isize][..], &[2usize][..]));
        assert_eq!(m.coefficient(&[0]), q(1));
        assert_eq!(m.coefficient(&[5]), q(0));
        let bad = SmoothnessOptions {
            tolerance: f64::NAN,
            ..opts()
        };
        assert!(matches!(
            smoothness(&m, &bad),
            Err(Error::InvalidValue {
                field: "tolerance",
                ..
            })
        ));
    }

    #[test]
    fn division_by_sigma_is_exact() {
        // (1 + z + z²)²/3 divided by 1 + z + z² is (1 + z + z²)/3, once more 1/3, then no more.
        let third = |v: i64| BigRational::new(v.into(), 3.into());
        let m = Mask::new(3, 0, [1, 2, 3, 2, 1].iter().map(|&v| third(v)).collect()).unwrap();
        let d = m.divided(0).unwrap();
        assert_eq!(d.coeffs, vec![third(1), third(1), third(1)]);
        assert_eq!(m.sum_rules(), vec![2]);
        // Bivariate: the tensor product divides along each direction separately.
        let t = m.tensor(&bspline(3, 0).shifted_to(0)).unwrap();
        assert_eq!(t.sum_rules(), vec![2, 1]);
    }

    #[test]
    fn supports_of_the_family() {
        // (2m+2)-point n-ary: support ±(n(m+1) − 1)/(n − 1).
        for (points, arity) in [(4, 2), (6, 2), (4, 3), (6, 3), (8, 5)] {
            let s = NaryScheme::new(points, arity).unwrap();
            let half = (arity * (s.m() + 1) - 1) as i64;
            let expect = BigRational::new(half.into(), (arity as i64 - 1).into());
            assert_eq!(s.mask().support(), vec![[-expect.clone(), expect]]);
        }
    }

    #[test]
    fn tensor_product_surface_mask_and_smoothness() {
        let s4 = NaryScheme::new(4, 2).unwrap();
        assert_eq!(s4.surface_mask(), s4.mask().tensor(&s4.mask()).unwrap());
        // Smaller budgets: the 12 × 12 digit matrices of the 2-D difference schemes are slow
        // in an unoptimized build.
        let small = SmoothnessOptions {
            max_length: 4,
            lower_words: 200,
            upper_products: 3_000,
            ..opts()
        };
        let s = smoothness(&s4.surface_mask(), &small).unwrap();
        assert_eq!(s.sum_rules, vec![4, 4]);
        let h = s.holder.unwrap();
        assert!(
            (h.upper - 2.0).abs() < 1e-9 && h.lower > 1.8 && h.lower <= 2.0,
            "{h:?}"
        );
        assert_eq!((s.smooth, s.not_smooth), (Some(1), Some(2)));
    }
}
