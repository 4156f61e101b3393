//! Knots, divided differences and discrete derivatives of piecewise-linear curves.
//!
//! This crate implements the vocabulary of S. N. Kersey, *near-interpolatory variational
//! refinement of piecewise-linear curves* (J. Comput. Appl. Math. 223, 2009; seed
//! `000_8a81be4d4deadca6.txt`), §2 and §3.6, and the parametrizations of its Algorithm 4.1 step
//! (iv). Indices are 0-based in code (the paper's are 1-based).
//!
//! # The math
//!
//! A curve is a polygon p_0..p_{N−1} in R^d with knots t_0 < … < t_{N−1} ([`Topology::Open`]) or
//! t_0 < … < t_N ([`Topology::Closed`]: the last span closes the curve, p_N = p_0, and knots and
//! points extend periodically, t_{i+N} = t_i + T, h_{i+N} = h_i). With h_i = t_{i+1} − t_i:
//!
//! - divided differences Δ_{i,n} f = \[t_i, …, t_{i+n}\] f by the recurrence, cross-checked by the
//!   explicit formula Δ_{i,n} f = Σ_k p_{i+k} / π'_{i,n}(t_{i+k}) ([`divided_difference`],
//!   [`divided_difference_explicit`]);
//! - slopes s_i = (p_{i+1} − p_i)/h_i ([`slopes`]) and second differences
//!   Δ_{i−1,2} f = (s_i − s_{i−1})/(h_{i−1} + h_i) centred at t_i ([`second_differences`]);
//! - the jump of the discrete third derivative (§2.2)
//!   jmp_i(D³f) = (h_{i−1,3}/h_i) Δ_{i−1,3} f − (h_{i−2,3}/h_{i−1}) Δ_{i−2,3} f ([`jumps`]);
//!   Theorem 2.1 says E(f) = Σ p_i · jmp_i (the energy lives in the `energy` crate);
//! - vertex derivatives Df(t_i) as linear stencils ([`derivative_stencil`]): the average (2.2)
//!   ½(s_{i−1} + s_i), and Bessel's rule — the derivative at t_i of the quadratic through
//!   p_{i−1}, p_i, p_{i+1}. **The printed (2.3) is the derivative at t_{i−1}**; this crate
//!   implements the derivative at t_i (exact on quadratics, tested). Open ends use §3.6: the
//!   derivative at the end of the end quadratic (printed correctly), or the one-sided difference;
//! - parametrizations u_{i+1} = u_i + |q_{i+1} − q_i|^e, not normalized, e = 0 uniform, ½
//!   centripetal, 1 chordal ([`parametrize`]).
//!
//! # Example
//!
//! ```
//! use divdiff::{
//!     jumps, parametrize, vertex_derivative, DerivativeRule, Parametrization, Points, Topology,
//! };
//! // A closed square, chordal knots 0, 1, 2, 3, 4.
//! let q = Points::from_rows(&[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]).unwrap();
//! let knots = parametrize(&q, Topology::Closed, Parametrization::Chordal).unwrap();
//! assert!(knots.values().iter().zip([0.0, 1.0, 2.0, 3.0, 4.0]).all(|(a, b)| (a - b).abs() < 1e-15));
//! // At a corner the Bessel derivative is the average of the two sides' directions.
//! let df = vertex_derivative(&knots, &q, 1, DerivativeRule::Bessel).unwrap();
//! assert!((df[0] - 0.5).abs() < 1e-15 && (df[1] - 0.5).abs() < 1e-15);
//! // By symmetry the third-derivative jump at a corner points outwards along the diagonal.
//! let j = jumps(&knots, &q).unwrap();
//! assert!(j.point(1)[0] > 0.0 && (j.point(1)[0] + j.point(1)[1]).abs() < 1e-15);
//! ```

mod derivative;
mod differences;
mod error;
mod knots;
mod parametrize;
mod points;

pub use derivative::{derivative_stencil, vertex_derivative, vertex_derivatives, DerivativeRule};
pub use differences::{
    divided_difference, divided_difference_explicit, jumps, second_differences, slopes,
};
pub use error::Error;
pub use knots::{Knots, Topology};
pub use parametrize::{accumulate, parametrize, span_count, span_powers, Parametrization};
pub use points::{all_finite, Points};
