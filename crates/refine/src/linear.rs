//! The linear fixed-knot problems: interpolation (3.3) and smoothing (3.6) — one banded solve,
//! exact to rounding — and the banded system H ⊗ I_d they share with the paper's iteration.

use divdiff::Points;
use energy::{Hessian, System};

use crate::operator::Stencil;
use crate::stage::{FixedProblem, FixedSolution};
use crate::Error;
use banded::lanes::{by_lanes, max_abs, raise, raise_all};

/// The system H ⊗ I_d of the Hessian `h` (its bands moved in).
pub(crate) fn hessian_system(h: Hessian, dim: usize) -> Result<System, Error> {
    let topology = h.topology();
    let (d0, d1, d2) = h.into_bands();
    Ok(System::from_bands(topology, d0, d1, d2, dim)?)
}

/// The weight from which smoothing is interpolation to rounding: w ≥ ‖H‖_∞/ε. At the optimum
/// w(p_{i_k} − q_i) = −(Hp)_{i_k}, and |Hp| ≤ ‖H‖_∞ L (H annihilates constants; L the extent
/// about the centroid), so |p_{i_k} − q_i| ≤ ε L: the vertex is q_i to rounding, and fixing it
/// there is exact to the certificate's stationarity allowance w·ε·L (`constraint/smoothing.rs`)
/// while it keeps w·q (1e300 × 1e10) from overflowing and the factorization well scaled.
pub(crate) fn stiff_weight(h: &Hessian) -> f64 {
    let (d0, d1, d2) = h.bands();
    let m = |b: &[f64]| b.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    (m(d0) + 2.0 * m(d1) + 2.0 * m(d2)) / f64::EPSILON
}

/// Interpolation at the data vertices whose `fixed` flag is set, plus weights `w` (0 = none) at
/// the others: (H + W)p = W q̃ with p_v = q_i at fixed data vertices (3.3), (3.5), (3.6). One
/// banded solve and `steps` steps of iterative refinement ([`Factored::refine`]) at most: they
/// stop once a correction is at rounding ([`SETTLED`]) or falls by less than a tenth.
///
/// One step is enough where the spans are even, and is what the exact solver's linear entry
/// takes (a second costs a fifth of a smoothing solve: its correction, measured on the sweeps'
/// problems and on smoothing of 10⁵ noisy points, k = 7, is 1e2 … 1e3 roundings of the largest
/// coordinate, after a first of up to 1e9). On a cluster of very short spans the factorization
/// loses the soft direction of the cluster as a whole — each stiff row solved to its rounding,
/// those roundings adding up to a net force on the cluster — and each step recovers it by about
/// the factor ε κ. Smoothing on an open arc with every other span 1e4 times shorter
/// (`tests/arcs.rs`) came back 0.57 % above its optimal objective after one step (measured in
/// 50-digit arithmetic on the same knots) and certified, until the certificate's arc test
/// ([`crate::arcs`]) refused it; a returned stage whose certificate refuses one step's answer
/// is solved again with [`CONVERGED_STEPS`] (`algorithm::stage_loop`), six steps there (a
/// factor of ~7 each). The heavily smoothed curve of `tests/conditioning.rs`
/// (`knot_updates_that_flatten_the_spans_are_solved_after_refinement`) takes 14 after its
/// second knot update and 30 after its third, a factor of 2 each.
pub(crate) fn linear(
    fp: &FixedProblem<'_>,
    fixed: &[bool],
    w: &[f64],
    steps: usize,
) -> Result<Points, Error> {
    let (sys, mut x) = Factored::new(fp, fixed, w)?;
    let d = fp.q.dim();
    let mut last = f64::INFINITY;
    for taken in 1..=steps {
        let step = sys.refine(
            &mut x,
            d,
            &mut (),
            |_, _| {},
            |_, _, r| sys.factor.solve_flat(r).map_err(Error::from),
        )?;
        // (After the last step there is nothing to decide: the exact solver's one step does not
        // pay for the size of x.)
        if taken == steps {
            break;
        }
        let size = max_abs(&x);
        if !(step > SETTLED * f64::EPSILON * size && step < 0.9 * last) {
            break;
        }
        last = step;
    }
    Ok(Points::new(d, x)?)
}

