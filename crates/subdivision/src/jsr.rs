//! Bounds on the joint spectral radius ρ(𝒜) = lim_{L→∞} max_{|π| = L} ‖A_π‖^{1/L} of a finite
//! family 𝒜 = {A_0, …, A_{q−1}} of small square `f64` matrices (A_π = A_{π_1} ⋯ A_{π_L}).
//!
//! - **Lower bound**: ρ(𝒜) ≥ ρ(A_π)^{1/|π|} for every product (Rota–Strang). The spectral radius
//!   of one product is bracketed without an eigen-solver: for M of size d and k = 2^s,
//!   (|tr M^k| / d)^{1/k} ≤ ρ(M) ≤ ‖M^k‖^{1/k} (|tr M^k| = |Σ λ_i^k| ≤ d ρ^k, and Gelfand),
//!   both computed by repeated squaring with renormalization; the largest lower value over
//!   s = 0..=[`SQUARINGS`] is used. Only primitive words that are the least of their rotations are
//!   evaluated (a rotation has the same spectrum; a power gives the same root).
//! - **Upper bound**: ρ(𝒜) ≤ max_{π ∈ 𝒯} ‖A_π‖_∞^{1/|π|} for every finite set 𝒯 of words such
//!   that every infinite word starts with a member of 𝒯 (a complete prefix code): a long product
//!   splits into consecutive members of 𝒯, and the norm is submultiplicative. 𝒯 is grown
//!   best-first (Gripenberg's branch-and-bound, 1996): the word of largest normalized norm is
//!   replaced by its q extensions until that largest value is within the tolerance of the lower
//!   bound, or the budget of products or the length limit is reached.
//!
//! Products are stored normalized (‖·‖_∞ = 1) with their logarithmic scale, so long products
//! neither overflow nor underflow. Everything is `f64`: the bounds are exact up to rounding
//! (relative errors of order d · 1e−16 per product, far below the tolerances used).

use std::cmp::Ordering;
use std::collections::BinaryHeap;

/// The longest word the upper-bound search forms.
const MAX_UPPER_WORD: usize = 256;

/// Squarings used to bracket the spectral radius of one product (k = 2^s up to 2^40: the trace
/// bound is then within a factor d^{1/k} ≈ 1 + 1e−12 ln d of ρ).
pub(crate) const SQUARINGS: u32 = 40;

/// A dense square matrix, row-major.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Square {
    pub(crate) dim: usize,
    pub(crate) data: Vec<f64>,
}

impl Square {
    pub(crate) fn zeros(dim: usize) -> Self {
        Square {
            dim,
            data: vec![0.0; dim * dim],
        }
    }

    fn mul(&self, other: &Square) -> Square {
        let d = self.dim;
        let mut out = Square::zeros(d);
        for i in 0..d {
            let row = &self.data[i * d..(i + 1) * d];
            let dst = &mut out.data[i * d..(i + 1) * d];
            for (k, &a) in row.iter().enumerate() {
                if a != 0.0 {
                    for (o, &b) in dst.iter_mut().zip(&other.data[k * d..(k + 1) * d]) {
                        *o += a * b;
                    }
                }
            }
        }
        out
    }

    /// ‖M‖_∞: the largest absolute row sum.
    fn norm_inf(&self) -> f64 {
        self.data
            .chunks_exact(self.dim.max(1))
            .map(|r| r.iter().map(|x| x.abs()).sum::<f64>())
            .fold(0.0, f64::max)
    }

    fn trace(&self) -> f64 {
        (0..self.dim).map(|i| self.data[i * self.dim + i]).sum()
    }

    /// `self / s` (s > 0).
    fn scaled(mut self, s: f64) -> Square {
        for x in &mut self.data {
            *x /= s;
        }
        self
    }
}

/// A product of the family, normalized: the product equals exp(`log_scale`) · `m`, ‖m‖_∞ = 1
/// (or m = 0 with `log_scale` = −∞).
#[derive(Clone, Debug)]
struct Product {
    m: Square,
    log_scale: f64,
    len: usize,
}

impl Product {
    fn new(m: Square, log_scale: f64, len: usize) -> Self {
        let n = m.norm_inf();
        if n == 0.0 || !n.is_finite() {
            let zero = Square::zeros(m.dim);
            return Product {
                m: zero,
                log_scale: if n == 0.0 {
                    f64::NEG_INFINITY
                } else {
                    f64::NAN
                },
                len,
            };
        }
        Product {
            m: m.scaled(n),
            log_scale: log_scale + n.ln(),
            len,
        }
    }

    fn times(&self, a: &Square) -> Product {
        Product::new(self.m.mul(a), self.log_scale, self.len + 1)
    }

