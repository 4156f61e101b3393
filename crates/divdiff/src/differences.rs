//! Divided differences of R^d vertex data on non-uniform knots (Kersey §2, §2.2).

use crate::{Error, Knots, Points};

/// Checks that `points` has one point per vertex of `knots`.
pub(crate) fn check_sizes(knots: &Knots, points: &Points) -> Result<(), Error> {
    if points.len() != knots.vertex_count() {
        return Err(Error::LengthMismatch {
            field: "points",
            expected: knots.vertex_count(),
            got: points.len(),
        });
    }
    Ok(())
}

/// The knot indices i..=i+order, checked for open curves, as (knot value, vertex index) pairs.
fn stencil(knots: &Knots, i: isize, order: usize) -> Result<Vec<(f64, usize)>, Error> {
    let n = knots.vertex_count();
    if !knots.is_closed() && (i < 0 || i as usize + order >= n) {
        return Err(Error::DifferenceOutOfRange {
            index: i,
            order,
            len: n,
        });
    }
    Ok((0..=order as isize)
        .map(|k| {
            let j = i + k;
            (knots.t(j), j.rem_euclid(n as isize) as usize)
        })
        .collect())
}

/// The divided difference Δ_{i,n} f = \[t_i, …, t_{i+n}\] f of the vertex data, by the recurrence
/// \[t_i..t_{i+n}\] f = (\[t_{i+1}..t_{i+n}\] f − \[t_i..t_{i+n−1}\] f) / (t_{i+n} − t_i), with
/// \[t_j\] f = p_j. One value per coordinate.
///
/// For closed curves any index is allowed: knots follow the periodic extension
/// t_{j+N} = t_j + T and vertices wrap, p_{j+N} = p_j (Kersey §2). For open curves the knots
/// t_i..t_{i+n} must exist.
///
/// # Errors
/// [`Error::LengthMismatch`] if `points` does not have one point per vertex;
/// [`Error::DifferenceOutOfRange`] for an open curve when i < 0 or i + n ≥ N.
///
/// ```
/// use divdiff::{divided_difference, Knots, Points};
/// // f(t) = t³ on non-uniform knots: every third divided difference is 1.
/// let t = vec![0.0, 0.5, 2.0, 2.5, 4.0];
/// let p = Points::new(1, t.iter().map(|x| x * x * x).collect()).unwrap();
/// let knots = Knots::open(t).unwrap();
/// let d3 = divided_difference(&knots, &p, 1, 3).unwrap();
/// assert!((d3[0] - 1.0).abs() < 1e-12);
/// ```
pub fn divided_difference(
    knots: &Knots,
    points: &Points,
    i: isize,
    order: usize,
) -> Result<Vec<f64>, Error> {
    check_sizes(knots, points)?;
    let s = stencil(knots, i, order)?;
    // Newton's table, one level at a time, in place: after level m, table[k] = [t_{i+k}..t_{i+k+m}] f.
    let mut table: Vec<Vec<f64>> = s.iter().map(|&(_, v)| points.point(v).to_vec()).collect();
    for m in 1..=order {
        for k in 0..=order - m {
            let dt = s[k + m].0 - s[k].0;
            let (lo, hi) = table.split_at_mut(k + 1);
            for (x, y) in lo[k].iter_mut().zip(&hi[0]) {
                *x = (y - *x) / dt;
            }
        }
    }
    Ok(table.swap_remove(0))
}

/// The same divided difference by the explicit formula (Abramowitz–Stegun 25.1.4, used in the
/// proof of Kersey's Theorem 2.1): Δ_{i,n} f = Σ_{k=0}^{n} p_{i+k} / π'_{i,n}(t_{i+k}), where
/// π_{i,n}(t) = Π_{k=0}^{n} (t − t_{i+k}).
///
/// An independent check of [`divided_difference`]; less accurate for high orders.
///
/// # Errors
/// As for [`divided_difference`].
pub fn divided_difference_explicit(
    knots: &Knots,
    points: &Points,
    i: isize,
    order: usize,
) -> Result<Vec<f64>, Error> {
    check_sizes(knots, points)?;
    let s = stencil(knots, i, order)?;
    let mut out = vec![0.0; points.dim()];
    for (k, &(tk, v)) in s.iter().enumerate() {
        let dpi: f64 = s
            .iter()
            .enumerate()
            .filter(|&(j, _)| j != k)
            .map(|(_, &(tj, _))| tk - tj)
            .product();
        for (o, x) in out.iter_mut().zip(points.point(v)) {
            *o += x / dpi;
        }
    }
    Ok(out)
}

