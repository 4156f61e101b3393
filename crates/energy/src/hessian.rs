//! The α coefficients of Kersey §2.1 and the banded Hessian H = AᵀA of E(f) = ½ pᵀHp.

use divdiff::{Knots, Points, Topology};

use crate::Error;
use banded::vector::dot;

/// The α coefficients of Kersey §2.1 (the rows of A), one row per vertex.
///
/// `alphas(knots)[i] = [α_{i,1}, α_{i,2}, α_{i,3}]` are the entries of row `i` of A on the columns
/// i − 1, i, i + 1 (indices wrap modulo N for closed curves):
///
/// α_{i,1} = √2 / (h_{i−1} √(h_{i−1} + h_i)),  α_{i,3} = √2 / (h_i √(h_{i−1} + h_i)),
/// α_{i,2} = −α_{i,1} − α_{i,3},
///
/// so that (Ap)_i = √2 √h_{i−1,2} Δ_{i−1,2} f and ½|Ap|² is the energy (2.1).
///
/// Closed curves use the periodic extension h_{−1} = h_{N−1} (the paper's h_0 = h_n), which is
/// what the definition of E needs; the printed shortcut α_{1,1} := α_{n,3} agrees with it only on
/// uniform knots. Open curves (Kersey §3.6) have zero first and last rows: the second difference
/// centred at an end vertex does not exist.
///
/// ```
/// use divdiff::Knots;
/// let a = energy::alphas(&Knots::open(vec![0.0, 1.0, 2.0]).unwrap());
/// // Uniform spacing 1: the middle row is (1, −2, 1).
/// assert!((a[1][0] - 1.0).abs() < 1e-15 && (a[1][1] + 2.0).abs() < 1e-15);
/// assert!(a[0].iter().chain(&a[2]).all(|&x| x == 0.0));
/// ```
pub fn alphas(knots: &Knots) -> Vec<[f64; 3]> {
    let mut a = vec![[0.0; 3]; knots.vertex_count()];
    for_each_row(knots, |i, row| a[i] = row);
    a
}

/// The row α of vertex i from the spans h_{i−1} (left) and h_i (right), as in [`alphas`].
#[inline(always)]
fn alpha_row(hl: f64, hr: f64) -> [f64; 3] {
    let root = (2.0 / (hl + hr)).sqrt();
    let a1 = root / hl;
    let a3 = root / hr;
    [a1, -a1 - a3, a3]
}

/// Calls `f(i, α_i)` for every interior row i of [`interior_rows`] in increasing order, the span
/// lengths read from the knot values directly (h_j = t_{j+1} − t_j, as [`Knots::h`], whose
/// periodic index reduction costs an integer division per call).
#[inline(always)]
fn for_each_row(knots: &Knots, mut f: impl FnMut(usize, [f64; 3])) {
    let t = knots.values();
    let n = knots.vertex_count();
    match knots.topology() {
        Topology::Open => {
            for (k, w) in t.windows(3).enumerate() {
                f(k + 1, alpha_row(w[1] - w[0], w[2] - w[1]));
            }
        }
        Topology::Closed if n == 0 => {}
        Topology::Closed => {
            // t has N + 1 values (t_N = t_0 + T): h_{−1} = h_{N−1}.
            f(0, alpha_row(t[n] - t[n - 1], t[1] - t[0]));
            for (k, w) in t.windows(3).enumerate() {
                f(k + 1, alpha_row(w[1] - w[0], w[2] - w[1]));
            }
        }
    }
}

/// The three bands of H = AᵀA summed row by row ([`Hessian::new`], [`Hessian::from_alphas`]).
struct Bands {
    diag: Vec<f64>,
    off1: Vec<f64>,
    off2: Vec<f64>,
}

impl Bands {
    fn zeros(n: usize) -> Bands {
        Bands {
            diag: vec![0.0; n],
            off1: vec![0.0; n],
            off2: vec![0.0; n],
        }
    }

