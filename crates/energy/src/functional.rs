//! The energy (2.1) and its derivatives with respect to the points and the knots.

use divdiff::{DerivativeRule, Knots, Points};

use crate::Error;

/// Checks that `points` has one point per vertex of `knots`.
pub(crate) fn check_sizes(knots: &Knots, points: &Points) -> Result<(), Error> {
    if points.len() != knots.vertex_count() {
        return Err(Error::WrongLength {
            field: "points",
            expected: knots.vertex_count(),
            got: points.len(),
        });
    }
    Ok(())
}

/// Kersey's energy (2.1), summed directly from the slopes:
///
/// E(f) = Σ_i |s_i − s_{i−1}|² / (h_{i−1} + h_i) = Σ_i |Δ_{i−1,2} f|² h_{i−1,2},
///
/// over every vertex i of a closed curve (indices wrapping) and the interior vertices of an open
/// one (§3.6). Here s_i = (p_{i+1} − p_i)/h_i is the slope of span i. It discretizes ½∫|f''|².
///
/// # Errors
/// [`Error::WrongLength`] if `points` does not have one point per vertex.
///
/// ```
/// use divdiff::{DerivativeRule, Knots, Points};
/// // f(t) = t² at t = 0, 1, 3: slopes 1 and 4, so E = (4 − 1)² / (1 + 2) = 3.
/// let knots = Knots::open(vec![0.0, 1.0, 3.0]).unwrap();
/// let p = Points::from_rows(&[[0.0], [1.0], [9.0]]).unwrap();
/// assert!((energy::energy(&knots, &p).unwrap() - 3.0).abs() < 1e-12);
/// ```
pub fn energy(knots: &Knots, points: &Points) -> Result<f64, Error> {
    check_sizes(knots, points)?;
    let mut e = 0.0;
    for i in crate::hessian::interior_rows(knots) {
        let (hl, hr) = (knots.h(i as isize - 1), knots.h(i as isize));
        let (l, c, r) = neighbours(knots, i);
        let d2: f64 = (0..points.dim())
            .map(|k| {
                let sl = (points.point(c)[k] - points.point(l)[k]) / hl;
                let sr = (points.point(r)[k] - points.point(c)[k]) / hr;
                (sr - sl).powi(2)
            })
            .sum();
        e += d2 / (hl + hr);
    }
    Ok(e)
}

/// The vertices (i − 1, i, i + 1), wrapping for closed curves; `i` must be interior for open ones.
pub(crate) fn neighbours(knots: &Knots, i: usize) -> (usize, usize, usize) {
    let n = knots.vertex_count();
    if knots.is_closed() {
        ((i + n - 1) % n, i, (i + 1) % n)
    } else {
        (i - 1, i, i + 1)
    }
}

/// E(f) by Kersey's Theorem 2.1: E(f) = Σ_i p_i · jmp_i(D³f), with the jumps of
/// [`divdiff::jumps`] (open curves drop the terms whose second difference does not exist).
///
/// An independent third way to the same number as [`energy`] and [`Hessian::energy`](crate::Hessian::energy).
///
/// # Errors
/// [`Error::WrongLength`] if `points` does not have one point per vertex.
pub fn energy_by_jumps(knots: &Knots, points: &Points) -> Result<f64, Error> {
    check_sizes(knots, points)?;
    let j = divdiff::jumps(knots, points)?;
    Ok(banded::vector::dot(points.coords(), j.coords()))
}

/// The second differences c_i = Δ_{i−1,2} f (zero at open ends) and the slopes s_j.
fn differences(knots: &Knots, points: &Points) -> Result<(Points, Points), Error> {
    check_sizes(knots, points)?;
    Ok((
        divdiff::second_differences(knots, points)?,
        divdiff::slopes(knots, points)?,
    ))
}

