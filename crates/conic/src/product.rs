//! The method's passes over every block of the product cone at once.
//!
//! Each pass applies one per-block operation of the method (the scalings, the step to the
//! boundary, the corrector's right-hand side, the scaled parts of a Newton solve) to all blocks.
//! When every block is the same small second-order cone (Q³: balls and wedges in the plane; Q⁴:
//! balls in space) the block's rows are a fixed-size array and the pass is one loop over them,
//! unrolled, without the per-block offsets, kinds and slices of the general path; when every
//! block is an orthant the product is one orthant, row by row. Anything else goes block by
//! block through [`crate::cone`]. The fixed-size kernels do the arithmetic of
//! [`crate::cone`]'s functions operation for operation (tested).

// The fixed-size kernels index several small arrays by the same row.
#![allow(clippy::needless_range_loop)]

use crate::cone::{
    add_identity, apply_nt, jordan_divide, jordan_product, nt_scaling, step_to_boundary, Cones,
    Kind, Layout,
};

/// J(u) = (u_0 − |ū|)(u_0 + |ū|) of a block of M rows ([`soc_residual`]).
#[inline(always)]
fn soc_j<const M: usize>(u: &[f64; M]) -> f64 {
    let mut r2 = 0.0;
    for k in 1..M {
        r2 += u[k] * u[k];
    }
    let r = f64::sqrt(r2);
    (u[0] - r) * (u[0] + r)
}

/// The block of M rows at `v` (a chunk of exactly M entries).
#[inline(always)]
fn arr<const M: usize>(v: &[f64]) -> [f64; M] {
    std::array::from_fn(|k| v[k])
}

/// V u (`INV` false) or V⁻¹ u (`INV` true) for the scaling (η, w̄) in `sc` (M + 1 entries), as
/// [`apply_nt`].
#[inline(always)]
fn soc_v<const M: usize, const INV: bool>(sc: &[f64], u: [f64; M]) -> [f64; M] {
    let (eta, w0) = (sc[0], sc[1]);
    let sg = if INV { -1.0 } else { 1.0 };
    let u0 = u[0];
    let mut wu = 0.0;
    for k in 1..M {
        wu += sc[1 + k] * u[k];
    }
    let new0 = w0 * u0 + sg * wu;
    let coef = sg * u0 + wu / (1.0 + w0);
    let f = if INV { 1.0 / eta } else { eta };
    let mut out = u;
    for k in 1..M {
        out[k] = (u[k] + coef * sc[1 + k]) * f;
    }
    out[0] = new0 * f;
    out
}

/// The NT scaling (η, w̄) of one block into `sc` (M + 1 entries), as [`nt_scaling`].
#[inline(always)]
fn soc_scaling<const M: usize>(s: &[f64; M], z: &[f64; M], sc: &mut [f64]) {
    let js = soc_j(s).max(f64::MIN_POSITIVE);
    let jz = soc_j(z).max(f64::MIN_POSITIVE);
    let (rs, rz) = (js.sqrt(), jz.sqrt());
    let mut sbzb = 0.0;
    for k in 0..M {
        sbzb += (s[k] / rs) * (z[k] / rz);
    }
    let gamma = ((1.0 + sbzb) / 2.0).max(0.0).sqrt();
    sc[0] = (js / jz).sqrt().sqrt();
    sc[1] = (s[0] / rs + z[0] / rz) / (2.0 * gamma);
    for k in 1..M {
        sc[1 + k] = (s[k] / rs - z[k] / rz) / (2.0 * gamma);
    }
}

/// The largest α in [0, cap] with u + α du in Q^M, as [`step_to_boundary`]: the block-by-block
/// chain that [`soc_max_step`] computes without branches (its reference in the tests).
#[cfg(test)]
fn soc_step<const M: usize>(u: &[f64; M], du: &[f64; M], cap: f64) -> f64 {
    let [a, b, c] = soc_quadratic(u, du);
    crate::cone::soc_step_from(a, b, c, u[0], du[0], cap)
}

/// J(u + α du) = a α² + b α + c of a block of M rows: [a, b, c].
#[inline(always)]
fn soc_quadratic<const M: usize>(u: &[f64; M], du: &[f64; M]) -> [f64; 3] {
    let mut ud = 0.0;
    for k in 1..M {
        ud += u[k] * du[k];
    }
    [soc_j(du), 2.0 * (u[0] * du[0] - ud), soc_j(u)]
}

