//! The cone model and its Jordan algebra.
//!
//! The slack s of a conic program lies in a product K = K_1 × … × K_B of cones, one block of
//! consecutive rows each:
//!
//! - the **zero cone** {0}^m (equalities: s = 0, any dual);
//! - the **nonnegative orthant** R^m_+ (inequalities: s_i ≥ 0);
//! - the **second-order cone** Q^m = {(u_0, ū) ∈ R × R^{m−1} : |ū| ≤ u_0}, m ≥ 2 (balls,
//!   direction wedges — a wedge {v : v·a ≥ |v| cos θ} is Q^{d+1} in the rotated frame
//!   (v·a / cos θ, v), and norms).
//!
//! The orthant and Q^m are self-dual and symmetric; the zero cone's dual is all of R^m.
//!
//! # Jordan algebra (Vandenberghe 2010, §2; Nesterov & Todd 1997)
//!
//! On R^m_+ the product is componentwise, u ∘ v = (u_i v_i), with identity e = (1, …, 1). On Q^m,
//! u ∘ v = (uᵀv, u_0 v̄ + v_0 ū) with identity e = (1, 0, …, 0); J = diag(1, −1, …, −1) and
//! J(u) := uᵀJu = u_0² − |ū|² is positive exactly in the interior. The **degree** ν of the
//! product cone (the number of "coordinates" the barrier counts) is m for R^m_+, 1 for Q^m, 0
//! for {0}^m; the duality measure is μ = sᵀz / ν.
//!
//! # Nesterov–Todd scaling
//!
//! For s, z in the interior of a block there is a unique scaling V (symmetric, positive
//! definite, an automorphism of the cone) with **V z = V⁻¹ s = λ** (the scaled point). On
//! R^m_+, V = diag(√(s_i / z_i)). On Q^m, with s̄ = s / √J(s), z̄ = z / √J(z),
//! γ = √((1 + s̄ᵀz̄)/2) and w̄ = (s̄ + J z̄)/(2γ) (so J(w̄) = 1), V = η (2 w̄w̄ᵀ − J) with
//! η = (J(s)/J(z))^{1/4}; V is stored as (η, w̄) and applied in O(m) as
//! V u = η (w̄_0 u_0 + w̄̄ᵀū, ū + (u_0 + w̄̄ᵀū/(1 + w̄_0)) w̄̄) (Vandenberghe 2010, (23)–(25); the
//! inverse flips the signs of the off-diagonal terms and divides by η).

use crate::vector::{dot, norm};

/// One cone block of the slack: its kind and number of rows.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Cone {
    /// {0}^m: equality rows.
    Zero(usize),
    /// R^m_+: inequality rows.
    Nonnegative(usize),
    /// Q^m (m ≥ 2): the first row bounds the norm of the others.
    SecondOrder(usize),
}

impl Cone {
    /// The number of rows m.
    pub fn dim(self) -> usize {
        match self {
            Cone::Zero(m) | Cone::Nonnegative(m) | Cone::SecondOrder(m) => m,
        }
    }

    /// The kind (without the dimension).
    pub fn kind(self) -> Kind {
        match self {
            Cone::Zero(_) => Kind::Zero,
            Cone::Nonnegative(_) => Kind::Nonnegative,
            Cone::SecondOrder(_) => Kind::SecondOrder,
        }
    }

    /// The degree ν of the block (m, 1 or 0; module docs).
    pub fn degree(self) -> usize {
        match self {
            Cone::Zero(_) => 0,
            Cone::Nonnegative(m) => m,
            Cone::SecondOrder(_) => 1,
        }
    }
}

/// The kind of a cone block.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Kind {
    /// {0}^m.
    Zero,
    /// R^m_+.
    Nonnegative,
    /// Q^m.
    SecondOrder,
}

