//! Interpolatory refinement (3.3) in closed form on the knots of the k-level split (3.1).
//!
//! The split divides data span i into m = k + 1 equal sub-spans of length h_i, so every *span
//! row* of A (the rows v_i + 1 … v_i + k, whose three vertices lie in one span) is
//! σ_i (1, −2, 1) with σ_i = h_i^{−3/2} (`alpha_row(h, h)`). The span matrix of
//! [`crate::fast`] is then B_i = σ_i L with L = tridiag(1, −2, 1) of order k, whose inverse is
//! known: (L⁻¹)_{jl} = −min(j, l)(m − max(j, l))/m. Everything [`crate::fast`] computes per span
//! by an LU chain has a closed form (l = 1 … k):
//!
//! - g_l = −(m − l)/(m σ), h_l = −l/(m σ);
//!   g·g = h·h = k(2k + 1)/(6 m σ²), g·h = k(k + 2)/(6 m σ²);
//! - g·c = −(k y_i + y_{i+1})/m, h·c = −(y_i + k y_{i+1})/m (c the fixed-end column of the span);
//! - with μ = α_{v_i,3} s_i and ν = α_{v_{i+1},1} s_{i+1} from the data-row system, the free
//!   vertices x = B⁻¹(−μ g − ν h − c) are
//!
//!   x_l = y_i + (y_{i+1} − y_i) l/m − h_i³ (μ W_g(l) + ν W_h(l)),
//!   W_g(l) = l(l − m)(l − 2m)/(6m),  W_h(l) = l(m − l)(m + l)/(6m),
//!
//!   because L W_g = (L⁻¹ e_1) = −(m − l)/m and L W_h = −l/m (second differences of cubics).
//!   Each span is a cubic in l: Kersey's Corollary 3.3 (jmp = 0 at the free vertices) in closed
//!   form.
//!
//! So one O(n) pass builds the data-row system, one cyclic tridiagonal solve gives s, and one
//! streaming pass writes the N vertices — no per-vertex divisions and no O(N) temporaries. The
//! result agrees with [`crate::fast::interpolate`] on the same knots to rounding (tested).

use divdiff::{Knots, Points};

use crate::operator::alpha_row;
use crate::Error;

/// Solves (3.3) on `knots`, which must be the k-level split of data knots (every data span
/// divided into `m` equal sub-spans; the data knots are `knots.values()[m·i]`), with q_i fixed
/// at vertex m·i.
///
/// # Errors
/// [`Error::Energy`] (`Singular`) naming a data vertex whose pivot in the data-row system is not
/// positive (impossible for valid knots: the system's diagonal is ≥ 1 and it is diagonally
/// dominant; reported rather than assumed).
pub(crate) fn interpolate(knots: &Knots, q: &Points, m: usize) -> Result<Points, Error> {
    let t = knots.values();
    let spans = knots.span_count() / m;
    let h: Vec<f64> = (0..spans)
        .map(|i| (t[(i + 1) * m] - t[i * m]) / m as f64)
        .collect();
    from_spans(&h, knots.is_closed(), q, m)
}

/// [`interpolate`] on the split of the data knots `u` (the refined knots are not built).
pub(crate) fn interpolate_from_data_knots(
    u: &Knots,
    q: &Points,
    m: usize,
) -> Result<Points, Error> {
    interpolate_from_data_values(u.values(), u.is_closed(), q, m)
}

/// [`interpolate`] on the split of the data knot values `u` (one more than the spans; the
/// refined knots are not built). On the values the split starts from (the exact grid of
/// [`crate::algorithm::split_knots`]) the sub-span lengths are those [`interpolate`] reads off
/// the split knots, bit for bit: every split knot u_i + j·step is exact there.
pub(crate) fn interpolate_from_data_values(
    u: &[f64],
    closed: bool,
    q: &Points,
    m: usize,
) -> Result<Points, Error> {
    let h: Vec<f64> = u.windows(2).map(|w| (w[1] - w[0]) / m as f64).collect();
    from_spans(&h, closed, q, m)
}

