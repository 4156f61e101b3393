//! Hard channels: the strip problems real users bring ("bounds that hold between the samples").
//!
//! The centre line on \[0, 1\] is a smooth wave 0.3 sin(2π·1.3 t) + 0.1 cos(2π·3.1 t) plus
//! `fronts` steep steps A_k tanh(κ_k (t − t_k)) (heights A_k ∈ ±\[0.1, 0.6\], slope A_k κ_k at the
//! front of order `front_slope`) plus `bumps` narrow Gaussian bumps of width `bump_width`. The
//! half-width w(t) varies smoothly in \[w_min, w_max\]. Bounds are c ∓ w either as polylines with
//! `breakpoints` vertices (nearly equispaced, jittered) or as one cubic per data interval (the
//! Hermite cubic of c at the sites ∓ the chord of w: their difference is twice the chord of
//! w > 0, so the strip never closes). Data are `sites` nearly equispaced (jittered) sites, the first at 0 and
//! the last at 1, with values on the centre line of the bounds as given — (e + d)/2 — so the
//! problem is always feasible: every data point lies strictly inside, and an open channel always
//! holds a C² function.
//!
//! With independent vertex abscissae (`shared_vertices = false`) the two polylines can cross
//! where M is coarse against a front, and [`strip::solve`] then refuses the problem (the strip
//! closes); with shared abscissae d − e is linear between vertices where it is 2w > 0.
//!
//! Everything is determined by `seed` (SplitMix64), so a failing case is reproduced from its
//! parameters.

use strip::{Bound, Problem};

/// How the bounds are given.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BoundKind {
    /// Polylines with `breakpoints` vertices each (lower and upper at different jitters).
    Polyline,
    /// One cubic per data interval (Hermite interpolation of c ∓ w at the sites).
    Pieces,
}

/// The parameters of a channel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Channel {
    /// Random seed.
    pub seed: u64,
    /// Polyline vertices per bound (ignored for [`BoundKind::Pieces`]).
    pub breakpoints: usize,
    /// Data sites (≥ 2).
    pub sites: usize,
    /// Steep tanh fronts.
    pub fronts: usize,
    /// Typical slope at a front (the actual slopes are this times a factor in \[0.5, 2\]).
    pub front_slope: f64,
    /// Narrow bumps.
    pub bumps: usize,
    /// Width (standard deviation) of a bump.
    pub bump_width: f64,
    /// Smallest half-width of the channel.
    pub w_min: f64,
    /// Largest half-width.
    pub w_max: f64,
    /// Jitter of sites and vertices, as a fraction of their spacing (< 0.5).
    pub jitter: f64,
    /// How the bounds are given.
    pub bounds: BoundKind,
    /// Whether the two polylines share their vertex abscissae (then the strip is open by
    /// construction; independent vertices can cross where M is coarse against a front).
    pub shared_vertices: bool,
}

impl Default for Channel {
    /// The channel of issue 15: five fronts of slope ~10³, three bumps of width 0.004,
    /// half-width 0.01–0.04, 10⁴ polyline vertices, 16 sites.
    fn default() -> Self {
        Channel {
            seed: 1,
            breakpoints: 10_000,
            sites: 16,
            fronts: 5,
            front_slope: 1e3,
            bumps: 3,
            bump_width: 0.004,
            w_min: 0.01,
            w_max: 0.04,
            jitter: 0.2,
            bounds: BoundKind::Polyline,
            shared_vertices: true,
        }
    }
}