/// The Jordan product u ∘ v on Q^M, as [`jordan_product`].
#[inline(always)]
fn soc_product<const M: usize>(u: &[f64; M], v: &[f64; M]) -> [f64; M] {
    let mut out = [0.0; M];
    let mut d = 0.0;
    for k in 0..M {
        d += u[k] * v[k];
    }
    out[0] = d;
    for k in 1..M {
        out[k] = u[0] * v[k] + v[0] * u[k];
    }
    out
}

/// x with λ ∘ x = r on Q^M, as [`jordan_divide`].
#[inline(always)]
fn soc_divide<const M: usize>(lambda: &[f64; M], r: &[f64; M]) -> [f64; M] {
    let jl = soc_j(lambda);
    let mut lr = 0.0;
    for k in 1..M {
        lr += lambda[k] * r[k];
    }
    let x0 = (lambda[0] * r[0] - lr) / jl;
    let mut out = [0.0; M];
    out[0] = x0;
    for k in 1..M {
        out[k] = (r[k] - x0 * lambda[k]) / lambda[0];
    }
    out
}

/// The NT scaling of every non-zero block into `sc` (block b from `sc_off[b]`: M + 1 entries
/// for Q^M, m for an orthant of m rows; [`crate::Weights::nt_layout`]) and λ = V z into
/// `lambda` (zero blocks untouched). `scratch` is work space of the general path.
pub(crate) fn scalings(
    cones: &Cones,
    s: &[f64],
    z: &[f64],
    sc: &mut [f64],
    sc_off: &[usize],
    lambda: &mut [f64],
    scratch: &mut Vec<f64>,
) {
    match cones.layout() {
        Layout::Soc3 => soc_scalings::<3>(s, z, sc, lambda),
        Layout::Soc4 => soc_scalings::<4>(s, z, sc, lambda),
        Layout::Orthant => {
            for (((w, l), a), b) in sc.iter_mut().zip(lambda.iter_mut()).zip(s).zip(z) {
                *w = (a / b).sqrt();
                *l = b * *w;
            }
        }
        Layout::Mixed => {
            for (bi, cone) in cones.blocks().iter().enumerate() {
                let r = cones.range(bi);
                if cone.kind() == Kind::Zero {
                    continue;
                }
                nt_scaling(cone.kind(), &s[r.clone()], &z[r.clone()], scratch);
                let l = &mut lambda[r.clone()];
                l.copy_from_slice(&z[r]);
                apply_nt(cone.kind(), scratch, l, false);
                sc[sc_off[bi]..sc_off[bi + 1]].copy_from_slice(scratch);
            }
        }
    }
}

fn soc_scalings<const M: usize>(s: &[f64], z: &[f64], sc: &mut [f64], lambda: &mut [f64]) {
    for (((sb, zb), w), l) in s
        .chunks_exact(M)
        .zip(z.chunks_exact(M))
        .zip(sc.chunks_exact_mut(M + 1))
        .zip(lambda.chunks_exact_mut(M))
    {
        let (sb, zb) = (arr::<M>(sb), arr::<M>(zb));
        soc_scaling(&sb, &zb, w);
        l.copy_from_slice(&soc_v::<M, false>(w, zb));
    }
}

/// Σ sᵀz over the non-zero blocks, summed block by block (the method's centring σ is sensitive
/// to its rounding on hard problems: every layout sums in the same order).
pub(crate) fn gap(cones: &Cones, s: &[f64], z: &[f64]) -> f64 {
    let block = |r: std::ops::Range<usize>| -> f64 {
        s[r.clone()]
            .iter()
            .zip(&z[r])
            .map(|(a, b)| a * b)
            .sum::<f64>()
    };
    match cones.layout() {
        Layout::Soc3 => (0..s.len() / 3).map(|b| block(3 * b..3 * b + 3)).sum(),
        Layout::Soc4 => (0..s.len() / 4).map(|b| block(4 * b..4 * b + 4)).sum(),
        Layout::Orthant | Layout::Mixed => {
            let mut g = 0.0;
            for (bi, cone) in cones.blocks().iter().enumerate() {
                if cone.kind() != Kind::Zero {
                    g += block(cones.range(bi));
                }
            }
            g
        }
    }
}

