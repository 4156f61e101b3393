//! The linear systems of the refinement problems, (H ⊗ I_d + M) x = b, on top of `banded`.
//!
//! The matrix K = H ⊗ I_d + M is block-pentadiagonal (open curves) or cyclic block-pentadiagonal
//! (closed curves) with d×d blocks: H is the scalar (cyclic) pentadiagonal Hessian of the energy,
//! M collects what the refinement problems add — scalar weights at vertices (w I_d), symmetric
//! d×d blocks at vertices, and stencil terms Lᵀ B L whose stencil L spans at most three cyclically
//! consecutive vertices (tangent constraints). Vertices can be *fixed* (their value is prescribed
//! and they are eliminated: their rows and columns become identity rows, and their couplings
//! move to the right-hand side).
//!
//! K is stored as a [`banded::BlockBand`]`<2>`: the scalar part H + weights, and the coupling
//! blocks once the first block or stencil is added. Two factorizations, both O(N):
//! - **scalar** (no coupling blocks): one LDLᵀ of the scalar (cyclic) pentadiagonal part,
//!   shared by the d coordinate columns ([`banded::SymBand`]);
//! - **block** (coupling blocks): block Cholesky with d×d blocks ([`banded::BlockBand`]).
//!
//! Closed curves are factored bordered (their last two vertices a border that decays), closed
//! curves with N ≤ 4 alias (entries naming the same position add up); see `banded`'s docs.
//! A pivot is accepted only if it exceeds [`PIVOT_RTOL`] times the diagonal entry of the same
//! row of K (the pivot of a positive semidefinite matrix never exceeds it), so the test is
//! relative to the matrix scale, row by row; otherwise [`Error::Singular`] names the vertex.

use crate::{Error, Hessian};
use banded::{BlockBand, BlockFactor, FactorOptions, SymBand, SymBandFactor};
use divdiff::{Points, Topology};

/// Relative pivot tolerance: a pivot `p` of row `i` is accepted only if `p > PIVOT_RTOL * K_ii`
/// (`banded`'s default, [`banded::PIVOT_RTOL`]).
///
/// A singular K (e.g. H with no weights: ker H = constants or linear polynomials) produces
/// pivots at rounding level, ~1e-16·K_ii times a modest growth factor; a genuinely positive
/// definite K whose smallest pivot is below 1e-13·K_ii has a condition number beyond 1e13 and
/// is treated as numerically singular.
pub const PIVOT_RTOL: f64 = banded::PIVOT_RTOL;

/// The linear system K = H ⊗ I_d + M on N vertices in R^d (see the module docs).
///
/// Build it from the Hessian bands, add weights, blocks and stencils, fix vertices, then
/// [`factor`](System::factor) once and [`solve`](Factor::solve) for any number of right-hand sides.
#[derive(Clone, Debug)]
pub struct System {
    topology: Topology,
    /// K: the scalar part H + diag(weights) and, once added, the coupling blocks.
    band: BlockBand<2>,
    fixed: Vec<bool>,
}

/// The `banded` topology of a curve's.
fn cyclic(topology: Topology) -> banded::Topology {
    match topology {
        Topology::Open => banded::Topology::Open,
        Topology::Closed => banded::Topology::Cyclic,
    }
}

impl System {
    /// K = H ⊗ I_dim for the energy Hessian `h` (no weights, nothing fixed yet).
    ///
    /// # Errors
    /// [`Error::WrongLength`] for `dim` = 0 or a closed curve with fewer than 3 vertices.
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
    /// [`Error::WrongLength`] if the bands differ in length, N = 0 or `dim` = 0 (field `"dim"`),
    /// or a closed curve has N < 3 (field `"vertices"`).
    pub fn from_bands(
        topology: Topology,
        diag: Vec<f64>,
        off1: Vec<f64>,
        off2: Vec<f64>,
        dim: usize,
    ) -> Result<System, Error> {
        let n = diag.len();
        if dim == 0 {
            return Err(Error::WrongLength {
                field: "dim",
                expected: 1,
                got: 0,
            });
        }
        let min = if topology == Topology::Closed { 3 } else { 1 };
        if n < min {
            return Err(Error::WrongLength {
                field: "vertices",
                expected: min,
                got: n,
            });
        }
        for (field, band) in [("off1", &off1), ("off2", &off2)] {
            if band.len() != n {
                return Err(Error::WrongLength {
                    field,
                    expected: n,
                    got: band.len(),
                });
            }
        }
        let mut off: Vec<[f64; 2]> = off1.iter().zip(&off2).map(|(&a, &b)| [a, b]).collect();
        if topology == Topology::Open {
            // Entries past the end of an open curve are ignored (and kept zero).
            off[n - 1] = [0.0; 2];
            if n >= 2 {
                off[n - 2][1] = 0.0;
            }
        }
        let scalar = SymBand::from_bands(cyclic(topology), diag, off)?;
        Ok(System {
            topology,
            band: BlockBand::from_scalar(scalar, dim)?,
            fixed: vec![false; n],
        })
    }

