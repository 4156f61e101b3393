//! Θ, the block-diagonal weight of the Newton matrix P + AᵀΘA that a [`crate::KktSystem`]
//! factors.
//!
//! In the interior-point iterations Θ_b = V_b⁻² for every cone block (V_b its Nesterov–Todd
//! scaling, [`crate::cone`]) and Θ_b = I/δ_b for a zero block (δ_b the regularization of the
//! equality rows, removed again by iterative refinement). At the start Θ = ω I. In the
//! active-set polish Θ_b carries the curvature of an active second-order constraint and the
//! stiff penalty on its normal, c(−J) + p u uᵀ, or the penalties of a block's active rows, a
//! diagonal ([`crate::polish`]). A backend may read the structure (e.g. invert V⁻² or the
//! polish's weight per eigenspace, as the condensed backend of `refine` does) or just apply
//! Θ_b through [`Weights::apply`].

use crate::cone::{apply_nt, Cones, Kind};

/// The weight of one block, as a backend sees it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum BlockWeight<'a> {
    /// Θ_b = V_b⁻² with the NT scaling of [`crate::cone::nt_scaling`] (`kind` orthant or
    /// second-order).
    Nt {
        /// The cone kind.
        kind: Kind,
        /// The scaling data: (√(s_i/z_i))_i or (η, w̄).
        scaling: &'a [f64],
    },
    /// Θ_b = c I (c ≥ 0; 0 for a block the polish treats as inactive).
    Scalar(f64),
    /// Θ_b = c (−J) + p u uᵀ on a second-order block, −J = diag(−1, 1, …, 1): the polish's
    /// weight of an active second-order constraint (c = y/|Js| its curvature, u its unit normal,
    /// p = 1/δ the stiff penalty on it).
    Active {
        /// c.
        curvature: f64,
        /// u (m entries).
        normal: &'a [f64],
        /// p.
        penalty: f64,
    },
    /// Θ_b = diag(θ) (m entries): the polish's penalties on a block's active rows (0 on the
    /// others).
    Diagonal(&'a [f64]),
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Tag {
    Nt(Kind),
    Scalar(f64),
    Active,
    Diagonal,
}

/// Θ = diag(Θ_1, …, Θ_B) over the blocks of a [`Cones`].
#[derive(Clone, Debug, PartialEq)]
pub struct Weights {
    tags: Vec<Tag>,
    /// Start of block b's data in `data` (NT scaling: m + 1 entries for Q^m, m for the orthant;
    /// the polish: (c, p, u) or θ).
    start: Vec<usize>,
    data: Vec<f64>,
    dims: Vec<usize>,
}

impl Weights {
    /// Θ = 0 on every block of `cones`.
    pub fn zero(cones: &Cones) -> Self {
        Self::uniform(cones, 0.0)
    }

    /// Θ = c I on every block.
    pub fn uniform(cones: &Cones, c: f64) -> Self {
        let nb = cones.len();
        Weights {
            tags: vec![Tag::Scalar(c); nb],
            start: vec![0; nb],
            data: Vec::new(),
            dims: cones.blocks().iter().map(|b| b.dim()).collect(),
        }
    }

    /// Θ_b = V_b⁻² on every non-zero block of `cones` with its scaling data laid out once
    /// (block b from the returned offset b: m + 1 entries for Q^m, m for an orthant, none for a
    /// zero block, which is Θ_b = 0 until [`Weights::set_scalar`]), for the method to write the
    /// scalings of each iteration in place ([`Weights::nt_data_mut`]).
    pub(crate) fn nt_layout(cones: &Cones) -> (Self, Vec<usize>) {
        let mut off = vec![0];
        let mut tags = Vec::with_capacity(cones.len());
        for b in cones.blocks() {
            let len = match b {
                crate::Cone::Zero(_) => 0,
                crate::Cone::Nonnegative(m) => *m,
                crate::Cone::SecondOrder(m) => m + 1,
            };
            tags.push(match b.kind() {
                Kind::Zero => Tag::Scalar(0.0),
                kind => Tag::Nt(kind),
            });
            off.push(off.last().copied().unwrap_or(0) + len);
        }
        let total = off.last().copied().unwrap_or(0);
        let w = Weights {
            tags,
            start: off[..cones.len()].to_vec(),
            data: vec![0.0; total],
            dims: cones.blocks().iter().map(|b| b.dim()).collect(),
        };
        (w, off)
    }

    /// The scaling data of a [`Weights::nt_layout`], to write in place.
    pub(crate) fn nt_data_mut(&mut self) -> &mut [f64] {
        &mut self.data
    }

    /// The scaling data of a [`Weights::nt_layout`].
    pub(crate) fn nt_data(&self) -> &[f64] {
        &self.data
    }

    /// The number of blocks.
    pub fn len(&self) -> usize {
        self.tags.len()
    }

    /// Whether there are no blocks.
    pub fn is_empty(&self) -> bool {
        self.tags.is_empty()
    }

    /// Removes every block's data, keeping the layout (each block becomes Θ_b = 0).
    pub(crate) fn clear(&mut self) {
        self.data.clear();
        self.tags.fill(Tag::Scalar(0.0));
    }

    /// Sets Θ_b = c I.
    pub(crate) fn set_scalar(&mut self, b: usize, c: f64) {
        self.tags[b] = Tag::Scalar(c);
    }

    /// Sets Θ_b = V⁻² for the NT scaling `scaling` of a block of kind `kind`.
    pub fn set_nt(&mut self, b: usize, kind: Kind, scaling: &[f64]) {
        self.start[b] = self.data.len();
        self.data.extend_from_slice(scaling);
        self.tags[b] = Tag::Nt(kind);
    }

    /// Sets Θ_b = c (−J) + p u uᵀ ([`BlockWeight::Active`]).
    pub fn set_active(&mut self, b: usize, curvature: f64, penalty: f64, normal: &[f64]) {
        debug_assert_eq!(normal.len(), self.dims[b]);
        self.start[b] = self.data.len();
        self.data.push(curvature);
        self.data.push(penalty);
        self.data.extend_from_slice(normal);
        self.tags[b] = Tag::Active;
    }

    /// Sets Θ_b = diag(θ) ([`BlockWeight::Diagonal`]).
    pub fn set_diagonal(&mut self, b: usize, theta: &[f64]) {
        debug_assert_eq!(theta.len(), self.dims[b]);
        self.start[b] = self.data.len();
        self.data.extend_from_slice(theta);
        self.tags[b] = Tag::Diagonal;
    }

    /// Block b's weight.
    #[inline]
    pub fn block(&self, b: usize) -> BlockWeight<'_> {
        let m = self.dims[b];
        match self.tags[b] {
            Tag::Scalar(c) => BlockWeight::Scalar(c),
            Tag::Nt(kind) => {
                let len = if kind == Kind::SecondOrder { m + 1 } else { m };
                BlockWeight::Nt {
                    kind,
                    scaling: &self.data[self.start[b]..self.start[b] + len],
                }
            }
            Tag::Active => {
                let d = &self.data[self.start[b]..self.start[b] + 2 + m];
                BlockWeight::Active {
                    curvature: d[0],
                    penalty: d[1],
                    normal: &d[2..],
                }
            }
            Tag::Diagonal => BlockWeight::Diagonal(&self.data[self.start[b]..self.start[b] + m]),
        }
    }

    /// u ← Θ_b u.
    #[inline]
    pub fn apply(&self, b: usize, u: &mut [f64]) {
        match self.block(b) {
            BlockWeight::Scalar(c) => u.iter_mut().for_each(|x| *x *= c),
            BlockWeight::Nt { kind, scaling } => {
                apply_nt(kind, scaling, u, true);
                apply_nt(kind, scaling, u, true);
            }
            BlockWeight::Active {
                curvature,
                normal,
                penalty,
            } => {
                let un: f64 = normal.iter().zip(u.iter()).map(|(a, b)| a * b).sum();
                for (k, (x, nk)) in u.iter_mut().zip(normal).enumerate() {
                    let j = if k == 0 { -curvature } else { curvature };
                    *x = j * *x + penalty * un * nk;
                }
            }
            BlockWeight::Diagonal(theta) => {
                for (x, t) in u.iter_mut().zip(theta) {
                    *x *= t;
                }
            }
        }
    }

    /// Θ_b as a dense m × m matrix into `out` (row-major).
    pub fn dense(&self, b: usize, out: &mut [f64]) {
        let m = self.dims[b];
        let mut col = vec![0.0; m];
        for c in 0..m {
            col.fill(0.0);
            col[c] = 1.0;
            self.apply(b, &mut col);
            for r in 0..m {
                out[r * m + c] = col[r];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cone::{nt_scaling, Cone};

    /// V⁻² applied through the scaling equals the dense block, and V⁻² z = V⁻¹λ = ... s:
    /// W² maps z to s, so Θ s = z (the NT identity V⁻² s = z).
    #[test]
    fn the_nt_weight_maps_s_to_z() {
        let cones = Cones::new(vec![Cone::SecondOrder(3), Cone::Nonnegative(2)]).unwrap();
        let (s, z) = ([2.0, 0.5, -0.7], [1.5, -0.2, 0.4]);
        let mut w = Weights::zero(&cones);
        let mut sc = Vec::new();
        nt_scaling(Kind::SecondOrder, &s, &z, &mut sc);
        w.set_nt(0, Kind::SecondOrder, &sc);
        let mut u = s.to_vec();
        w.apply(0, &mut u);
        for k in 0..3 {
            assert!((u[k] - z[k]).abs() < 1e-12, "{u:?} vs {z:?}");
        }
        let mut d = vec![0.0; 9];
        w.dense(0, &mut d);
        for r in 0..3 {
            for c in 0..3 {
                assert!((d[r * 3 + c] - d[c * 3 + r]).abs() < 1e-12, "symmetric");
            }
        }
        w.set_scalar(1, 3.0);
        let mut v = vec![1.0, 2.0];
        w.apply(1, &mut v);
        assert_eq!(v, vec![3.0, 6.0]);
    }
}