/// Σ (s + α ds)ᵀ(z + α dz) over the non-zero blocks, in one running sum.
pub(crate) fn gap_along(
    cones: &Cones,
    s: &[f64],
    ds: &[f64],
    z: &[f64],
    dz: &[f64],
    alpha: f64,
) -> f64 {
    let mut g = 0.0;
    let mut add = |r: std::ops::Range<usize>| {
        for k in r {
            g += (s[k] + alpha * ds[k]) * (z[k] + alpha * dz[k]);
        }
    };
    if cones.layout() == Layout::Mixed {
        for (bi, cone) in cones.blocks().iter().enumerate() {
            if cone.kind() != Kind::Zero {
                add(cones.range(bi));
            }
        }
    } else {
        add(0..s.len());
    }
    g
}

/// The largest α in [0, cap] keeping s + α ds and z + α dz in their cones.
pub(crate) fn max_step(
    cones: &Cones,
    s: &[f64],
    ds: &[f64],
    z: &[f64],
    dz: &[f64],
    cap: f64,
) -> f64 {
    match cones.layout() {
        layout @ (Layout::Soc3 | Layout::Soc4 | Layout::Orthant) => {
            pulp::Arch::new().dispatch(UniformStep {
                layout,
                s,
                ds,
                z,
                dz,
                cap,
            })
        }
        Layout::Mixed => {
            let mut a = cap;
            for (bi, cone) in cones.blocks().iter().enumerate() {
                let r = cones.range(bi);
                a = step_to_boundary(cone.kind(), &s[r.clone()], &ds[r.clone()], a);
                a = step_to_boundary(cone.kind(), &z[r.clone()], &dz[r], a);
            }
            a
        }
    }
}

/// Blocks (or orthant rows) per tile of the uniform steps.
const STEP_TILE: usize = 32;

/// [`max_step`] when every block is Q³, every block Q⁴, or the product one orthant, compiled
/// for the widest vector instructions of the processor, chosen at run time (pulp: AVX2 on
/// x86-64 when present, the baseline otherwise; the same bits either way — the loops keep their
/// operations, and nothing is fused into a·b + c). Its body and the kernels it calls are
/// `#[inline(always)]`: only inlined code gets the wider instructions.
struct UniformStep<'a> {
    layout: Layout,
    s: &'a [f64],
    ds: &'a [f64],
    z: &'a [f64],
    dz: &'a [f64],
    cap: f64,
}

impl pulp::WithSimd for UniformStep<'_> {
    type Output = f64;
    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) -> f64 {
        let UniformStep {
            layout,
            s,
            ds,
            z,
            dz,
            cap,
        } = self;
        match layout {
            Layout::Soc3 => soc_max_step::<3>(s, ds, z, dz, cap),
            Layout::Soc4 => soc_max_step::<4>(s, ds, z, dz, cap),
            _ => orthant_max_step(s, ds, z, dz, cap),
        }
    }
}

/// [`max_step`] on one orthant: min(cap, −x/dx over the falling rows of s and z), in
/// [`STEP_TILE`] lanes of running minima without a branch (masked candidates are +∞), combined at
/// the end: the same number as the row-by-row chain (min is exact; both skip NaN), vectorized.
#[inline(always)]
fn orthant_max_step(s: &[f64], ds: &[f64], z: &[f64], dz: &[f64], cap: f64) -> f64 {
    let mut lanes = [cap; STEP_TILE];
    let mut a = cap;
    for (u, du) in [(s, ds), (z, dz)] {
        let (uc, duc) = (u.chunks_exact(STEP_TILE), du.chunks_exact(STEP_TILE));
        for (x, dx) in uc.remainder().iter().zip(duc.remainder()) {
            a = a.min(candidate(*x, *dx));
        }
        for (x, dx) in uc.zip(duc) {
            for j in 0..STEP_TILE {
                lanes[j] = lanes[j].min(candidate(x[j], dx[j]));
            }
        }
    }
    lanes.iter().fold(a, |a, &l| a.min(l))
}

/// The step to the boundary of one falling row (−x/dx), +∞ for a rising or NaN one.
#[inline(always)]
fn candidate(x: f64, dx: f64) -> f64 {
    let r = -x / dx;
    if (dx < 0.0) & !r.is_nan() {
        r
    } else {
        f64::INFINITY
    }
}

