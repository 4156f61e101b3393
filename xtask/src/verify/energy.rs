//! Verification cases for `divdiff` and `energy` (Kersey §2, §3.6, Algorithm 4.1 (iv);
//! Warren–Weimer §6.2).
//!
//! Every case runs on a few fixed, seeded, non-uniform problems (open and closed, d = 1..3) and
//! reports the worst relative residual over them.

use super::{Case, Outcome};
use divdiff::{
    derivative_stencil, divided_difference, divided_difference_explicit, jumps, parametrize,
    vertex_derivative, DerivativeRule, Knots, Parametrization, Points, Topology,
};
use energy::{
    alpha_matrix, energy, energy_by_jumps, knot_gradient, knot_gradient_printed,
    orthogonality_residuals, vertex_knot_gradient, warren_weimer_matrix, Hessian,
};

/// Round-off tolerance for identities that hold exactly in exact arithmetic (relative).
const EXACT_TOL: f64 = 1e-11;
/// Tolerance for central finite differences (relative to the gradient's size).
const FD_TOL: f64 = 1e-6;
/// Relative step of the central finite differences in the knots (times the shortest span).
const FD_STEP: f64 = 1e-5;

/// A reproducible random non-uniform problem: spans in [0.2, 2.0], coordinates in [−3, 3].
struct Problem {
    knots: Knots,
    points: Points,
}

