//! Verification cases for the `subdivision` crate: Khan et al. (seed 001) and Warren–Weimer's
//! chapter 6 (seed 003). Exact checks report as residual the largest |difference| of the compared
//! rationals (0 means identical) or a count of mismatches; floating-point checks report the
//! largest deviation. Every case names its oracle.
//!
//! # Inventory of seed 001 (Khan, Mukhtar, Batool 2013)
//!
//! | item | what it says | case(s) |
//! |---|---|---|
//! | (2.1) | n-ary refinement p^{k+1}_{ni+α} = Σ_j a_{j,α} p^k_{i+j} | `khan/2.1/closed-apply-vs-naive`, `khan/3.13/interpolating-old-points-kept` |
//! | (2.2) | each rule sums to 1 | `khan/2.2/partition-of-unity` |
//! | (2.3)–(2.5) | Newton form, divided differences, Newton basis | `khan/2.3-2.5/newton-form-equals-lagrange` |
//! | (3.1)–(3.4) | 2-point binary rule p_{2i+1} = (p_i + p_{i+1})/2 | `khan/3.3/binary-2-point` |
//! | (3.5)–(3.6) | 4-point and (2m+2)-point binary rules, coefficients C in product form | `khan/3.13/binary-4-point-DD`, `khan/3.13/binary-6-point-DD`, `khan/3.13/lagrange-barycentric-vs-product` |
//! | (3.7)–(3.9) | ternary Newton form and parameter values 1/3, 2/3 | `khan/3.8/ternary-newton-form-at-(3.9)` |
//! | (3.10) | ternary 4-point rules as printed | `khan/3.13/ternary-4-point-a1`, `…-a2-mirror`; printed: `khan/3.10/printed-ternary-4-point-a1`, `…-a2` (expected failures: 4/80, 5/80 for 4/81, 5/81) |
//! | (3.11)–(3.12) | ternary compact and general forms | covered by (3.13) with n = 3: `khan/3.13/ternary-*`, `khan/3.13/polynomial-reproduction-2m+1` |
//! | (3.13) | the (2m+2)-point n-ary family | `khan/3.13/polynomial-reproduction-2m+1`, `khan/3.13/floats-correctly-rounded`, `khan/3.13/open-ends-reproduce-cubics`, `khan/3.13/ternary-6-point-a1` |
//! | Remark 3.1 | four named members as printed | `khan/remark3.1/printed-binary-4-point`, `…-binary-6-point` (hold); `…-ternary-4-point`, `…-ternary-4-point-a2`, `…-ternary-6-point` (expected failures, coefficient by coefficient) |
//! | (4.1) | tensor-product refinement | `khan/4.1/separable-equals-2d-masks`, `khan/4.2/open-grid-reproduces-bicubics` |
//! | (4.2) | the tensor-product formula | `khan/4.2/surface-mask-is-tensor-product` |
//! | Remark 4.1 | printed Kobbelt and ternary 2-D masks | `khan/4.2/kobbelt-mask-(1,1)`, `khan/4.2/ternary-mask-(a,b)` ×4, `khan/remark4.1/printed-edge-rules` |
//! | Lemma 4.1 | four-sided support regions | `khan/lemma4.1/curve-support-exact`, `khan/lemma4.1/surface-support-four-sided` |
//! | Remark 4.2 | support = tensor product of the curve supports | `khan/remark4.2/surface-support-is-product` |
//! | Lemma 4.2 | tensor products have the continuity of the curve scheme | `khan/lemma4.2/tensor-smoothness-{4,6}-point-{binary,ternary}` |
//! | §1 | higher arity: lower support | `khan/sec1/support-shrinks-with-arity` |
//! | §1 | higher arity: higher approximation order | `khan/sec1/approximation-order-grows-with-arity` (expected failure: 2m+1 for every n) |
//! | smoothness (issue 16 §2) | the seed states no continuity per (m, n); it cites \[12\] (Dubuc–Deslauriers) and \[13\] (Lian) | `khan/smoothness/binary-4-point-DD-holder-2`, `…-6-point-DD-holder-2.830` (published values), `khan/smoothness/finite-difference-holder-estimates` (family, n = 2..4) |
//! | Figures 1–2 | labelling of old and new points | not numeric: the labelling is (2.1)/(4.1), checked above |
//! | Figures 3–4 | pictures of refined curves and a surface | not numeric: redrawn by `cargo xtask figures` (schemes); the initial polygons are not printed |
//!
//! # Inventory of seed 003 (Warren & Weimer, ch. 6, pp. 174–183)
//!
//! | item | what it says | case(s) |
//! |---|---|---|
//! | (6.15) | the differential method's relation | referred to only; its statement lies outside the excerpt |
//! | E_k, U_k (§6.2.2–6.2.3) | E_k = 8^k E, upsampling i = 2j | `ww/thm6.3/two-scale-relation-independent` (library vs definitions) |
//! | (6.16) | multiscale relation E_k p_k = U_{k−1}⋯U_0 E_0 p_0 | `ww/thm6.3/multiscale-relation-6.16`, `ww/fig6.4/differences-vanish-off-integers` |
//! | Theorem 6.3, (6.17), Fig. 6.3 | two-scale relation ⇒ multiscale relation | `ww/thm6.3/two-scale-relation-independent` (printed S, E and U from definitions), `ww/thm6.3/multiscale-relation-6.16` |
//! | Fig. 6.4 | E_k p_k replicate E_0 p_0 on Z, zero elsewhere | `ww/fig6.4/differences-vanish-off-integers` |
//! | §6.2.4 null space | (6.17) leaves S free by constants and linears | `ww/6.2.4/kernel-needs-end-conditions` |
//! | §6.2.4 S | ends unit vectors, (½, ½), (⅛, ¾, ⅛) | `ww/6.2.4/S-end-unit-interior-bspline` |
//! | §6.2.4 Bézier table on [0, 4], Fig. 6.5 | the five basis functions | `ww/6.2.4/bezier-table-on-[0,4]` |
//! | §6.2.4 | basis C² piecewise cubic, natural ends, middle = cubic B-spline | `ww/6.2.4/basis-C2-natural-ends` |
//! | §6.2.4 | p_∞ ∈ C² | `ww/6.2.4/interior-rule-C2` (Hölder exponent of the interior rule), `ww/6.2.4/basis-C2-natural-ends` (the ends) |
//! | Fig. 6.6 | parametric use | `ww/fig6.6/parametric-R3-per-coordinate` |
//! | §6.3.1 N | Uᵀ N S = N, rows sum to 1, (⅙, ⅔, ⅙) | `ww/6.3.1/N-closed-form-and-recurrence` |
//! | §6.3.1 / Fig. 6.7 | p_0 = N⁻¹ b interpolates b | `ww/6.3.1/interpolation-via-N-inverse` (closed form of the deviation after k levels) |
//! | §6.3 | the limit minimizes energy among interpolants | `ww/thm6.4/limit-energy-equals-spline-energy` (equal to the natural spline's, the minimizer) |
//! | Theorem 6.4 | ⟨p_∞, q_∞⟩ = p_0ᵀ E_0 N_0 q_0 | `ww/thm6.4/limit-energy-equals-spline-energy`, `ww/thm6.4/inner-product-bilinear`, `ww/thm6.4/energy-gap-exactly-quartered` |
//! | §6.3.2 example | energies 71.3139 … 32.5338 → 32.4959 | `ww/thm6.4/book-sequence-consistent` (the polygon is not printed; a polygon with the same e_0 and E must reproduce e_1..e_5) |

