//! O(N) solves of (H ⊗ I_d + M) x = b: banded (open) and cyclic (closed).
//!
//! The matrix K = H ⊗ I_d + M is block-pentadiagonal (open curves) or cyclic block-pentadiagonal
//! (closed curves) with d×d blocks: H is the scalar (cyclic) pentadiagonal Hessian of the energy,
//! M collects what the refinement problems add — scalar weights at vertices (w I_d), symmetric
//! d×d blocks at vertices, and stencil terms Lᵀ B L whose stencil L spans at most three cyclically
//! consecutive vertices (tangent constraints). Vertices can be *fixed* (their value is prescribed
//! and they are eliminated).
//!
//! Two factorizations, both O(N) in time and memory:
//! - **scalar fast path** (no coupling blocks): one scalar pentadiagonal LDLᵀ shared by all d
//!   coordinate columns. For closed curves the two last rows are a dense *border* (the wrap-around
//!   couplings fill them in), stored as two length-N vectors.
//! - **block band path** (coupling blocks, d ≤ 4): a block LDLᵀ with d×d blocks fixed at compile
//!   time, rows with two block subdiagonals and, for closed curves, a two-block-row border.
//! - **envelope path** (d > 4, or closed curves with N ≤ 4 where the bands alias and entries add
//!   up): a block Cholesky factorization on the block *envelope* of K — rows 0..N−3 span their
//!   band, the last two block rows of a closed curve span everything (border); for N ≤ 4 the
//!   envelope is the whole lower triangle.
//!
//! A pivot is accepted only if it exceeds [`PIVOT_RTOL`] times the diagonal entry of the same row
//! of K (the pivot of a positive semidefinite matrix never exceeds it), so the test is relative to
//! the matrix scale, row by row; otherwise [`Error::Singular`] names the vertex.

mod band;
mod block;
mod blockband;

use crate::{Error, Hessian};
use divdiff::{Points, Topology};

/// Relative pivot tolerance: a pivot `p` of row `i` is accepted only if `p > PIVOT_RTOL * K_ii`.
///
/// A singular K (e.g. H with no weights: ker H = constants or linear polynomials) produces
/// pivots at rounding level, ~1e-16·K_ii times a modest growth factor; a genuinely positive
/// definite K whose smallest pivot is below 1e-13·K_ii has a condition number beyond 1e13 and
/// is treated as numerically singular.
pub const PIVOT_RTOL: f64 = 1e-13;

/// The linear system K = H ⊗ I_d + M on N vertices in R^d (see the module docs).
///
/// Build it from the Hessian bands, add weights, blocks and stencils, fix vertices, then
/// [`factor`](System::factor) once and [`solve`](Factor::solve) for any number of right-hand sides.
#[derive(Clone, Debug)]
pub struct System {
    topology: Topology,
    n: usize,
    dim: usize,
    /// Scalar bands of H + diag(weights): `diag[j]`, `off1[j]` couples (j, j+1), `off2[j]` (j, j+2).
    diag: Vec<f64>,
    off1: Vec<f64>,
    off2: Vec<f64>,
    /// Coupling blocks (block envelope storage), allocated on the first block or stencil.
    blocks: Option<Vec<f64>>,
    fixed: Vec<bool>,
}

/// The envelope pattern of the lower block triangle: row `i` holds columns `first(i)..=i`.
/// Open: the band (first(i) = i − 2). Closed, N ≥ 5: the band, and the last two rows are full
/// (the border). Closed, N ≤ 4: the whole lower triangle.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Envelope {
    n: usize,
    full: bool,
    closed: bool,
}

impl Envelope {
    pub(crate) fn new(topology: Topology, n: usize) -> Self {
        let closed = topology == Topology::Closed;
        Envelope {
            n,
            full: closed && n <= 4,
            closed,
        }
    }

    /// First column of row `i`.
    #[inline]
    pub(crate) fn first(&self, i: usize) -> usize {
        if self.full || (self.closed && i + 2 >= self.n) {
            0
        } else {
            i.saturating_sub(2)
        }
    }

    /// Offset (in blocks) of row `i`.
    #[inline]
    pub(crate) fn offset(&self, i: usize) -> usize {
        if self.full {
            return i * (i + 1) / 2;
        }
        let band = |i: usize| if i < 2 { i * (i + 1) / 2 } else { 3 * i - 3 };
        if self.closed && i == self.n - 1 {
            band(self.n - 2) + (self.n - 1)
        } else {
            band(i)
        }
    }

