//! Solving a [`Problem`]: Algorithm 4.1 on centred data, the closed-form interpolatory
//! refinement, and the stage-0 solve the free-knot optimizer calls.

use crate::problem::{Problem, Solver};
use crate::stage::FixedProblem;
use crate::{algorithm, strategy, uniform, Refinement};

impl Problem {
    /// Validates the problem and runs Algorithm 4.1 (see the crate docs).
    ///
    /// # Errors
    /// Any validation error of [`Problem::validate`]; [`crate::Error::DegenerateRefinedSpan`]
    /// when a knot update meets coincident refined vertices; [`crate::Error::Energy`] if a
    /// linear system is numerically singular — reported as [`crate::Error::InvalidParameter`]
    /// naming `knot_iterations` when it turns singular after a knot update, or the smoothing
    /// `weights` when they are too small against the curve's stiffness;
    /// [`crate::Error::NotConverged`] when the exact solver cannot certify a fixed-knot solve,
    /// [`crate::Error::NotConvergedAfterUpdate`] when that happens after a knot update (the solve
    /// before it certified); [`crate::Error::Unsupported`] for combinations a solver does not
    /// handle.
    pub fn solve(&self) -> Result<Refinement, crate::Error> {
        // Solve on data centred at their centroid and translate back: every part of the
        // problem is translation invariant, but the interior-point method measures its
        // convergence relative to absolute coordinates, so data far from the origin (relative
        // to their extent) stopped early with a wrong active set (tests/invariance.rs).
        self.validate()?;
        // The O(N) passes are parallel (`par`): a solve spanning several chunks runs from the
        // pool.
        let vertices = Self::refined_len(self.topology, self.points.len(), self.k);
        if vertices > crate::par::CHUNK_VERTICES {
            crate::par::on_pool(|| self.solve_validated())
        } else {
            self.solve_validated()
        }
    }

    /// [`Problem::solve`] of a validated problem.
    fn solve_validated(&self) -> Result<Refinement, crate::Error> {
        // Interpolation with natural ends is a direct solve (closed form or span condensation,
        // `linear`), with no convergence test to protect: solved where the data are, not
        // centred — but rescaled where the data or their spans are beyond `RESCALE_BEYOND`.
        if self.interpolates_with_natural_ends() {
            return self.accept(run_rescaled(self)?);
        }
        let (n, d) = (self.points.len(), self.points.dim());
        let mut centroid = vec![0.0; d];
        for x in self.points.iter() {
            for (c, v) in centroid.iter_mut().zip(x) {
                *c += v / n as f64;
            }
        }
        if centroid.iter().all(|&c| c == 0.0) {
            return self.accept(run_rescaled(self)?);
        }
        let mut centred = self.clone();
        for i in 0..n {
            for (x, c) in centred.points.point_mut(i).iter_mut().zip(&centroid) {
                *x -= c;
            }
        }
        // Each kind moves its own data with the points (half-space offsets, …).
        let offset: Vec<f64> = centroid.iter().map(|c| -c).collect();
        for kind in self.kinds() {
            kind.translate(&offset, &mut centred);
        }
        // (Centring rounds: points distinct before may coincide after; refused, not solved.)
        centred.validate()?;
        let mut r = run_rescaled(&centred)?;
        // (In parallel chunks: at N = 8·10⁵, d = 2, one core took ~1 ms over the 12.8 MB.)
        let chunks = r
            .points
            .coords_mut()
            .chunks_mut(crate::par::CHUNK_VERTICES * d);
        crate::par::map(chunks.collect(), |chunk| {
            for x in chunk.chunks_exact_mut(d) {
                for (x, c) in x.iter_mut().zip(&centroid) {
                    *x += c;
                }
            }
        });
        self.accept(r)
    }

    /// The interpolatory k-level refinement (3.3) of the data on their knots (the given knots or
    /// the parametrization), from data to refined vertices in closed form and without the
    /// certificate: O(N) with one streaming write of the N vertices (see the `uniform` module:
    /// every span of the split is a cubic). The points are those of [`Problem::solve`] with
    /// `knot_iterations = 0` and no further levels, to rounding (tested); their knots are
    /// [`Problem::refined_knots`]. Use `solve` for the energy, reactions and the KKT certificate.
    ///
    /// # Errors
    /// Any validation error of [`Problem::validate`]; [`crate::Error::Unsupported`] unless the
    /// constraint is [`crate::Constraint::Interpolate`] with no tangents and natural ends.
    ///
    /// ```
    /// use divdiff::Points;
    /// use refine::Problem;
    /// let square = Points::from_rows(&[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]).unwrap();
    /// let problem = Problem::new(square).with_k(3);
    /// let p = problem.refine_points().unwrap();
    /// assert_eq!((p.len(), problem.refined_knots().unwrap().values().len()), (16, 17));
    /// assert_eq!(p.point(4), &[1.0, 0.0]); // the data are interpolated
    /// ```
    pub fn refine_points(&self) -> Result<divdiff::Points, crate::Error> {
        self.validate()?;
        if !self.interpolates_with_natural_ends() {
            return Err(crate::Error::Unsupported {
                field: "constraint",
                reason: "refine_points is interpolation with natural ends; use solve",
            });
        }
        uniform::interpolate_from_data_knots(
            &self.data_knots_unvalidated()?,
            &self.points,
            self.k + 1,
        )
    }