/// The closed forms, given the sub-span length h_i of every data span.
fn from_spans(h: &[f64], closed: bool, q: &Points, m: usize) -> Result<Points, Error> {
    let n = q.len();
    let d = q.dim();
    let spans = if closed { n } else { n - 1 };
    let k = (m - 1) as f64;
    let mf = m as f64;
    let y = q.coords();
    let yn = |i: usize| if i == n { 0 } else { i };

    let gg_unit = k * (2.0 * k + 1.0) / (6.0 * mf);
    let gh_unit = k * (k + 2.0) / (6.0 * mf);
    // α₁ and α₃ of the data rows (α₂ = −α₁ − α₃ is not needed).
    let (a1s, a3s) = data_alphas(h, closed, n);

    let first = usize::from(!closed);
    let last = if closed { n } else { n - 1 }; // exclusive
    let size = last.saturating_sub(first);
    // The data-row values s (zero at the end rows of an open curve), solved in place from the
    // right-hand side, with T assembled straight into its band.
    let mut s = vec![0.0; n * d];
    if size > 0 {
        let mut diag = vec![0.0; size];
        let mut off = vec![[0.0]; size];
        let rhs = &mut s[first * d..last * d];
        // Rows in parallel chunks (`crate::par`): each row is its own formula.
        crate::par::band_rows(&mut diag, &mut off, rhs, d, m, |j, dg, of, r| {
            let i = first + j;
            let (a1, a3) = (a1s[i], a3s[i]);
            let prev = if i == 0 { spans - 1 } else { i - 1 };
            let (h3p, h3c) = (h[prev].powi(3), h[i].powi(3)); // (i < spans)
            *dg = 1.0 + (a1 * a1 * h3p + a3 * a3 * h3c) * gg_unit;
            if i + 1 < last || closed {
                *of = a3 * a1s[yn(i + 1)] * gh_unit * h3c;
            }
            let (ip, inext) = (if i == 0 { n - 1 } else { i - 1 }, yn(i + 1));
            for (c, rc) in r.iter_mut().enumerate() {
                let (yp, yi, ynx) = (y[ip * d + c], y[i * d + c], y[inext * d + c]);
                // α₂ y_i − α₁ (h·c)_{i−1} − α₃ (g·c)_i with (h·c)_{i−1} = −(y_{i−1} + k y_i)/m
                // and (g·c)_i = −(k y_i + y_{i+1})/m; by α₂ = −α₁ − α₃ this is a difference
                // form, exact under translation of the data.
                *rc = (a1 * (yp - yi) + a3 * (ynx - yi)) / mf;
            }
        });
        crate::fast::solve_band(diag, off, rhs, d, closed && size >= 3).map_err(|j| {
            Error::from(energy::Error::Singular {
                vertex: (first + j) * m,
            })
        })?;
    }

    // The cubic weights, shared by every span.
    let w: Vec<[f64; 3]> = (1..m)
        .map(|l| {
            let l = l as f64;
            [
                l / mf,
                l * (l - mf) * (l - 2.0 * mf) / (6.0 * mf),
                l * (mf - l) * (mf + l) / (6.0 * mf),
            ]
        })
        .collect();
    let total = m * spans + usize::from(!closed);
    // One span (its data vertex and free vertices) per unit; an open curve's last data point
    // is the last unit, alone.
    let span = |i: usize, mu: &mut [f64], nu: &mut [f64], dy: &mut [f64]| -> usize {
        if i == spans {
            return n - 1;
        }
        let r = yn(i + 1);
        let h3 = h[i].powi(3);
        let (ya, yb) = (&y[i * d..(i + 1) * d], &y[r * d..(r + 1) * d]);
        let (a3, b1) = (a3s[i], a1s[r]);
        for c in 0..d {
            mu[c] = a3 * s[i * d + c] * h3;
            nu[c] = b1 * s[r * d + c] * h3;
            dy[c] = yb[c] - ya[c];
        }
        i
    };
    match d {
        1 => vertices::<1>(total, m, q, &w, span),
        2 => vertices::<2>(total, m, q, &w, span),
        3 => vertices::<3>(total, m, q, &w, span),
        _ => {
            // Spans in parallel chunks (`crate::par`), written into zeroed points.
            let fill =
                |(mu, nu, dy): &mut (Vec<f64>, Vec<f64>, Vec<f64>), i: usize, buf: &mut [f64]| {
                    let ya = q.point(span(i, mu, nu, dy));
                    buf[..d].copy_from_slice(ya);
                    for (o, wl) in buf[d..].chunks_exact_mut(d).zip(&w) {
                        for c in 0..d {
                            o[c] = free_vertex(ya[c], dy[c], mu[c], nu[c], wl);
                        }
                    }
                };
            let scratch = || (vec![0.0; d], vec![0.0; d], vec![0.0; d]);
            Ok(crate::par::points_by_units(
                d, total, None, m, scratch, fill,
            )?)
        }
    }
}

