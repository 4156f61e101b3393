//! Hard test data shared by the test files: the noisy star of `cargo xtask bench hard`.
// (Each test file uses part of it.)
#![allow(dead_code)]

use divdiff::Points;

/// A noisy star: n points at jittered angles θ_i = 2π(i + u_i)/n, u_i ∈ [−0.4, 0.4], radii
/// alternating 1 and 1.35 with ±0.05 noise (the `hard` bench's data; a fixed-seed LCG here).
pub fn noisy_star(n: usize) -> Points {
    star(n, 20261125, 0.35, 0.05)
}

/// The noisy star with its LCG's `seed`, radii alternating 1 and 1 + `jump` with ±`noise`.
pub fn star(n: usize, seed: u64, jump: f64, noise: f64) -> Points {
    let mut state = seed;
    let mut uniform = || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut rows = Vec::with_capacity(2 * n);
    for i in 0..n {
        let theta = 2.0 * std::f64::consts::PI * (i as f64 + 0.8 * uniform() - 0.4) / n as f64;
        let r = 1.0 + jump * (i % 2) as f64 + 2.0 * noise * uniform() - noise;
        rows.extend([r * theta.cos(), r * theta.sin()]);
    }
    Points::new(2, rows).unwrap()
}