/// The slopes s_j = \[t_j, t_{j+1}\] f = (p_{j+1} − p_j) / h_j, one per span (N − 1 open, N closed;
/// the last slope of a closed curve is that of the closing span p_{N−1} → p_0).
///
/// # Errors
/// [`Error::LengthMismatch`] if `points` does not have one point per vertex.
pub fn slopes(knots: &Knots, points: &Points) -> Result<Points, Error> {
    check_sizes(knots, points)?;
    let n = knots.vertex_count();
    let d = points.dim();
    let mut out = Vec::with_capacity(knots.span_count() * d);
    for j in 0..knots.span_count() {
        let h = knots.h(j as isize);
        let (a, b) = (points.point(j), points.point((j + 1) % n));
        out.extend(a.iter().zip(b).map(|(x, y)| (y - x) / h));
    }
    Points::new(d, out)
}

/// The second divided differences centred at each vertex: row i is
/// Δ_{i−1,2} f = \[t_{i−1}, t_i, t_{i+1}\] f = (s_i − s_{i−1}) / (h_{i−1} + h_i).
///
/// N rows. For an open curve the rows of the two end vertices are zero: the difference centred
/// there does not exist, and storing zero is exactly "dropping the term" in the energy and the
/// jump (Kersey §3.6).
///
/// # Errors
/// [`Error::LengthMismatch`] if `points` does not have one point per vertex.
pub fn second_differences(knots: &Knots, points: &Points) -> Result<Points, Error> {
    let s = slopes(knots, points)?;
    let n = knots.vertex_count();
    let d = points.dim();
    let mut out = Points::zeros(n, d);
    let rows = if knots.is_closed() {
        0..n
    } else {
        1..n.saturating_sub(1)
    };
    for i in rows {
        let l = (i + knots.span_count() - 1) % knots.span_count();
        let denom = knots.h(i as isize - 1) + knots.h(i as isize);
        for c in 0..d {
            out.point_mut(i)[c] = (s.point(i)[c] - s.point(l)[c]) / denom;
        }
    }
    Ok(out)
}

/// The jump of the discrete third derivative at every vertex (Kersey §2.2):
///
/// jmp_i(D³f) = (h_{i−1,3}/h_i) Δ_{i−1,3} f − (h_{i−2,3}/h_{i−1}) Δ_{i−2,3} f
///            = (Δ_{i,2} f − Δ_{i−1,2} f)/h_i − (Δ_{i−1,2} f − Δ_{i−2,2} f)/h_{i−1}.
///
/// N rows. Closed curves wrap. Open curves drop the terms whose second difference (or span)
/// does not exist, as the proof of Theorem 2.1 does, so that E(f) = Σ p_i · jmp_i and
/// jmp = ½Hp still hold: e.g. jmp_0 = Δ_{0,2} f / h_0.
///
/// # Errors
/// [`Error::LengthMismatch`] if `points` does not have one point per vertex.
///
/// ```
/// use divdiff::{jumps, Knots, Points};
/// // A quadratic has constant second differences, so on an open curve jmp_i = 0 wherever all
/// // three of Δ_{i−2,2}, Δ_{i−1,2}, Δ_{i,2} exist (2 ≤ i ≤ N − 3).
/// let t = vec![0.0, 0.3, 1.0, 1.8, 2.0, 3.1];
/// let p = Points::new(1, t.iter().map(|x| 2.0 * x * x - x).collect()).unwrap();
/// let j = jumps(&Knots::open(t).unwrap(), &p).unwrap();
/// assert!(j.point(2)[0].abs() < 1e-12 && j.point(3)[0].abs() < 1e-12);
/// ```
pub fn jumps(knots: &Knots, points: &Points) -> Result<Points, Error> {
    let c = second_differences(knots, points)?;
    let n = knots.vertex_count();
    let d = points.dim();
    let closed = knots.is_closed();
    let mut out = Points::zeros(n, d);
    for i in 0..n {
        let next = (i + 1) % n;
        let prev = (i + n - 1) % n;
        // Right term (Δ_{i,2} − Δ_{i−1,2}) / h_i needs span i; left term needs span i − 1.
        let right = closed || i + 1 < n;
        let left = closed || i >= 1;
        for k in 0..d {
            let mut v = 0.0;
            if right {
                v += (c.point(next)[k] - c.point(i)[k]) / knots.h(i as isize);
            }
            if left {
                v -= (c.point(i)[k] - c.point(prev)[k]) / knots.h(i as isize - 1);
            }
            out.point_mut(i)[k] = v;
        }
    }
    Ok(out)
}