/// [`max_step`] on Q^M blocks: the step of every block of s and of z in tiles of
/// [`STEP_TILE`] blocks, first the quadratic J(u + α du) = a α² + b α + c of each block, then its
/// candidates for the step without a branch ([`soc_step_candidates`], a loop the compiler
/// vectorizes), then their minimum. The chain of [`soc_step`] calls it replaces, α ←
/// max(min(α, candidates), 0) block after block, is max(min(cap, every candidate), 0): the same
/// number, since min is exact and both skip NaN (tested bit for bit). The branches of the chain
/// went either way at random on a dense active set (11 % of a balls solve at n = 10⁴).
#[inline(always)]
fn soc_max_step<const M: usize>(s: &[f64], ds: &[f64], z: &[f64], dz: &[f64], cap: f64) -> f64 {
    let mut best = cap;
    let mut q = QuadTile::default();
    for (u, du) in [(s, ds), (z, dz)] {
        for (ut, dut) in u.chunks(STEP_TILE * M).zip(du.chunks(STEP_TILE * M)) {
            let nb = ut.len() / M;
            for (j, (ub, dub)) in ut.chunks_exact(M).zip(dut.chunks_exact(M)).enumerate() {
                let (ub, dub) = (arr::<M>(ub), arr::<M>(dub));
                [q.a[j], q.b[j], q.c[j]] = soc_quadratic(&ub, &dub);
                q.u0[j] = ub[0];
                q.du0[j] = dub[0];
            }
            let steps = soc_step_candidates(&q);
            for &r in &steps[..nb] {
                best = best.min(r);
            }
        }
    }
    best.max(0.0)
}

/// Per block of a tile: J(u + α du) = a α² + b α + c, u₀ and du₀.
#[derive(Default)]
struct QuadTile {
    a: [f64; STEP_TILE],
    b: [f64; STEP_TILE],
    c: [f64; STEP_TILE],
    u0: [f64; STEP_TILE],
    du0: [f64; STEP_TILE],
}

/// The smallest candidate step of each block of the tile, +∞ where none applies: the candidates
/// of [`soc_step_from`] (the positive roots of the quadratic, or −c/b when it is linear and
/// falling; −u₀/du₀ when u₀ falls), every one computed and the inapplicable ones masked, so
/// the loop has no branch. (The masked values may be NaN or ±∞; they are never selected.)
#[inline(always)]
fn soc_step_candidates(t: &QuadTile) -> [f64; STEP_TILE] {
    const INF: f64 = f64::INFINITY;
    let mut out = [INF; STEP_TILE];
    for j in 0..STEP_TILE {
        let (a, b, c) = (t.a[j], t.b[j], t.c[j]);
        // (`&`, not `&&`: both sides are computed anyway, and a branch would stop the
        // vectorizer.)
        let linear = a.abs() <= f64::EPSILON * (b.abs() + c.abs());
        let r_lin = -c / b;
        let r_lin = if linear & (b < 0.0) & !r_lin.is_nan() {
            r_lin
        } else {
            INF
        };
        let disc = b * b - 4.0 * a * c;
        let quadratic = !linear & (disc >= 0.0);
        // copysign, not signum: they differ only at a NaN b, where `quadratic` is false.
        let q = -0.5 * (b + 1.0f64.copysign(b) * disc.sqrt());
        let (r1, r2) = (q / a, c / q);
        let r1 = if quadratic & (r1 > 0.0) { r1 } else { INF };
        let r2 = if quadratic & (q != 0.0) & (r2 > 0.0) {
            r2
        } else {
            INF
        };
        let r_end = -t.u0[j] / t.du0[j];
        let r_end = if (t.du0[j] < 0.0) & !r_end.is_nan() {
            r_end
        } else {
            INF
        };
        out[j] = r_lin.min(r1).min(r2).min(r_end);
    }
    out
}