/// How the blocks of a product are laid out, for the method's passes over all of them
/// (`crate::product`): uniform layouts run one kernel over the whole slack, the others go block
/// by block.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub(crate) enum Layout {
    /// Every block is Q³ (a ball in the plane, a wedge in the plane).
    Soc3,
    /// Every block is Q⁴ (a ball in space).
    Soc4,
    /// Every block is an orthant: the product is one orthant, row by row (polytopes).
    Orthant,
    /// Anything else (zero cones, mixed kinds or sizes, no block at all).
    #[default]
    Mixed,
}

/// The blocks of a product cone, with the row offset of each.
#[derive(Clone, Debug, PartialEq, Eq, Default)]
pub struct Cones {
    blocks: Vec<Cone>,
    offsets: Vec<usize>,
    rows: usize,
    degree: usize,
    layout: Layout,
    equalities: bool,
}

impl Cones {
    /// The product of `blocks`, in row order.
    ///
    /// # Errors
    /// [`crate::Error::InvalidValue`] (`field` `"cones"`) for a block of dimension 0 or a
    /// second-order cone of dimension 1.
    pub fn new(blocks: Vec<Cone>) -> Result<Self, crate::Error> {
        let mut offsets = Vec::with_capacity(blocks.len());
        let (mut rows, mut degree) = (0, 0);
        for (i, &b) in blocks.iter().enumerate() {
            let invalid = |reason| crate::Error::InvalidValue {
                field: "cones",
                index: i,
                reason,
            };
            if b.dim() == 0 {
                return Err(invalid("a cone block has at least one row"));
            }
            if matches!(b, Cone::SecondOrder(1)) {
                return Err(invalid("a second-order cone has at least two rows"));
            }
            offsets.push(rows);
            rows += b.dim();
            degree += b.degree();
        }
        let blocks_have_zero = blocks.iter().any(|b| matches!(b, Cone::Zero(_)));
        let layout = if blocks.is_empty() {
            Layout::Mixed
        } else if blocks.iter().all(|b| *b == Cone::SecondOrder(3)) {
            Layout::Soc3
        } else if blocks.iter().all(|b| *b == Cone::SecondOrder(4)) {
            Layout::Soc4
        } else if blocks.iter().all(|b| b.kind() == Kind::Nonnegative) {
            Layout::Orthant
        } else {
            Layout::Mixed
        };
        Ok(Cones {
            blocks,
            offsets,
            rows,
            degree,
            layout,
            equalities: blocks_have_zero,
        })
    }

    /// m when every block is Q^m of a uniform layout (3 or 4), else `None`.
    #[inline]
    pub(crate) fn uniform_soc(&self) -> Option<usize> {
        match self.layout {
            Layout::Soc3 => Some(3),
            Layout::Soc4 => Some(4),
            _ => None,
        }
    }

    /// The layout of the blocks (see [`Layout`]).
    #[inline]
    pub(crate) fn layout(&self) -> Layout {
        self.layout
    }

    /// The blocks, in row order.
    pub fn blocks(&self) -> &[Cone] {
        &self.blocks
    }

    /// The number of blocks.
    pub fn len(&self) -> usize {
        self.blocks.len()
    }

    /// Whether there are no blocks (an unconstrained problem).
    pub fn is_empty(&self) -> bool {
        self.blocks.is_empty()
    }

    /// The rows of block `b`.
    #[inline]
    pub fn range(&self, b: usize) -> std::ops::Range<usize> {
        self.offsets[b]..self.offsets[b] + self.blocks[b].dim()
    }

    /// The total number of rows m.
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// The degree ν of the product (module docs).
    pub fn degree(&self) -> usize {
        self.degree
    }

    /// Whether any block is a zero cone.
    pub fn has_equalities(&self) -> bool {
        self.equalities
    }
}

/// J(u) = u_0² − |ū|² of a second-order block, formed as (u_0 − |ū|)(u_0 + |ū|) (no cancellation
/// of the squares near the boundary).
#[inline]
pub fn soc_residual(u: &[f64]) -> f64 {
    let r = norm(&u[1..]);
    (u[0] - r) * (u[0] + r)
}

/// u_0 − |ū| of a second-order block: how far u lies inside the cone along its axis (negative
/// outside).
#[inline]
pub(crate) fn soc_margin(u: &[f64]) -> f64 {
    u[0] - norm(&u[1..])
}

