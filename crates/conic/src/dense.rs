//! A dense backend: P and A stored in full, the Newton matrix factored by Cholesky. For small
//! problems, the tests of the method, and as the simplest example of the seam.

// Dense kernels index rows and columns by the same loop variables.
#![allow(clippy::needless_range_loop)]

use crate::cone::Cones;
use crate::kkt::{KktSystem, Scales};
use crate::weights::Weights;
use crate::Error;

/// minimize ½xᵀPx + qᵀx s.t. b − Ax ∈ K with P (n × n) and A (m × n) dense, row-major.
#[derive(Clone, Debug, PartialEq)]
pub struct DenseProblem {
    n: usize,
    p: Vec<f64>,
    q: Vec<f64>,
    a: Vec<f64>,
    b: Vec<f64>,
    cones: Cones,
    scales: Scales,
    /// Cholesky factor (lower, row-major) of the last `factor`.
    l: Vec<f64>,
}

impl DenseProblem {
    /// The problem with P (n × n, symmetric positive semidefinite), q (n), A (m × n), b (m) and
    /// the cones of the m rows.
    ///
    /// # Errors
    /// [`Error::WrongLength`] for inconsistent sizes, [`Error::NonFinite`] for a NaN or
    /// infinite entry, [`Error::InvalidValue`] for an asymmetric P.
    pub fn new(
        p: Vec<f64>,
        q: Vec<f64>,
        a: Vec<f64>,
        b: Vec<f64>,
        cones: Cones,
    ) -> Result<Self, Error> {
        let n = q.len();
        let m = cones.rows();
        for (field, v, expected) in [("p", &p, n * n), ("a", &a, m * n), ("b", &b, m)] {
            if v.len() != expected {
                return Err(Error::WrongLength {
                    field,
                    expected,
                    got: v.len(),
                });
            }
        }
        for (field, v) in [("p", &p), ("q", &q), ("a", &a), ("b", &b)] {
            if let Some(i) = v.iter().position(|x| !x.is_finite()) {
                return Err(Error::NonFinite { field, index: i });
            }
        }
        for i in 0..n {
            for j in 0..i {
                let (x, y) = (p[i * n + j], p[j * n + i]);
                if (x - y).abs() > 1e-12 * (x.abs() + y.abs()) {
                    return Err(Error::InvalidValue {
                        field: "p",
                        index: i * n + j,
                        reason: "P must be symmetric",
                    });
                }
            }
        }
        Ok(DenseProblem {
            n,
            p,
            q,
            a,
            b,
            cones,
            scales: Scales::default(),
            l: Vec::new(),
        })
    }

    /// Sets the fixed scales of [`Scales`].
    pub fn with_scales(mut self, scales: Scales) -> Self {
        self.scales = scales;
        self
    }
}

impl KktSystem for DenseProblem {
    fn num_vars(&self) -> usize {
        self.n
    }

    fn cones(&self) -> &Cones {
        &self.cones
    }

    fn b(&self) -> &[f64] {
        &self.b
    }

    fn gradient(&mut self, x: &[f64], g: &mut [f64]) -> f64 {
        let n = self.n;
        let mut f = 0.0;
        for i in 0..n {
            let px: f64 = (0..n).map(|j| self.p[i * n + j] * x[j]).sum();
            g[i] = px + self.q[i];
            f += x[i] * (0.5 * px + self.q[i]);
        }
        f
    }

    fn apply_p(&mut self, v: &[f64], y: &mut [f64]) {
        let n = self.n;
        for i in 0..n {
            y[i] = (0..n).map(|j| self.p[i * n + j] * v[j]).sum();
        }
    }

    fn apply_a(&self, x: &[f64], y: &mut [f64]) {
        let n = self.n;
        for (r, yr) in y.iter_mut().enumerate() {
            *yr = (0..n).map(|j| self.a[r * n + j] * x[j]).sum();
        }
    }