/// The corrector's scaled right-hand side ξ = λ⁻¹ ∘ (σμe − λ∘λ − (V⁻¹ds_a)∘(V dz_a)) of every
/// non-zero block (0 on zero blocks). `t` is work space of the general path.
#[allow(clippy::too_many_arguments)]
pub(crate) fn corrector(
    cones: &Cones,
    sc: &[f64],
    sc_off: &[usize],
    lambda: &[f64],
    ds: &[f64],
    dz: &[f64],
    sigma_mu: f64,
    xi: &mut [f64],
    t: &mut [Vec<f64>; 4],
) {
    match cones.layout() {
        Layout::Soc3 => soc_corrector::<3>(sc, lambda, ds, dz, sigma_mu, xi),
        Layout::Soc4 => soc_corrector::<4>(sc, lambda, ds, dz, sigma_mu, xi),
        Layout::Orthant => {
            for k in 0..xi.len() {
                let (w, l) = (sc[k], lambda[k]);
                let t1 = (ds[k] / w) * (dz[k] * w);
                let t2 = -(l * l) - t1 + sigma_mu;
                xi[k] = t2 / l;
            }
        }
        Layout::Mixed => {
            let [ca, cc, t1, t2] = t;
            for (bi, cone) in cones.blocks().iter().enumerate() {
                let kind = cone.kind();
                let r = cones.range(bi);
                if kind == Kind::Zero {
                    xi[r].fill(0.0);
                    continue;
                }
                let mb = r.len();
                let scb = &sc[sc_off[bi]..sc_off[bi + 1]];
                ca.clear();
                ca.extend_from_slice(&ds[r.clone()]);
                apply_nt(kind, scb, ca, true);
                cc.clear();
                cc.extend_from_slice(&dz[r.clone()]);
                apply_nt(kind, scb, cc, false);
                t1.resize(mb, 0.0);
                jordan_product(kind, ca, cc, t1);
                t2.resize(mb, 0.0);
                let l = &lambda[r.clone()];
                jordan_product(kind, l, l, t2);
                for k in 0..mb {
                    t2[k] = -t2[k] - t1[k];
                }
                add_identity(kind, t2, sigma_mu);
                jordan_divide(kind, l, t2, &mut xi[r]);
            }
        }
    }
}

fn soc_corrector<const M: usize>(
    sc: &[f64],
    lambda: &[f64],
    ds: &[f64],
    dz: &[f64],
    sigma_mu: f64,
    xi: &mut [f64],
) {
    for ((((w, l), dsb), dzb), x) in sc
        .chunks_exact(M + 1)
        .zip(lambda.chunks_exact(M))
        .zip(ds.chunks_exact(M))
        .zip(dz.chunks_exact(M))
        .zip(xi.chunks_exact_mut(M))
    {
        let l = arr::<M>(l);
        let ca = soc_v::<M, true>(w, arr::<M>(dsb));
        let cc = soc_v::<M, false>(w, arr::<M>(dzb));
        let t1 = soc_product(&ca, &cc);
        let mut t2 = soc_product(&l, &l);
        for k in 0..M {
            t2[k] = -t2[k] - t1[k];
        }
        t2[0] += sigma_mu;
        x.copy_from_slice(&soc_divide(&l, &t2));
    }
}

/// t = V⁻¹(V⁻¹u + v) on every non-zero block (zero blocks untouched): with u = r_s and v = ξ
/// the scaled part of a Newton right-hand side, V⁻¹ξ + V⁻²r_s; with u = r_s + A dx, the dz of
/// the direction.
pub(crate) fn scaled_sum(
    cones: &Cones,
    sc: &[f64],
    sc_off: &[usize],
    u: &[f64],
    v: &[f64],
    t: &mut [f64],
) {
    match cones.layout() {
        Layout::Soc3 => soc_scaled_sum::<3>(sc, u, v, t),
        Layout::Soc4 => soc_scaled_sum::<4>(sc, u, v, t),
        Layout::Orthant => {
            for (((o, w), a), b) in t.iter_mut().zip(sc).zip(u).zip(v) {
                *o = (a / w + b) / w;
            }
        }
        Layout::Mixed => {
            for (bi, cone) in cones.blocks().iter().enumerate() {
                if cone.kind() == Kind::Zero {
                    continue;
                }
                let r = cones.range(bi);
                let scb = &sc[sc_off[bi]..sc_off[bi + 1]];
                let tb = &mut t[r.clone()];
                tb.copy_from_slice(&u[r.clone()]);
                apply_nt(cone.kind(), scb, tb, true);
                for (a, x) in tb.iter_mut().zip(&v[r]) {
                    *a += x;
                }
                apply_nt(cone.kind(), scb, tb, true);
            }
        }
    }
}

fn soc_scaled_sum<const M: usize>(sc: &[f64], u: &[f64], v: &[f64], t: &mut [f64]) {
    for (((w, ub), vb), tb) in sc
        .chunks_exact(M + 1)
        .zip(u.chunks_exact(M))
        .zip(v.chunks_exact(M))
        .zip(t.chunks_exact_mut(M))
    {
        let mut x = soc_v::<M, true>(w, arr::<M>(ub));
        for k in 0..M {
            x[k] += vb[k];
        }
        tb.copy_from_slice(&soc_v::<M, true>(w, x));
    }
}

