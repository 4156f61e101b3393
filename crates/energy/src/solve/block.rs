//! Block Cholesky K = L Lᵀ on the block envelope (d×d blocks, lower triangular diagonal blocks).

use super::{Envelope, Parts};
use crate::Error;
use divdiff::Topology;

#[derive(Clone, Debug)]
pub(crate) struct BlockFactor {
    n: usize,
    dim: usize,
    env: Envelope,
    /// The factor L in envelope storage (d² per block, row-major).
    l: Vec<f64>,
    /// Couplings between a free and a fixed vertex: (free, fixed, block index into `fc`).
    fixed_couplings: Vec<(usize, usize)>,
    fc: Vec<f64>,
}

impl BlockFactor {
    pub(crate) fn new(s: &Parts<'_>) -> Result<Self, Error> {
        let (n, d) = (s.n, s.dim);
        let dd = d * d;
        let env = Envelope::new(s.topology, n);
        let mut a = match s.blocks {
            Some(b) => b.to_vec(),
            None => vec![0.0; env.total() * dd],
        };
        // Scalar part ⊗ I_d (aliasing entries add up).
        let mut add_scalar = |i: usize, j: usize, v: f64| {
            let (i, j) = if i >= j { (i, j) } else { (j, i) };
            let base = env.index(i, j) * dd;
            for c in 0..d {
                a[base + c * d + c] += v;
            }
        };
        for j in 0..n {
            add_scalar(j, j, s.diag[j]);
            for (band, step) in [(s.off1, 1), (s.off2, 2)] {
                if s.topology == Topology::Open && j + step >= n {
                    continue;
                }
                add_scalar(j, (j + step) % n, band[j]);
            }
        }
        // Eliminate fixed vertices.
        let mut fixed_couplings = Vec::new();
        let mut fc = Vec::new();
        for i in 0..n {
            for j in env.first(i)..=i {
                let base = env.index(i, j) * dd;
                let blk = &mut a[base..base + dd];
                match (s.fixed[i], s.fixed[j]) {
                    (false, false) => {}
                    (true, true) if i == j => {
                        blk.fill(0.0);
                        for c in 0..d {
                            blk[c * d + c] = 1.0;
                        }
                    }
                    (true, true) => blk.fill(0.0),
                    (false, true) => {
                        fixed_couplings.push((i, j));
                        fc.extend_from_slice(blk);
                        blk.fill(0.0);
                    }
                    (true, false) => {
                        // K_ji = K_ijᵀ: rows of the free vertex j.
                        fixed_couplings.push((j, i));
                        for r in 0..d {
                            for c in 0..d {
                                fc.push(blk[c * d + r]);
                            }
                        }
                        blk.fill(0.0);
                    }
                }
            }
        }
        let diag_ref: Vec<f64> = (0..n)
            .flat_map(|i| {
                let base = env.index(i, i) * dd;
                let a = &a;
                (0..d).map(move |c| a[base + c * d + c])
            })
            .collect();
        match d {
            1 => cholesky::<1>(&env, &mut a, &diag_ref, 1, s.rtol)?,
            2 => cholesky::<2>(&env, &mut a, &diag_ref, 2, s.rtol)?,
            3 => cholesky::<3>(&env, &mut a, &diag_ref, 3, s.rtol)?,
            4 => cholesky::<4>(&env, &mut a, &diag_ref, 4, s.rtol)?,
            _ => cholesky::<0>(&env, &mut a, &diag_ref, d, s.rtol)?,
        }
        Ok(BlockFactor {
            n,
            dim: d,
            env,
            l: a,
            fixed_couplings,
            fc,
        })
    }

    pub(crate) fn solve(&self, x: &mut [f64]) {
        let d = self.dim;
        let dd = d * d;
        for (k, &(i, j)) in self.fixed_couplings.iter().enumerate() {
            let b = &self.fc[k * dd..(k + 1) * dd];
            for r in 0..d {
                let mut s = 0.0;
                for c in 0..d {
                    s += b[r * d + c] * x[j * d + c];
                }
                x[i * d + r] -= s;
            }
        }
        match d {
            1 => self.solve_d::<1>(x, 1),
            2 => self.solve_d::<2>(x, 2),
            3 => self.solve_d::<3>(x, 3),
            4 => self.solve_d::<4>(x, 4),
            _ => self.solve_d::<0>(x, d),
        }
    }

