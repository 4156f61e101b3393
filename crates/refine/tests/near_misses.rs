//! The ball problems that once ended just above the 1e-9 certificate in every strategy
//! (ROBUSTNESS.md, limit 10): the house example open with radii [1, 1, 0.02, 1, 1], noisy
//! 200-point ball problems (k = 3, radii 0.02–0.12 of the extent, open and closed), a d = 3
//! noisy helix, and rotated and translated copies of each. Every one must be returned certified
//! ≤ 1e-9 by the solver's independent certificate, and the certificate is recomputed here from
//! the returned curve and multipliers (Kersey (3.5): Hp + w(p − q) = 0 at the data vertices,
//! Hp = 0 elsewhere, w ≥ 0, w·(ε − |p − q|) = 0) against the largest force, so the check does not
//! take the solver's word for it.
//!
//! `cargo test -p refine --test near_misses -- --nocapture` prints each case's certificate and
//! the strategies that ran (the progress observer's solver names).

use std::sync::{Arc, Mutex};

use divdiff::{Points, Topology};
use refine::{Constraint, Problem, Progress, Refinement, SolveOptions};

/// A small deterministic generator (xorshift64), uniform on [0, 1).
struct Rng(u64);

impl Rng {
    fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// One near-miss case: the data, open or closed, the radii.
struct Case {
    name: String,
    q: Points,
    topology: Topology,
    radii: Vec<f64>,
}

/// The largest coordinate extent of the data (its bounding box's largest side).
fn extent(q: &Points) -> f64 {
    (0..q.dim())
        .map(|c| {
            let (lo, hi) = q
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
                    (a.min(x[c]), b.max(x[c]))
                });
            hi - lo
        })
        .fold(0.0, f64::max)
}

/// 200 noisy points on a wobbly closed loop (d = 2), or a noisy helix (d = 3), with radii drawn
/// from 0.02–0.12 of the extent.
fn noisy(seed: u64, d: usize, topology: Topology) -> Case {
    let n = 200;
    let mut rng = Rng(seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1);
    let mut y = Vec::with_capacity(n * d);
    for i in 0..n {
        let t = std::f64::consts::TAU * i as f64 / n as f64;
        let r = 1.0 + 0.3 * (3.0 * t).sin() + 0.1 * (7.0 * t + seed as f64).cos();
        let noise = 0.03;
        y.push(r * t.cos() + noise * (rng.uniform() - 0.5));
        y.push(r * t.sin() + noise * (rng.uniform() - 0.5));
        if d == 3 {
            y.push(0.4 * (2.0 * t).sin() + noise * (rng.uniform() - 0.5));
        }
    }
    let q = Points::new(d, y).unwrap();
    let l = extent(&q);
    let radii = (0..n).map(|_| (0.02 + 0.10 * rng.uniform()) * l).collect();
    Case {
        name: format!("noisy d={d} {topology:?} seed {seed}"),
        q,
        topology,
        radii,
    }
}

/// The smooth wavy circle of the benches (`xtask/src/bench/refine.rs`, `curvefit-py/bench`):
/// r(θ) = 1 + 0.3 sin 5θ + 0.1 cos 17θ at θ_i = 2πi/n, closed, radii (0.2 … 0.7) × the mean
/// spacing — most balls inactive. Its first strategy entry ended at 2.2e-9 (n = 10³, no knot
/// update: 251
/// iterations through the strict entry instead of 60); here with the default knot updates.
fn wavy(n: usize) -> Case {
    let mut rng = Rng(0x2545_f491_4f6c_dd1d);
    let y: Vec<f64> = (0..n)
        .flat_map(|i| {
            let t = std::f64::consts::TAU * i as f64 / n as f64;
            let r = 1.0 + 0.3 * (5.0 * t).sin() + 0.1 * (17.0 * t).cos();
            [r * t.cos(), r * t.sin()]
        })
        .collect();
    let q = Points::new(2, y).unwrap();
    let spacing = (0..n)
        .map(|i| {
            let (a, b) = (q.point(i), q.point((i + 1) % n));
            ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt()
        })
        .sum::<f64>()
        / n as f64;
    let radii = (0..n)
        .map(|_| (0.2 + 0.5 * rng.uniform()) * spacing)
        .collect();
    Case {
        name: format!("wavy circle n={n}"),
        q,
        topology: Topology::Closed,
        radii,
    }
}

/// The house example of `kersey.rs`, open, radii [1, 1, 0.02, 1, 1].
fn house() -> Case {
    Case {
        name: "house open [1, 1, 0.02, 1, 1]".into(),
        q: Points::from_rows(&[
            &[0.0, 0.0],
            &[2.0, 0.1],
            &[2.2, 1.9],
            &[1.0, 3.0],
            &[-0.1, 2.0],
        ])
        .unwrap(),
        topology: Topology::Open,
        radii: vec![1.0, 1.0, 0.02, 1.0, 1.0],
    }
}

/// The case rotated by `angle` in the plane of its first two coordinates and translated by
/// `shift` in every coordinate (the optimum moves along: the certificate must not care).
fn moved(c: &Case, angle: f64, shift: f64) -> Case {
    let d = c.q.dim();
    let (s, co) = angle.sin_cos();
    let y =
        c.q.iter()
            .flat_map(|x| {
                let mut v = x.to_vec();
                v[0] = co * x[0] - s * x[1] + shift;
                v[1] = s * x[0] + co * x[1] + shift;
                for w in v.iter_mut().skip(2) {
                    *w += shift;
                }
                v
            })
            .collect();
    Case {
        name: format!("{} rotated {angle} shifted {shift}", c.name),
        q: Points::new(d, y).unwrap(),
        topology: c.topology,
        radii: c.radii.clone(),
    }
}