/// t = V⁻²u = Θu on every non-zero block (zero blocks untouched).
pub(crate) fn theta(cones: &Cones, sc: &[f64], sc_off: &[usize], u: &[f64], t: &mut [f64]) {
    match cones.layout() {
        Layout::Soc3 => soc_theta::<3>(sc, u, t),
        Layout::Soc4 => soc_theta::<4>(sc, u, t),
        Layout::Orthant => {
            for ((o, w), a) in t.iter_mut().zip(sc).zip(u) {
                *o = a / w / w;
            }
        }
        Layout::Mixed => {
            for (bi, cone) in cones.blocks().iter().enumerate() {
                if cone.kind() == Kind::Zero {
                    continue;
                }
                let r = cones.range(bi);
                let scb = &sc[sc_off[bi]..sc_off[bi + 1]];
                let tb = &mut t[r.clone()];
                tb.copy_from_slice(&u[r]);
                apply_nt(cone.kind(), scb, tb, true);
                apply_nt(cone.kind(), scb, tb, true);
            }
        }
    }
}

fn soc_theta<const M: usize>(sc: &[f64], u: &[f64], t: &mut [f64]) {
    for ((w, ub), tb) in sc
        .chunks_exact(M + 1)
        .zip(u.chunks_exact(M))
        .zip(t.chunks_exact_mut(M))
    {
        let x = soc_v::<M, true>(w, arr::<M>(ub));
        tb.copy_from_slice(&soc_v::<M, true>(w, x));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cone::Cone;

    /// A deterministic interior point of Q^m (u_0 above |ū| by a margin).
    fn interior(seed: usize, m: usize) -> Vec<f64> {
        let mut v: Vec<f64> = (0..m)
            .map(|k| (((seed * 7 + k * 13) % 17) as f64 / 8.0) - 1.0)
            .collect();
        let r = v[1..].iter().map(|x| x * x).sum::<f64>().sqrt();
        v[0] = r + 0.1 + (seed % 3) as f64 * 0.3;
        v
    }

    /// The fixed-size passes do what the general path (block by block through `cone`) does, to
    /// the last bit or within rounding.
    #[test]
    fn the_uniform_passes_match_the_general_path() {
        for m in [3usize, 4] {
            let nb = 7;
            let blocks = vec![Cone::SecondOrder(m); nb];
            let cones = Cones::new(blocks).unwrap();
            let rows = cones.rows();
            let s: Vec<f64> = (0..nb).flat_map(|b| interior(b, m)).collect();
            let z: Vec<f64> = (0..nb).flat_map(|b| interior(b + 11, m)).collect();
            let ds: Vec<f64> = (0..rows)
                .map(|k| ((k * 5 % 11) as f64 - 5.0) / 3.0)
                .collect();
            let dz: Vec<f64> = (0..rows)
                .map(|k| ((k * 3 % 7) as f64 - 3.0) / 2.0)
                .collect();
            let sc_off: Vec<usize> = (0..=nb).map(|b| b * (m + 1)).collect();
            // General path: block by block.
            let (mut sc_g, mut lam_g) = (vec![0.0; nb * (m + 1)], vec![0.0; rows]);
            let mut scratch = Vec::new();
            let mut step_g = 10.0;
            let mut xi_g = vec![0.0; rows];
            let mut t_g = vec![0.0; rows];
            let mut th_g = vec![0.0; rows];
            for b in 0..nb {
                let r = cones.range(b);
                nt_scaling(
                    Kind::SecondOrder,
                    &s[r.clone()],
                    &z[r.clone()],
                    &mut scratch,
                );
                sc_g[b * (m + 1)..(b + 1) * (m + 1)].copy_from_slice(&scratch);
                let l = &mut lam_g[r.clone()];
                l.copy_from_slice(&z[r.clone()]);
                apply_nt(Kind::SecondOrder, &scratch, l, false);
                step_g = step_to_boundary(Kind::SecondOrder, &s[r.clone()], &ds[r.clone()], step_g);
                step_g = step_to_boundary(Kind::SecondOrder, &z[r.clone()], &dz[r.clone()], step_g);
                let mut ca = ds[r.clone()].to_vec();
                apply_nt(Kind::SecondOrder, &scratch, &mut ca, true);
                let mut cc = dz[r.clone()].to_vec();
                apply_nt(Kind::SecondOrder, &scratch, &mut cc, false);
                let mut t1 = vec![0.0; m];
                jordan_product(Kind::SecondOrder, &ca, &cc, &mut t1);
                let mut t2 = vec![0.0; m];
                let lb = lam_g[r.clone()].to_vec();
                jordan_product(Kind::SecondOrder, &lb, &lb, &mut t2);
                for k in 0..m {
                    t2[k] = -t2[k] - t1[k];
                }
                add_identity(Kind::SecondOrder, &mut t2, 0.3);
                jordan_divide(Kind::SecondOrder, &lb, &t2, &mut xi_g[r.clone()]);
                let mut u = ds[r.clone()].to_vec();
                apply_nt(Kind::SecondOrder, &scratch, &mut u, true);
                for (a, x) in u.iter_mut().zip(&dz[r.clone()]) {
                    *a += x;
                }
                apply_nt(Kind::SecondOrder, &scratch, &mut u, true);
                t_g[r.clone()].copy_from_slice(&u);
                let mut u = ds[r.clone()].to_vec();
                apply_nt(Kind::SecondOrder, &scratch, &mut u, true);
                apply_nt(Kind::SecondOrder, &scratch, &mut u, true);
                th_g[r].copy_from_slice(&u);
            }
            // The uniform passes.
            let (mut sc, mut lam) = (vec![0.0; nb * (m + 1)], vec![0.0; rows]);
            scalings(&cones, &s, &z, &mut sc, &sc_off, &mut lam, &mut scratch);
            let step = max_step(&cones, &s, &ds, &z, &dz, 10.0);
            let mut xi = vec![0.0; rows];
            let mut work: [Vec<f64>; 4] = Default::default();
            corrector(
                &cones, &sc, &sc_off, &lam, &ds, &dz, 0.3, &mut xi, &mut work,
            );
            let mut t = vec![0.0; rows];
            scaled_sum(&cones, &sc, &sc_off, &ds, &dz, &mut t);
            let mut th = vec![0.0; rows];
            theta(&cones, &sc, &sc_off, &ds, &mut th);
            let close = |a: &[f64], b: &[f64]| {
                a.iter()
                    .zip(b)
                    .all(|(x, y)| (x - y).abs() <= 1e-14 * (1.0 + x.abs().max(y.abs())))
            };
            assert!(close(&sc, &sc_g), "{sc:?}\n{sc_g:?}");
            assert!(close(&lam, &lam_g));
            assert!(
                (step - step_g).abs() <= 1e-14 * step_g,
                "{step} vs {step_g}"
            );
            assert!(close(&xi, &xi_g), "{xi:?}\n{xi_g:?}");
            assert!(close(&t, &t_g));
            assert!(close(&th, &th_g));
        }
    }

    /// The orthant's lanes of minima give the row-by-row chain's step bit for bit (falling,
    /// rising, zero and NaN rows; lengths around the lane count).
    #[test]
    fn the_orthant_step_is_the_chain_of_row_steps() {
        for len in [0usize, 1, 7, STEP_TILE, STEP_TILE + 5, 4 * STEP_TILE + 3] {
            // (An orthant has a row at least; with no rows the layout is the same.)
            let cones = Cones::new(vec![Cone::Nonnegative(len.max(1))]).unwrap();
            for seed in 0..20usize {
                let val = |k: usize, salt: usize| -> f64 {
                    let h = (k * 2654435761 + seed * 40503 + salt * 97) % 1000;
                    match h % 23 {
                        0 => 0.0,
                        1 => -0.0,
                        2 if seed == 3 => f64::NAN,
                        _ => h as f64 / 100.0 - 4.0,
                    }
                };
                let s: Vec<f64> = (0..len).map(|k| val(k, 1).abs()).collect();
                let z: Vec<f64> = (0..len).map(|k| val(k, 2).abs()).collect();
                let ds: Vec<f64> = (0..len).map(|k| val(k, 3)).collect();
                let dz: Vec<f64> = (0..len).map(|k| val(k, 4)).collect();
                for cap in [1.0f64, 0.01] {
                    let mut want = cap;
                    for (u, du) in [(&s, &ds), (&z, &dz)] {
                        for (x, dx) in u.iter().zip(du.iter()) {
                            if *dx < 0.0 {
                                want = want.min(-x / dx);
                            }
                        }
                    }
                    let got = max_step(&cones, &s, &ds, &z, &dz, cap);
                    assert_eq!(got.to_bits(), want.to_bits(), "{got} vs {want}");
                }
            }
        }
    }

    /// The tiled, branch-free step equals the chain of per-block steps bit for bit, on blocks
    /// inside, on and outside the cone, with directions that leave it at one root, two roots or
    /// none or a double one, linear quadratics (a = 0: du on the cone's boundary), zero and NaN entries, over
    /// more blocks than a tile.
    #[test]
    fn the_tiled_step_is_the_chain_of_block_steps() {
        let mut seed: u64 = 0x9E37_79B9_7F4A_7C15;
        let mut unif = move || {
            seed = seed
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        fn check<const M: usize>(u: &[f64], du: &[f64], v: &[f64], dv: &[f64], cap: f64) {
            let mut want = cap;
            for b in 0..u.len() / M {
                let r = b * M..(b + 1) * M;
                want = soc_step(&arr::<M>(&u[r.clone()]), &arr::<M>(&du[r.clone()]), want);
                want = soc_step(&arr::<M>(&v[r.clone()]), &arr::<M>(&dv[r]), want);
            }
            let got = soc_max_step::<M>(u, du, v, dv, cap);
            assert_eq!(got.to_bits(), want.to_bits(), "{got} vs {want}");
        }
        for m in [3usize, 4] {
            for nb in [1usize, 5, STEP_TILE, STEP_TILE + 3, 3 * STEP_TILE + 1] {
                for case in 0..40 {
                    let mut block = |kind: usize| -> (Vec<f64>, Vec<f64>) {
                        let mut u: Vec<f64> = (0..m).map(|_| unif()).collect();
                        let r = u[1..].iter().map(|x| x * x).sum::<f64>().sqrt();
                        u[0] = match kind % 4 {
                            0 => r + 0.1 + unif().abs(),
                            1 => r,
                            2 => r * 1.000_000_1,
                            _ => r + 1e-12,
                        };
                        let mut du: Vec<f64> = (0..m).map(|_| unif() * 3.0).collect();
                        match kind % 7 {
                            0 => {
                                // On the cone's boundary: a = J(du) = 0.
                                let rd = du[1..].iter().map(|x| x * x).sum::<f64>().sqrt();
                                du[0] = if kind.is_multiple_of(2) { rd } else { -rd };
                            }
                            1 => du.fill(0.0),
                            2 => du[0] = -du[0].abs() * 10.0,
                            3 => du.iter_mut().for_each(|x| *x *= 1e-9),
                            // Straight at the vertex from a point with integer |ū|:
                            // J(u − 2αu) = (1 − 2α)² J(u), a double root (disc = 0 exactly)
                            // at α = 1/2.
                            4 => {
                                u = if m == 3 {
                                    vec![6.0, 3.0, 4.0]
                                } else {
                                    vec![8.0, 2.0, 3.0, 6.0]
                                };
                                du = u.iter().map(|x| -2.0 * x).collect();
                            }
                            _ => {}
                        }
                        if case == 17 && kind.is_multiple_of(5) {
                            du[1] = f64::NAN;
                        }
                        (u, du)
                    };
                    let (mut u, mut du, mut v, mut dv) = (vec![], vec![], vec![], vec![]);
                    for b in 0..nb {
                        let (x, dx) = block(case * 31 + b);
                        u.extend(x);
                        du.extend(dx);
                        let (x, dx) = block(case * 17 + 3 * b + 1);
                        v.extend(x);
                        dv.extend(dx);
                    }
                    // Each block alone (the other cone's block inert), so that no other
                    // block's smaller step hides its own.
                    let mut inert = vec![0.0; m];
                    inert[0] = 1.0;
                    for b in 0..nb {
                        let r = b * m..(b + 1) * m;
                        let (x, dx) = (&u[r.clone()], &du[r]);
                        let zero = vec![0.0; m];
                        if m == 3 {
                            check::<3>(x, dx, &inert, &zero, 10.0);
                        } else {
                            check::<4>(x, dx, &inert, &zero, 10.0);
                        }
                    }
                    for cap in [1.0, 10.0, 1e-3] {
                        if m == 3 {
                            check::<3>(&u, &du, &v, &dv, cap);
                        } else {
                            check::<4>(&u, &du, &v, &dv, cap);
                        }
                    }
                }
            }
        }
    }
}
