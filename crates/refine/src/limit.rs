//! The limit curve of a refinement: the cubic spline that the refined polygon tends to as the
//! split parameter grows (docs/limit.md has the derivation).
//!
//! # The math
//!
//! Kersey's energy (2.1), E = Σ |s_j − s_{j−1}|² / (h_{j−1} + h_j), discretizes ½∫|f''|²: for the
//! polygon inscribed in a C² curve at knots of mesh h,
//! |s_j − s_{j−1}| = f''(t_j)(h_{j−1} + h_j)/2 + O(h²), so E = Σ_j ¼ |f''(t_j)|² (h_{j−1} + h_j) + O(h) → ½∫|f''|². A constraint that acts on
//! data vertices only (interpolation, balls, smoothing, half-space sets) fixes nothing but the
//! values f(u_i) at the data parameters, and among curves with prescribed values at u_0 < … <
//! u_{n−1} the minimizer of ∫|f''|² is the cubic spline with breakpoints u_i (Holladay's theorem; de Boor,
//! *A Practical Guide to Splines*, rev. ed. 2001, ch. V; Warren–Weimer ch. 6, the natural cubic spline as the
//! limit of variational subdivision; math.md §4 for the strip's version of the same statement):
//! natural ends (f'' = 0) for an open curve without end conditions, periodic for a closed curve,
//! clamped (f' prescribed) where a first derivative is prescribed. So the limit curve of a
//! refinement is the cubic spline through its constrained vertices at their knots:
//!
//! - after part 1 only (`levels = 0`): through the data vertices p_{i_k} at t_{i_k};
//! - after interpolatory levels (`levels ≥ 1`): the last level interpolates every vertex of the
//!   level before it, with no derivative constraint, so through those vertices (every
//!   (level_k + 1)-th vertex of the result), natural or periodic;
//! - clamped ends: f'(t_0) = `start`, f'(t_{N−1}) = `end`, the problem's vectors with respect
//!   to the returned knots' parameter;
//! - near-clamped ends and tangent constraints (stage 0 only): f' at that vertex is prescribed to
//!   be the returned discrete derivative Df(t_{i_k}) (the problem's [`divdiff::DerivativeRule`]).
//!   Where the constraint is active this is the limit's condition (a prescribed derivative makes
//!   the spline C¹ and generally not C² there: the curve splits into clamped pieces); where it is
//!   inactive the continuous minimizer is C² there instead, and the returned curve differs from
//!   it by the O(h) error of Df. That is the one case where the curve is not the exact limit of
//!   the returned data values.
//!
//! **Solve**: with M_j = f''(t_j) and δ_j = (y_{j+1} − y_j)/h_j, C² continuity at a break j is
//! h_{j−1} M_{j−1} + 2(h_{j−1} + h_j) M_j + h_j M_{j+1} = 6(δ_j − δ_{j−1}) (de Boor ch. IV), a
//! clamped left end with slope s is 2h_0 M_0 + h_0 M_1 = 6(δ_0 − s) (the right end mirrored), a
//! natural end is M = 0. The matrix is symmetric and strictly diagonally dominant: one
//! [`banded::SymBand`]`<1>` (cyclic for a closed curve without prescribed slopes) per run between
//! prescribed slopes, d columns at once. Each piece is then stored as a cubic Bézier segment:
//! with the one-sided slopes m_0 = δ − h(2M_0 + M_1)/6 and m_1 = δ + h(M_0 + 2M_1)/6, the control
//! points are y_0, y_0 + h m_0/3, y_1 − h m_1/3, y_1.

use banded::{SymBand, Topology as BandTopology};
use divdiff::{Knots, Points, Topology};

use crate::constraint::Boundary;
use crate::{Error, Problem, Refinement};

/// A C² (C¹ where a slope is prescribed) cubic spline curve in R^d, stored as one cubic Bézier
/// segment per piece.
///
/// Piece i runs over [t_i, t_{i+1}] (`breaks`); its control points b_0..b_3 give
/// f(t_i + s h_i) = Σ_r C(3, r) (1 − s)^{3−r} s^r b_r. A closed curve is periodic with period
/// t_last − t_0; an open one is evaluated outside [t_0, t_last] by its end pieces' polynomials
/// (as scipy's `CubicSpline(extrapolate=True)`).
#[derive(Clone, Debug, PartialEq)]
pub struct CubicSpline {
    dim: usize,
    closed: bool,
    breaks: Vec<f64>,
    /// 4 · dim coordinates per piece: b_0, b_1, b_2, b_3.
    control: Vec<f64>,
}

