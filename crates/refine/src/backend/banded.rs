//! A symmetric positive definite block-banded matrix and its Cholesky factor, with a cyclic band
//! taken as an ordinary band of twice the width in the zig-zag order 0, n−1, 1, n−2, … (the
//! condensed backend's T and T + K D⁻¹ Kᵀ). To be replaced by `crates/banded` when it lands.

// The block kernels index several small arrays by the same row/column.
#![allow(clippy::needless_range_loop)]

/// A symmetric positive definite block-banded matrix (blocks of `bs` × `bs`, `bw` blocks below
/// the diagonal after the ordering) and its Cholesky factor, in place.
#[derive(Clone, Debug)]
pub(crate) struct Banded {
    nb: usize,
    bs: usize,
    bw: usize,
    /// Position of each block in the factored order.
    pos: Vec<usize>,
    /// Block (p, p − t) at [(p (bw + 1) + t) bs², …), row-major.
    a: Vec<f64>,
    /// Solve workspace (positions × columns).
    work: Vec<f64>,
    /// Reciprocals of the diagonal entries of the factor's diagonal blocks (by position).
    rdiag: Vec<f64>,
}

impl Banded {
    /// `nb` blocks coupled within `band` (cyclically when `cyclic`), solves with up to
    /// `ncols` right-hand sides.
    pub(crate) fn new(nb: usize, bs: usize, band: usize, cyclic: bool, ncols: usize) -> Self {
        let half = nb.div_ceil(2);
        let pos: Vec<usize> = if cyclic {
            (0..nb)
                .map(|i| {
                    if i < half {
                        2 * i
                    } else {
                        2 * (nb - 1 - i) + 1
                    }
                })
                .collect()
        } else {
            (0..nb).collect()
        };
        let bw = if cyclic { 2 * band } else { band }.min(nb.saturating_sub(1));
        Banded {
            nb,
            bs,
            bw,
            pos,
            a: vec![0.0; nb * (bw + 1) * bs * bs],
            work: vec![0.0; nb * bs * ncols],
            rdiag: vec![0.0; nb * bs],
        }
    }

    pub(crate) fn clear(&mut self) {
        self.a.fill(0.0);
    }

    #[inline]
    fn at(&self, p: usize, t: usize) -> usize {
        (p * (self.bw + 1) + t) * self.bs * self.bs
    }

    /// Adds `f · blk` to block (i, j) of the symmetric matrix (and so its transpose to (j, i));
    /// `blk(r, c)` is the entry of row r of block i and column c of block j.
    #[inline]
    pub(crate) fn add(&mut self, i: usize, j: usize, f: f64, blk: &[f64]) {
        let bs = self.bs;
        let (pi, pj) = (self.pos[i], self.pos[j]);
        if pi >= pj {
            let o = self.at(pi, pi - pj);
            for (x, b) in self.a[o..o + bs * bs].iter_mut().zip(blk) {
                *x += f * b;
            }
        } else {
            let o = self.at(pj, pj - pi);
            for r in 0..bs {
                for c in 0..bs {
                    self.a[o + r * bs + c] += f * blk[c * bs + r];
                }
            }
        }
    }

    /// Adds f to the scalar-identity part of block (i, j): f I_bs.
    #[inline]
    pub(crate) fn add_identity(&mut self, i: usize, j: usize, f: f64) {
        let bs = self.bs;
        let (pi, pj) = (self.pos[i], self.pos[j]);
        let (p, t) = if pi >= pj {
            (pi, pi - pj)
        } else {
            (pj, pj - pi)
        };
        let o = self.at(p, t);
        for r in 0..bs {
            self.a[o + r * bs + r] += f;
        }
    }

    /// Block Cholesky in place. Returns the (original) block index of a non-positive pivot.
    pub(crate) fn factor(&mut self) -> Result<(), usize> {
        match self.bs {
            1 => self.factor_impl::<1>(),
            2 => self.factor_impl::<2>(),
            3 => self.factor_impl::<3>(),
            _ => self.factor_impl::<0>(),
        }
    }

    /// [`Banded::factor`] with the block size a compile-time constant (`BS` = 0: `self.bs`).
    fn factor_impl<const BS: usize>(&mut self) -> Result<(), usize> {
        let bs = if BS == 0 { self.bs } else { BS };
        let bw = self.bw;
        let bb = bs * bs;
        let mut inv_pos = vec![0; self.nb];
        for (i, &p) in self.pos.iter().enumerate() {
            inv_pos[p] = i;
        }
        let mut mbuf = [0.0; 16];
        let mut mvec = Vec::new();
        let m: &mut [f64] = if bb <= mbuf.len() {
            &mut mbuf[..bb]
        } else {
            mvec.resize(bb, 0.0);
            &mut mvec
        };
        for p in 0..self.nb {
            let lo = p.saturating_sub(bw);
            for c in lo..=p {
                // M = A[p][c] − Σ_{c' < c} L[p][c'] L[c][c']ᵀ.
                let o = self.at(p, p - c);
                m.copy_from_slice(&self.a[o..o + bb]);
                for cp in lo.max(c.saturating_sub(bw))..c {
                    let x = self.at(p, p - cp);
                    let y = self.at(c, c - cp);
                    let (xs, ys) = (&self.a[x..x + bb], &self.a[y..y + bb]);
                    for r in 0..bs {
                        for s in 0..bs {
                            let mut acc = 0.0;
                            for t in 0..bs {
                                acc += xs[r * bs + t] * ys[s * bs + t];
                            }
                            m[r * bs + s] -= acc;
                        }
                    }
                }
                if c < p {
                    // L[p][c] = M L[c][c]⁻ᵀ: each row solves L[c][c] xᵀ = mᵀ.
                    let dgo = self.at(c, 0);
                    let dg = &self.a[dgo..dgo + bb];
                    let rc = &self.rdiag[c * bs..(c + 1) * bs];
                    for r in 0..bs {
                        for s in 0..bs {
                            let mut v = m[r * bs + s];
                            for t in 0..s {
                                v -= m[r * bs + t] * dg[s * bs + t];
                            }
                            m[r * bs + s] = v * rc[s];
                        }
                    }
                    self.a[o..o + bb].copy_from_slice(m);
                } else {
                    // Dense Cholesky of the diagonal block (lower triangle stored).
                    for s in 0..bs {
                        let mut v = m[s * bs + s];
                        for t in 0..s {
                            v -= m[s * bs + t] * m[s * bs + t];
                        }
                        if v.is_nan() || v <= 0.0 {
                            return Err(inv_pos[p]);
                        }
                        let piv = v.sqrt();
                        let rpiv = 1.0 / piv;
                        self.rdiag[p * bs + s] = rpiv;
                        m[s * bs + s] = piv;
                        for r in s + 1..bs {
                            let mut w = m[r * bs + s];
                            for t in 0..s {
                                w -= m[r * bs + t] * m[s * bs + t];
                            }
                            m[r * bs + s] = w * rpiv;
                        }
                        for r in 0..s {
                            m[r * bs + s] = 0.0;
                        }
                    }
                    self.a[o..o + bb].copy_from_slice(m);
                }
            }
        }
        Ok(())
    }

