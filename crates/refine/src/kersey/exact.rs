//! The exact optimum of the fixed-knot ball problem (3.4) by a primal log-barrier method with
//! Newton steps on the O(N) block-banded system of [`energy::System`].
//!
//! For barrier parameter τ the centre p(τ) minimizes
//!
//! φ_τ(p) = τ ½pᵀ(H ⊗ I_d)p − Σ_i log ψ_i(p),  ψ_i = ε_i² − |p_{i_k} − q_i|²,
//!
//! (data points with ε_i = 0 are fixed at q_i). Each Newton system is
//! τ H ⊗ I_d + Σ_i e_{i_k}e_{i_k}ᵀ ⊗ (2I/ψ_i + 4 r_i r_iᵀ/ψ_i²), r_i = p_{i_k} − q_i — block
//! pentadiagonal, factored in O(N). At a centre, Hp + w_i r_i = 0 at the data vertices with
//! w_i = 2/(τ ψ_i) ≥ 0: these are Kersey's multipliers of (3.5), and the complementarity gap is
//! w_i(ε_i − |r_i|) = 2/(τ(ε_i + |r_i|)). τ grows by [`BARRIER_GROWTH`] until the certificate's
//! relative KKT residual is at most [`EXACT_KKT_TARGET`].
//!
//! φ_τ is self-concordant, so the Newton decrement λ² = −∇φᵀΔ is an affine-invariant,
//! scale-free stopping test ([`NEWTON_DECREMENT_TOL`]); steps are damped by backtracking that
//! keeps every ψ_i > 0 and satisfies the Armijo condition.
//!
//! Reference: S. Boyd, L. Vandenberghe, *Convex Optimization*, §11.3 (barrier method), §9.5–9.6
//! (Newton's method, self-concordance).

use divdiff::Points;
use energy::Hessian;

use super::algorithm::{FixedProblem, FixedSolution};
use super::certify::{certify, ACTIVE_REL_TOL};
use super::operator::Stencil;
use super::problem::Constraint;
use crate::Error;

/// The exact solver stops once the certificate's relative KKT residual is at most this.
pub const EXACT_KKT_TARGET: f64 = 1e-10;
/// If the barrier's precision floor is reached first, the best centre is returned when its
/// relative KKT residual is at most this (issue 3's requirement), else
/// [`Error::NotConverged`].
pub const EXACT_KKT_ACCEPT: f64 = 1e-9;
/// Factor by which the barrier parameter grows between centrings.
pub const BARRIER_GROWTH: f64 = 16.0;
/// Centring stops when half the squared Newton decrement is below this.
pub const NEWTON_DECREMENT_TOL: f64 = 1e-14;
/// Newton steps per centring.
pub const MAX_NEWTON_STEPS: usize = 60;
/// Centrings (barrier updates).
pub const MAX_CENTRINGS: usize = 40;