/// The Nesterov–Todd scaling of one block at (s, z), both interior (module docs), into `out`:
/// nothing for the zero cone, (√(s_i/z_i))_i for the orthant, (η, w̄_0, …, w̄_{m−1}) for Q^m.
#[inline]
pub fn nt_scaling(kind: Kind, s: &[f64], z: &[f64], out: &mut Vec<f64>) {
    out.clear();
    match kind {
        Kind::Zero => {}
        Kind::Nonnegative => out.extend(s.iter().zip(z).map(|(a, b)| (a / b).sqrt())),
        Kind::SecondOrder => {
            let js = soc_residual(s).max(f64::MIN_POSITIVE);
            let jz = soc_residual(z).max(f64::MIN_POSITIVE);
            let (rs, rz) = (js.sqrt(), jz.sqrt());
            // s̄ = s/√J(s), z̄ = z/√J(z), formed entry by entry (no allocation per block).
            let sbzb: f64 = s.iter().zip(z).map(|(a, b)| (a / rs) * (b / rz)).sum();
            let gamma = ((1.0 + sbzb) / 2.0).max(0.0).sqrt();
            let eta = (js / jz).sqrt().sqrt();
            out.push(eta);
            out.push((s[0] / rs + z[0] / rz) / (2.0 * gamma));
            for k in 1..s.len() {
                out.push((s[k] / rs - z[k] / rz) / (2.0 * gamma));
            }
        }
    }
}

/// u ← V u (`inverse` false) or u ← V⁻¹ u (`inverse` true) for the NT scaling `sc` of
/// [`nt_scaling`]; the identity on a zero block.
#[inline]
pub fn apply_nt(kind: Kind, sc: &[f64], u: &mut [f64], inverse: bool) {
    match kind {
        Kind::Zero => {}
        Kind::Nonnegative => {
            for (x, v) in u.iter_mut().zip(sc) {
                if inverse {
                    *x /= v;
                } else {
                    *x *= v;
                }
            }
        }
        Kind::SecondOrder => {
            let eta = sc[0];
            let w0 = sc[1];
            let w1 = &sc[2..];
            let sg = if inverse { -1.0 } else { 1.0 };
            let u0 = u[0];
            let wu = dot(w1, &u[1..]);
            let new0 = w0 * u0 + sg * wu;
            let coef = sg * u0 + wu / (1.0 + w0);
            for (x, w) in u[1..].iter_mut().zip(w1) {
                *x += coef * w;
            }
            u[0] = new0;
            let f = if inverse { 1.0 / eta } else { eta };
            for x in u.iter_mut() {
                *x *= f;
            }
        }
    }
}

/// The Jordan product u ∘ v (module docs) into `out` (zero on a zero block).
#[inline]
pub fn jordan_product(kind: Kind, u: &[f64], v: &[f64], out: &mut [f64]) {
    match kind {
        Kind::Zero => out.fill(0.0),
        Kind::Nonnegative => {
            for ((o, a), b) in out.iter_mut().zip(u).zip(v) {
                *o = a * b;
            }
        }
        Kind::SecondOrder => {
            out[0] = dot(u, v);
            for k in 1..u.len() {
                out[k] = u[0] * v[k] + v[0] * u[k];
            }
        }
    }
}

/// x with λ ∘ x = r, for λ in the interior (zero on a zero block): componentwise division on
/// the orthant; on Q^m, x_0 = (λ_0 r_0 − λ̄ᵀr̄)/J(λ) and x̄ = (r̄ − x_0 λ̄)/λ_0.
#[inline]
pub fn jordan_divide(kind: Kind, lambda: &[f64], r: &[f64], out: &mut [f64]) {
    match kind {
        Kind::Zero => out.fill(0.0),
        Kind::Nonnegative => {
            for ((o, a), b) in out.iter_mut().zip(lambda).zip(r) {
                *o = b / a;
            }
        }
        Kind::SecondOrder => {
            let jl = soc_residual(lambda);
            let x0 = (lambda[0] * r[0] - dot(&lambda[1..], &r[1..])) / jl;
            out[0] = x0;
            for k in 1..lambda.len() {
                out[k] = (r[k] - x0 * lambda[k]) / lambda[0];
            }
        }
    }
}