/// The refinement steps of a smoothing solve taken again when one step's answer was not
/// certified ([`linear`]).
pub(crate) const CONVERGED_STEPS: usize = 30;

/// The steps stop once a correction is at most this many roundings of the largest coordinate
/// (2.2e-10 of it): the answer is then within a few roundings.
const SETTLED: f64 = 1e6;

/// K = H ⊗ I_d + W factored, with what its iterative refinement needs: the rows of A
/// (H = AᵀA, [`Stencil`]), the weight at each vertex, the right-hand side b and the fixed
/// vertices.
struct Factored {
    factor: energy::Factor,
    stencil: Stencil,
    weight: Vec<f64>,
    b: Vec<f64>,
    is_fixed: Vec<bool>,
}

impl Factored {
    /// Assembles ([`assemble`], H from the stencil's rows of A) and factors K, and solves
    /// K x = b.
    fn new(
        fp: &FixedProblem<'_>,
        fixed: &[bool],
        w: &[f64],
    ) -> Result<(Factored, Vec<f64>), Error> {
        let stencil = Stencil::new(fp.knots);
        let (sys, b, is_fixed) = assemble(fp, &stencil, fixed, w)?;
        let factor = sys.factor()?;
        drop(sys);
        let mut x = b.clone();
        factor.solve_flat(&mut x)?;
        let mut weight = vec![0.0; fp.knots.vertex_count()];
        for (i, &v) in fp.data_vertex.iter().enumerate() {
            if !is_fixed[v] {
                weight[v] = w[i];
            }
        }
        let sys = Factored {
            factor,
            stencil,
            weight,
            b,
            is_fixed,
        };
        Ok((sys, x))
    }

    /// K p = Aᵀ(Ap) + W p with (Ap)_i = α_{i,1}(p_{i−1} − p_i) + α_{i,3}(p_{i+1} − p_i) (the
    /// middle coefficient is −α_{i,1} − α_{i,3}): in difference form, whose rounding is relative
    /// to the differences. The band form Σ_j K_vj p_j cancels terms of size ‖H‖|p| (H
    /// annihilates constants, and its entries grow as h⁻³ on short spans): on chordal spans
    /// from 2e-5 to 3e-2 its rounding alone was a residual of 0.1, and refining with it did
    /// not move the answer.
    fn apply(&self, p: &[f64], d: usize) -> Vec<f64> {
        let mut out = vec![0.0; p.len()];
        self.stencil.apply_h_flat(p, d, &mut out);
        for ((o, pv), w) in out
            .chunks_exact_mut(d)
            .zip(p.chunks_exact(d))
            .zip(&self.weight)
        {
            for (ok, pk) in o.iter_mut().zip(pv) {
                *ok += w * pk;
            }
        }
        out
    }

    /// One step of iterative refinement of x ≈ K⁻¹b: r = b − Kx − f at the free vertices (0 at
    /// the fixed ones; `forces` adds f, read off `state`, to Kx), `correct` turns r into the
    /// correction (a solve with K, or the bordered system's, which also updates `state` and
    /// reads x), added to x; nothing when r is 0 or not finite. One step: on the badly scaled
    /// knots of `tests/linear_accuracy.rs` it takes the answer from 4e-6 to 1e-8 … 1e-11 of the
    /// extent and a second did not change that, while each costs a residual and a solve (a
    /// smoothing solve at n = 10⁵, k = 7 took 46 ms in process without, 66 with one step, 82
    /// with two).
    fn refine<S>(
        &self,
        x: &mut [f64],
        d: usize,
        state: &mut S,
        forces: impl Fn(&S, &mut [f64]),
        correct: impl FnOnce(&mut S, &[f64], &mut Vec<f64>) -> Result<(), Error>,
    ) -> Result<f64, Error> {
        let mut r = self.apply(x, d);
        forces(state, &mut r);
        for ((rv, bv), &fixed) in r
            .chunks_exact_mut(d)
            .zip(self.b.chunks_exact(d))
            .zip(&self.is_fixed)
        {
            for (rk, bk) in rv.iter_mut().zip(bv) {
                *rk = if fixed { 0.0 } else { bk - *rk };
            }
        }
        let size = max_abs(&r);
        if !size.is_finite() || size == 0.0 {
            return Ok(0.0);
        }
        correct(state, x, &mut r)?;
        // The correction applied and its size taken in one pass, in four independent maxima.
        let mut step = [0.0f64; 4];
        by_lanes(x.len().min(r.len()), |l, k| {
            x[k] += r[k];
            raise(&mut step[l], r[k].abs());
        });
        let mut size = 0.0;
        raise_all(&mut size, step);
        Ok(size)
    }
}