    /// Number of vertices N.
    pub fn len(&self) -> usize {
        self.band.len()
    }

    /// Whether the system has no vertices (never true for a constructed system).
    pub fn is_empty(&self) -> bool {
        self.band.is_empty()
    }

    /// The dimension d.
    pub fn dim(&self) -> usize {
        self.band.dim()
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
        if vertex >= self.len() {
            Err(Error::IndexOutOfRange {
                field,
                index: vertex,
                len: self.len(),
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
        self.band.scalar_mut().diag_mut()[vertex] += w;
        Ok(())
    }

    /// Adds the symmetric d×d `block` (row-major, d² entries) to the diagonal block of `vertex`.
    /// Only the symmetric part ½(B + Bᵀ) is used.
    ///
    /// # Errors
    /// [`Error::IndexOutOfRange`] for a vertex ≥ N, [`Error::WrongLength`] for a block that does
    /// not have d² entries.
    pub fn add_block(&mut self, vertex: usize, block: &[f64]) -> Result<(), Error> {
        self.add_stencil(&[(vertex, 1.0)], block)
    }

    /// Adds Lᵀ B L with L = Σ_k c_k e_{v_k}ᵀ ⊗ I_d for `stencil` = [(v_k, c_k)]: at most three
    /// entries whose vertices lie within two steps of each other (cyclically for closed curves),
    /// so K stays block-pentadiagonal. `block` is B (row-major, d², symmetric part used).
    ///
    /// # Errors
    /// [`Error::IndexOutOfRange`] for a vertex ≥ N, [`Error::WrongLength`] for a block that does
    /// not have d² entries or a stencil with more than three entries (field `"stencil"`),
    /// [`Error::StencilTooWide`] if two stencil vertices are more than two steps apart.
    pub fn add_stencil(&mut self, stencil: &[(usize, f64)], block: &[f64]) -> Result<(), Error> {
        let (n, d) = (self.len(), self.dim());
        if block.len() != d * d {
            return Err(Error::WrongLength {
                field: "block",
                expected: d * d,
                got: block.len(),
            });
        }
        if stencil.len() > 3 {
            return Err(Error::WrongLength {
                field: "stencil",
                expected: 3,
                got: stencil.len(),
            });
        }
        for &(v, _) in stencil {
            self.check_vertex("stencil", v)?;
        }
        // Validate the pattern before touching the storage.
        for &(a, _) in stencil {
            for &(b, _) in stencil {
                let gap = a.abs_diff(b);
                let too_wide = match self.topology {
                    Topology::Open => gap > 2,
                    Topology::Closed => gap > 2 && n - gap > 2,
                };
                if too_wide {
                    return Err(Error::StencilTooWide {
                        first: a,
                        second: b,
                    });
                }
            }
        }
        // The symmetric part of B, once (on the stack for d ≤ 4: this runs per constraint and
        // interior-point iteration).
        let mut stack = [0.0; 16];
        let mut heap = Vec::new();
        let sym: &mut [f64] = if d * d <= stack.len() {
            &mut stack[..d * d]
        } else {
            heap.resize(d * d, 0.0);
            &mut heap
        };
        for r in 0..d {
            for c in 0..d {
                sym[r * d + c] = 0.5 * (block[r * d + c] + block[c * d + r]);
            }
        }
        for &(a, ca) in stencil {
            for &(b, cb) in stencil {
                // K_ab += ca cb B for every ordered pair: `add_scaled` adds (a, b) and its
                // transpose at once, so a pair of distinct vertices is visited once.
                if a >= b {
                    self.band.add_scaled(a, b, ca * cb, sym)?;
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
    /// [`Error::WrongLength`] if `x` is not N points of dimension d.
    pub fn apply(&self, x: &Points) -> Result<Points, Error> {
        self.check_points("x", x)?;
        let mut y = vec![0.0; self.len() * self.dim()];
        self.band.mul_add(x.coords(), &mut y, 1)?;
        Ok(Points::new(self.dim(), y)?)
    }

    /// [`apply`](System::apply) on flat vertex-major slices of length N·d: y = K x (y is
    /// overwritten), without allocating.
    ///
    /// # Errors
    /// [`Error::WrongLength`] if `x` or `y` does not have N·d entries.
    pub fn apply_flat(&self, x: &[f64], y: &mut [f64]) -> Result<(), Error> {
        let len = self.len() * self.dim();
        for (field, got) in [("x", x.len()), ("y", y.len())] {
            if got != len {
                return Err(Error::WrongLength {
                    field,
                    expected: len,
                    got,
                });
            }
        }
        y.fill(0.0);
        Ok(self.band.mul_add(x, y, 1)?)
    }

    /// Removes every coupling block and stencil term (K = H ⊗ I_d + weights again, fixed vertices
    /// kept) but keeps their storage, so a system rebuilt every iteration does not reallocate.
    pub fn clear_blocks(&mut self) {
        self.band.clear_blocks();
    }

    fn check_points(&self, field: &'static str, x: &Points) -> Result<(), Error> {
        if x.dim() != self.dim() {
            return Err(Error::WrongLength {
                field,
                expected: self.dim(),
                got: x.dim(),
            });
        }
        if x.len() != self.len() {
            return Err(Error::WrongLength {
                field,
                expected: self.len(),
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
        let mut f = Factor::empty();
        self.factor_into(pivot_rtol, &mut f)?;
        Ok(f)
    }

    /// [`factor_with_tolerance`](System::factor_with_tolerance) into an existing factor,
    /// reusing its storage: no allocation once it has held a factor of this system's size and
    /// kind (the interior-point method factors a system of N vertices at every iteration; a
    /// fresh factor each time was N·d²·3 doubles of new memory, 38 MB at N = 4·10⁵, d = 2, whose
    /// first touch is a page fault per page). On error `f` is left empty: its solves report
    /// [`Error::WrongLength`].
    ///
    /// # Errors
    /// As [`factor_with_tolerance`](System::factor_with_tolerance).
    pub fn factor_into(&self, pivot_rtol: f64, f: &mut Factor) -> Result<(), Error> {
        let any_fixed = self.fixed.iter().any(|&f| f);
        let mut options = FactorOptions::default().pivot_rtol(pivot_rtol);
        if any_fixed {
            options = options.eliminated(&self.fixed);
        }
        // Empty until it holds this system's factor.
        (f.n, f.dim) = (0, 0);
        f.fixed_couplings.clear();
        if self.band.has_blocks() {
            if !matches!(f.inner, Inner::Block(_)) {
                f.inner = Inner::Block(BlockFactor::default());
            }
            if let Inner::Block(b) = &mut f.inner {
                self.band.factor_into(&options, b)?;
            }
        } else {
            if !matches!(f.inner, Inner::Scalar(_)) {
                f.inner = Inner::Scalar(SymBandFactor::default());
            }
            if let Inner::Scalar(sf) = &mut f.inner {
                self.band.scalar().factor_into(&options, sf)?;
            }
        }
        if any_fixed {
            self.fixed_couplings_into(&mut f.fixed_couplings);
        }
        (f.n, f.dim) = (self.len(), self.dim());
        Ok(())
    }

    /// The couplings K_{free, fixed} that the elimination moves to the right-hand side: per
    /// free neighbour g (within two steps) of a fixed vertex f, the d×d block K_gf (row-major).
    fn fixed_couplings_into(&self, out: &mut Couplings) {
        let (n, d) = (self.len(), self.dim());
        let closed = self.topology == Topology::Closed;
        out.clear();
        let mut blk = vec![0.0; d * d];
        for f in (0..n).filter(|&f| self.fixed[f]) {
            // The vertices within two steps of f; on a small closed curve several steps name
            // the same vertex (and `get` sums the aliasing entries), so each is visited once.
            let near: [Option<usize>; 4] = if closed {
                [1, 2, n - 1, n - 2].map(|s| Some((f + s) % n))
            } else {
                [
                    f.checked_sub(2),
                    f.checked_sub(1),
                    (f + 1 < n).then_some(f + 1),
                    (f + 2 < n).then_some(f + 2),
                ]
            };
            for (k, g) in near.iter().enumerate() {
                let Some(g) = *g else { continue };
                if g == f || self.fixed[g] || near[..k].contains(&Some(g)) {
                    continue;
                }
                if self.band.get(g, f, &mut blk).is_ok() && blk.iter().any(|&v| v != 0.0) {
                    out.pairs.push((g, f));
                    out.blocks.extend_from_slice(&blk);
                }
            }
        }
    }
}

/// A factorization of a [`System`], reusable for any number of right-hand sides.
#[derive(Clone, Debug)]
pub struct Factor {
    n: usize,
    dim: usize,
    inner: Inner,
    /// Couplings between a free and a fixed vertex.
    fixed_couplings: Couplings,
}

/// The couplings K_{free, fixed}: the pairs (free, fixed) and their d×d blocks, flat (one
/// allocation, not one per pair: a solve with every data vertex fixed has 4n of them per
/// factorization).
#[derive(Clone, Debug, Default)]
struct Couplings {
    pairs: Vec<(usize, usize)>,
    blocks: Vec<f64>,
}

impl Couplings {
    /// No couplings, the storage kept.
    fn clear(&mut self) {
        self.pairs.clear();
        self.blocks.clear();
    }
}

#[derive(Clone, Debug)]
enum Inner {
    /// No coupling blocks: the scalar LDLᵀ, applied to the d columns at once.
    Scalar(SymBandFactor<2>),
    /// The block Cholesky factor.
    Block(BlockFactor<2>),
}

impl Factor {
    /// A factor of no system (every solve reports [`Error::WrongLength`]), for
    /// [`System::factor_into`] to fill.
    pub fn empty() -> Factor {
        Factor {
            n: 0,
            dim: 0,
            inner: Inner::Block(BlockFactor::default()),
            fixed_couplings: Couplings::default(),
        }
    }

    /// Solves K x = b. Rows of fixed vertices in `rhs` hold their prescribed *values* (copied to
    /// x); the other rows hold b.
    ///
    /// # Errors
    /// [`Error::WrongLength`] if `rhs` is not N points of dimension d.
    pub fn solve(&self, rhs: &Points) -> Result<Points, Error> {
        let mut x = rhs.clone();
        self.solve_in_place(&mut x)?;
        Ok(x)
    }

    /// [`solve`](Factor::solve) overwriting `x` (which holds the right-hand side on entry).
    ///
    /// # Errors
    /// [`Error::WrongLength`] if `x` is not N points of dimension d.
    pub fn solve_in_place(&self, x: &mut Points) -> Result<(), Error> {
        if x.dim() != self.dim || x.len() != self.n {
            return Err(Error::WrongLength {
                field: "rhs",
                expected: self.n * self.dim,
                got: x.len() * x.dim(),
            });
        }
        self.solve_slice(x.coords_mut())
    }

    /// Solves K x = b for a flat vertex-major right-hand side of length N·d, in place.
    ///
    /// # Errors
    /// [`Error::WrongLength`] if the length is not N·d.
    pub fn solve_flat(&self, x: &mut [f64]) -> Result<(), Error> {
        if x.len() != self.n * self.dim {
            return Err(Error::WrongLength {
                field: "rhs",
                expected: self.n * self.dim,
                got: x.len(),
            });
        }
        self.solve_slice(x)
    }

    /// Solves in place on a flat vertex-major slice of length N·d (checked by the callers):
    /// b_free −= K_free,fixed x_fixed, then the eliminated system.
    fn solve_slice(&self, x: &mut [f64]) -> Result<(), Error> {
        let d = self.dim;
        let cp = &self.fixed_couplings;
        for (&(g, f), k) in cp.pairs.iter().zip(cp.blocks.chunks_exact(d * d)) {
            // (A direction's fixed vertices are 0: nothing to move.)
            if x[f * d..(f + 1) * d].iter().all(|&v| v == 0.0) {
                continue;
            }
            for r in 0..d {
                let s: f64 = (0..d).map(|c| k[r * d + c] * x[f * d + c]).sum();
                x[g * d + r] -= s;
            }
        }
        match &self.inner {
            Inner::Scalar(f) => f.solve_in_place(x, d)?,
            Inner::Block(f) => f.solve_in_place(x, 1)?,
        }
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
/// [`Error::WrongLength`] if `values` does not have one point per fixed index,
/// [`Error::IndexOutOfRange`] for an index ≥ N, [`Error::DuplicateFixed`] for an index given
/// twice, [`Error::Singular`] if the fixed set does not determine the curve (a closed curve with
/// nothing fixed, an open curve with fewer than two fixed vertices).
pub fn solve_interpolatory(h: &Hessian, fixed: &[usize], values: &Points) -> Result<Points, Error> {
    if values.len() != fixed.len() {
        return Err(Error::WrongLength {
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