/// The largest α in [0, `cap`] with u + α du in the (closed) cone, for u in the interior;
/// `cap` on a zero block.
#[inline]
pub fn step_to_boundary(kind: Kind, u: &[f64], du: &[f64], cap: f64) -> f64 {
    match kind {
        Kind::Zero => cap,
        Kind::Nonnegative => u
            .iter()
            .zip(du)
            .fold(cap, |a, (x, dx)| if *dx < 0.0 { a.min(-x / dx) } else { a }),
        Kind::SecondOrder => {
            // J(u + α du) = a α² + b α + c with c = J(u) > 0: the first positive root.
            let a = soc_residual(du);
            let b = 2.0 * (u[0] * du[0] - dot(&u[1..], &du[1..]));
            let c = soc_residual(u);
            soc_step_from(a, b, c, u[0], du[0], cap)
        }
    }
}

/// The largest α in [0, `cap`] with J(u + α du) = a α² + b α + c ≥ 0 (c = J(u) > 0: the first
/// positive root) and u₀ + α du₀ ≥ 0 (the same nappe): the second-order case of
/// [`step_to_boundary`]. (`product`'s kernel for Q³ and Q⁴ computes the same candidates for many
/// blocks at once without branches, and is tested against this.)
#[inline(always)]
pub(crate) fn soc_step_from(a: f64, b: f64, c: f64, u0: f64, du0: f64, cap: f64) -> f64 {
    let mut best = cap;
    let disc = b * b - 4.0 * a * c;
    if a.abs() <= f64::EPSILON * (b.abs() + c.abs()) {
        if b < 0.0 {
            best = best.min(-c / b);
        }
    } else if disc >= 0.0 {
        let q = -0.5 * (b + b.signum() * disc.sqrt());
        for r in [q / a, if q != 0.0 { c / q } else { f64::INFINITY }] {
            if r > 0.0 {
                best = best.min(r);
            }
        }
    }
    if du0 < 0.0 {
        best = best.min(-u0 / du0);
    }
    best.max(0.0)
}

/// The Euclidean projection onto the cone of the block's *dual*: the orthant and Q^m are
/// self-dual; the zero cone's dual is R^m (no change).
#[inline]
pub fn project_dual(kind: Kind, u: &mut [f64]) {
    match kind {
        Kind::Zero => {}
        Kind::Nonnegative => {
            for x in u.iter_mut() {
                *x = x.max(0.0);
            }
        }
        Kind::SecondOrder => {
            let r = norm(&u[1..]);
            if r <= u[0] {
                return;
            }
            if r <= -u[0] {
                u.fill(0.0);
                return;
            }
            let t = 0.5 * (u[0] + r);
            u[0] = t;
            for x in u[1..].iter_mut() {
                *x *= t / r;
            }
        }
    }
}

/// The Euclidean distance of u to the (primal) cone: 0 inside; the norm of the negative part
/// on the orthant; on Q^m the distance to the projection; |u| on a zero block.
pub fn distance_to_cone(kind: Kind, u: &[f64]) -> f64 {
    match kind {
        Kind::Zero => norm(u),
        Kind::Nonnegative => u
            .iter()
            .map(|x| x.min(0.0) * x.min(0.0))
            .sum::<f64>()
            .sqrt(),
        Kind::SecondOrder => {
            let r = norm(&u[1..]);
            if r <= u[0] {
                0.0
            } else if r <= -u[0] {
                norm(u)
            } else {
                // Projection t(1, ū/r) with t = (u_0 + r)/2: distance (r − u_0)/√2.
                (r - u[0]) / std::f64::consts::SQRT_2
            }
        }
    }
}