/// The system of [`linear`]: K = H ⊗ I_d + W with its fixed vertices, the right-hand side
/// (W q̃ at weighted vertices, q_i at fixed ones) and which vertices are fixed.
fn assemble(
    fp: &FixedProblem<'_>,
    stencil: &Stencil,
    fixed: &[bool],
    w: &[f64],
) -> Result<(System, Vec<f64>, Vec<bool>), Error> {
    let n_vert = fp.knots.vertex_count();
    let d = fp.q.dim();
    // (The rows the refinement's residual applies, summed once: `Hessian::new` would form them
    // again.)
    let h = Hessian::from_alphas(fp.knots.topology(), &stencil.rows);
    let stiff = stiff_weight(&h);
    let mut sys = hessian_system(h, d)?;
    let mut rhs = vec![0.0; n_vert * d];
    let mut is_fixed = vec![false; n_vert];
    for (i, &v) in fp.data_vertex.iter().enumerate() {
        let qi = fp.q.point(i);
        if fixed[i] || w[i] >= stiff {
            sys.fix(v)?;
            is_fixed[v] = true;
            rhs[v * d..(v + 1) * d].copy_from_slice(qi);
        } else if w[i] > 0.0 {
            sys.add_weight(v, w[i])?;
            for c in 0..d {
                rhs[v * d + c] = w[i] * qi[c];
            }
        }
    }
    Ok((sys, rhs, is_fixed))
}