    /// Total number of blocks.
    pub(crate) fn total(&self) -> usize {
        self.offset(self.n - 1) + (self.n - 1 - self.first(self.n - 1)) + 1
    }

    /// Index (in blocks) of the lower entry (i, j), i ≥ j, which must lie in the envelope.
    #[inline]
    pub(crate) fn index(&self, i: usize, j: usize) -> usize {
        debug_assert!(j <= i && j >= self.first(i));
        self.offset(i) + (j - self.first(i))
    }
}

impl System {
    /// K = H ⊗ I_dim for the energy Hessian `h` (no weights, nothing fixed yet).
    ///
    /// # Errors
    /// [`Error::SizeMismatch`] for `dim` = 0 or a closed curve with fewer than 3 vertices.
    pub fn new(h: &Hessian, dim: usize) -> Result<System, Error> {
        let (d, o1, o2) = h.bands();
        System::from_bands(h.topology(), d.to_vec(), o1.to_vec(), o2.to_vec(), dim)
    }

    /// K = H ⊗ I_dim from the three bands of the (cyclic) pentadiagonal H (see the crate docs
    /// for the band convention: `off1[j]` couples vertices j and j+1, `off2[j]` couples j and
    /// j+2, indices mod N for closed curves — where for N = 3, 4 aliasing entries add up; for
    /// open curves `off1[N−1]`, `off2[N−2]`, `off2[N−1]` are ignored).
    ///
    /// # Errors
    /// [`Error::SizeMismatch`] if the bands differ in length, N = 0 or `dim` = 0 (field `"dim"`),
    /// or a closed curve has N < 3 (field `"vertices"`).
    pub fn from_bands(
        topology: Topology,
        diag: Vec<f64>,
        mut off1: Vec<f64>,
        mut off2: Vec<f64>,
        dim: usize,
    ) -> Result<System, Error> {
        let n = diag.len();
        if dim == 0 {
            return Err(Error::SizeMismatch {
                field: "dim",
                expected: 1,
                got: 0,
            });
        }
        let min = if topology == Topology::Closed { 3 } else { 1 };
        if n < min {
            return Err(Error::SizeMismatch {
                field: "vertices",
                expected: min,
                got: n,
            });
        }
        for (field, band) in [("off1", &off1), ("off2", &off2)] {
            if band.len() != n {
                return Err(Error::SizeMismatch {
                    field,
                    expected: n,
                    got: band.len(),
                });
            }
        }
        if topology == Topology::Open {
            off1[n - 1] = 0.0;
            off2[n - 1] = 0.0;
            if n >= 2 {
                off2[n - 2] = 0.0;
            }
        }
        Ok(System {
            topology,
            n,
            dim,
            diag,
            off1,
            off2,
            blocks: None,
            fixed: vec![false; n],
        })
    }

    /// Number of vertices N.
    pub fn len(&self) -> usize {
        self.n
    }

    /// Whether the system has no vertices (never true for a constructed system).
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// The dimension d.
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// Open or closed.
    pub fn topology(&self) -> Topology {
        self.topology
    }

    /// Whether `vertex` is fixed.
    pub fn is_fixed(&self, vertex: usize) -> bool {
        self.fixed.get(vertex).copied().unwrap_or(false)
    }

    fn check_vertex(&self, field: &'static str, vertex: usize) -> Result<(), Error> {
        if vertex >= self.n {
            Err(Error::IndexOutOfRange {
                field,
                index: vertex,
                len: self.n,
            })
        } else {
            Ok(())
        }
    }

    /// Adds w I_d to the diagonal block of `vertex` (a smoothing weight).
    ///
    /// # Errors
    /// [`Error::IndexOutOfRange`] for a vertex ≥ N.
    pub fn add_weight(&mut self, vertex: usize, w: f64) -> Result<(), Error> {
        self.check_vertex("vertex", vertex)?;
        self.diag[vertex] += w;
        Ok(())
    }

    fn blocks_mut(&mut self) -> &mut Vec<f64> {
        let total = Envelope::new(self.topology, self.n).total() * self.dim * self.dim;
        self.blocks.get_or_insert_with(|| vec![0.0; total])
    }