    /// ln ‖A_π‖^{1/|π|}.
    fn log_normalized_norm(&self) -> f64 {
        self.log_scale / self.len as f64
    }
}

/// Bounds on ln ρ(M) for one matrix: (lower, upper).
///
/// With k = 2^s: ln ρ ≤ ln ‖M^k‖ / k, and ln ρ ≥ (ln |tr M^k| − ln d) / k whenever the trace
/// does not vanish. Traces of powers 2^s alone can all vanish (a cyclic permutation of three
/// entries has tr M^{2^s} = 0); then, at the last scale, the traces of the d consecutive powers
/// M^{k+1}, …, M^{k+d} are tried: by Turán's power-sum theorem they cannot all be small when
/// ρ > 0.
fn log_spectral_radius(m: &Square) -> (f64, f64) {
    let d = m.dim as f64;
    let first = Product::new(m.clone(), 0.0, 1);
    let mut p = first.clone();
    let mut lower = f64::NEG_INFINITY;
    let mut upper = p.log_scale;
    let mut k = 1.0f64;
    for s in 0..=SQUARINGS {
        // p = M^k / ‖M^k‖ with ln ‖M^k‖ = log_scale.
        if p.log_scale == f64::NEG_INFINITY {
            // Nilpotent: ρ = 0.
            return (f64::NEG_INFINITY, f64::NEG_INFINITY);
        }
        let tr = p.m.trace().abs();
        if tr > 0.0 {
            lower = lower.max((tr.ln() + p.log_scale - d.ln()) / k);
        }
        upper = upper.min(p.log_scale / k);
        if s == SQUARINGS && lower == f64::NEG_INFINITY {
            // M^{k+j} = (p · M̂^j) · exp(log_scale + j · ln ‖M‖), M̂ = M/‖M‖.
            let mut q = p.clone();
            for j in 1..=m.dim {
                q = q.times(&first.m);
                let tr = q.m.trace().abs();
                if tr > 0.0 && q.log_scale.is_finite() {
                    let scale = q.log_scale + j as f64 * first.log_scale;
                    lower = lower.max((tr.ln() + scale - d.ln()) / (k + j as f64));
                }
            }
            break;
        }
        if s == SQUARINGS {
            break;
        }
        let sq = p.m.mul(&p.m);
        p = Product::new(sq, 2.0 * p.log_scale, 1);
        k *= 2.0;
    }
    (lower, upper)
}

/// Bounds on ρ(𝒜) and the word whose product gave the lower bound.
#[derive(Clone, Debug)]
pub(crate) struct JsrBounds {
    pub(crate) lower: f64,
    pub(crate) upper: f64,
    /// The digits of the product π with ρ(A_π)^{1/|π|} = `lower` (up to rounding).
    pub(crate) word: Vec<usize>,
}

/// Bounds on ρ(𝒜), the budgets and the tolerance as in [`crate::SmoothnessOptions`]. `target`
/// is a value the caller already knows to be at most the quantity it needs (e.g. the larger
/// lower bound of a family computed before): the upper-bound search stops once every word is
/// below max(target, lower) · (1 + tolerance).
pub(crate) fn bounds(
    family: &[Square],
    max_length: usize,
    lower_words: usize,
    upper_products: usize,
    tolerance: f64,
    target: f64,
) -> JsrBounds {
    let (lower, word) = lower_bound(family, max_length, lower_words);
    let upper = upper_bound(family, upper_products, tolerance, lower.max(target));
    JsrBounds {
        lower,
        upper: upper.max(lower),
        word,
    }
}

/// The next word over q letters in lexicographic order; `false` after the last.
fn next_word(word: &mut [usize], q: usize) -> bool {
    for i in (0..word.len()).rev() {
        word[i] += 1;
        if word[i] < q {
            return true;
        }
        word[i] = 0;
    }
    false
}

/// max over primitive least-rotation words π with |π| ≤ `max_length` (and at most `budget`
/// words in all) of the lower bound on ρ(A_π)^{1/|π|}, with the word attaining it.
pub(crate) fn lower_bound(
    family: &[Square],
    max_length: usize,
    budget: usize,
) -> (f64, Vec<usize>) {
    let q = family.len();
    let mut best = (f64::NEG_INFINITY, vec![0usize]);
    let mut evaluated = 0usize;
    'lengths: for len in 1..=max_length.max(1) {
        let mut word = vec![0usize; len];
        loop {
            if is_least_primitive_rotation(&word) {
                if evaluated >= budget {
                    break 'lengths;
                }
                evaluated += 1;
                let mut m = family[word[0]].clone();
                for &e in &word[1..] {
                    m = m.mul(&family[e]);
                }
                let (lo, _) = log_spectral_radius(&m);
                if lo / len as f64 > best.0 {
                    best = (lo / len as f64, word.clone());
                }
            }
            if !next_word(&mut word, q) {
                break;
            }
        }
    }
    (best.0.exp(), best.1)
}