    #[inline(always)]
    fn solve_d<const D: usize>(&self, x: &mut [f64], dyn_d: usize) {
        let d = if D == 0 { dyn_d } else { D };
        let dd = d * d;
        let (n, env, l) = (self.n, &self.env, &self.l);
        // Forward: L z = b.
        for i in 0..n {
            for j in env.first(i)..i {
                let b = &l[env.index(i, j) * dd..][..dd];
                for r in 0..d {
                    let mut s = 0.0;
                    for c in 0..d {
                        s += b[r * d + c] * x[j * d + c];
                    }
                    x[i * d + r] -= s;
                }
            }
            let b = &l[env.index(i, i) * dd..][..dd];
            for r in 0..d {
                let mut s = x[i * d + r];
                for c in 0..r {
                    s -= b[r * d + c] * x[i * d + c];
                }
                x[i * d + r] = s / b[r * d + r];
            }
        }
        // Backward: Lᵀ x = z.
        for i in (0..n).rev() {
            let b = &l[env.index(i, i) * dd..][..dd];
            for r in (0..d).rev() {
                let mut s = x[i * d + r];
                for c in r + 1..d {
                    s -= b[c * d + r] * x[i * d + c];
                }
                x[i * d + r] = s / b[r * d + r];
            }
            for j in env.first(i)..i {
                let b = &l[env.index(i, j) * dd..][..dd];
                for c in 0..d {
                    let mut s = 0.0;
                    for r in 0..d {
                        s += b[r * d + c] * x[i * d + r];
                    }
                    x[j * d + c] -= s;
                }
            }
        }
    }
}

/// In-place block Cholesky on the envelope. `diag_ref` holds the diagonal of K (N·d entries) for
/// the relative pivot test.
#[inline(always)]
fn cholesky<const D: usize>(
    env: &Envelope,
    a: &mut [f64],
    diag_ref: &[f64],
    dyn_d: usize,
    rtol: f64,
) -> Result<(), Error> {
    let d = if D == 0 { dyn_d } else { D };
    let dd = d * d;
    let n = diag_ref.len() / d;
    let mut s = vec![0.0; dd];
    for i in 0..n {
        for j in env.first(i)..=i {
            let ij = env.index(i, j) * dd;
            s.copy_from_slice(&a[ij..ij + dd]);
            let k0 = env.first(i).max(env.first(j));
            for k in k0..j {
                let ik = env.index(i, k) * dd;
                let jk = env.index(j, k) * dd;
                // S −= L_ik L_jkᵀ
                for r in 0..d {
                    for c in 0..d {
                        let mut t = 0.0;
                        for q in 0..d {
                            t += a[ik + r * d + q] * a[jk + c * d + q];
                        }
                        s[r * d + c] -= t;
                    }
                }
            }
            if j < i {
                // L_ij = S L_jj^{-T}: each row x of L_ij solves L_jj xᵀ = (row of S)ᵀ.
                let jj = env.index(j, j) * dd;
                for r in 0..d {
                    for c in 0..d {
                        let mut t = s[r * d + c];
                        for q in 0..c {
                            t -= s[r * d + q] * a[jj + c * d + q];
                        }
                        s[r * d + c] = t / a[jj + c * d + c];
                    }
                }
                a[ij..ij + dd].copy_from_slice(&s);
            } else {
                // Dense Cholesky of the d×d block S (lower).
                for c in 0..d {
                    let mut p = s[c * d + c];
                    for q in 0..c {
                        p -= s[c * d + q] * s[c * d + q];
                    }
                    let kref = diag_ref[i * d + c];
                    if !(p.is_finite() && p > rtol * kref) {
                        return Err(Error::Singular { vertex: i });
                    }
                    let lcc = p.sqrt();
                    s[c * d + c] = lcc;
                    for r in c + 1..d {
                        let mut t = s[r * d + c];
                        for q in 0..c {
                            t -= s[r * d + q] * s[c * d + q];
                        }
                        s[r * d + c] = t / lcc;
                    }
                    for r in 0..c {
                        s[r * d + c] = 0.0;
                    }
                }
                a[ij..ij + dd].copy_from_slice(&s);
            }
        }
    }
    Ok(())
}