    /// Adds the symmetric d×d `block` (row-major, d² entries) to the diagonal block of `vertex`.
    /// Only the symmetric part ½(B + Bᵀ) is used.
    ///
    /// # Errors
    /// [`Error::IndexOutOfRange`] for a vertex ≥ N, [`Error::SizeMismatch`] for a block that does
    /// not have d² entries.
    pub fn add_block(&mut self, vertex: usize, block: &[f64]) -> Result<(), Error> {
        self.add_stencil(&[(vertex, 1.0)], block)
    }

    /// Adds Lᵀ B L with L = Σ_k c_k e_{v_k}ᵀ ⊗ I_d for `stencil` = [(v_k, c_k)]: at most three
    /// entries whose vertices lie within two steps of each other (cyclically for closed curves),
    /// so K stays block-pentadiagonal. `block` is B (row-major, d², symmetric part used).
    ///
    /// # Errors
    /// [`Error::IndexOutOfRange`] for a vertex ≥ N, [`Error::SizeMismatch`] for a block that does
    /// not have d² entries or a stencil with more than three entries (field `"stencil"`),
    /// [`Error::StencilTooWide`] if two stencil vertices are more than two steps apart.
    pub fn add_stencil(&mut self, stencil: &[(usize, f64)], block: &[f64]) -> Result<(), Error> {
        let d = self.dim;
        if block.len() != d * d {
            return Err(Error::SizeMismatch {
                field: "block",
                expected: d * d,
                got: block.len(),
            });
        }
        if stencil.len() > 3 {
            return Err(Error::SizeMismatch {
                field: "stencil",
                expected: 3,
                got: stencil.len(),
            });
        }
        for &(v, _) in stencil {
            self.check_vertex("stencil", v)?;
        }
        let n = self.n;
        let env = Envelope::new(self.topology, n);
        // Validate the pattern before touching the storage.
        for &(a, _) in stencil {
            for &(b, _) in stencil {
                let (i, j) = if a >= b { (a, b) } else { (b, a) };
                if j < env.first(i) || (self.topology == Topology::Open && i - j > 2) {
                    return Err(Error::StencilTooWide {
                        first: a,
                        second: b,
                    });
                }
                if self.topology == Topology::Closed && i - j > 2 && n - (i - j) > 2 {
                    return Err(Error::StencilTooWide {
                        first: a,
                        second: b,
                    });
                }
            }
        }
        let blocks = self.blocks_mut();
        for &(a, ca) in stencil {
            for &(b, cb) in stencil {
                // K_ab += ca cb B; store only the lower entry (a > b) and the diagonal (a == b).
                if a < b {
                    continue;
                }
                let base = env.index(a, b) * d * d;
                let s = ca * cb;
                for r in 0..d {
                    for c in 0..d {
                        let sym = 0.5 * (block[r * d + c] + block[c * d + r]);
                        blocks[base + r * d + c] += s * sym;
                    }
                }
            }
        }
        Ok(())
    }

    /// Fixes `vertex`: its value is prescribed (given in the right-hand side at solve time) and it
    /// is eliminated from the system.
    ///
    /// # Errors
    /// [`Error::IndexOutOfRange`] for a vertex ≥ N.
    pub fn fix(&mut self, vertex: usize) -> Result<(), Error> {
        self.check_vertex("fixed", vertex)?;
        self.fixed[vertex] = true;
        Ok(())
    }

    /// K x for the assembled matrix, ignoring which vertices are fixed (all rows of K).
    ///
    /// # Errors
    /// [`Error::SizeMismatch`] if `x` is not N points of dimension d.
    pub fn apply(&self, x: &Points) -> Result<Points, Error> {
        self.check_points("x", x)?;
        let (n, d) = (self.n, self.dim);
        let xs = x.coords();
        let mut y = vec![0.0; n * d];
        for j in 0..n {
            for c in 0..d {
                y[j * d + c] += self.diag[j] * xs[j * d + c];
            }
            for (band, step) in [(&self.off1, 1), (&self.off2, 2)] {
                let v = band[j];
                if v == 0.0 {
                    continue;
                }
                let k = if j + step >= n {
                    j + step - n
                } else {
                    j + step
                };
                for c in 0..d {
                    y[j * d + c] += v * xs[k * d + c];
                    y[k * d + c] += v * xs[j * d + c];
                }
            }
        }
        if let Some(blocks) = &self.blocks {
            let env = Envelope::new(self.topology, n);
            // Envelope entries are stored row by row, columns first(i)..=i consecutively.
            let mut blocks_iter = blocks.chunks_exact(d * d);
            for i in 0..n {
                for j in env.first(i)..=i {
                    let Some(b) = blocks_iter.next() else {
                        break;
                    };
                    if b.iter().all(|&v| v == 0.0) {
                        continue;
                    }
                    for r in 0..d {
                        for c in 0..d {
                            y[i * d + r] += b[r * d + c] * xs[j * d + c];
                            if i != j {
                                y[j * d + c] += b[r * d + c] * xs[i * d + r];
                            }
                        }
                    }
                }
            }
        }
        Ok(Points::new(d, y)?)
    }

