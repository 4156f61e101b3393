//! Hard data shared by the tests and `cargo xtask bench`: a noisy star with jittered angles and
//! constraints sized to the local chord, deterministic (a small xorshift generator seeded by
//! the caller), for every constraint class of the exact solver.
#![allow(dead_code)]

use divdiff::{Points, Topology};
use refine::{Boundary, Constraint, HalfSpace, Problem, Tangent};

/// A small deterministic generator (xorshift64*), so tests, bench and peers see the same data.
pub struct Rng(u64);

impl Rng {
    /// A generator from a seed (any value; 0 is replaced).
    pub fn new(seed: u64) -> Self {
        Rng(seed.max(1))
    }
    /// Uniform in [0, 1).
    pub fn next(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64
    }
    /// Uniform in [a, b).
    pub fn range(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * self.next()
    }
}

/// A noisy five-pointed star: n points at angles 2πi/n jittered by up to ±0.4 of the angular
/// step (so spans vary by a factor of about 5), radius 1 + 0.3 sin 5θ plus noise of ±0.5 % —
/// closed, or (open) the same points as an open curve. d = 2, or d = 3 with a small wave in z.
pub fn noisy_star(n: usize, d: usize, seed: u64) -> Points {
    let mut rng = Rng::new(seed);
    let step = std::f64::consts::TAU / n as f64;
    let mut c = Vec::with_capacity(n * d);
    for i in 0..n {
        let th = step * (i as f64 + rng.range(-0.4, 0.4));
        let r = (1.0 + 0.3 * (5.0 * th).sin()) * (1.0 + rng.range(-0.005, 0.005));
        c.push(r * th.cos());
        c.push(r * th.sin());
        if d == 3 {
            c.push(0.2 * (3.0 * th).sin() + rng.range(-0.002, 0.002));
        }
    }
    Points::new(d, c).expect("finite points")
}

/// Every point of `q` in an axis-aligned box of half-width `half_width(i)` (a tolerance per
/// coordinate): 2d half-spaces per point, ±e_j · x ≤ ±q_ij + w in the order j, then sign.
pub fn axis_boxes(q: &Points, half_width: impl Fn(usize) -> f64) -> Constraint {
    Constraint::HalfSpaces(
        q.iter()
            .enumerate()
            .map(|(i, x)| {
                let w = half_width(i);
                let mut set = Vec::new();
                for (j, &c) in x.iter().enumerate() {
                    for sign in [1.0, -1.0] {
                        let mut normal = vec![0.0; x.len()];
                        normal[j] = sign;
                        set.push(HalfSpace {
                            offset: sign * c + w,
                            normal,
                        });
                    }
                }
                set
            })
            .collect(),
    )
}

/// The local chord at each point: the mean distance to its neighbours (one neighbour at the
/// ends of an open curve).
pub fn local_chords(q: &Points, topology: Topology) -> Vec<f64> {
    let n = q.len();
    let dist = |a: usize, b: usize| {
        q.point(a)
            .iter()
            .zip(q.point(b))
            .map(|(x, y)| (x - y) * (x - y))
            .sum::<f64>()
            .sqrt()
    };
    (0..n)
        .map(|i| {
            let closed = topology == Topology::Closed;
            let prev = (closed || i > 0).then(|| dist(i, (i + n - 1) % n));
            let next = (closed || i + 1 < n).then(|| dist(i, (i + 1) % n));
            match (prev, next) {
                (Some(a), Some(b)) => 0.5 * (a + b),
                (Some(a), None) | (None, Some(a)) => a,
                (None, None) => 1.0,
            }
        })
        .collect()
}

/// The problem classes of the bench and the hardness tests.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Class {
    /// Balls of radius 0.05–0.25 of the local chord about every point.
    Balls,
    /// A rotated box of half-width 0.05–0.25 of the local chord about every point.
    HalfSpaces,
    /// Interpolation with a tangent wedge (half-angle 0.3, along the local chord) at every
    /// 8th point.
    Tangents,
    /// Interpolation with clamped ends (open curves; the derivatives of the data polygon's end
    /// chords, per unit of parameter).
    Clamped,
}

impl Class {
    /// Its name in tables.
    pub fn name(self) -> &'static str {
        match self {
            Class::Balls => "balls",
            Class::HalfSpaces => "half-spaces",
            Class::Tangents => "tangents",
            Class::Clamped => "clamped ends",
        }
    }
}

/// The problem of `class` on the noisy star of n points (k intermediate points, no knot update:
/// one fixed-knot solve, the solve the bench times).
pub fn problem(
    class: Class,
    n: usize,
    d: usize,
    topology: Topology,
    k: usize,
    seed: u64,
) -> Problem {
    let q = noisy_star(n, d, seed);
    let chords = local_chords(&q, topology);
    let mut rng = Rng::new(seed ^ 0x5DEE_CE66);
    let base = Problem::new(q.clone())
        .with_topology(topology)
        .with_k(k)
        .with_knot_iterations(0);
    match class {
        Class::Balls => {
            let radii = chords.iter().map(|c| c * rng.range(0.05, 0.25)).collect();
            base.with_constraint(Constraint::Balls(radii))
        }
        Class::HalfSpaces => {
            let sets = (0..n)
                .map(|i| {
                    let w = chords[i] * rng.range(0.05, 0.25);
                    let a = rng.range(0.0, std::f64::consts::FRAC_PI_2);
                    let qi = q.point(i);
                    let mut set = Vec::new();
                    // A box rotated by a in the plane of the first two coordinates, and the
                    // slab |z − q_z| ≤ w in 3-D.
                    for (nx, ny) in [(a.cos(), a.sin()), (-a.sin(), a.cos())] {
                        for s in [1.0, -1.0] {
                            let mut normal = vec![0.0; d];
                            normal[0] = s * nx;
                            normal[1] = s * ny;
                            let c = normal.iter().zip(qi).map(|(u, x)| u * x).sum::<f64>() + w;
                            set.push(HalfSpace { normal, offset: c });
                        }
                    }
                    if d == 3 {
                        for s in [1.0, -1.0] {
                            set.push(HalfSpace {
                                normal: vec![0.0, 0.0, s],
                                offset: s * qi[2] + w,
                            });
                        }
                    }
                    set
                })
                .collect();
            base.with_constraint(Constraint::HalfSpaces(sets))
        }
        Class::Tangents => {
            let tangents = (0..n)
                .map(|i| {
                    (i % 8 == 3).then(|| {
                        let (a, b) = (q.point((i + n - 1) % n), q.point((i + 1) % n));
                        let direction: Vec<f64> = a.iter().zip(b).map(|(x, y)| y - x).collect();
                        Tangent::Wedge {
                            direction,
                            half_angle: 0.3,
                        }
                    })
                })
                .collect();
            base.with_tangents(tangents)
        }
        Class::Clamped => {
            let chord = |a: usize, b: usize| -> Vec<f64> {
                q.point(b)
                    .iter()
                    .zip(q.point(a))
                    .map(|(x, y)| x - y)
                    .collect()
            };
            base.with_topology(Topology::Open)
                .with_boundary(Boundary::Clamped {
                    start: chord(0, 1),
                    end: chord(n - 2, n - 1),
                })
        }
    }
}