    /// Adds row i = (a0, a1, a2) of A: it touches columns l = i − 1, i, r = i + 1 (mod N for
    /// closed curves; an open curve's non-zero rows are interior, so no wrap is needed there).
    /// Rows are added in increasing order, as `alphas` gives them: every entry sums its terms in
    /// that order.
    #[inline(always)]
    fn add(&mut self, i: usize, [a0, a1, a2]: [f64; 3]) {
        let n = self.diag.len();
        let l = if i == 0 { n - 1 } else { i - 1 };
        let r = if i + 1 == n { 0 } else { i + 1 };
        self.diag[l] += a0 * a0;
        self.diag[i] += a1 * a1;
        self.diag[r] += a2 * a2;
        self.off1[l] += a0 * a1; // entry (i − 1, i)
        self.off1[i] += a1 * a2; // entry (i, i + 1)
        self.off2[l] += a0 * a2; // entry (i − 1, i + 1)
    }

    fn into_hessian(self, topology: Topology) -> Hessian {
        Hessian {
            topology,
            diag: self.diag,
            off1: self.off1,
            off2: self.off2,
        }
    }
}

/// The Hessian H = AᵀA of Kersey's energy E(f) = ½ pᵀHp (Kersey (2.1), §3.6), stored as three bands.
///
/// H is symmetric positive semidefinite; pentadiagonal for open curves, cyclic pentadiagonal for
/// closed ones. Its kernel is the constants (closed, dimension 1) or the linear polynomials in t
/// (open, dimension 2). The same H acts on every coordinate column of R^d data.
#[derive(Clone, Debug, PartialEq)]
pub struct Hessian {
    topology: Topology,
    diag: Vec<f64>,
    off1: Vec<f64>,
    off2: Vec<f64>,
}

impl Hessian {
    /// Assembles H = AᵀA from the rows of [`alphas`], in O(N).
    ///
    /// ```
    /// use divdiff::Knots;
    /// use energy::Hessian;
    /// // Uniform open knots of spacing 1 and 5 vertices: H = D₂ᵀD₂ (Warren–Weimer E_0).
    /// let h = Hessian::new(&Knots::open(vec![0.0, 1.0, 2.0, 3.0, 4.0]).unwrap());
    /// let (d, o1, o2) = h.bands();
    /// assert!((d[2] - 6.0).abs() < 1e-12 && (o1[1] + 4.0).abs() < 1e-12 && (o2[0] - 1.0).abs() < 1e-12);
    /// ```
    pub fn new(knots: &Knots) -> Hessian {
        let mut bands = Bands::zeros(knots.vertex_count());
        for_each_row(knots, |i, row| bands.add(i, row));
        bands.into_hessian(knots.topology())
    }

    /// H = AᵀA from the rows of A already formed, one per vertex as [`alphas`] gives them: the
    /// bands of [`Hessian::new`] on the knots the rows came from, bit for bit (an open curve's
    /// zero end rows are skipped, as there), without forming the rows again.
    ///
    /// ```
    /// use divdiff::Knots;
    /// use energy::{alphas, Hessian};
    /// let knots = Knots::open(vec![0.0, 0.5, 2.0, 2.25, 4.0]).unwrap();
    /// let h = Hessian::from_alphas(knots.topology(), &alphas(&knots));
    /// assert_eq!(h, Hessian::new(&knots));
    /// ```
    pub fn from_alphas(topology: Topology, rows: &[[f64; 3]]) -> Hessian {
        let n = rows.len();
        let mut bands = Bands::zeros(n);
        for (i, &row) in rows.iter().enumerate() {
            if topology == Topology::Closed || (i > 0 && i + 1 < n) {
                bands.add(i, row);
            }
        }
        bands.into_hessian(topology)
    }

    /// Open or closed.
    pub fn topology(&self) -> Topology {
        self.topology
    }

    /// The number N of vertices (H is N×N).
    pub fn len(&self) -> usize {
        self.diag.len()
    }