/// Solves the fixed-knot ball problem exactly (see the module docs).
pub(crate) fn solve(fp: &FixedProblem<'_>) -> Result<FixedSolution, Error> {
    let Constraint::Balls(radii) = fp.constraint else {
        return Err(Error::Unsupported {
            field: "constraint",
            reason: "the exact solver in this build handles interpolation, smoothing and balls",
        });
    };
    let q = fp.q;
    let d = q.dim();
    let n = q.len();
    let hess = Hessian::new(fp.knots);
    let (b0, b1, b2) = hess.bands();
    let stencil = Stencil::new(fp.knots);
    let fixed: Vec<bool> = radii.iter().map(|&e| e == 0.0).collect();
    let balls: Vec<usize> = (0..n).filter(|&i| !fixed[i]).collect();
    let m = balls.len() as f64;

    // Strictly feasible start: interpolate the centres.
    let mut p = super::fast::interpolate(fp.knots, &stencil, q, fp.stride)?;
    let r_of = |p: &Points, i: usize| -> Vec<f64> {
        p.point(fp.data_vertex[i])
            .iter()
            .zip(q.point(i))
            .map(|(a, b)| a - b)
            .collect()
    };
    let psi = |p: &Points, i: usize| {
        let r = r_of(p, i);
        radii[i] * radii[i] - r.iter().map(|x| x * x).sum::<f64>()
    };
    let energy_of = |p: &Points| -> Result<f64, Error> { Ok(hess.energy(p)?) };
    let e0 = energy_of(&p)?;
    // τ₀ balances the two terms: the barrier's gap m/τ is about the energy of the start.
    let mut tau = if e0 > 0.0 { m / e0 } else { 1.0 };
    let phi = |p: &Points, tau: f64| -> Result<Option<f64>, Error> {
        let mut bar = 0.0;
        for &i in &balls {
            let s = psi(p, i);
            if s <= 0.0 {
                return Ok(None);
            }
            bar -= s.ln();
        }
        Ok(Some(tau * energy_of(p)? + bar))
    };
    let mut newton_steps = 0usize;
    let mut weights = vec![0.0; n];
    let mut best: Option<(f64, Points, Vec<Vec<f64>>)> = None;
    for _ in 0..MAX_CENTRINGS {
        // Centring: Newton's method on φ_τ.
        let mut last_decrement = f64::INFINITY;
        for _ in 0..MAX_NEWTON_STEPS {
            let hp = hess.apply(&p);
            let mut grad: Vec<f64> = hp.coords().iter().map(|x| tau * x).collect();
            let mut sys = energy::System::from_bands(
                fp.knots.topology(),
                b0.iter().map(|x| tau * x).collect(),
                b1.iter().map(|x| tau * x).collect(),
                b2.iter().map(|x| tau * x).collect(),
                d,
            )?;
            for (i, &is_fixed) in fixed.iter().enumerate() {
                let v = fp.data_vertex[i];
                if is_fixed {
                    sys.fix(v)?;
                    grad[v * d..(v + 1) * d].iter_mut().for_each(|g| *g = 0.0);
                    continue;
                }
                let r = r_of(&p, i);
                let s = psi(&p, i);
                let mut block = vec![0.0; d * d];
                for a in 0..d {
                    grad[v * d + a] += 2.0 * r[a] / s;
                    for b in 0..d {
                        block[a * d + b] = 4.0 * r[a] * r[b] / (s * s);
                    }
                    block[a * d + a] += 2.0 / s;
                }
                sys.add_block(v, &block)?;
            }
            let factor = sys.factor()?;
            let mut step: Vec<f64> = grad.iter().map(|g| -g).collect();
            factor.solve_flat(&mut step)?;
            newton_steps += 1;
            let decrement: f64 = -grad.iter().zip(&step).map(|(g, s)| g * s).sum::<f64>();
            // Converged, or stalled at the rounding floor (quadratic convergence stopped).
            if decrement / 2.0 <= NEWTON_DECREMENT_TOL
                || (decrement < 0.25 && decrement >= 0.5 * last_decrement)
            {
                break;
            }
            last_decrement = decrement;
            // Inside the region of quadratic convergence (λ < ½) the full Newton step of a
            // self-concordant function stays in the domain and decreases φ; taking it without
            // comparing values of φ avoids the cancellation in τE − Σ log ψ at large τ. Outside it,
            // backtrack: stay strictly feasible, then Armijo.
            let full = decrement < 0.25;
            let f0 = if full {
                0.0
            } else {
                phi(&p, tau)?.expect("the iterate is strictly feasible")
            };
            let mut t = 1.0;
            let mut accepted = false;
            for _ in 0..60 {
                let mut trial = p.clone();
                for (x, s) in trial.coords_mut().iter_mut().zip(&step) {
                    *x += t * s;
                }
                let feasible = balls.iter().all(|&i| psi(&trial, i) > 0.0);
                if feasible {
                    let ok =
                        full || phi(&trial, tau)?.is_some_and(|f| f <= f0 - 0.25 * t * decrement);
                    if ok {
                        p = trial;
                        accepted = true;
                        break;
                    }
                }
                t *= 0.5;
            }
            if !accepted {
                // No descent within rounding: the centre is as good as this precision allows.
                break;
            }
        }
        // Multipliers: w_i = 2/(τψ_i) at a centre. Near the sphere ψ_i = ε² − |r|² loses its
        // relative accuracy to cancellation, so there w_i is taken from the normal component of
        // the stationarity condition (Hp)_{i_k} + w_i r_i = 0 instead (least squares).
        let hp = hess.apply(&p);
        for &i in &balls {
            let r = r_of(&p, i);
            let rr: f64 = r.iter().map(|x| x * x).sum();
            let s = psi(&p, i);
            weights[i] = if s < 0.5 * radii[i] * radii[i] && rr > 0.0 {
                let v = fp.data_vertex[i];
                let hr: f64 = hp.point(v).iter().zip(&r).map(|(a, b)| a * b).sum();
                (-hr / rr).max(0.0)
            } else {
                2.0 / (tau * s)
            };
        }
        let mult = multipliers(&p, &weights, &fixed, &hess, fp, d);
        let (cert, _) = certify(
            &stencil,
            &p,
            q,
            fp.data_vertex,
            fp.constraint,
            Some(mult.clone()),
            ACTIVE_REL_TOL,
        );
        let kkt = cert.kkt_residual;
        let improving = best.as_ref().is_none_or(|b| kkt < b.0);
        if improving {
            best = Some((kkt, p.clone(), mult));
        }
        if kkt <= EXACT_KKT_TARGET {
            break;
        }
        // Past the precision floor of the barrier (centres at huge τ lose accuracy), the
        // residual grows again: keep the best centre.
        if !improving && best.as_ref().is_some_and(|b| kkt > 4.0 * b.0) {
            break;
        }
        tau *= BARRIER_GROWTH;
    }
    match best {
        Some((kkt, points, mult)) if kkt <= EXACT_KKT_ACCEPT => Ok(FixedSolution {
            points,
            multipliers: Some(mult),
            iterations: newton_steps,
            stencil: Some(stencil),
        }),
        best => Err(Error::NotConverged {
            solver: "exact barrier method",
            iterations: newton_steps,
            residual: best.map_or(f64::INFINITY, |b| b.0),
        }),
    }
}

/// Multipliers in the conventions of [`crate::Refinement::multipliers`]: `[w_i]` for balls,
/// the reaction −(Hp)_{i_k} for fixed points.
fn multipliers(
    p: &Points,
    weights: &[f64],
    fixed: &[bool],
    hess: &Hessian,
    fp: &FixedProblem<'_>,
    d: usize,
) -> Vec<Vec<f64>> {
    let hp = if fixed.iter().any(|&f| f) {
        Some(hess.apply(p))
    } else {
        None
    };
    (0..weights.len())
        .map(|i| {
            if fixed[i] {
                let v = fp.data_vertex[i];
                let h = hp.as_ref().expect("computed when a point is fixed");
                h.point(v).iter().map(|x| -x).collect()
            } else {
                vec![weights[i]]
            }
        })
        .inspect(|v: &Vec<f64>| debug_assert!(v.len() == 1 || v.len() == d))
        .collect()
}