/// Noisy 2-D problems per topology. Measured with 60 seeds (369 cases with the helices and the
/// house; `conic`'s polish as of ROBUSTNESS.md limit 10): 95 refused at 1.0e-9 … 7.4e-9 before,
/// none after, the largest certificate 7.6e-11.
const SEEDS: u64 = 6;

/// The house, the wavy circle, noisy 2-D problems open and closed, a noisy helix open and closed, and two rotated
/// and translated copies of each.
fn cases() -> Vec<Case> {
    let mut base = vec![house(), wavy(1000)];
    for seed in 1..=SEEDS {
        base.push(noisy(seed, 2, Topology::Closed));
        base.push(noisy(seed, 2, Topology::Open));
    }
    base.push(noisy(101, 3, Topology::Closed));
    base.push(noisy(102, 3, Topology::Open));
    let mut all = Vec::new();
    for c in base {
        all.push(moved(&c, 0.7, 0.0));
        all.push(moved(&c, -1.3, 25.0));
        all.push(c);
    }
    all
}

/// The relative KKT residual of a ball refinement recomputed from its curve and multipliers:
/// stationarity (Hp from `energy::Hessian`, dense, plus w(p − q) at the data vertices) and
/// complementarity over the largest |Hp| (floored by rounding), feasibility over the extent. An
/// independent check of the solver's own certificate (on the 372 cases of 60 seeds it read at
/// most 1.0e-10).
fn recheck(r: &Refinement, q: &Points, radii: &[f64]) -> f64 {
    let (d, nv) = (q.dim(), r.points.len());
    let h = energy::Hessian::new(&r.knots).to_dense();
    // H annihilates constants: Hp = H(p − q₀), which keeps a translated copy's rounding (of
    // |p| ~ 25 in the dense products) out of the check.
    let q0 = q.point(0);
    let mut hp = vec![0.0; nv * d];
    for i in 0..nv {
        for j in 0..nv {
            let a = h[(i, j)];
            if a != 0.0 {
                for c in 0..d {
                    hp[i * d + c] += a * (r.points.point(j)[c] - q0[c]);
                }
            }
        }
    }
    // The force scale: the largest |Hp|, but no less than what rounding the stored coordinates
    // (max |p|) exerts through H (‖H‖∞ from the dense rows) counted as 1e-9 — a translated copy's
    // coordinates of 25 carry that much.
    let h_norm = (0..nv)
        .map(|i| (0..nv).map(|j| h[(i, j)].abs()).sum::<f64>())
        .fold(0.0, f64::max);
    let magnitude = r.points.coords().iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let force = hp
        .iter()
        .fold(0.0f64, |a, v| a.max(v.abs()))
        .max(16.0 * f64::EPSILON * h_norm * magnitude / 1e-9);
    let mut res = hp.clone();
    let mut comp = 0.0f64;
    let mut primal = 0.0f64;
    for (i, &v) in r.data_vertex.iter().enumerate() {
        let (p, qi) = (r.points.point(v), q.point(i));
        let dist = p
            .iter()
            .zip(qi)
            .map(|(a, b)| (a - b) * (a - b))
            .sum::<f64>()
            .sqrt();
        primal = primal.max(dist - radii[i]);
        let w = r.multipliers[i][0];
        comp = comp.max((w * (radii[i] - dist)).abs()).max(-w);
        for c in 0..d {
            res[v * d + c] += w * (p[c] - qi[c]);
        }
    }
    let stat = res.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    (stat / force)
        .max(comp / force)
        .max(primal.max(0.0) / extent(q))
}

/// Every case is returned certified ≤ 1e-9 (ROBUSTNESS.md, limit 10), and the recomputed
/// residual agrees (≤ 1e-9 too).
#[test]
fn near_misses_certify() {
    let mut failures = Vec::new();
    for c in cases() {
        let solvers = Arc::new(Mutex::new(Vec::<&'static str>::new()));
        let seen = Arc::clone(&solvers);
        let options = SolveOptions::default().with_progress(move |e| {
            if let Progress::Iteration { solver, .. } = e {
                let mut s = seen.lock().unwrap();
                if s.last() != Some(solver) {
                    s.push(solver);
                }
            }
        });
        let problem = Problem::new(c.q.clone())
            .with_topology(c.topology)
            .with_k(3)
            .with_constraint(Constraint::Balls(c.radii.clone()))
            .with_options(options);
        let started = std::time::Instant::now();
        let result = problem.solve();
        let ran = solvers.lock().unwrap().join(" → ");
        let ms = started.elapsed().as_secs_f64() * 1e3;
        match result {
            Ok(r) => {
                let again = recheck(&r, &c.q, &c.radii);
                println!(
                    "{:<48} ok   kkt {:.2e}  recheck {:.2e}  {ms:7.1} ms  [{ran}]",
                    c.name, r.kkt_residual, again
                );
                if r.kkt_residual > 1e-9 || again.is_nan() || again > 1e-9 {
                    failures.push(format!(
                        "{}: kkt {:e}, recheck {again:e}",
                        c.name, r.kkt_residual
                    ));
                }
            }
            Err(e) => {
                println!("{:<48} ERR  {e}  {ms:7.1} ms  [{ran}]", c.name);
                failures.push(format!("{}: {e}", c.name));
            }
        }
    }
    assert!(failures.is_empty(), "refused or uncertified: {failures:#?}");
}