/// The `total` vertices of the closed form for fixed dimension D, span by span (module docs):
/// a span's data vertex y_i, then its free vertices y_i + (y_{i+1} − y_i) l/m − (μ W_g(l) +
/// ν W_h(l)) with h_i³ in μ and ν; `span(i, μ, ν, y_{i+1} − y_i)` writes those of span i and
/// returns the data point it starts at (the last unit of an open curve: its last data point,
/// alone). Collected straight into the result ([`crate::par::collect_units`]), each vertex
/// checked for finiteness as it is written.
///
/// # Errors
/// [`divdiff::Error::NonFinite`] naming the first vertex with a non-finite coordinate.
fn vertices<const D: usize>(
    total: usize,
    m: usize,
    q: &Points,
    w: &[[f64; 3]],
    span: impl Fn(usize, &mut [f64], &mut [f64], &mut [f64]) -> usize + Sync + Send,
) -> Result<Points, Error> {
    let head = |i: usize| {
        let (mut mu, mut nu, mut dy) = ([0.0; D], [0.0; D], [0.0; D]);
        let at = span(i, &mut mu, &mut nu, &mut dy);
        let ya: [f64; D] = q.point(at).try_into().expect("D coordinates");
        (ya, dy, mu, nu)
    };
    let value = |&(ya, dy, mu, nu): &([f64; D], [f64; D], [f64; D], [f64; D]), l: usize| {
        let Some(wl) = l.checked_sub(1).map(|l| w[l]) else {
            return ya;
        };
        std::array::from_fn(|c| free_vertex(ya[c], dy[c], mu[c], nu[c], &wl))
    };
    let bad = |x: &[f64; D]| x.iter().fold(false, |b, x| b | !x.is_finite());
    crate::par::collect_units(crate::par::Units {
        len: total,
        per_unit: m,
        head,
        value,
        bad,
    })
    .map(Points::from_array_rows)
    .map_err(|index| {
        Error::from(divdiff::Error::NonFinite {
            field: "points",
            index,
        })
    })
}

/// One coordinate of a free vertex (module docs): y_i + (y_{i+1} − y_i) l/m − (μ W_g(l) +
/// ν W_h(l)), with `wl` = [l/m, W_g(l), W_h(l)] and h_i³ in μ and ν.
#[inline(always)]
fn free_vertex(y: f64, dy: f64, mu: f64, nu: f64, wl: &[f64; 3]) -> f64 {
    y + dy * wl[0] - (mu * wl[1] + nu * wl[2])
}