fn lcg(seed: u64) -> impl FnMut() -> f64 {
    let mut s = seed;
    move || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (s >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn seeded(n: usize, d: usize, topology: Topology, seed: u64) -> Problem {
    let mut next = lcg(seed);
    let m = if topology == Topology::Closed {
        n + 1
    } else {
        n
    };
    let mut t = vec![-1.0 + next()];
    for _ in 1..m {
        let last = t[t.len() - 1];
        t.push(last + 0.2 + 1.8 * next());
    }
    let coords = (0..n * d).map(|_| 6.0 * next() - 3.0).collect();
    Problem {
        knots: Knots::new(topology, t).expect("increasing knots"),
        points: Points::new(d, coords).expect("finite points"),
    }
}

/// The fixed problem set: two closed and two open curves, d = 1..3, N = 7..11.
fn problems() -> Vec<Problem> {
    vec![
        seeded(9, 2, Topology::Closed, 11),
        seeded(7, 3, Topology::Closed, 12),
        seeded(11, 2, Topology::Open, 13),
        seeded(8, 1, Topology::Open, 14),
    ]
}

fn max_abs(x: &[f64]) -> f64 {
    x.iter().fold(0.0, |m, v| m.max(v.abs()))
}

fn rel_err(a: &[f64], b: &[f64]) -> f64 {
    let diff: Vec<f64> = a.iter().zip(b).map(|(x, y)| x - y).collect();
    max_abs(&diff) / max_abs(b).max(f64::MIN_POSITIVE)
}

fn min_span(k: &Knots) -> f64 {
    (0..k.span_count())
        .map(|j| k.h(j as isize))
        .fold(f64::INFINITY, f64::min)
}

/// Central finite differences of E, one entry per vertex (closed: vertex 0 moves t_0 and t_N).
fn fd_vertex_knot_gradient(pr: &Problem) -> anyhow::Result<Vec<f64>> {
    let d = FD_STEP * min_span(&pr.knots);
    let n = pr.knots.vertex_count();
    let closed = pr.knots.is_closed();
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        let e = |dt: f64| -> anyhow::Result<f64> {
            let mut t = pr.knots.values().to_vec();
            t[i] += dt;
            if closed && i == 0 {
                t[n] += dt;
            }
            Ok(energy(&Knots::new(pr.knots.topology(), t)?, &pr.points)?)
        };
        out.push((e(d)? - e(-d)?) / (2.0 * d));
    }
    Ok(out)
}

/// Worst value of `f` over the problem set, with a detail naming the worst problem.
fn worst(f: impl Fn(&Problem) -> anyhow::Result<f64>) -> anyhow::Result<(f64, &'static str)> {
    const NAMES: [&str; 4] = [
        "closed N=9 d=2",
        "closed N=7 d=3",
        "open N=11 d=2",
        "open N=8 d=1",
    ];
    let mut w = (0.0f64, NAMES[0]);
    for (pr, name) in problems().iter().zip(NAMES) {
        let r = f(pr)?;
        if r.is_nan() || r > w.0 {
            w = (r, name);
        }
    }
    Ok(w)
}

fn h_equals_ata() -> anyhow::Result<Outcome> {
    let (r, which) = worst(|pr| {
        let a = alpha_matrix(&pr.knots);
        let h = Hessian::new(&pr.knots).to_dense();
        Ok((a.transpose() * &a - &h).amax() / h.amax())
    })?;
    Ok(Outcome::check(
        r,
        EXACT_TOL,
        format!("max|AᵀA − H| / max|H| (worst: {which})"),
    ))
}

fn h_symmetric_psd() -> anyhow::Result<Outcome> {
    let (r, which) = worst(|pr| {
        let h = Hessian::new(&pr.knots).to_dense();
        let ev = h.symmetric_eigenvalues();
        Ok((-ev.min()).max(0.0) / ev.amax())
    })?;
    Ok(Outcome::check(
        r,
        EXACT_TOL,
        format!("max(0, −λ_min) / λ_max of the dense H (worst: {which})"),
    ))
}

/// Dimension of ker H: eigenvalues below `KERNEL_REL`·λ_max count as zero. On these problems the
/// smallest non-zero eigenvalue is far above and round-off far below that threshold (the residual
/// printed is the ratio of the first non-kernel eigenvalue to λ_max, for the record).
fn kernel_dimension() -> anyhow::Result<Outcome> {
    const KERNEL_REL: f64 = 1e-10;
    let mut ok = true;
    let mut dims = Vec::new();
    let mut gap = f64::INFINITY;
    for pr in problems() {
        let mut ev: Vec<f64> = Hessian::new(&pr.knots)
            .to_dense()
            .symmetric_eigenvalues()
            .iter()
            .copied()
            .collect();
        ev.sort_by(f64::total_cmp);
        let lmax = ev[ev.len() - 1];
        let dim = ev.iter().filter(|l| l.abs() <= KERNEL_REL * lmax).count();
        let want = if pr.knots.is_closed() { 1 } else { 2 };
        ok &= dim == want;
        dims.push(format!("{dim}/{want}"));
        gap = gap.min(ev[want] / lmax);
    }
    Ok(Outcome::flag(
        ok,
        format!(
            "dim ker H (got/want, closed 1, open 2): {}; smallest non-zero λ/λ_max = {gap:.2e}",
            dims.join(" ")
        ),
    ))
}

fn energy_three_ways() -> anyhow::Result<Outcome> {
    let (r, which) = worst(|pr| {
        let e1 = energy(&pr.knots, &pr.points)?;
        let e2 = Hessian::new(&pr.knots).energy(&pr.points)?;
        let e3 = energy_by_jumps(&pr.knots, &pr.points)?;
        Ok((e1 - e2).abs().max((e1 - e3).abs()) / e1)
    })?;
    Ok(Outcome::check(
        r,
        EXACT_TOL,
        format!("(2.1) Σ|Δs|²/h₂ vs ½pᵀHp vs pᵀjmp, relative (worst: {which})"),
    ))
}

fn jmp_half_hp() -> anyhow::Result<Outcome> {
    let (r, which) = worst(|pr| {
        let hp = Hessian::new(&pr.knots).apply(&pr.points);
        let half: Vec<f64> = hp.coords().iter().map(|x| 0.5 * x).collect();
        let j = jumps(&pr.knots, &pr.points)?;
        Ok(rel_err(j.coords(), &half))
    })?;
    Ok(Outcome::check(
        r,
        EXACT_TOL,
        format!("|jmp − ½Hp|∞ / |½Hp|∞ (worst: {which})"),
    ))
}

fn point_gradient() -> anyhow::Result<Outcome> {
    // E is quadratic in p: central differences are exact up to rounding for any step.
    const STEP: f64 = 1e-3;
    let (r, which) = worst(|pr| {
        let hp = Hessian::new(&pr.knots).apply(&pr.points);
        let mut fd = Vec::new();
        for idx in 0..pr.points.coords().len() {
            let e = |dx: f64| -> anyhow::Result<f64> {
                let mut p = pr.points.clone();
                p.coords_mut()[idx] += dx;
                Ok(energy(&pr.knots, &p)?)
            };
            fd.push((e(STEP)? - e(-STEP)?) / (2.0 * STEP));
        }
        Ok(rel_err(hp.coords(), &fd))
    })?;
    Ok(Outcome::check(
        r,
        1e-8,
        format!("|Hp − central FD of E in p|∞ / |FD|∞, step {STEP} (worst: {which})"),
    ))
}

/// Σ_k |p_(i+k)|∞ / |π'(t_(i+k))|: the size of the explicit formula's terms, the scale of the
/// rounding error of both formulas (the result itself may be much smaller by cancellation).
fn term_scale(pr: &Problem, i: isize, order: usize) -> f64 {
    let n = pr.knots.vertex_count() as isize;
    (0..=order as isize)
        .map(|k| {
            let tk = pr.knots.t(i + k);
            let dpi: f64 = (0..=order as isize)
                .filter(|&j| j != k)
                .map(|j| tk - pr.knots.t(i + j))
                .product();
            max_abs(pr.points.point((i + k).rem_euclid(n) as usize)) / dpi.abs()
        })
        .sum()
}

fn divided_differences() -> anyhow::Result<Outcome> {
    let (r, which) = worst(|pr| {
        let n = pr.knots.vertex_count() as isize;
        let mut worst = 0.0f64;
        for order in 0..=4usize {
            // Closed curves: indices over three periods, negative ones included.
            let range = if pr.knots.is_closed() {
                -n..2 * n
            } else {
                0..n - order as isize
            };
            for i in range {
                let a = divided_difference(&pr.knots, &pr.points, i, order)?;
                let b = divided_difference_explicit(&pr.knots, &pr.points, i, order)?;
                let diff: Vec<f64> = a.iter().zip(&b).map(|(x, y)| x - y).collect();
                worst = worst.max(max_abs(&diff) / term_scale(pr, i, order));
            }
        }
        Ok(worst)
    })?;
    Ok(Outcome::check(
        r,
        EXACT_TOL,
        format!("recurrence vs Σ p_(i+k)/π'(t_(i+k)), orders 0..4, relative to Σ|terms| (worst: {which})"),
    ))
}

fn jump_forms() -> anyhow::Result<Outcome> {
    let (r, which) = worst(|pr| {
        let j = jumps(&pr.knots, &pr.points)?;
        let n = pr.knots.vertex_count();
        let k = &pr.knots;
        let range = if k.is_closed() { 0..n } else { 2..n - 2 };
        let mut got = Vec::new();
        let mut want = Vec::new();
        for i in range {
            let ii = i as isize;
            let d1 = divided_difference(k, &pr.points, ii - 1, 3)?;
            let d0 = divided_difference(k, &pr.points, ii - 2, 3)?;
            let (h13, h23) = (k.t(ii + 2) - k.t(ii - 1), k.t(ii + 1) - k.t(ii - 2));
            let (hi, hl) = (k.t(ii + 1) - k.t(ii), k.t(ii) - k.t(ii - 1));
            for c in 0..pr.points.dim() {
                want.push(h13 / hi * d1[c] - h23 / hl * d0[c]);
                got.push(j.point(i)[c]);
            }
        }
        Ok(rel_err(&got, &want))
    })?;
    Ok(Outcome::check(
        r,
        EXACT_TOL,
        format!("jmp_i from 2nd differences vs (h_(i−1,3)/h_i)Δ_(i−1,3) − (h_(i−2,3)/h_(i−1))Δ_(i−2,3) (worst: {which})"),
    ))
}

/// Error of a derivative stencil on the quadratic q(t) = 1 − t + 3t² at every vertex.
fn quadratic_error(
    k: &Knots,
    coeffs: impl Fn(usize) -> anyhow::Result<[(usize, f64); 3]>,
) -> anyhow::Result<f64> {
    let q = |t: f64| 1.0 - t + 3.0 * t * t;
    let dq = |t: f64| -1.0 + 6.0 * t;
    let n = k.vertex_count();
    let mut worst = 0.0f64;
    for i in 0..n {
        let mut df = 0.0;
        for (v, c) in coeffs(i)? {
            // A closed stencil is (i − 1, i, i + 1) modulo N: evaluate q at the periodically
            // extended knot the neighbour stands for. Open stencils never wrap.
            let t = if !k.is_closed() || v == i {
                k.t(v as isize)
            } else if v == (i + 1) % n {
                k.t(i as isize + 1)
            } else {
                k.t(i as isize - 1)
            };
            df += c * q(t);
        }
        worst = worst.max((df - dq(k.t(i as isize))).abs() / dq(k.t(i as isize)).abs().max(1.0));
    }
    Ok(worst)
}

fn bessel_exact() -> anyhow::Result<Outcome> {
    let (r, which) = worst(|pr| {
        quadratic_error(&pr.knots, |i| {
            Ok(derivative_stencil(&pr.knots, i, DerivativeRule::Bessel)?)
        })
    })?;
    Ok(Outcome::check(
        r,
        EXACT_TOL,
        format!("Bessel Df(t_i) (interior, wrapped, §3.6 ends) vs q'(t_i), q quadratic (worst: {which})"),
    ))
}

/// The printed (2.3): coefficients −(a + (a+b))/(a(a+b)), (a+b)/(ab), −a/((a+b)b) on
/// (i − 1, i, i + 1), a = h_(i−1), b = h_i. Exact only for the derivative at t_(i−1).
fn printed_bessel() -> anyhow::Result<Outcome> {
    let (r, which) = worst(|pr| {
        let k = &pr.knots;
        let n = k.vertex_count();
        let interior: Vec<usize> = if k.is_closed() {
            (0..n).collect()
        } else {
            (1..n - 1).collect()
        };
        let mut w = 0.0f64;
        for i in interior {
            let (a, b) = (k.h(i as isize - 1), k.h(i as isize));
            let printed = [
                -(2.0 * a + b) / (a * (a + b)),
                (a + b) / (a * b),
                -a / ((a + b) * b),
            ];
            let ts = [k.t(i as isize - 1), k.t(i as isize), k.t(i as isize + 1)];
            let q = |t: f64| 1.0 - t + 3.0 * t * t;
            let df: f64 = printed.iter().zip(ts).map(|(c, t)| c * q(t)).sum();
            let want = -1.0 + 6.0 * ts[1];
            w = w.max((df - want).abs() / want.abs().max(1.0));
        }
        Ok(w)
    })?;
    Ok(Outcome::check(
        r,
        EXACT_TOL,
        format!("printed (2.3) vs q'(t_i), q quadratic (worst: {which}) — it is q'(t_(i−1))"),
    ))
}

fn average_ends() -> anyhow::Result<Outcome> {
    // Average (2.2) and the one-sided end differences are exact on lines.
    let (r, which) = worst(|pr| {
        let k = &pr.knots;
        let line = Points::new(
            1,
            (0..k.vertex_count())
                .map(|i| 2.0 - 0.5 * k.values()[i])
                .collect(),
        )?;
        let n = k.vertex_count();
        let mut w = 0.0f64;
        let range = if k.is_closed() { 1..n - 1 } else { 0..n };
        for i in range {
            let df = vertex_derivative(k, &line, i, DerivativeRule::Average)?[0];
            w = w.max((df + 0.5).abs() / 0.5);
        }
        Ok(w)
    })?;
    Ok(Outcome::check(
        r,
        EXACT_TOL,
        format!("Average (2.2) + one-sided ends vs slope of a line (worst: {which})"),
    ))
}

fn lemma_2_4_printed() -> anyhow::Result<Outcome> {
    let (r, which) = worst(|pr| {
        let fd = fd_vertex_knot_gradient(pr)?;
        Ok(rel_err(&knot_gradient_printed(&pr.knots, &pr.points)?, &fd))
    })?;
    // `worst` keeps the largest error; for an expected failure the smallest matters too.
    let mut best = f64::INFINITY;
    for pr in problems() {
        let fd = fd_vertex_knot_gradient(&pr)?;
        best = best.min(rel_err(&knot_gradient_printed(&pr.knots, &pr.points)?, &fd));
    }
    Ok(Outcome::check(
        best,
        FD_TOL,
        format!("printed ∂E/∂t_i vs central FD, relative: smallest {best:.3e}, largest {r:.3e} ({which})"),
    ))
}

fn lemma_2_4_corrected() -> anyhow::Result<Outcome> {
    let (r, which) = worst(|pr| {
        let fd = fd_vertex_knot_gradient(pr)?;
        Ok(rel_err(&vertex_knot_gradient(&pr.knots, &pr.points)?, &fd))
    })?;
    Ok(Outcome::check(
        r,
        FD_TOL,
        format!("exact ∂E/∂t_i vs central FD (step {FD_STEP}·min h), relative (worst: {which})"),
    ))
}

fn knot_gradient_euler() -> anyhow::Result<Outcome> {
    let (r, which) = worst(|pr| {
        let g = knot_gradient(&pr.knots, &pr.points)?;
        let e = energy(&pr.knots, &pr.points)?;
        let t = pr.knots.values();
        let scale: f64 = g
            .iter()
            .zip(t)
            .map(|(a, b)| (a * b).abs() + a.abs())
            .sum::<f64>()
            + e;
        let sum: f64 = g.iter().sum();
        let euler: f64 = g.iter().zip(t).map(|(a, b)| a * b).sum::<f64>() + 3.0 * e;
        Ok(sum.abs().max(euler.abs()) / scale)
    })?;
    Ok(Outcome::check(
        r,
        EXACT_TOL,
        format!("Σ∂E/∂t_k = 0 and Σ t_k ∂E/∂t_k = −3E, relative (worst: {which})"),
    ))
}

/// Corollary 2.7 on a regular heptagon with uniform knots: by symmetry (Hp)_i is radial and
/// Df(t_i) tangential, so the residuals vanish; the exact knot gradient vanishes too.
fn orthogonality_symmetric() -> anyhow::Result<Outcome> {
    let n = 7;
    let rows: Vec<[f64; 2]> = (0..n)
        .map(|i| {
            let a = std::f64::consts::TAU * i as f64 / n as f64;
            [a.cos(), a.sin()]
        })
        .collect();
    let p = Points::from_rows(&rows)?;
    let k = Knots::closed((0..=n).map(|i| 0.5 * i as f64).collect())?;
    let e = energy(&k, &p)?;
    let r1 = max_abs(&orthogonality_residuals(&k, &p, DerivativeRule::Bessel)?);
    let r2 = max_abs(&vertex_knot_gradient(&k, &p)?);
    Ok(Outcome::check(
        r1.max(r2) / e,
        EXACT_TOL,
        format!("regular heptagon: max|Df·(Hp)_i| = {r1:.1e}, max|∂E/∂t_i| = {r2:.1e}, over E"),
    ))
}

/// Corollary 2.7 as a diagnostic on the random problems (which are not knot-optimal, so the
/// residuals are not small): the residuals are Df(t_i)·(Hp)_i = 2 Df(t_i)·jmp_i.
fn orthogonality_diagnostic() -> anyhow::Result<Outcome> {
    let (r, which) = worst(|pr| {
        let res = orthogonality_residuals(&pr.knots, &pr.points, DerivativeRule::Bessel)?;
        let j = jumps(&pr.knots, &pr.points)?;
        let mut want = Vec::new();
        for i in 0..pr.knots.vertex_count() {
            let df = vertex_derivative(&pr.knots, &pr.points, i, DerivativeRule::Bessel)?;
            want.push(2.0 * df.iter().zip(j.point(i)).map(|(a, b)| a * b).sum::<f64>());
        }
        Ok(rel_err(&res, &want))
    })?;
    Ok(Outcome::check(
        r,
        EXACT_TOL,
        format!("Df·(Hp)_i vs 2 Df·jmp_i (worst: {which})"),
    ))
}

fn parametrization() -> anyhow::Result<Outcome> {
    // Chords 5, 1, 4, and the closing chord |(4,0) − (0,0)| = 4: closed chordal knots
    // 0, 5, 6, 10, 14; centripetal 0, √5, √5+1, √5+3, √5+5.
    let q = Points::from_rows(&[[0.0, 0.0], [3.0, 4.0], [4.0, 4.0], [4.0, 0.0]])?;
    let s5 = 5f64.sqrt();
    let cases = [
        (Parametrization::Chordal, vec![0.0, 5.0, 6.0, 10.0, 14.0]),
        (
            Parametrization::Centripetal,
            vec![0.0, s5, s5 + 1.0, s5 + 3.0, s5 + 5.0],
        ),
        (Parametrization::Uniform, vec![0.0, 1.0, 2.0, 3.0, 4.0]),
    ];
    let mut w = 0.0f64;
    for (p, want) in cases {
        let got = parametrize(&q, Topology::Closed, p)?;
        w = w.max(rel_err(got.values(), &want));
    }
    let coincident = Points::from_rows(&[[0.0, 0.0], [1.0, 0.0], [0.0, 0.0]])?;
    let err_ok = matches!(
        parametrize(&coincident, Topology::Closed, Parametrization::Centripetal),
        Err(divdiff::Error::ZeroLengthSpan { index: 2, next: 0 })
    );
    Ok(Outcome::check(
        if err_ok { w } else { f64::INFINITY },
        EXACT_TOL,
        format!("closed knots vs hand-computed chords; coincident closing pair → ZeroLengthSpan: {err_ok}"),
    ))
}

fn warren_weimer() -> anyhow::Result<Outcome> {
    let mut w = 0.0f64;
    for level in 0..=4u32 {
        for n in [3usize, 5, 9, 17] {
            let h = 0.5f64.powi(level as i32);
            let k = Knots::open((0..n).map(|i| i as f64 * h).collect())?;
            let ek = warren_weimer_matrix(n, level)?;
            w = w.max((Hessian::new(&k).to_dense() - &ek).amax() / ek.amax());
        }
    }
    Ok(Outcome::check(
        w,
        EXACT_TOL,
        "max|H − 8^k D₂ᵀD₂| / max|E_k|, uniform open knots of spacing 2^(−k), k = 0..4, n = 3,5,9,17",
    ))
}

/// The cases of this area.
pub fn cases() -> Vec<Case> {
    vec![
        Case::holds("kersey/2.1/H-equals-AtA", h_equals_ata),
        Case::holds("kersey/2.1/H-positive-semidefinite", h_symmetric_psd),
        Case::holds("kersey/2.1+3.6/kernel-dimension", kernel_dimension),
        Case::holds("kersey/thm2.1/energy-three-ways", energy_three_ways),
        Case::holds("kersey/cor2.2/jmp-equals-half-Hp", jmp_half_hp),
        Case::holds("kersey/lemma2.3/point-gradient-equals-Hp", point_gradient),
        Case::holds(
            "kersey/2.2/divided-difference-recurrence-vs-explicit",
            divided_differences,
        ),
        Case::holds("kersey/2.2/jump-two-forms", jump_forms),
        Case::holds("kersey/2.3/bessel-exact-on-quadratics", bessel_exact),
        Case::fails(
            "kersey/2.3/printed-bessel-formula",
            "printed (2.3) gives the quadratic's derivative at t_(i−1), not t_i (math.md §1)",
            printed_bessel,
        ),
        Case::holds(
            "kersey/2.2+3.6/average-and-one-sided-exact-on-lines",
            average_ends,
        ),
        Case::fails(
            "kersey/lemma2.4/printed-formula",
            "printed Lemma 2.4 drops a factor 2 and |Δ_(i,2)|² − |Δ_(i−2,2)|² (math.md §1)",
            lemma_2_4_printed,
        ),
        Case::holds("kersey/lemma2.4/corrected-gradient", lemma_2_4_corrected),
        Case::holds(
            "kersey/lemma2.4/translation-and-scaling-identities",
            knot_gradient_euler,
        ),
        Case::holds(
            "kersey/cor2.7/orthogonality-regular-polygon",
            orthogonality_symmetric,
        ),
        Case::holds(
            "kersey/cor2.7/residuals-equal-2Df-dot-jmp",
            orthogonality_diagnostic,
        ),
        Case::holds("kersey/alg4.1/parametrizations", parametrization),
        Case::holds("warren-weimer/6.2/E_k-equals-H", warren_weimer),
    ]
}
