//! The linear fixed-knot problems: interpolation (3.3) and smoothing (3.6) — one banded solve,
//! exact to rounding — and the banded system H ⊗ I_d they share with the paper's iteration.

use divdiff::Points;
use energy::{Hessian, System};

use crate::stage::{FixedProblem, FixedSolution};
use crate::Error;

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
/// the others: (H + W)p = W q̃ with p_v = q_i at fixed data vertices (3.3), (3.5), (3.6).
pub(crate) fn linear(fp: &FixedProblem<'_>, fixed: &[bool], w: &[f64]) -> Result<Points, Error> {
    let (sys, mut rhs, _) = assemble(fp, fixed, w)?;
    sys.factor()?.solve_flat(&mut rhs)?;
    Ok(Points::new(fp.q.dim(), rhs)?)
}

/// The system of [`linear`]: K = H ⊗ I_d + W with its fixed vertices, the right-hand side
/// (W q̃ at weighted vertices, q_i at fixed ones) and which vertices are fixed.
fn assemble(
    fp: &FixedProblem<'_>,
    fixed: &[bool],
    w: &[f64],
) -> Result<(System, Vec<f64>, Vec<bool>), Error> {
    let n_vert = fp.knots.vertex_count();
    let d = fp.q.dim();
    let h = Hessian::new(fp.knots);
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
/// K and b of [`linear`], by one banded factorization of K and three solves: x₀ = K⁻¹b, the two
/// columns of Y = K⁻¹L̃ᵀ (L̃: L with its fixed vertices' entries zeroed; one column per end,
/// the same for every coordinate since K is H ⊗ I_d plus a diagonal), the 2 × 2 system
/// S = L̃Y (positive definite when the two stencils' free parts are independent), then, per
/// coordinate, λ = S⁻¹(L x₀ − v) and p = x₀ − Yλ. This is the equality-constrained minimizer of
/// the energy (plus the smoothing term): stationarity Kp + Lᵀλ = b at the free vertices, the
/// end conditions exact. λ_s, λ_e are the ends' forces (the certificate's derivative terms);
/// interpolation's data multipliers are the reactions −(Hp)_v less those forces.
///
/// # Errors
/// [`Error::Unsupported`] when an end's stencil reaches no free vertex or S is singular to
/// rounding (the conic solver then decides, and reports an infeasible pair); errors of the
/// factorization.
pub(crate) fn clamped(fp: &FixedProblem<'_>, ends: [&[f64]; 2]) -> Result<FixedSolution, Error> {
    use crate::constraint::Constraint;
    let n = fp.q.len();
    let d = fp.q.dim();
    let n_vert = fp.knots.vertex_count();
    let (fixed, w): (Vec<bool>, &[f64]) = match fp.constraint {
        Constraint::Smoothing(w) => (vec![false; n], w),
        _ => (vec![true; n], &[]),
    };
    let no_weights = vec![0.0; n];
    let w = if w.is_empty() { &no_weights } else { w };
    let (sys, rhs, is_fixed) = assemble(fp, &fixed, w)?;
    let factor = sys.factor()?;
    let mut x = rhs;
    factor.solve_flat(&mut x)?;
    let rule = fp.problem.derivative;
    let stencils = [0, n_vert - 1].map(|v| divdiff::derivative_stencil(fp.knots, v, rule));
    let [ls, le] = stencils;
    let stencils = [ls?, le?];
    // Y's columns, each solved with its stencil in every coordinate (fixed rows 0).
    let mut y = [vec![0.0; n_vert * d], vec![0.0; n_vert * d]];
    for (col, st) in y.iter_mut().zip(&stencils) {
        let mut free = false;
        for &(u, c) in st {
            if !is_fixed[u] && c != 0.0 {
                free = true;
                for k in 0..d {
                    col[u * d + k] += c;
                }
            }
        }
        if !free {
            return Err(Error::Unsupported {
                field: "boundary",
                reason: "an end's derivative stencil reaches no free vertex",
            });
        }
        factor.solve_flat(col)?;
    }
    // S = L̃ Y (coordinate 0 of each column; every coordinate holds the same).
    let apply = |st: &[(usize, f64); 3], v: &[f64], k: usize| -> f64 {
        st.iter().map(|&(u, c)| c * v[u * d + k]).sum::<f64>()
    };
    let s = [
        [apply(&stencils[0], &y[0], 0), apply(&stencils[0], &y[1], 0)],
        [apply(&stencils[1], &y[0], 0), apply(&stencils[1], &y[1], 0)],
    ];
    let det = s[0][0] * s[1][1] - s[0][1] * s[1][0];
    if !(det.is_finite() && det > 1e-12 * (s[0][0] * s[1][1]).abs()) {
        return Err(Error::Unsupported {
            field: "boundary",
            reason: "the two end conditions act on the same free vertices",
        });
    }
    let mut lambda = [vec![0.0; d], vec![0.0; d]];
    for k in 0..d {
        let r0 = apply(&stencils[0], &x, k) - ends[0][k];
        let r1 = apply(&stencils[1], &x, k) - ends[1][k];
        lambda[0][k] = (s[1][1] * r0 - s[0][1] * r1) / det;
        lambda[1][k] = (s[0][0] * r1 - s[1][0] * r0) / det;
    }
    for (col, l) in y.iter().zip(&lambda) {
        for (i, (xv, yv)) in x.iter_mut().zip(col).enumerate() {
            *xv -= yv * l[i % d];
        }
    }
    let points = Points::new(d, x)?;
    let multipliers = match fp.constraint {
        Constraint::Smoothing(w) => w.iter().map(|&x| vec![x]).collect(),
        _ => {
            // The reactions: −(Hp)_v less the ends' forces there (K is H ⊗ I_d here).
            let mut hp = vec![0.0; n_vert * d];
            sys.apply_flat(points.coords(), &mut hp)?;
            let mut forces = vec![0.0; n_vert * d];
            for (st, l) in stencils.iter().zip(&lambda) {
                for &(u, c) in st {
                    for k in 0..d {
                        forces[u * d + k] += c * l[k];
                    }
                }
            }
            (0..n)
                .map(|i| crate::constraint::interpolate::reaction(fp, &forces, &hp, i))
                .collect()
        }
    };
    let mut sol = FixedSolution::new(points, Some(multipliers), 1);
    // (cone dual, force) of each end's zero-cone rows s = F y + g with F = I: ζ = −λ.
    sol.derivative = lambda
        .into_iter()
        .map(|l| (l.iter().map(|v| -v).collect(), l))
        .collect();
    Ok(sol)
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
    let p = crate::fast::interpolate(fp.knots, fp.q, fp.stride)?;
    Ok(FixedSolution::new(p, None, 1))
}

/// The linear problems of [`crate::strategy`]: interpolation (also balls of radius 0 at every
/// point) and smoothing, without derivative constraints.
pub(crate) fn solve(fp: &FixedProblem<'_>) -> Result<FixedSolution, Error> {
    use crate::constraint::Constraint;
    let n = fp.q.len();
    match fp.constraint {
        Constraint::Smoothing(w) => Ok(FixedSolution::new(
            linear(fp, &vec![false; n], w)?,
            Some(w.iter().map(|&x| vec![x]).collect()),
            1,
        )),
        _ => interpolate(fp),
    }
}