    fn check_points(&self, field: &'static str, x: &Points) -> Result<(), Error> {
        if x.dim() != self.dim {
            return Err(Error::SizeMismatch {
                field,
                expected: self.dim,
                got: x.dim(),
            });
        }
        if x.len() != self.n {
            return Err(Error::SizeMismatch {
                field,
                expected: self.n,
                got: x.len(),
            });
        }
        Ok(())
    }

    /// Factors K (with the fixed vertices eliminated) in O(N) time and memory.
    ///
    /// # Errors
    /// [`Error::Singular`] naming the vertex of the first pivot that is not above
    /// [`PIVOT_RTOL`] times its diagonal entry (or not finite).
    pub fn factor(&self) -> Result<Factor, Error> {
        self.factor_with_tolerance(PIVOT_RTOL)
    }

    /// [`factor`](System::factor) with a caller-chosen relative pivot tolerance instead of
    /// [`PIVOT_RTOL`]: for matrices known to be positive definite whose pivots may legitimately
    /// be tiny relative to their diagonal (interior-point Newton systems, where barrier terms
    /// grow without bound on some rows).
    ///
    /// # Errors
    /// [`Error::Singular`] naming the vertex of the first pivot that is not above
    /// `pivot_rtol` times its diagonal entry (or not finite).
    pub fn factor_with_tolerance(&self, pivot_rtol: f64) -> Result<Factor, Error> {
        let banded = self.topology == Topology::Open || self.n >= 5;
        let parts = self.parts(pivot_rtol);
        let inner = match (banded, self.blocks.is_some(), self.dim) {
            (true, false, _) => Inner::Band(band::BandFactor::new(&parts)?),
            (true, true, 1) => Inner::Bb1(blockband::BlockBand::new(&parts)?),
            (true, true, 2) => Inner::Bb2(blockband::BlockBand::new(&parts)?),
            (true, true, 3) => Inner::Bb3(blockband::BlockBand::new(&parts)?),
            (true, true, 4) => Inner::Bb4(blockband::BlockBand::new(&parts)?),
            _ => Inner::Block(block::BlockFactor::new(&parts)?),
        };
        Ok(Factor {
            n: self.n,
            dim: self.dim,
            inner,
        })
    }

    pub(crate) fn parts(&self, rtol: f64) -> Parts<'_> {
        Parts {
            rtol,
            topology: self.topology,
            n: self.n,
            dim: self.dim,
            diag: &self.diag,
            off1: &self.off1,
            off2: &self.off2,
            blocks: self.blocks.as_deref(),
            fixed: &self.fixed,
        }
    }
}

/// Borrowed view of a system for the factorizations.
pub(crate) struct Parts<'a> {
    pub(crate) rtol: f64,
    pub(crate) topology: Topology,
    pub(crate) n: usize,
    pub(crate) dim: usize,
    pub(crate) diag: &'a [f64],
    pub(crate) off1: &'a [f64],
    pub(crate) off2: &'a [f64],
    pub(crate) blocks: Option<&'a [f64]>,
    pub(crate) fixed: &'a [bool],
}

/// A factorization of a [`System`], reusable for any number of right-hand sides.
#[derive(Clone, Debug)]
pub struct Factor {
    n: usize,
    dim: usize,
    inner: Inner,
}

#[derive(Clone, Debug)]
enum Inner {
    Band(band::BandFactor),
    Bb1(blockband::BlockBand<1>),
    Bb2(blockband::BlockBand<2>),
    Bb3(blockband::BlockBand<3>),
    Bb4(blockband::BlockBand<4>),
    Block(block::BlockFactor),
}