/// SplitMix64: a tiny, well-mixed generator (no dependency).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in \[a, b).
    fn uniform(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// The centre line, its derivative, and the half-width with its derivative.
struct Shape {
    fronts: Vec<(f64, f64, f64)>,
    bumps: Vec<(f64, f64, f64)>,
    w: (f64, f64, f64, f64),
}

impl Shape {
    fn centre(&self, t: f64) -> (f64, f64) {
        use std::f64::consts::PI;
        let (a1, a2) = (2.0 * PI * 1.3, 2.0 * PI * 3.1);
        let mut v = 0.3 * (a1 * t).sin() + 0.1 * (a2 * t).cos();
        let mut d = 0.3 * a1 * (a1 * t).cos() - 0.1 * a2 * (a2 * t).sin();
        for &(t0, a, k) in &self.fronts {
            let th = (k * (t - t0)).tanh();
            v += a * th;
            d += a * k * (1.0 - th * th);
        }
        for &(t0, a, s) in &self.bumps {
            let u = (t - t0) / s;
            let g = (-u * u).exp();
            v += a * g;
            d += a * g * (-2.0 * u / s);
        }
        (v, d)
    }
    fn half_width(&self, t: f64) -> (f64, f64) {
        let (mid, amp, freq, phase) = self.w;
        let a = 2.0 * std::f64::consts::PI * freq;
        (
            mid + amp * (a * t + phase).sin(),
            amp * a * (a * t + phase).cos(),
        )
    }
}

/// `count` sites from 0 to 1, nearly equispaced: interior ones moved by up to `jitter` of the
/// spacing.
fn jittered(rng: &mut Rng, count: usize, jitter: f64) -> Vec<f64> {
    let m = count - 1;
    (0..count)
        .map(|k| {
            if k == 0 || k == m {
                k as f64 / m as f64
            } else {
                (k as f64 + rng.uniform(-jitter, jitter)) / m as f64
            }
        })
        .collect()
}

impl Channel {
    /// The problem.
    ///
    /// # Panics
    /// When `sites < 2`, `breakpoints < 2` for polylines, or `jitter ≥ 0.5` (parameters of the
    /// test, not user input).
    pub fn problem(&self) -> Problem {
        assert!(self.sites >= 2 && self.jitter < 0.5);
        let mut rng = Rng(self.seed);
        let fronts = (0..self.fronts)
            .map(|_| {
                let t0 = rng.uniform(0.05, 0.95);
                let a = rng.uniform(0.1, 0.6) * if rng.next() & 1 == 0 { 1.0 } else { -1.0 };
                let slope = self.front_slope * rng.uniform(0.5, 2.0);
                (t0, a, slope / a.abs())
            })
            .collect();
        let bumps = (0..self.bumps)
            .map(|_| {
                let t0 = rng.uniform(0.05, 0.95);
                let a = rng.uniform(-0.15, 0.15);
                (t0, a, self.bump_width)
            })
            .collect();
        let mid = 0.5 * (self.w_min + self.w_max);
        let amp = 0.5 * (self.w_max - self.w_min);
        let shape = Shape {
            fronts,
            bumps,
            w: (mid, amp, rng.uniform(1.5, 3.5), rng.uniform(0.0, 6.0)),
        };
        let t = jittered(&mut rng, self.sites, self.jitter);
        match self.bounds {
            BoundKind::Polyline => {
                assert!(self.breakpoints >= 2);
                let xs_lower = jittered(&mut rng, self.breakpoints, self.jitter);
                let xs_upper = if self.shared_vertices {
                    xs_lower.clone()
                } else {
                    jittered(&mut rng, self.breakpoints, self.jitter)
                };
                let side = |xs: &[f64], sign: f64| -> Vec<[f64; 2]> {
                    xs.iter()
                        .map(|&x| [x, shape.centre(x).0 + sign * shape.half_width(x).0])
                        .collect()
                };
                let lower = side(&xs_lower, -1.0);
                let upper = side(&xs_upper, 1.0);
                let at = |p: &[[f64; 2]], x: f64| {
                    let k = p.partition_point(|q| q[0] <= x).clamp(1, p.len() - 1);
                    let (a, b) = (p[k - 1], p[k]);
                    a[1] + (b[1] - a[1]) * (x - a[0]) / (b[0] - a[0])
                };
                let y = t
                    .iter()
                    .map(|&x| 0.5 * (at(&lower, x) + at(&upper, x)))
                    .collect();
                Problem {
                    t,
                    y,
                    lower: Bound::Polyline(lower),
                    upper: Bound::Polyline(upper),
                    end_slopes: [None, None],
                }
            }
            BoundKind::Pieces => {
                // the Hermite cubic of the centre line ∓ the chord of the half-width: their
                // difference is twice the chord of w > 0, so the strip never closes (a Hermite
                // cubic of w itself can dip below zero between the sites)
                let hermite = |sign: f64| -> Vec<[f64; 4]> {
                    t.windows(2)
                        .map(|w| {
                            let h = w[1] - w[0];
                            let ((v0, d0), (v1, d1)) = (shape.centre(w[0]), shape.centre(w[1]));
                            let s = (v1 - v0) / h;
                            let (r0, r1) = (shape.half_width(w[0]).0, shape.half_width(w[1]).0);
                            [
                                v0 + sign * r0,
                                d0 + sign * (r1 - r0) / h,
                                (3.0 * s - 2.0 * d0 - d1) / h,
                                (d0 + d1 - 2.0 * s) / (h * h),
                            ]
                        })
                        .collect()
                };
                let y = t.iter().map(|&x| shape.centre(x).0).collect();
                Problem {
                    t: t.clone(),
                    y,
                    lower: Bound::Pieces(hermite(-1.0)),
                    upper: Bound::Pieces(hermite(1.0)),
                    end_slopes: [None, None],
                }
            }
        }
    }
}