impl CubicSpline {
    /// The cubic spline through `values` at `knots` (one value per vertex; a closed curve's last
    /// knot closes it), with ∫|f''|² minimal among the C¹ curves through those values whose first
    /// derivative is `slopes[j]` wherever that is `Some`. An open curve's end without a slope is
    /// natural (f'' = 0); a closed curve without slopes is periodic C².
    ///
    /// # Errors
    /// [`Error::WrongLength`] (`values`, `slopes`), [`Error::WrongDimension`] (`slopes`),
    /// [`Error::NonFiniteInput`] (`values`, `slopes`).
    ///
    /// ```
    /// use divdiff::{Knots, Points};
    /// use refine::CubicSpline;
    /// // f(t) = t³ on 0, 1, 3 with its own end slopes: a single cubic reproduces it exactly.
    /// let knots = Knots::open(vec![0.0, 1.0, 3.0]).unwrap();
    /// let y = Points::new(1, vec![0.0, 1.0, 27.0]).unwrap();
    /// let s = CubicSpline::through(&knots, &y, &[Some(vec![0.0]), None, Some(vec![27.0])]).unwrap();
    /// assert!((s.eval(2.0)[0] - 8.0).abs() < 1e-12);
    /// assert!((s.derivative(2.0, 2)[0] - 12.0).abs() < 1e-12);
    /// ```
    pub fn through(
        knots: &Knots,
        values: &Points,
        slopes: &[Option<Vec<f64>>],
    ) -> Result<CubicSpline, Error> {
        let n = knots.vertex_count();
        let d = values.dim();
        let closed = knots.is_closed();
        if values.len() != n {
            return Err(Error::WrongLength {
                field: "values",
                expected: n,
                got: values.len(),
            });
        }
        if slopes.len() != n {
            return Err(Error::WrongLength {
                field: "slopes",
                expected: n,
                got: slopes.len(),
            });
        }
        if let Some(index) = values.coords().iter().position(|x| !x.is_finite()) {
            return Err(Error::NonFiniteInput {
                field: "values",
                index: index / d.max(1),
            });
        }
        for (index, s) in slopes.iter().enumerate() {
            if let Some(s) = s {
                if s.len() != d {
                    return Err(Error::WrongDimension {
                        field: "slopes",
                        index,
                        expected: d,
                        got: s.len(),
                    });
                }
                if s.iter().any(|x| !x.is_finite()) {
                    return Err(Error::NonFiniteInput {
                        field: "slopes",
                        index,
                    });
                }
            }
        }
        let t = knots.values().to_vec();
        let pieces = if closed { n } else { n - 1 };
        // Values at breaks 0..=pieces (a closed curve repeats its first vertex).
        let y = |j: usize| values.point(j % n);
        let h: Vec<f64> = (0..pieces).map(|j| t[j + 1] - t[j]).collect();
        let delta: Vec<f64> = (0..pieces)
            .flat_map(|j| {
                let (a, b, hj) = (y(j), y(j + 1), h[j]);
                (0..d).map(move |c| (b[c] - a[c]) / hj)
            })
            .collect();
        // Second derivatives at both ends of every piece (equal across a C² break).
        let mut m_left = vec![0.0; pieces * d];
        let mut m_right = vec![0.0; pieces * d];
        let fixed: Vec<usize> = (0..n).filter(|&j| slopes[j].is_some()).collect();
        if closed && fixed.is_empty() {
            let m = periodic_second_derivatives(&h, &delta, d)?;
            for j in 0..pieces {
                let next = (j + 1) % n;
                m_left[j * d..(j + 1) * d].copy_from_slice(&m[j * d..(j + 1) * d]);
                m_right[j * d..(j + 1) * d].copy_from_slice(&m[next * d..(next + 1) * d]);
            }
        } else {
            // Runs of pieces between prescribed slopes (and the ends of an open curve), each an
            // open clamped/natural problem. A closed curve's runs go around from one prescribed
            // vertex to the next (the last run wraps past the closing knot).
            let runs: Vec<(usize, usize)> = if closed {
                (0..fixed.len())
                    .map(|r| {
                        let a = fixed[r];
                        let b = if r + 1 < fixed.len() {
                            fixed[r + 1]
                        } else {
                            fixed[0] + n
                        };
                        (a, b)
                    })
                    .collect()
            } else {
                let mut cuts = vec![0];
                cuts.extend(fixed.iter().copied().filter(|&j| j != 0 && j != n - 1));
                cuts.push(n - 1);
                cuts.windows(2).map(|w| (w[0], w[1])).collect()
            };
            for (a, b) in runs {
                // Pieces a..b (indices mod n for a closed curve); breaks a..=b.
                let piece = |i: usize| i % pieces;
                let hs: Vec<f64> = (a..b).map(|i| h[piece(i)]).collect();
                let ds: Vec<f64> = (a..b)
                    .flat_map(|i| delta[piece(i) * d..(piece(i) + 1) * d].iter().copied())
                    .collect();
                let left = slopes[a % n].as_deref();
                let right = slopes[b % n].as_deref();
                let m = run_second_derivatives(&hs, &ds, d, left, right)?;
                for (r, i) in (a..b).enumerate() {
                    let p = piece(i);
                    m_left[p * d..(p + 1) * d].copy_from_slice(&m[r * d..(r + 1) * d]);
                    m_right[p * d..(p + 1) * d].copy_from_slice(&m[(r + 1) * d..(r + 2) * d]);
                }
            }
        }
        let mut control = Vec::with_capacity(pieces * 4 * d);
        for j in 0..pieces {
            let (a, b, hj) = (y(j), y(j + 1), h[j]);
            let (mut b1, mut b2) = (vec![0.0; d], vec![0.0; d]);
            for c in 0..d {
                let (ml, mr, dl) = (m_left[j * d + c], m_right[j * d + c], delta[j * d + c]);
                let s0 = dl - hj * (2.0 * ml + mr) / 6.0;
                let s1 = dl + hj * (ml + 2.0 * mr) / 6.0;
                b1[c] = a[c] + hj * s0 / 3.0;
                b2[c] = b[c] - hj * s1 / 3.0;
            }
            control.extend_from_slice(a);
            control.extend_from_slice(&b1);
            control.extend_from_slice(&b2);
            control.extend_from_slice(b);
        }
        Ok(CubicSpline {
            dim: d,
            closed,
            breaks: t,
            control,
        })
    }