/// α₁ and α₃ of every data row ([`alpha_row`] of the sub-spans on either side, bit for bit;
/// zero rows at the ends of an open curve), in one [`crate::par::vectorized`] pass. Why a
/// table (1.6 MB at n = 10⁵): formed where they were used, in the system's assembly and in
/// every span of the spans' pass, the rows' square roots and divisions were a call each, a
/// latency chain the processor could not overlap — 15 % of a certified 10⁵-point solve.
fn data_alphas(h: &[f64], closed: bool, n: usize) -> (Vec<f64>, Vec<f64>) {
    let (mut a1, mut a3) = (vec![0.0; n], vec![0.0; n]);
    // Rows 1 .. end read the sub-spans h_{i−1}, h_i; row 0 of a closed curve wraps.
    let end = if closed { n } else { n - 1 };
    if end > 1 {
        crate::par::vectorized(Alphas {
            hl: &h[..end - 1],
            hr: &h[1..end],
            a1: &mut a1[1..end],
            a3: &mut a3[1..end],
        });
    }
    if closed {
        let [x, _, z] = alpha_row(h[n - 1], h[0]);
        (a1[0], a3[0]) = (x, z);
    }
    (a1, a3)
}

/// [`data_alphas`]' straight loop, as [`crate::par::vectorized`] runs it.
struct Alphas<'a> {
    hl: &'a [f64],
    hr: &'a [f64],
    a1: &'a mut [f64],
    a3: &'a mut [f64],
}