    /// The conic program of the first fixed-knot solve — stage 0 on the k-level split of the
    /// data knots, before any knot update — as the constraint kinds state it: what the exact
    /// solver's full-vertex entries solve (module `strategy`), for inspection and for
    /// solving with another method (e.g. `ConicProblem::solve_clarabel`, feature `clarabel`). The data are not
    /// centred ([`Problem::solve`] centres them first).
    ///
    /// # Errors
    /// Any validation error of [`Problem::validate`]; errors of the derivative stencils.
    pub fn conic_problem(&self) -> Result<crate::ConicProblem, crate::Error> {
        self.validate()?;
        let knots = algorithm::split_knots(&self.data_knots_unvalidated()?, self.k)?;
        let stride = self.k + 1;
        let dv: Vec<usize> = (0..self.points.len()).map(|i| stride * i).collect();
        let fp = FixedProblem {
            knots: &knots,
            q: &self.points,
            data_vertex: &dv,
            constraint: &self.constraint,
            problem: self,
            derivatives: true,
            stride,
            uniform_spans: true,
            warm: None,
            recycled: Default::default(),
            options: &self.options,
        };
        let mut rows = crate::constraint::Rows::new(&fp)?;
        for k in fp.kinds() {
            k.rows(&fp, &mut rows)?;
        }
        Ok(rows.problem)
    }

    /// The knots of the k-level split (3.1) of the data knots: the knots of
    /// [`Problem::refine_points`] (and of the first solve of [`Problem::solve`]).
    ///
    /// # Errors
    /// Any validation error of [`Problem::validate`].
    pub fn refined_knots(&self) -> Result<divdiff::Knots, crate::Error> {
        self.validate()?;
        algorithm::split_knots(&self.data_knots_unvalidated()?, self.k)
    }

    /// Refuses an exact result whose independent certificate (the largest over its stages) is
    /// above [`crate::SolveOptions::accept_kkt`]: an answer that is not optimal is an error
    /// carrying the best residual reached, never a result.
    fn accept(&self, r: Refinement) -> Result<Refinement, crate::Error> {
        // The data's extent is validated, so an energy that overflows comes from derivatives
        // asked for far beyond the data's slopes (a clamped end of 1e200): no certificate can
        // vouch for it, and it was written as `"energy": null` with exit code 0.
        if !r.energy.is_finite() {
            let field = if self.boundary != crate::Boundary::Natural {
                "boundary"
            } else if self
                .tangents
                .as_ref()
                .is_some_and(|t| t.iter().any(Option::is_some))
            {
                "tangents"
            } else {
                "points"
            };
            return Err(crate::Error::InvalidParameter {
                field,
                value: r.energy,
                reason: "the optimal curve's energy overflows: the derivatives asked for are too large against the data's slopes; rescale them",
            });
        }
        // A multiplier that overflows (a ball's force over a radius of 1e-260 against data of
        // 1e-100: ~1e310) is no certificate either; it was written as null.
        // (A branch-free scan of the flat values first; the row is searched for only when one
        // fails: row by row the scan was 0.3 ms of a 10⁵-point interpolation's 10.)
        let finite = r
            .multipliers
            .values()
            .iter()
            .fold(true, |ok, x| ok & x.is_finite());
        if let Some(index) = (!finite)
            .then(|| {
                (0..r.multipliers.len())
                    .find(|&i| r.multipliers.row(i).iter().any(|x| !x.is_finite()))
            })
            .flatten()
        {
            let (field, reason) = self.constraint.kind().multiplier_overflow();
            return Err(crate::Error::InvalidValue {
                field,
                index,
                value: f64::INFINITY,
                reason,
            });
        }
        // Knots too unequal for the certificate to vouch for a conic answer (balls with a
        // positive radius, half-spaces, derivative constraints): refused, whatever it scored.
        let conic = !self.constraint.kind().linear() || self.has_derivative_constraints();
        if self.solver == Solver::Exact && conic {
            let ratio = span_ratio(&r.knots);
            if ratio > crate::MAX_CERTIFIED_SPAN_RATIO {
                return Err(crate::Error::SpansTooUnequal {
                    ratio,
                    limit: crate::MAX_CERTIFIED_SPAN_RATIO,
                });
            }
        }
        let certified = r.kkt_residual <= self.options.accept_kkt; // false for NaN too
        if self.solver == Solver::Exact && !certified {
            return Err(crate::Error::NotConverged {
                solver: "exact refinement",
                iterations: r.iterations.solver,
                residual: r.kkt_residual,
            });
        }
        Ok(r)
    }
}

