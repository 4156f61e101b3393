//! profiling scratch
use divdiff::Points;
use refine::{Constraint, Problem};
fn wavy_circle(n: usize) -> Points {
    let mut c = Vec::with_capacity(2 * n);
    for i in 0..n {
        let th = 2.0 * std::f64::consts::PI * i as f64 / n as f64;
        let r = 1.0 + 0.3 * (5.0 * th).sin() + 0.1 * (17.0 * th).cos();
        c.push(r * th.cos());
        c.push(r * th.sin());
    }
    Points::new(2, c).unwrap()
}
fn radii(q: &Points) -> Vec<f64> {
    let n = q.len();
    let mut spacing = 0.0;
    for i in 0..n {
        let (a, b) = (q.point(i), q.point((i + 1) % n));
        spacing += ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt() / n as f64;
    }
    let mut s: u64 = 0x9E37_79B9_7F4A_7C15;
    (0..n)
        .map(|_| {
            s = s.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1);
            let u = (s >> 11) as f64 / (1u64 << 53) as f64;
            (0.2 + 0.5 * u) * spacing
        })
        .collect()
}
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args.get(1).map_or(10000, |s| s.parse().unwrap());
    let reps: usize = args.get(2).map_or(20, |s| s.parse().unwrap());
    let q = wavy_circle(n);
    let r = radii(&q);
    let p = Problem::new(q)
        .with_k(3)
        .with_knot_iterations(0)
        .with_constraint(Constraint::Balls(r));
    let mut best = f64::INFINITY;
    for _ in 0..reps {
        let t = std::time::Instant::now();
        let s = p.solve().unwrap();
        best = best.min(t.elapsed().as_secs_f64());
        std::hint::black_box(s.energy);
    }
    let s = p.solve().unwrap();
    println!(
        "n {n}: best {:.2} ms, kkt {:.1e}, iters {}, E {:.12e}",
        best * 1e3,
        s.kkt_residual,
        s.iterations.solver,
        s.energy
    );
}