/// Interpolation or smoothing with clamped ends Df(t_1) = v_1, Df(t_N) = v_n (Kersey §3.6) on
/// the end vertices' derivative stencils L_s, L_e (`divdiff::derivative_stencil`, the problem's
/// rule): the bordered system
///
/// ```text
/// [ K   Lᵀ ] [ p ]   [ b ]
/// [ L   0  ] [ λ ] = [ v ],   L = [L_s; L_e] ⊗ I_d,
/// ```
///
/// K and b of [`linear`]. With x₀ = K⁻¹b (the answer without end conditions) and the two
/// columns of Y = K⁻¹L̃ᵀ (L̃: L with its fixed vertices' entries zeroed; one column per end, the
/// same for every coordinate since K is H ⊗ I_d plus a diagonal), S = L̃Y is 2 × 2 (positive
/// definite when the two stencils' free parts are independent), and per coordinate
/// λ = S⁻¹(L x₀ − v), p = x₀ − Yλ: stationarity Kp + Lᵀλ = b at the free vertices, the end
/// conditions exact. λ_s, λ_e are the ends' forces (the certificate's derivative terms);
/// interpolation's data multipliers are the reactions −(Hp)_v less those forces, which the
/// certificate computes from its own Hp (`certify`, given none; from the α-rows here they were a
/// tenth of a clamped interpolation of 10⁵ points).
///
/// x₀ and Y come from one factorization of K and three solves ([`whole_curve`]); for
/// interpolation on at least 4 × [`WINDOW_SPANS`] spans, x₀ is interpolation's own O(N) solve
/// ([`interpolate`]) and Y's columns are solved on the [`WINDOW_SPANS`] spans at their end
/// ([`end_windows`]), where they decay to rounding.
///
/// # Errors
/// [`Error::Unsupported`] when the problem is not one of these
/// ([`crate::Problem::linear_clamped_ends`]), an end's stencil reaches no free vertex or S is
/// singular to rounding (the conic solver then decides, and reports an infeasible pair); errors
/// of the factorization.
pub(crate) fn clamped(fp: &FixedProblem<'_>) -> Result<FixedSolution, Error> {
    let ends = fp.problem.linear_clamped_ends().ok_or(Error::Unsupported {
        field: "boundary",
        reason: "the bordered solve holds clamped ends of interpolation or smoothing",
    })?;
    let n = fp.q.len();
    let d = fp.q.dim();
    let n_vert = fp.knots.vertex_count();
    let rule = fp.problem.derivative;
    let [ls, le] = [0, n_vert - 1].map(|v| divdiff::derivative_stencil(fp.knots, v, rule));
    let stencils = [ls?, le?];
    let (fixed, w) = data_terms(fp);
    let windowed = if w.is_none() && n > 4 * WINDOW_SPANS {
        end_windows(fp, &stencils)?
    } else {
        None
    };
    let (mut x, y, whole) = match windowed {
        Some(y) => (interpolate(fp)?.points.into_coords(), y, None),
        None => {
            let (x, y, sys) = whole_curve(fp, &fixed, w, &stencils)?;
            (x, y, Some(sys))
        }
    };
    // S = L̃ Y.
    let s = [0, 1].map(|e| [0, 1].map(|f| y[f].dot(&stencils[e])));
    let det = s[0][0] * s[1][1] - s[0][1] * s[1][0];
    if !(det.is_finite() && det > 1e-12 * (s[0][0] * s[1][1]).abs()) {
        return Err(Error::Unsupported {
            field: "boundary",
            reason: "the two end conditions act on the same free vertices",
        });
    }
    let apply = |st: &[(usize, f64); 3], x: &[f64], k: usize| -> f64 {
        st.iter().map(|&(u, c)| c * x[u * d + k]).sum::<f64>()
    };
    // From x = K⁻¹r to the bordered system's solution with right-hand side (r, targets):
    // λ = S⁻¹(L x − targets), x −= Yλ; returns λ.
    let border = |x: &mut [f64], targets: [&[f64]; 2]| -> [Vec<f64>; 2] {
        let mut lambda = [vec![0.0; d], vec![0.0; d]];
        for k in 0..d {
            let r0 = apply(&stencils[0], x, k) - targets[0][k];
            let r1 = apply(&stencils[1], x, k) - targets[1][k];
            lambda[0][k] = (s[1][1] * r0 - s[0][1] * r1) / det;
            lambda[1][k] = (s[0][0] * r1 - s[1][0] * r0) / det;
        }
        for (col, l) in y.iter().zip(&lambda) {
            for (j, yv) in col.values.iter().enumerate() {
                let v = col.first + j;
                for (xv, lk) in x[v * d..(v + 1) * d].iter_mut().zip(l) {
                    *xv -= yv * lk;
                }
            }
        }
        lambda
    };
    let mut lambda = border(&mut x, ends);
    if let Some(sys) = &whole {
        // On the whole curve, iterative refinement of the bordered system: the residual
        // (b − Kp − L̃ᵀλ at the free vertices, v − Lp) through the same solves, λ updated with
        // the correction's.
        sys.refine(
            &mut x,
            d,
            &mut lambda,
            |lambda, r| {
                for (st, l) in stencils.iter().zip(lambda) {
                    for &(u, c) in st {
                        for k in 0..d {
                            r[u * d + k] += c * l[k];
                        }
                    }
                }
            },
            |lambda, x, r| {
                let r2: [Vec<f64>; 2] = [0, 1].map(|e| {
                    (0..d)
                        .map(|k| ends[e][k] - apply(&stencils[e], x, k))
                        .collect()
                });
                sys.factor.solve_flat(r)?;
                let dl = border(r, [&r2[0], &r2[1]]);
                for (l, dl) in lambda.iter_mut().zip(&dl) {
                    for (a, b) in l.iter_mut().zip(dl) {
                        *a += b;
                    }
                }
                Ok(())
            },
        )?;
    }
    let points = Points::new(d, x)?;
    // Interpolation's reactions, −(Hp)_v less the ends' forces there, are computed by the
    // certificate (`certify`, given none) from its own Hp.
    let multipliers = w.map(smoothing_multipliers);
    let mut sol = FixedSolution::new(points, multipliers, 1);
    // (cone dual, force) of each end's zero-cone rows s = F y + g with F = I: ζ = −λ.
    sol.derivative = lambda
        .into_iter()
        .map(|l| (l.iter().map(|v| -v).collect(), l))
        .collect();
    Ok(sol)
}