/// The largest span of `knots` over the smallest (∞ when a span is 0).
fn span_ratio(knots: &divdiff::Knots) -> f64 {
    // (four spans at a time into four lanes, from arrays of four: one running minimum and
    // maximum waited on each other's compares, ~1 ms at N = 8·10⁵; both are exact, so the same
    // in any order)
    let t = knots.values();
    let spans = t.len().saturating_sub(1);
    let (a, b) = (&t[..spans], t.get(1..).unwrap_or_default());
    let ((a, a_rest), (b, b_rest)) = (a.as_chunks::<4>(), b.as_chunks::<4>());
    let (mut lo, mut hi) = ([f64::INFINITY; 4], [0.0f64; 4]);
    let mut take = |l: usize, h: f64| {
        lo[l] = lo[l].min(h);
        hi[l] = hi[l].max(h);
    };
    for (a, b) in a.iter().zip(b) {
        for l in 0..4 {
            take(l, b[l] - a[l]);
        }
    }
    for (a, b) in a_rest.iter().zip(b_rest) {
        take(0, b - a);
    }
    let lo = lo.into_iter().fold(f64::INFINITY, f64::min);
    let hi = hi.into_iter().fold(0.0f64, f64::max);
    if lo > 0.0 {
        hi / lo
    } else {
        f64::INFINITY
    }
}

/// Where [`run_rescaled`] rescales balls and half-spaces: a data extent or a mean data knot
/// span outside 2^−64 … 2^64 (about 1e−19 … 1e19).
const RESCALE_BEYOND: i32 = 64;

/// Where [`run_rescaled`] rescales a problem with derivative constraints (tangents, end
/// conditions), whatever its data constraint: outside 2^−40 … 2^40 (about 1e−12 … 1e12). On a
/// noisy star such problems were refused from 1e±15 and, at 1e80, some were certified with 1e73
/// times the optimal energy (ROBUSTNESS.md item 35); from 1e−12 to 1e12 they solved. (Not
/// nearer 1: the interior-point method is not scale invariant to the last step, and at 2^±20 a
/// random problem certified as given was refused scaled.)
const RESCALE_DERIVATIVES_BEYOND: i32 = 40;