/// Adds α e (the block's identity) to u: 1 on every orthant row, 1 on the first row of Q^m.
#[inline]
pub fn add_identity(kind: Kind, u: &mut [f64], alpha: f64) {
    match kind {
        Kind::Zero => {}
        Kind::Nonnegative => u.iter_mut().for_each(|x| *x += alpha),
        Kind::SecondOrder => u[0] += alpha,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nt_scaling_maps_s_and_z_to_the_same_point() {
        let s = [2.0, 0.5, -0.7, 0.3];
        let z = [1.5, -0.2, 0.4, 0.9];
        let mut sc = Vec::new();
        nt_scaling(Kind::SecondOrder, &s, &z, &mut sc);
        let mut vz = z.to_vec();
        apply_nt(Kind::SecondOrder, &sc, &mut vz, false);
        let mut vis = s.to_vec();
        apply_nt(Kind::SecondOrder, &sc, &mut vis, true);
        for k in 0..4 {
            assert!((vz[k] - vis[k]).abs() < 1e-12, "{vz:?} vs {vis:?}");
        }
        let mut u = vec![0.3, -1.0, 2.0, 0.5];
        apply_nt(Kind::SecondOrder, &sc, &mut u, false);
        apply_nt(Kind::SecondOrder, &sc, &mut u, true);
        for (a, b) in u.iter().zip([0.3, -1.0, 2.0, 0.5]) {
            assert!((a - b).abs() < 1e-12);
        }
        // The orthant: V = diag(√(s/z)).
        let (s, z) = ([4.0, 0.25], [1.0, 4.0]);
        nt_scaling(Kind::Nonnegative, &s, &z, &mut sc);
        let mut vz = z.to_vec();
        apply_nt(Kind::Nonnegative, &sc, &mut vz, false);
        assert_eq!(vz, vec![2.0, 1.0]);
    }

    #[test]
    fn jordan_division_inverts_the_product() {
        let lam = [2.0, 0.5, -0.7];
        let r = [0.4, 1.0, -2.0];
        let mut x = [0.0; 3];
        jordan_divide(Kind::SecondOrder, &lam, &r, &mut x);
        let mut back = [0.0; 3];
        jordan_product(Kind::SecondOrder, &lam, &x, &mut back);
        for k in 0..3 {
            assert!((back[k] - r[k]).abs() < 1e-12);
        }
    }

    #[test]
    fn the_step_reaches_the_boundary() {
        let u = [2.0, 0.5, 0.0];
        let du = [-1.0, 1.0, 0.5];
        let a = step_to_boundary(Kind::SecondOrder, &u, &du, 10.0);
        let v: Vec<f64> = u.iter().zip(&du).map(|(x, y)| x + a * y).collect();
        assert!(soc_residual(&v).abs() < 1e-10 && v[0] > 0.0, "{a} {v:?}");
        let a = step_to_boundary(Kind::Nonnegative, &[1.0, 2.0], &[-0.5, -4.0], 9.0);
        assert!((a - 0.5).abs() < 1e-15);
    }

    #[test]
    fn projection_and_distance_agree() {
        let mut u = [0.5, 3.0, 4.0];
        let d = distance_to_cone(Kind::SecondOrder, &u);
        let orig = u;
        project_dual(Kind::SecondOrder, &mut u);
        let moved = norm(&[orig[0] - u[0], orig[1] - u[1], orig[2] - u[2]]);
        assert!((moved - d).abs() < 1e-12, "{moved} vs {d}");
        assert!(soc_residual(&u).abs() < 1e-12);
    }

    #[test]
    fn cones_lay_out_their_rows() {
        let c = Cones::new(vec![
            Cone::Zero(2),
            Cone::SecondOrder(3),
            Cone::Nonnegative(4),
        ])
        .unwrap();
        assert_eq!((c.rows(), c.degree()), (9, 5));
        assert_eq!(c.range(1), 2..5);
        assert!(Cones::new(vec![Cone::SecondOrder(1)]).is_err());
        assert!(Cones::new(vec![Cone::Nonnegative(0)]).is_err());
    }
}