    /// The dimension d of the curve's points.
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// Whether the curve is closed (periodic).
    pub fn is_closed(&self) -> bool {
        self.closed
    }

    /// The breakpoints t_0 < … < t_P (P pieces; a closed curve's last one closes it).
    pub fn breaks(&self) -> &[f64] {
        &self.breaks
    }

    /// The number P of pieces.
    pub fn pieces(&self) -> usize {
        self.breaks.len() - 1
    }

    /// The parameter interval [t_0, t_P].
    pub fn domain(&self) -> (f64, f64) {
        (self.breaks[0], self.breaks[self.breaks.len() - 1])
    }

    /// The four Bézier control points of piece `i` (4 · d coordinates, b_0..b_3), or `None`
    /// if `i` ≥ P.
    pub fn bezier(&self, i: usize) -> Option<&[f64]> {
        let w = 4 * self.dim;
        self.control.get(i * w..(i + 1) * w)
    }

    /// f(u).
    pub fn eval(&self, u: f64) -> Vec<f64> {
        self.derivative(u, 0)
    }

    /// The derivative of order `order` at u (order 0 is f(u); orders above 3 are zero). At a
    /// breakpoint the piece to its right is used (the last piece at the end of an open curve).
    /// A non-finite u gives NaN coordinates.
    pub fn derivative(&self, u: f64, order: usize) -> Vec<f64> {
        let d = self.dim;
        if !u.is_finite() {
            return vec![f64::NAN; d];
        }
        if order > 3 {
            return vec![0.0; d];
        }
        let (i, s, h) = self.locate(u);
        let b = self.bezier(i).expect("locate returns a piece");
        // Differences of the control points: the r-th derivative is a Bézier curve of degree
        // 3 − r with control points 3!/(3 − r)! Δ^r b / h^r.
        let mut pts: Vec<Vec<f64>> = (0..4).map(|r| b[r * d..(r + 1) * d].to_vec()).collect();
        let mut scale = 1.0;
        for r in 0..order {
            let deg = 3 - r;
            pts = (0..deg)
                .map(|j| (0..d).map(|c| pts[j + 1][c] - pts[j][c]).collect())
                .collect();
            scale *= deg as f64 / h;
        }
        // de Casteljau.
        while pts.len() > 1 {
            pts = pts
                .windows(2)
                .map(|w| (0..d).map(|c| (1.0 - s) * w[0][c] + s * w[1][c]).collect())
                .collect();
        }
        pts.pop()
            .expect("one point")
            .into_iter()
            .map(|x| x * scale)
            .collect()
    }