/// ∂E/∂h_j for every span j, with c_j = Δ_{j−1,2} f and s_j the slope of span j:
/// ∂E/∂h_j = (2/h_j) s_j · (c_{j+1} − c_j) − |c_j|² − |c_{j+1}|²
/// (each term present only if its second difference exists; zero rows make that automatic).
fn span_derivatives(knots: &Knots, c: &Points, s: &Points) -> Vec<f64> {
    let n = knots.vertex_count();
    (0..knots.span_count())
        .map(|j| {
            let (cj, cn, sj) = (c.point(j), c.point((j + 1) % n), s.point(j));
            let h = knots.h(j as isize);
            (0..c.dim())
                .map(|k| 2.0 / h * sj[k] * (cn[k] - cj[k]) - cj[k] * cj[k] - cn[k] * cn[k])
                .sum()
        })
        .collect()
}

/// The exact gradient of E(f) = Σ |s_i − s_{i−1}|²/(h_{i−1} + h_i) with respect to the knot
/// values, the points held fixed: one entry per knot (N open, N + 1 closed, all free; for a
/// closed curve moving t_N alone changes only the closing span).
///
/// With c_i = Δ_{i−1,2} f and h_j = t_{j+1} − t_j, E depends on the knots through the spans, and
/// ∂E/∂h_j = (2/h_j) s_j·(c_{j+1} − c_j) − |c_j|² − |c_{j+1}|², so ∂E/∂t_k = ∂E/∂h_{k−1} − ∂E/∂h_k.
/// For the knot of an interior vertex this is
///
/// ∂E/∂t_i = 2 [ s_{i−1}·(Δ_{i−1,2} − Δ_{i−2,2})/h_{i−1} − s_i·(Δ_{i,2} − Δ_{i−1,2})/h_i ]
///           + |Δ_{i,2} f|² − |Δ_{i−2,2} f|²,
///
/// which is what Kersey's Lemma 2.4 should read: the printed version (see
/// [`knot_gradient_printed`]) lacks the factor 2 and the last two terms. Two exact identities
/// follow from E being invariant under translation and homogeneous of degree −3 under scaling
/// of the knots: Σ_k ∂E/∂t_k = 0 and Σ_k t_k ∂E/∂t_k = −3E.
///
/// # Errors
/// [`Error::WrongLength`] if `points` does not have one point per vertex.
///
/// ```
/// use divdiff::{DerivativeRule, Knots, Points};
/// let knots = Knots::closed(vec![0.0, 0.7, 1.5, 3.0, 3.4]).unwrap();
/// let p = Points::from_rows(&[[0.0, 0.0], [1.0, 0.2], [0.8, 1.1], [-0.3, 0.9]]).unwrap();
/// let g = energy::knot_gradient(&knots, &p).unwrap();
/// // Central finite difference in t_2.
/// let d = 1e-6;
/// let e = |dt: f64| {
///     let mut t = knots.values().to_vec();
///     t[2] += dt;
///     energy::energy(&Knots::closed(t).unwrap(), &p).unwrap()
/// };
/// assert!((g[2] - (e(d) - e(-d)) / (2.0 * d)).abs() < 1e-6);
/// ```
pub fn knot_gradient(knots: &Knots, points: &Points) -> Result<Vec<f64>, Error> {
    let (c, s) = differences(knots, points)?;
    let de_dh = span_derivatives(knots, &c, &s);
    let m = knots.values().len();
    Ok((0..m)
        .map(|k| {
            let left = if k >= 1 { de_dh[k - 1] } else { 0.0 };
            let right = if k < de_dh.len() { de_dh[k] } else { 0.0 };
            left - right
        })
        .collect())
}