/// Whether `w` is primitive (not a power of a shorter word) and the least of its rotations.
fn is_least_primitive_rotation(w: &[usize]) -> bool {
    let n = w.len();
    (1..n).all(|r| {
        let rotated = w[r..].iter().chain(&w[..r]);
        match rotated.cmp(w.iter()) {
            Ordering::Greater => true,
            // Equal to a proper rotation: periodic, not primitive.
            Ordering::Equal | Ordering::Less => false,
        }
    })
}

/// A word in the best-first search, ordered by its normalized log-norm.
struct Node(Product);

impl PartialEq for Node {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}
impl Eq for Node {}
impl PartialOrd for Node {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Node {
    fn cmp(&self, other: &Self) -> Ordering {
        self.0
            .log_normalized_norm()
            .total_cmp(&other.0.log_normalized_norm())
    }
}

/// Gripenberg's best-first bound: max over a complete prefix code of ‖A_π‖_∞^{1/|π|}.
pub(crate) fn upper_bound(
    family: &[Square],
    budget: usize,
    tolerance: f64,
    known_lower: f64,
) -> f64 {
    let stop = (known_lower * (1.0 + tolerance)).ln();
    let mut heap: BinaryHeap<Node> = family
        .iter()
        .map(|a| Node(Product::new(a.clone(), 0.0, 1)))
        .collect();
    let mut formed = 0usize;
    while let Some(Node(worst)) = heap.pop() {
        let v = worst.log_normalized_norm();
        if v.is_nan() {
            return f64::NAN;
        }
        if v <= stop || worst.len >= MAX_UPPER_WORD || formed + family.len() > budget {
            return v.exp();
        }
        for a in family {
            formed += 1;
            heap.push(Node(worst.times(a)));
        }
    }
    // An empty family: ρ = 0.
    0.0
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sq(dim: usize, data: &[f64]) -> Square {
        Square {
            dim,
            data: data.to_vec(),
        }
    }

    #[test]
    fn spectral_radius_of_small_matrices() {
        // Eigenvalues 3 and −1; a rotation by 90° scaled by 2 (eigenvalues ±2i); a Jordan block.
        for (m, rho) in [
            (sq(2, &[1.0, 2.0, 2.0, 1.0]), 3.0),
            (sq(2, &[0.0, -2.0, 2.0, 0.0]), 2.0),
            (sq(2, &[0.5, 1.0, 0.0, 0.5]), 0.5),
            (sq(3, &[0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]), 1.0),
        ] {
            let (lo, hi) = log_spectral_radius(&m);
            assert!(lo.exp() <= rho * (1.0 + 1e-12) && hi.exp() >= rho * (1.0 - 1e-12));
            assert!((lo.exp() - rho).abs() < 1e-6 * rho, "{lo} {rho}");
        }
    }

    #[test]
    fn primitive_least_rotations() {
        assert!(is_least_primitive_rotation(&[0]));
        assert!(is_least_primitive_rotation(&[0, 1]));
        assert!(!is_least_primitive_rotation(&[1, 0]));
        assert!(!is_least_primitive_rotation(&[0, 0]));
        assert!(!is_least_primitive_rotation(&[0, 1, 0, 1]));
        assert!(is_least_primitive_rotation(&[0, 0, 1]));
        assert!(!is_least_primitive_rotation(&[0, 1, 0]));
    }

    #[test]
    fn joint_spectral_radius_of_a_classical_pair() {
        // {[[1, 1], [0, 1]], [[1, 0], [1, 1]]}: ρ = φ, the golden ratio. ρ ≥ ρ(AB)^{1/2} = φ
        // (AB = [[2, 1], [1, 1]], eigenvalue φ²); ρ ≤ φ because the entries of a product of L
        // factors are bounded by Fibonacci numbers F_{L+2} (induction on L).
        let a = sq(2, &[1.0, 1.0, 0.0, 1.0]);
        let b = sq(2, &[1.0, 0.0, 1.0, 1.0]);
        let golden = (1.0 + 5f64.sqrt()) / 2.0;
        let b = bounds(&[a, b], 8, 10_000, 20_000, 1e-3, 0.0);
        assert!((b.lower - golden).abs() < 1e-9, "{b:?}");
        assert!(b.upper >= b.lower && b.upper < golden * 1.1, "{b:?}");
        assert_eq!(b.word, vec![0, 1]);
    }
}