    /// The piece containing u, the local parameter s = (u − t_i)/h_i and h_i.
    fn locate(&self, u: f64) -> (usize, f64, f64) {
        let t = &self.breaks;
        let (t0, t1) = self.domain();
        let u = if self.closed && !(t0..t1).contains(&u) {
            let period = t1 - t0;
            let w = t0 + (u - t0).rem_euclid(period);
            // Rounding can land exactly on t1.
            if w >= t1 {
                t0
            } else {
                w
            }
        } else {
            u
        };
        // The last break ≤ u, clamped to the pieces.
        let i = t.partition_point(|&x| x <= u).saturating_sub(1);
        let i = i.min(self.pieces() - 1);
        let h = t[i + 1] - t[i];
        (i, (u - t[i]) / h, h)
    }
}

/// M at the breaks of a periodic spline (n unknowns, cyclic tridiagonal).
fn periodic_second_derivatives(h: &[f64], delta: &[f64], d: usize) -> Result<Vec<f64>, Error> {
    let n = h.len();
    let mut a = SymBand::<1>::zeros(n, BandTopology::Cyclic);
    let mut rhs = vec![0.0; n * d];
    for j in 0..n {
        let prev = (j + n - 1) % n;
        a.add(j, j, 2.0 * (h[prev] + h[j])).map_err(singular)?;
        a.add(j, (j + 1) % n, h[j]).map_err(singular)?;
        for c in 0..d {
            rhs[j * d + c] = 6.0 * (delta[j * d + c] - delta[prev * d + c]);
        }
    }
    a.factor()
        .and_then(|f| f.solve_in_place(&mut rhs, d))
        .map_err(singular)?;
    Ok(rhs)
}

/// M at the breaks 0..=P of an open run of P pieces with spans `h` and slopes `delta`; each end
/// clamped to its slope if given, natural otherwise.
fn run_second_derivatives(
    h: &[f64],
    delta: &[f64],
    d: usize,
    left: Option<&[f64]>,
    right: Option<&[f64]>,
) -> Result<Vec<f64>, Error> {
    let p = h.len();
    let mut m = vec![0.0; (p + 1) * d];
    // Unknowns: breaks lo..=hi (a natural end's M is 0 and drops out).
    let lo = if left.is_some() { 0 } else { 1 };
    let hi = if right.is_some() { p } else { p - 1 };
    if hi < lo {
        return Ok(m);
    }
    let len = hi - lo + 1;
    let mut a = SymBand::<1>::zeros(len, BandTopology::Open);
    let mut rhs = vec![0.0; len * d];
    for j in lo..=hi {
        let r = j - lo;
        let mut diag = 0.0;
        if j > 0 {
            diag += 2.0 * h[j - 1];
        }
        if j < p {
            diag += 2.0 * h[j];
            if j < hi {
                a.add(r, r + 1, h[j]).map_err(singular)?;
            }
        }
        a.add(r, r, diag).map_err(singular)?;
        for c in 0..d {
            let after = if j < p {
                delta[j * d + c]
            } else {
                right.expect("a clamped right end")[c]
            };
            let before = if j > 0 {
                delta[(j - 1) * d + c]
            } else {
                left.expect("a clamped left end")[c]
            };
            rhs[r * d + c] = 6.0 * (after - before);
        }
    }
    a.factor()
        .and_then(|f| f.solve_in_place(&mut rhs, d))
        .map_err(singular)?;
    m[lo * d..(hi + 1) * d].copy_from_slice(&rhs);
    Ok(m)
}