/// Spans at each end of a long clamped interpolation on which [`end_windows`] solves Y's
/// columns (64). Interpolation fixes every (k+1)-th vertex, and a force at the end stencil's
/// free vertices is felt across a fixed vertex only through the band's reach of two: its
/// response falls geometrically from span to span, as a cubic spline's does (the check in
/// [`end_windows`] measures that it reached rounding rather than assuming a rate).
const WINDOW_SPANS: usize = 64;

/// One column of Y: scalar values on the vertices `first ..`, zero elsewhere.
struct Column {
    first: usize,
    values: Vec<f64>,
}

impl Column {
    /// L̃ y for a stencil (its vertices outside the column read 0).
    fn dot(&self, st: &[(usize, f64); 3]) -> f64 {
        st.iter()
            .filter_map(|&(u, c)| {
                u.checked_sub(self.first)
                    .and_then(|j| self.values.get(j))
                    .map(|y| c * y)
            })
            .sum()
    }
}

/// x₀, Y's columns and K's factorization, by one factorization and three solves (`fixed`, `w`:
/// [`data_terms`]).
fn whole_curve(
    fp: &FixedProblem<'_>,
    fixed: &[bool],
    w: Option<&[f64]>,
    stencils: &[[(usize, f64); 3]; 2],
) -> Result<(Vec<f64>, [Column; 2], Factored), Error> {
    let d = fp.q.dim();
    let n_vert = fp.knots.vertex_count();
    let no_weights = vec![0.0; fp.q.len()];
    let (sys, x) = Factored::new(fp, fixed, w.unwrap_or(&no_weights))?;
    let column = |st: &[(usize, f64); 3]| -> Result<Column, Error> {
        let mut col = vec![0.0; n_vert * d];
        free_stencil(
            st,
            |u| sys.is_fixed[u],
            |u, c| {
                for k in 0..d {
                    col[u * d + k] += c;
                }
            },
        )?;
        sys.factor.solve_flat(&mut col)?;
        Ok(Column {
            first: 0,
            values: col.iter().step_by(d).copied().collect(),
        })
    };
    let columns = [column(&stencils[0])?, column(&stencils[1])?];
    Ok((x, columns, sys))
}

/// Calls `f(u, c)` for the stencil's entries on free vertices; [`Error::Unsupported`] when there
/// is none (the data fix the end derivative: the conic solver decides whether it is met).
fn free_stencil(
    st: &[(usize, f64); 3],
    is_fixed: impl Fn(usize) -> bool,
    mut f: impl FnMut(usize, f64),
) -> Result<(), Error> {
    let mut free = false;
    for &(u, c) in st {
        if !is_fixed(u) && c != 0.0 {
            free = true;
            f(u, c);
        }
    }
    if free {
        Ok(())
    } else {
        Err(Error::Unsupported {
            field: "boundary",
            reason: "an end's derivative stencil reaches no free vertex",
        })
    }
}