/// [`algorithm::run`] for the exact solver on data or knots of extreme scale, solved on points,
/// radii, offsets and derivative bounds scaled by powers of two that bring the data's extent
/// and the mean data span near 1 (points by 2^−e, knots by 2^−f), and mapped back. It applies
/// to data constraints alone beyond [`RESCALE_BEYOND`] (the extent or the span beyond it scaled,
/// the other left) and to any problem with derivative constraints beyond
/// [`RESCALE_DERIVATIVES_BEYOND`] (both scaled). (Interpolation and smoothing were solved where
/// they are until a sweep with chordal knots, spans ~ the extent, met data at 1e−140: the rows
/// of H, ~1/h³ on spans of 1e−141, overflowed, and an interpolant with 1800 times the optimal
/// energy came back with a certificate of 0; ROBUSTNESS.md item 39.)
///
/// Why: a ball's multiplier is its force over its radius, w ∝ 1/h³ on spans h, and the forces
/// scale with the points: on centripetal knots of data at 1e80 (spans ~1e40) or 1e−80 the
/// interior-point method's products of such numbers under- or overflowed, and it stopped in one
/// or two iterations. Half-spaces failed from an extent of ~1e30 (a fuzz find: three points in
/// boxes of width 0 at 1e37, ROBUSTNESS.md item 34); derivative constraints from ~1e15 (item
/// 35). Every kind is homogeneous: the optimum on knots 2^−f·t for data 2^−e·q, each kind's
/// data scaled with them ([`crate::constraint::Kind::rescale`]: radii and offsets 2^−e·c,
/// smoothing weights 2^(3f)·w, derivative bounds 2^(f−e)·v, normals and wedges as given), is
/// 2^−e·p, and powers of two scale exactly, so the certificate — every part relative — is the
/// original problem's. The data knots are computed once, from the data as given, and passed
/// scaled (knot updates map back onto their span); the result maps back as points 2^e·p, knots
/// 2^f·t, E 2^(2e−3f)·E, and the multipliers by the data kind's
/// [`crate::constraint::Kind::multiplier_power`] (weights 2^(−3f)·w, forces 2^(e−3f)·λ).
fn run_rescaled(problem: &Problem) -> Result<Refinement, crate::Error> {
    let derivatives = problem.has_derivative_constraints();
    let limit = if derivatives {
        RESCALE_DERIVATIVES_BEYOND
    } else {
        RESCALE_BEYOND
    };
    if problem.solver != Solver::Exact {
        return algorithm::run(problem);
    }
    let q = &problem.points;
    let extent = banded::vector::max_dist_from(q.coords(), q.point(0));
    let u = problem.data_knots_unvalidated()?;
    let t = u.values();
    let mean_span = (t[t.len() - 1] - t[0]) / (t.len() - 1) as f64;
    // The powers of two nearest the extent and the mean span.
    let (e, f) = (
        extent.log2().round() as i32,
        mean_span.log2().round() as i32,
    );
    if e.abs() <= limit && f.abs() <= limit {
        return algorithm::run_on(problem, u);
    }
    // Balls and half-spaces scale only what is beyond (as since item 29); derivative bounds
    // involve both, and are solved with both near 1 (a problem whose points alone were brought
    // near 1 kept spans of 1e9 and was refused).
    let (e, f) = if derivatives {
        (e, f)
    } else {
        (
            if e.abs() > limit { e } else { 0 },
            if f.abs() > limit { f } else { 0 },
        )
    };
    let mut scaled = problem.clone();
    scaled
        .points
        .coords_mut()
        .iter_mut()
        .for_each(|x| *x = times_power_of_two(*x, -e));
    // Each kind scales its own data (radii, offsets, weights, derivative bounds).
    for kind in problem.kinds() {
        kind.rescale(-e, -f, &mut scaled)?;
    }
    let t_scaled: Vec<f64> = t.iter().map(|&x| times_power_of_two(x, -f)).collect();
    // (Given knots stay given, scaled: a failed split then names them, else the points.)
    scaled.knots = problem.knots.as_ref().map(|_| t_scaled.clone());
    let mut r = algorithm::run_on(&scaled, divdiff::Knots::new(u.topology(), t_scaled)?)?;
    r.points
        .coords_mut()
        .iter_mut()
        .for_each(|x| *x = times_power_of_two(*x, e));
    r.knots = divdiff::Knots::new(
        r.knots.topology(),
        r.knots
            .values()
            .iter()
            .map(|&x| times_power_of_two(x, f))
            .collect(),
    )?;
    r.energy = times_power_of_two(r.energy, 2 * e - 3 * f);
    for s in &mut r.stages {
        s.energy = times_power_of_two(s.energy, 2 * e - 3 * f);
    }
    let data = problem.constraint.kind();
    r.multipliers = r
        .multipliers
        .to_vecs()
        .into_iter()
        .enumerate()
        .map(|(i, m)| {
            let k = data.multiplier_power(i, e, f);
            m.into_iter().map(|x| times_power_of_two(x, k)).collect()
        })
        .collect::<Vec<Vec<f64>>>()
        .into();
    Ok(r)
}

/// x·2^k, exact unless the result over- or underflows (in steps: 2^k alone need not be
/// representable, e.g. k = −3f for knots of 1e300).
pub(crate) fn times_power_of_two(mut x: f64, mut k: i32) -> f64 {
    while k != 0 {
        let step = k.clamp(-1000, 1000);
        x *= 2f64.powi(step);
        k -= step;
    }
    x
}

/// One exact fixed-knot solve of stage 0 (the near-interpolatory k-level step) on the given
/// refined knots, certified: the points, E, and the relative KKT residual. Used by the free-knot
/// optimizer ([`crate::optimize_knots`]), which validates `problem` and `knots` first.
pub(crate) fn solve_stage0_on(
    problem: &Problem,
    knots: &divdiff::Knots,
) -> Result<(divdiff::Points, f64, f64), crate::Error> {
    let q = &problem.points;
    let stride = problem.k + 1;
    let dv: Vec<usize> = (0..q.len()).map(|i| stride * i).collect();
    let fp = FixedProblem {
        knots,
        q,
        data_vertex: &dv,
        constraint: &problem.constraint,
        problem,
        derivatives: true,
        stride,
        uniform_spans: false,
        warm: None,
        recycled: Default::default(),
        options: &problem.options,
    };
    let s = strategy::exact(&fp)?;
    let (cert, _) = strategy::certificate(&fp, &s);
    let kkt = cert.kkt_residual;
    Ok((s.points, cert.energy, kkt))
}