/// The exact derivative of E with respect to each vertex's parameter: one entry per vertex.
///
/// Open curves: the same as [`knot_gradient`]. Closed curves: entry i ≥ 1 is ∂E/∂t_i; entry 0
/// moves vertex 0's parameter in the periodic sense, i.e. t_0 and t_N together (the period is
/// unchanged), so it is ∂E/∂t_0 + ∂E/∂t_N. This is the quantity Kersey's Lemma 2.4 and
/// Corollary 2.5 talk about (the free-knot condition is that it vanishes).
///
/// # Errors
/// [`Error::WrongLength`] if `points` does not have one point per vertex.
pub fn vertex_knot_gradient(knots: &Knots, points: &Points) -> Result<Vec<f64>, Error> {
    let mut g = knot_gradient(knots, points)?;
    if knots.is_closed() {
        let last = g.pop().unwrap_or(0.0);
        g[0] += last;
    }
    Ok(g)
}

/// Kersey's Lemma 2.4 **as printed** — known to be wrong (math.md §1); kept to document that:
///
/// ∂_{t_i} E(f) "=" −(h_{i−1,3}/h_i) Δ_{i−1,3} f · f'(t_i⁺) + (h_{i−2,3}/h_{i−1}) Δ_{i−2,3} f · f'(t_i⁻),
///
/// one entry per vertex (compare with [`vertex_knot_gradient`]), evaluated through
/// h_{i−1,3} Δ_{i−1,3} f = Δ_{i,2} f − Δ_{i−1,2} f, f'(t_i⁺) = s_i and f'(t_i⁻) = s_{i−1}. Open curves
/// drop the terms whose second difference or span does not exist. It disagrees with central
/// finite differences of [`energy`]: its proof drops a factor 2 and the terms
/// |Δ_{i,2} f|² − |Δ_{i−2,2} f|² in its last steps (see [`knot_gradient`]).
///
/// # Errors
/// [`Error::WrongLength`] if `points` does not have one point per vertex.
pub fn knot_gradient_printed(knots: &Knots, points: &Points) -> Result<Vec<f64>, Error> {
    let (c, s) = differences(knots, points)?;
    let n = knots.vertex_count();
    let closed = knots.is_closed();
    Ok((0..n)
        .map(|i| {
            let (prev, next) = ((i + n - 1) % n, (i + 1) % n);
            let mut v = 0.0;
            if closed || i + 1 < n {
                let h = knots.h(i as isize);
                let jump = c
                    .point(next)
                    .iter()
                    .zip(c.point(i))
                    .map(|(a, b)| (a - b) / h);
                v -= jump.zip(s.point(i)).map(|(a, b)| a * b).sum::<f64>();
            }
            if closed || i >= 1 {
                let h = knots.h(i as isize - 1);
                let sl = s.point((i + knots.span_count() - 1) % knots.span_count());
                let jump = c
                    .point(i)
                    .iter()
                    .zip(c.point(prev))
                    .map(|(a, b)| (a - b) / h);
                v += jump.zip(sl).map(|(a, b)| a * b).sum::<f64>();
            }
            v
        })
        .collect())
}

/// The free-knot orthogonality residuals of Kersey's Corollary 2.7, Df(t_i) · (Hp)_i, one per
/// vertex, with Df by `rule` (a diagnostic: the corollary says they are ≈ 0 at optimal knots).
///
/// Note that the corollary inherits the error of the printed Lemma 2.4: the exact free-knot
/// condition is [`vertex_knot_gradient`] = 0, which with s_{i−1} ≈ s_i ≈ Df(t_i) reads
/// −Df(t_i)·(Hp)_i + |Δ_{i,2} f|² − |Δ_{i−2,2} f|² ≈ 0.
///
/// # Errors
/// [`Error::WrongLength`] if `points` does not have one point per vertex.
pub fn orthogonality_residuals(
    knots: &Knots,
    points: &Points,
    rule: DerivativeRule,
) -> Result<Vec<f64>, Error> {
    check_sizes(knots, points)?;
    let hp = crate::Hessian::new(knots).try_apply(points)?;
    let df = divdiff::vertex_derivatives(knots, points, rule)?;
    Ok((0..knots.vertex_count())
        .map(|i| banded::vector::dot(df.point(i), hp.point(i)))
        .collect())
}