    fn apply_at(&self, z: &[f64], out: &mut [f64]) {
        let n = self.n;
        out.fill(0.0);
        for (r, zr) in z.iter().enumerate() {
            for j in 0..n {
                out[j] += self.a[r * n + j] * zr;
            }
        }
    }

    fn diagonal_scale(&self, block: usize) -> f64 {
        let n = self.n;
        let rows = self.cones.range(block);
        let (mut pd, mut an): (f64, f64) = (0.0, 0.0);
        for r in rows {
            for j in 0..n {
                let a = self.a[r * n + j];
                if a != 0.0 {
                    pd = pd.max(self.p[j * n + j]);
                    an = an.max(a.abs());
                }
            }
        }
        if an > 0.0 && pd > 0.0 {
            pd / (an * an)
        } else {
            1.0
        }
    }

    fn scales(&self) -> Scales {
        self.scales
    }

    fn factor(&mut self, weights: &Weights, sigma: f64) -> Result<(), Error> {
        let n = self.n;
        let mut k = self.p.clone();
        let mut col = vec![0.0; 0];
        for bi in 0..self.cones.len() {
            let r = self.cones.range(bi);
            // AᵀΘA over this block: for each variable j, Θ A_{·j}.
            for j in 0..n {
                col.clear();
                col.extend(r.clone().map(|row| self.a[row * n + j]));
                if col.iter().all(|&v| v == 0.0) {
                    continue;
                }
                weights.apply(bi, &mut col);
                for i in 0..n {
                    let mut acc = 0.0;
                    for (t, row) in r.clone().enumerate() {
                        acc += self.a[row * n + i] * col[t];
                    }
                    k[i * n + j] += acc;
                }
            }
        }
        if sigma > 0.0 {
            for i in 0..n {
                k[i * n + i] += sigma * self.p[i * n + i].abs().max(f64::MIN_POSITIVE);
            }
        }
        // Cholesky, lower.
        for j in 0..n {
            let mut d = k[j * n + j];
            for t in 0..j {
                d -= k[j * n + t] * k[j * n + t];
            }
            if !(d > 0.0 && d.is_finite()) {
                return Err(Error::Singular { index: j });
            }
            let piv = d.sqrt();
            k[j * n + j] = piv;
            for i in j + 1..n {
                let mut v = k[i * n + j];
                for t in 0..j {
                    v -= k[i * n + t] * k[j * n + t];
                }
                k[i * n + j] = v / piv;
            }
        }
        self.l = k;
        Ok(())
    }

    fn solve(&mut self, rhs: &mut [f64]) {
        let n = self.n;
        let l = &self.l;
        for i in 0..n {
            let mut v = rhs[i];
            for t in 0..i {
                v -= l[i * n + t] * rhs[t];
            }
            rhs[i] = v / l[i * n + i];
        }
        for i in (0..n).rev() {
            let mut v = rhs[i];
            for t in i + 1..n {
                v -= l[t * n + i] * rhs[t];
            }
            rhs[i] = v / l[i * n + i];
        }
    }
}

#[cfg(feature = "clarabel")]
impl DenseProblem {
    /// The program as triplets (for the Clarabel backend).
    pub(crate) fn to_sparse(&self) -> crate::clarabel::SparseProgram {
        let n = self.n;
        let mut p = crate::clarabel::Triplets::default();
        for i in 0..n {
            for j in i..n {
                if self.p[i * n + j] != 0.0 {
                    p.push(i, j, self.p[i * n + j]);
                }
            }
        }
        let mut a = crate::clarabel::Triplets::default();
        for r in 0..self.cones.rows() {
            for j in 0..n {
                if self.a[r * n + j] != 0.0 {
                    a.push(r, j, self.a[r * n + j]);
                }
            }
        }
        crate::clarabel::SparseProgram {
            n,
            p,
            q: self.q.clone(),
            a,
            b: self.b.clone(),
            cones: self.cones.blocks().to_vec(),
        }
    }
}