/// Y's columns of a clamped interpolation solved on the [`WINDOW_SPANS`] spans at their end, Y
/// taken as 0 beyond: the principal block of K on the window's vertices (the sub-curve's
/// Hessian on the window's knots and one more, whose rows inside the window are K's own),
/// every data vertex fixed and the vertex past the window too. `None` when a column has not
/// decayed to rounding (1e-17 of its largest entry) at the window's far data span: the whole
/// curve's solve is used instead.
fn end_windows(
    fp: &FixedProblem<'_>,
    stencils: &[[(usize, f64); 3]; 2],
) -> Result<Option<[Column; 2]>, Error> {
    let stride = fp.stride;
    let n_vert = fp.knots.vertex_count();
    let w = WINDOW_SPANS * stride;
    if stride < 2 || n_vert < 2 * w + 3 {
        return Ok(None);
    }
    let t = fp.knots.values();
    let window = |end: usize| -> Result<Option<Column>, Error> {
        // Global vertices first ..= first + w + 1; the data vertices are global multiples of
        // the stride; the vertex past the window (the last at the start, the first at the end)
        // is held at 0.
        let first = if end == 0 { 0 } else { n_vert - w - 2 };
        let sub = divdiff::Knots::open(t[first..first + w + 2].to_vec())?;
        let mut sys = hessian_system(Hessian::new(&sub), 1)?;
        let outside = if end == 0 { w + 1 } else { 0 };
        let mut is_fixed = vec![false; w + 2];
        for (j, f) in is_fixed.iter_mut().enumerate() {
            *f = j == outside || (first + j) % stride == 0;
            if *f {
                sys.fix(j)?;
            }
        }
        let mut y = vec![0.0; w + 2];
        let held = |v: usize| v < first || v >= first + w + 2 || is_fixed[v - first];
        free_stencil(&stencils[end], held, |u, c| y[u - first] += c)?;
        sys.factor()?.solve_flat(&mut y)?;
        // Decayed to rounding over the data span farthest from the stencil.
        let peak = y.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let far = if end == 0 {
            &y[w - stride..=w]
        } else {
            &y[1..=stride + 1]
        };
        let decayed = peak.is_finite() && far.iter().all(|v| v.abs() <= 1e-17 * peak);
        Ok(decayed.then_some(Column { first, values: y }))
    };
    let Some(start) = window(0)? else {
        return Ok(None);
    };
    Ok(window(1)?.map(|end| [start, end]))
}

/// Interpolation (3.3) at every data vertex: the closed forms of [`crate::uniform`] on the knots
/// of the split, else the fused banded solver of [`crate::fast`].
pub(crate) fn interpolate(fp: &FixedProblem<'_>) -> Result<FixedSolution, Error> {
    if fp.uniform_spans {
        return Ok(FixedSolution::new(
            crate::uniform::interpolate(fp.knots, fp.q, fp.stride)?,
            None,
            1,
        ));
    }
    let p = crate::fast::interpolate(fp.knots, fp.q, fp.stride, fp.recycled.take())?;
    Ok(FixedSolution::new(p, None, 1))
}

/// The data terms of a linear problem: which data points are fixed and the smoothing weights —
/// none fixed and its weights for smoothing; every point fixed and no weights (`None`) for
/// interpolation and balls of radius 0.
fn data_terms<'a>(fp: &FixedProblem<'a>) -> (Vec<bool>, Option<&'a [f64]>) {
    use crate::constraint::Constraint;
    let n = fp.q.len();
    match fp.constraint {
        Constraint::Smoothing(w) => (vec![false; n], Some(w)),
        _ => (vec![true; n], None),
    }
}

/// Smoothing's multipliers in the convention of [`crate::Refinement::multipliers`]: its weights.
fn smoothing_multipliers(w: &[f64]) -> Vec<Vec<f64>> {
    w.iter().map(|&x| vec![x]).collect()
}

/// The linear problems of [`crate::strategy`]: interpolation (also balls of radius 0 at every
/// point) and smoothing, without derivative constraints.
pub(crate) fn solve(fp: &FixedProblem<'_>, steps: usize) -> Result<FixedSolution, Error> {
    match data_terms(fp) {
        (fixed, Some(w)) => Ok(FixedSolution::new(
            linear(fp, &fixed, w, steps)?,
            Some(smoothing_multipliers(w)),
            1,
        )),
        _ => interpolate(fp),
    }
}