mod khan;
mod khan_shape;
mod ww;

use subdivision::{rational_to_f64, BigRational, RationalMatrix};

use super::{worst, Case};

fn q(s: &str) -> BigRational {
    s.parse().expect("a rational literal")
}

fn qs(v: &[&str]) -> Vec<BigRational> {
    v.iter().map(|s| q(s)).collect()
}

/// Largest |a_i − b_i| (as f64 of the exact difference); ∞ if the lengths differ.
fn max_diff(a: &[BigRational], b: &[BigRational]) -> f64 {
    if a.len() != b.len() {
        return f64::INFINITY;
    }
    worst(
        a.iter()
            .zip(b)
            .map(|(x, y)| rational_to_f64(&(x - y)).abs()),
    )
}

fn show(w: &[BigRational]) -> String {
    let v: Vec<String> = w.iter().map(|x| x.to_string()).collect();
    format!("({})", v.join(", "))
}

fn abs(x: &BigRational) -> BigRational {
    if x < &q("0") {
        q("0") - x
    } else {
        x.clone()
    }
}

fn lcg(seed: &mut u64) -> f64 {
    *seed = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    ((*seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
}

/// Largest entrywise |a − b|; ∞ if the shapes differ.
fn mismatches(a: &RationalMatrix, b: &RationalMatrix) -> f64 {
    if (a.rows(), a.cols()) != (b.rows(), b.cols()) {
        return f64::INFINITY;
    }
    worst((0..a.rows()).map(|i| max_diff(a.row(i), b.row(i))))
}

/// The cases of this area.
pub fn cases() -> Vec<Case> {
    let mut v = khan::cases();
    v.extend(khan_shape::cases());
    v.extend(ww::cases());
    v
}