impl Factor {
    /// Solves K x = b. Rows of fixed vertices in `rhs` hold their prescribed *values* (copied to
    /// x); the other rows hold b.
    ///
    /// # Errors
    /// [`Error::SizeMismatch`] if `rhs` is not N points of dimension d.
    pub fn solve(&self, rhs: &Points) -> Result<Points, Error> {
        let mut x = rhs.clone();
        self.solve_in_place(&mut x)?;
        Ok(x)
    }

    /// [`solve`](Factor::solve) overwriting `x` (which holds the right-hand side on entry).
    ///
    /// # Errors
    /// [`Error::SizeMismatch`] if `x` is not N points of dimension d.
    pub fn solve_in_place(&self, x: &mut Points) -> Result<(), Error> {
        if x.dim() != self.dim || x.len() != self.n {
            return Err(Error::SizeMismatch {
                field: "rhs",
                expected: self.n * self.dim,
                got: x.len() * x.dim(),
            });
        }
        self.solve_slice(x.coords_mut());
        Ok(())
    }

    /// Solves in place on a flat vertex-major slice of length N·d (no size checks beyond debug).
    pub(crate) fn solve_slice(&self, x: &mut [f64]) {
        debug_assert_eq!(x.len(), self.n * self.dim);
        match &self.inner {
            Inner::Band(f) => f.solve(x),
            Inner::Bb1(f) => f.solve(x),
            Inner::Bb2(f) => f.solve(x),
            Inner::Bb3(f) => f.solve(x),
            Inner::Bb4(f) => f.solve(x),
            Inner::Block(f) => f.solve(x),
        }
    }

    /// Solves K x = b for a flat vertex-major right-hand side of length N·d, in place.
    ///
    /// # Errors
    /// [`Error::SizeMismatch`] if the length is not N·d.
    pub fn solve_flat(&self, x: &mut [f64]) -> Result<(), Error> {
        if x.len() != self.n * self.dim {
            return Err(Error::SizeMismatch {
                field: "rhs",
                expected: self.n * self.dim,
                got: x.len(),
            });
        }
        self.solve_slice(x);
        Ok(())
    }
}

/// Interpolatory refinement (Kersey (3.2)/(3.3)): the curve p with p_j = `values[k]` at the
/// vertices j = `fixed[k]` and (Hp)_j = 0 at every free vertex j — the minimizer of the energy
/// under the interpolation constraints. One banded factorization, O(N) for all d coordinates.
///
/// ```
/// use divdiff::{Knots, Points};
/// use energy::{solve_interpolatory, Hessian};
/// // Closed uniform curve with 8 vertices, every other one fixed on the unit square's corners…
/// let knots = Knots::closed((0..=8).map(f64::from).collect()).unwrap();
/// let h = Hessian::new(&knots);
/// let q = Points::from_rows(&[[1.0, 0.0], [0.0, 1.0], [-1.0, 0.0], [0.0, -1.0]]).unwrap();
/// let p = solve_interpolatory(&h, &[0, 2, 4, 6], &q).unwrap();
/// assert_eq!(p.point(2), &[0.0, 1.0]);
/// // …the free vertices satisfy (Hp)_j = 0.
/// let hp = h.apply(&p);
/// assert!(hp.point(1).iter().all(|v| v.abs() < 1e-12));
/// ```
///
/// # Errors
/// [`Error::SizeMismatch`] if `values` does not have one point per fixed index,
/// [`Error::IndexOutOfRange`] for an index ≥ N, [`Error::DuplicateFixed`] for an index given
/// twice, [`Error::Singular`] if the fixed set does not determine the curve (a closed curve with
/// nothing fixed, an open curve with fewer than two fixed vertices).
pub fn solve_interpolatory(h: &Hessian, fixed: &[usize], values: &Points) -> Result<Points, Error> {
    if values.len() != fixed.len() {
        return Err(Error::SizeMismatch {
            field: "values",
            expected: fixed.len(),
            got: values.len(),
        });
    }
    let d = values.dim();
    let mut sys = System::new(h, d)?;
    let mut rhs = Points::zeros(sys.len(), d);
    for (k, &j) in fixed.iter().enumerate() {
        if sys.is_fixed(j) {
            return Err(Error::DuplicateFixed { index: j });
        }
        sys.fix(j)?;
        rhs.point_mut(j).copy_from_slice(values.point(k));
    }
    let f = sys.factor()?;
    f.solve_in_place(&mut rhs)?;
    Ok(rhs)
}