/// The spline systems are strictly diagonally dominant for increasing knots, so a failure here
/// means knots too close for floating point.
fn singular(_: banded::Error) -> Error {
    Error::InvalidKnots {
        index: 0,
        reason: "the spline system through them is numerically singular (spans too unequal)",
    }
}

/// The limit curve of `refinement`, the result of `problem` (see the module docs above for
/// what that is and the one case where it is an approximation): the cubic spline through the
/// constrained vertices of its last stage, on the returned knots' parameter.
///
/// # Errors
/// As [`limit_curve_of`].
pub fn limit_curve(problem: &Problem, refinement: &Refinement) -> Result<CubicSpline, Error> {
    limit_curve_of(
        problem,
        &refinement.points,
        &refinement.knots,
        &refinement.data_vertex,
    )
}

/// [`limit_curve`] from the parts of a result (as a front end that keeps only the points, the
/// knots and the data vertices has them): `points` on `knots` solved from `problem`, `data_vertex`
/// the vertex of each data point. The last stage is part 1 when `problem.levels` is 0, else the
/// last interpolatory level (its constrained vertices every `level_k + 1`-th).
///
/// # Errors
/// [`Error::WrongLength`] if the parts do not fit `problem` (`data_vertex`) or each other
/// (`points`), [`Error::VertexOutOfRange`] for a data vertex past the points, and the errors of
/// [`CubicSpline::through`] and [`divdiff::vertex_derivative`].
pub fn limit_curve_of(
    problem: &Problem,
    points: &Points,
    knots: &Knots,
    data_vertex: &[usize],
) -> Result<CubicSpline, Error> {
    let n = problem.points.len();
    if data_vertex.len() != n {
        return Err(Error::WrongLength {
            field: "data_vertex",
            expected: n,
            got: data_vertex.len(),
        });
    }
    if points.len() != knots.vertex_count() {
        return Err(Error::WrongLength {
            field: "points",
            expected: knots.vertex_count(),
            got: points.len(),
        });
    }
    if let Some(&v) = data_vertex.iter().find(|&&v| v >= points.len()) {
        return Err(Error::VertexOutOfRange {
            field: "data_vertex",
            index: v,
            len: points.len(),
        });
    }
    let closed = knots.is_closed();
    let t = knots.values();
    let interpolatory_levels = problem.levels > 0;
    let vertices: Vec<usize> = if interpolatory_levels {
        // The last level interpolates every (level_k + 1)-th vertex.
        (0..points.len())
            .step_by(problem.level_k.max(1) + 1)
            .collect()
    } else {
        data_vertex.to_vec()
    };
    let m = vertices.len();
    let mut kt: Vec<f64> = vertices.iter().map(|&v| t[v]).collect();
    if closed {
        kt.push(t[t.len() - 1]);
    }
    let topology = if closed {
        Topology::Closed
    } else {
        Topology::Open
    };
    let spline_knots = Knots::new(topology, kt)?;
    let mut coords = Vec::with_capacity(m * points.dim());
    for &v in &vertices {
        coords.extend_from_slice(points.point(v));
    }
    let values = Points::new(points.dim(), coords)?;
    let mut slopes: Vec<Option<Vec<f64>>> = vec![None; m];
    if !interpolatory_levels {
        let df = |v: usize| divdiff::vertex_derivative(knots, points, v, problem.derivative);
        if let Some(tangents) = &problem.tangents {
            for (i, tan) in tangents.iter().enumerate() {
                if tan.is_some() && i < m {
                    slopes[i] = Some(df(data_vertex[i])?);
                }
            }
        }
        if !closed {
            match &problem.boundary {
                Boundary::Natural => {}
                Boundary::Clamped { start, end } => {
                    slopes[0] = Some(start.clone());
                    slopes[m - 1] = Some(end.clone());
                }
                Boundary::NearClamped { .. } => {
                    slopes[0] = Some(df(data_vertex[0])?);
                    slopes[m - 1] = Some(df(data_vertex[m - 1])?);
                }
            }
        }
    }
    CubicSpline::through(&spline_knots, &values, &slopes)
}