    /// Solves A x = b in place for `ncols` columns (b in the original block order, unknown-major).
    pub(crate) fn solve(&mut self, b: &mut [f64], ncols: usize) {
        match (self.bs, ncols) {
            (1, 1) => self.solve_impl::<1, 1>(b),
            (1, 2) => self.solve_impl::<1, 2>(b),
            (1, 3) => self.solve_impl::<1, 3>(b),
            (2, 1) => self.solve_impl::<2, 1>(b),
            (3, 1) => self.solve_impl::<3, 1>(b),
            _ => self.solve_inner(b, self.bs, ncols),
        }
    }

    /// [`Banded::solve`] with block size and column count compile-time constants.
    fn solve_impl<const BS: usize, const NC: usize>(&mut self, b: &mut [f64]) {
        self.solve_inner(b, BS, NC);
    }

    #[inline(always)]
    fn solve_inner(&mut self, b: &mut [f64], bs: usize, ncols: usize) {
        let (bw, nb) = (self.bw, self.nb);
        let row = bs * ncols;
        let w = &mut self.work[..nb * row];
        for i in 0..nb {
            let p = self.pos[i];
            w[p * row..(p + 1) * row].copy_from_slice(&b[i * row..(i + 1) * row]);
        }
        let a = &self.a;
        let rd = &self.rdiag;
        let bb = bs * bs;
        let at = |p: usize, t: usize| (p * (bw + 1) + t) * bb;
        // The unknowns of one block row are accumulated in a local buffer (no stores to `w`
        // between the contributions of its neighbours).
        let mut buf = [0.0; 16];
        let mut vbuf = Vec::new();
        let x: &mut [f64] = if row <= buf.len() {
            &mut buf[..row]
        } else {
            vbuf.resize(row, 0.0);
            &mut vbuf
        };
        // Forward: L x = b.
        for p in 0..nb {
            x.copy_from_slice(&w[p * row..(p + 1) * row]);
            for c in p.saturating_sub(bw)..p {
                let blk = &a[at(p, p - c)..at(p, p - c) + bb];
                let xc = &w[c * row..(c + 1) * row];
                for r in 0..bs {
                    for e in 0..ncols {
                        let mut acc = 0.0;
                        for t in 0..bs {
                            acc += blk[r * bs + t] * xc[t * ncols + e];
                        }
                        x[r * ncols + e] -= acc;
                    }
                }
            }
            let dg = &a[at(p, 0)..at(p, 0) + bb];
            let rp = &rd[p * bs..(p + 1) * bs];
            for r in 0..bs {
                for e in 0..ncols {
                    let mut v = x[r * ncols + e];
                    for t in 0..r {
                        v -= dg[r * bs + t] * x[t * ncols + e];
                    }
                    x[r * ncols + e] = v * rp[r];
                }
            }
            w[p * row..(p + 1) * row].copy_from_slice(x);
        }
        // Backward: Lᵀ x = y.
        for p in (0..nb).rev() {
            x.copy_from_slice(&w[p * row..(p + 1) * row]);
            for rr in p + 1..(p + bw + 1).min(nb) {
                let blk = &a[at(rr, rr - p)..at(rr, rr - p) + bb];
                let xr = &w[rr * row..(rr + 1) * row];
                for s in 0..bs {
                    for e in 0..ncols {
                        let mut acc = 0.0;
                        for t in 0..bs {
                            acc += blk[t * bs + s] * xr[t * ncols + e];
                        }
                        x[s * ncols + e] -= acc;
                    }
                }
            }
            let dg = &a[at(p, 0)..at(p, 0) + bb];
            let rp = &rd[p * bs..(p + 1) * bs];
            for r in (0..bs).rev() {
                for e in 0..ncols {
                    let mut v = x[r * ncols + e];
                    for t in r + 1..bs {
                        v -= dg[t * bs + r] * x[t * ncols + e];
                    }
                    x[r * ncols + e] = v * rp[r];
                }
            }
            w[p * row..(p + 1) * row].copy_from_slice(x);
        }
        for i in 0..nb {
            let p = self.pos[i];
            b[i * row..(i + 1) * row].copy_from_slice(&w[p * row..(p + 1) * row]);
        }
    }
}