    /// Whether H is empty (never, for valid knots).
    pub fn is_empty(&self) -> bool {
        self.diag.is_empty()
    }

    /// The bands `(diag, off1, off2)`, each of length N:
    ///
    /// H = Σ_j diag\[j\] e_j e_jᵀ + off1\[j\] (e_j e_{j+1}ᵀ + e_{j+1} e_jᵀ) + off2\[j\] (e_j e_{j+2}ᵀ + e_{j+2} e_jᵀ),
    ///
    /// with indices modulo N for closed curves — so for N = 3 or 4 different bands alias the same
    /// entry and their contributions ADD. For open curves off1\[N−1\] = off2\[N−2\] = off2\[N−1\] = 0.
    pub fn bands(&self) -> (&[f64], &[f64], &[f64]) {
        (&self.diag, &self.off1, &self.off2)
    }

    /// The bands of [`Hessian::bands`], moved out (`(diag, off1, off2)`), e.g. for
    /// [`crate::System::from_bands`] without a copy.
    pub fn into_bands(self) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        (self.diag, self.off1, self.off2)
    }

    /// Hp, applied to each coordinate column of `p`, in O(N d).
    ///
    /// # Panics
    /// If `p.len() != self.len()`; see [`Hessian::try_apply`] for the checked version.
    pub fn apply(&self, p: &Points) -> Points {
        match self.try_apply(p) {
            Ok(y) => y,
            Err(e) => panic!("Hessian::apply: {e}"),
        }
    }

    /// Hp, applied to each coordinate column of `p`, in O(N d).
    ///
    /// # Errors
    /// [`Error::WrongLength`] if `p` does not have one point per vertex.
    pub fn try_apply(&self, p: &Points) -> Result<Points, Error> {
        let n = self.len();
        if p.len() != n {
            return Err(Error::WrongLength {
                field: "points",
                expected: n,
                got: p.len(),
            });
        }
        let d = p.dim();
        let x = p.coords();
        let mut y = vec![0.0; n * d];
        let closed = self.topology == Topology::Closed;
        // Adds w·x[from] to y[to] for every coordinate.
        let mut add = |to: usize, from: usize, w: f64| {
            for c in 0..d {
                y[to * d + c] += w * x[from * d + c];
            }
        };
        for j in 0..n {
            add(j, j, self.diag[j]);
            for (k, band) in [(1, &self.off1), (2, &self.off2)] {
                let w = band[j];
                let m = j + k;
                let m = if closed {
                    m % n
                } else if m < n {
                    m
                } else {
                    continue;
                };
                add(j, m, w);
                add(m, j, w);
            }
        }
        // Overflow to infinity is reported (as a divdiff NonFinite error), not returned.
        Ok(Points::new(d, y)?)
    }

    /// The energy ½ pᵀHp, summed over the coordinates.
    ///
    /// # Errors
    /// [`Error::WrongLength`] if `p` does not have one point per vertex.
    pub fn energy(&self, p: &Points) -> Result<f64, Error> {
        let hp = self.try_apply(p)?;
        Ok(0.5 * dot(p.coords(), hp.coords()))
    }

    /// The largest absolute band entry, a scale for tolerances: ‖H‖₂ ≤ 5·`max_abs()`, since each
    /// row of H sums at most five band entries (also when bands alias for N = 3, 4).
    pub fn max_abs(&self) -> f64 {
        self.diag
            .iter()
            .chain(&self.off1)
            .chain(&self.off2)
            .fold(0.0, |m, x| m.max(x.abs()))
    }
}

/// The rows of A that may be non-zero: all N for closed curves, 1..N−1 for open ones.
pub(crate) fn interior_rows(knots: &Knots) -> std::ops::Range<usize> {
    let n = knots.vertex_count();
    match knots.topology() {
        Topology::Closed => 0..n,
        Topology::Open => 1..n.saturating_sub(1),
    }
}