impl pulp::WithSimd for Alphas<'_> {
    type Output = ();
    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) {
        let Alphas { hl, hr, a1, a3 } = self;
        for (((a1, a3), &hl), &hr) in a1.iter_mut().zip(a3).zip(hl).zip(hr) {
            let [x, _, z] = alpha_row(hl, hr);
            (*a1, *a3) = (x, z);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::operator::Stencil;
    use proptest::prelude::*;

    fn split_knots(u: &[f64], m: usize, closed: bool) -> Knots {
        let mut t = Vec::new();
        for i in 0..u.len() - 1 {
            for j in 0..m {
                let s = j as f64 / m as f64;
                t.push((1.0 - s) * u[i] + s * u[i + 1]);
            }
        }
        t.push(u[u.len() - 1]);
        if closed {
            Knots::closed(t).unwrap()
        } else {
            Knots::open(t).unwrap()
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        /// The closed forms agree with the LU-based condensation of `fast` on random
        /// non-uniform data knots, open and closed, k = 1 … 6, d = 1 … 4.
        #[test]
        fn agrees_with_the_lu_condensation(
            n in 3usize..12,
            m in 2usize..8,
            d in 1usize..5,
            closed in any::<bool>(),
            seed in 0u64..1_000_000,
        ) {
            let mut state = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            let mut rnd = || {
                state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                (state >> 11) as f64 / (1u64 << 53) as f64
            };
            let spans = if closed { n } else { n - 1 };
            let mut u = vec![0.0];
            for _ in 0..spans {
                let last = *u.last().unwrap();
                u.push(last + 0.05 + 3.0 * rnd());
            }
            let q = Points::new(d, (0..n * d).map(|_| 4.0 * rnd() - 2.0).collect()).unwrap();
            let knots = split_knots(&u, m, closed);
            let ours = interpolate(&knots, &q, m).unwrap();
            let reference = crate::fast::interpolate_condensed(&knots, &Stencil::new(&knots), &q, m).unwrap();
            let streamed = crate::fast::interpolate(&knots, &q, m, None).unwrap();
            // The streaming passes do the condensation's arithmetic operation for operation.
            prop_assert_eq!(streamed.coords(), reference.coords());
            prop_assert_eq!(ours.len(), reference.len());
            let scale = q.coords().iter().fold(1.0f64, |a, v| a.max(v.abs()));
            for (a, b) in ours.coords().iter().zip(reference.coords()) {
                prop_assert!((a - b).abs() <= 1e-11 * scale, "{a} vs {b}");
            }
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(32))]
        /// `Problem::refine_points` returns the points and knots of `Problem::solve` (one
        /// interpolatory step, no knot update), whose certificate holds; also far from the origin.
        #[test]
        fn refine_points_equals_the_certified_solve(
            n in 3usize..10,
            k in 1usize..6,
            closed in any::<bool>(),
            shift in prop_oneof![Just(0.0), Just(1e4)],
            seed in 0u64..1_000_000,
        ) {
            use crate::{Parametrization, Problem};
            let mut state = seed.wrapping_mul(6364136223846793005).wrapping_add(7);
            let mut rnd = || {
                state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                (state >> 11) as f64 / (1u64 << 53) as f64
            };
            let coords: Vec<f64> = (0..n)
                .flat_map(|i| {
                    let th = std::f64::consts::TAU * (i as f64 + 0.4 * rnd()) / n as f64;
                    let r = 1.0 + 0.5 * rnd();
                    [shift + r * th.cos(), r * th.sin()]
                })
                .collect();
            let topology = if closed { divdiff::Topology::Closed } else { divdiff::Topology::Open };
            let problem = Problem::new(Points::new(2, coords).unwrap())
                .with_topology(topology)
                .with_k(k)
                .with_parametrization(Parametrization::Centripetal)
                .with_knot_iterations(0);
            let (p, t) = (problem.refine_points().unwrap(), problem.refined_knots().unwrap());
            let solved = problem.solve().unwrap();
            prop_assert!(solved.kkt_residual <= 1e-9, "kkt {}", solved.kkt_residual);
            // (`solve` parametrizes the centred data: the chords agree to rounding.)
            for (a, b) in t.values().iter().zip(solved.knots.values()) {
                prop_assert!((a - b).abs() <= 1e-12 * (1.0 + shift) * (1.0 + b.abs()), "{a} vs {b}");
            }
            for (a, b) in p.coords().iter().zip(solved.points.coords()) {
                prop_assert!((a - b).abs() <= 1e-12 * (1.0 + shift), "{a} vs {b}");
            }
        }
    }

    #[test]
    fn refine_points_refuses_constraints() {
        use crate::{Constraint, Error, Problem};
        let q = Points::from_rows(&[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]]).unwrap();
        let e = Problem::new(q)
            .with_constraint(Constraint::Balls(vec![0.1; 3]))
            .refine_points()
            .unwrap_err();
        assert!(
            matches!(
                e,
                Error::Unsupported {
                    field: "constraint",
                    ..
                }
            ),
            "{e}"
        );
    }

    /// The smallest problems: an open segment (no data-row unknowns) is the straight line, and
    /// a closed triangle and d = 1 agree with the certified solve.
    #[test]
    fn smallest_problems_agree_with_solve() {
        use crate::Problem;
        let segment = Problem::new(Points::from_rows(&[[0.0, 0.0], [3.0, 1.5]]).unwrap())
            .with_topology(divdiff::Topology::Open)
            .with_k(5)
            .with_knot_iterations(0);
        let p = segment.refine_points().unwrap();
        assert_eq!(p.len(), 7);
        for (j, x) in p.iter().enumerate() {
            let s = j as f64 / 6.0;
            assert!(
                (x[0] - 3.0 * s).abs() < 1e-15 && (x[1] - 1.5 * s).abs() < 1e-15,
                "{x:?}"
            );
        }
        for (q, topology) in [
            (
                vec![vec![0.0, 0.0], vec![1.0, 0.0], vec![0.0, 1.0]],
                divdiff::Topology::Closed,
            ),
            (
                vec![vec![0.0], vec![1.0], vec![-2.0], vec![0.5]],
                divdiff::Topology::Open,
            ),
        ] {
            let problem = Problem::new(Points::from_rows(&q).unwrap())
                .with_topology(topology)
                .with_k(1)
                .with_knot_iterations(0);
            let (a, b) = (
                problem.refine_points().unwrap(),
                problem.solve().unwrap().points,
            );
            for (x, y) in a.coords().iter().zip(b.coords()) {
                assert!((x - y).abs() < 1e-13, "{x} vs {y}");
            }
        }
    }
}
