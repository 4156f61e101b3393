//! The Clarabel backend (feature `clarabel`): the same conic program handed to Clarabel
//! (Goulart & Chen 2024: an interior-point method on the quasi-definite KKT system with a sparse
//! LDLᵀ), and its answer certified by this crate's own residuals.
//!
//! A [`KktSystem`] that can write its matrices out implements [`Sparse`]. The exported program
//! may carry auxiliary variables after the backend's n and auxiliary rows after its m (e.g. the
//! factored energy z = A x with P = I on z, which Clarabel solves where P = AᵀA itself stalls on
//! its condition number); the solution keeps the first n entries of x and the first m of s and z.

use ::clarabel::algebra::CscMatrix;
use ::clarabel::solver::{
    DefaultSettingsBuilder, DefaultSolver, IPSolver, SolverStatus, SupportedConeT,
};

use crate::cone::Cone;
use crate::ipm::{certify, floors, Solution, Status};
use crate::{Error, KktSystem};

/// A sparse matrix as coordinate triplets; repeated (row, column) pairs add.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Triplets {
    /// Row indices.
    pub rows: Vec<usize>,
    /// Column indices.
    pub cols: Vec<usize>,
    /// Values.
    pub vals: Vec<f64>,
}

impl Triplets {
    /// Appends the entry (row, col, val).
    pub fn push(&mut self, row: usize, col: usize, val: f64) {
        self.rows.push(row);
        self.cols.push(col);
        self.vals.push(val);
    }
}

/// minimize ½xᵀPx + qᵀx s.t. b − Ax ∈ K with P, A sparse (P: both triangles or the upper one;
/// entries below the diagonal are dropped).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SparseProgram {
    /// The number of variables (the backend's n, then any auxiliary ones).
    pub n: usize,
    /// P.
    pub p: Triplets,
    /// q.
    pub q: Vec<f64>,
    /// A (rows: the backend's m, then any auxiliary ones).
    pub a: Triplets,
    /// b.
    pub b: Vec<f64>,
    /// The cones of all rows, in order.
    pub cones: Vec<Cone>,
}

/// A problem that can export itself as a [`SparseProgram`].
pub trait Sparse {
    /// The program (module docs for auxiliary variables and rows).
    ///
    /// # Errors
    /// [`Error::Unsupported`] when the backend cannot write its matrices.
    fn sparse(&self) -> Result<SparseProgram, Error>;
}

/// Clarabel's settings used here.
#[derive(Clone, Debug, PartialEq)]
pub struct ClarabelOptions {
    /// Gap and feasibility tolerances (default 1e-10: Clarabel's 1e-8 is looser than the 1e-9
    /// certificate this workspace accepts).
    pub tolerance: f64,
    /// Iteration limit (default 200, Clarabel's).
    pub max_iterations: u32,
    /// Time limit in seconds (default none).
    pub time_limit: Option<f64>,
}

impl Default for ClarabelOptions {
    fn default() -> Self {
        ClarabelOptions {
            tolerance: 1e-10,
            max_iterations: 200,
            time_limit: None,
        }
    }
}

fn csc(t: &Triplets, m: usize, n: usize, upper: bool) -> CscMatrix<f64> {
    let mut cols: Vec<Vec<(usize, f64)>> = vec![Vec::new(); n];
    for ((&r, &c), &v) in t.rows.iter().zip(&t.cols).zip(&t.vals) {
        if v != 0.0 && (!upper || r <= c) {
            cols[c].push((r, v));
        }
    }
    let mut colptr = Vec::with_capacity(n + 1);
    colptr.push(0);
    let (mut rowval, mut nzval) = (Vec::new(), Vec::new());
    for mut col in cols {
        col.sort_by_key(|e| e.0);
        let mut last: Option<usize> = None;
        for (r, v) in col {
            if last == Some(r) {
                *nzval.last_mut().expect("an entry") += v;
            } else {
                rowval.push(r);
                nzval.push(v);
                last = Some(r);
            }
        }
        colptr.push(rowval.len());
    }
    CscMatrix::new(m, n, colptr, rowval, nzval)
}

/// Solves the program behind `kkt` with Clarabel and certifies the answer with this crate's
/// residuals ([`crate::Residuals`], independent of Clarabel's own stopping test).
/// [`Solution::iterations`] counts Clarabel's iterations; [`Status::Converged`] means status
/// `Solved`, [`Status::Stalled`] anything else (`AlmostSolved`, limits, infeasibility).
///
/// # Errors
/// As [`Sparse::sparse`]; [`Error::Unsupported`] when Clarabel refuses the data or settings.
pub fn solve<K: KktSystem + Sparse + ?Sized>(
    kkt: &mut K,
    options: &ClarabelOptions,
) -> Result<Solution, Error> {
    let prog = kkt.sparse()?;
    let (n, m) = (kkt.num_vars(), kkt.cones().rows());
    let rows = prog.b.len();
    let p = csc(&prog.p, prog.n, prog.n, true);
    let a = csc(&prog.a, rows, prog.n, false);
    let cones: Vec<SupportedConeT<f64>> = prog
        .cones
        .iter()
        .map(|c| match *c {
            Cone::Zero(d) => SupportedConeT::ZeroConeT(d),
            Cone::Nonnegative(d) => SupportedConeT::NonnegativeConeT(d),
            Cone::SecondOrder(d) => SupportedConeT::SecondOrderConeT(d),
        })
        .collect();
    let mut builder = DefaultSettingsBuilder::default();
    builder
        .verbose(false)
        .tol_gap_abs(options.tolerance)
        .tol_gap_rel(options.tolerance)
        .tol_feas(options.tolerance)
        .max_iter(options.max_iterations);
    if let Some(t) = options.time_limit {
        builder.time_limit(t);
    }
    let settings = builder.build().map_err(|_| Error::Unsupported {
        field: "clarabel",
        reason: "Clarabel refused the settings",
    })?;
    let mut solver =
        DefaultSolver::new(&p, &prog.q, &a, &prog.b, &cones, settings).map_err(|_| {
            Error::Unsupported {
                field: "clarabel",
                reason: "Clarabel refused the problem data",
            }
        })?;
    solver.solve();
    let sol = &solver.solution;
    let x = sol.x[..n].to_vec();
    let z = sol.z[..m].to_vec();
    let fl = floors(kkt);
    let (residuals, s, objective) = certify(kkt, &x, &z, fl);
    Ok(Solution {
        x,
        s,
        z,
        residuals,
        objective,
        iterations: sol.iterations as usize,
        status: if sol.status == SolverStatus::Solved {
            Status::Converged
        } else {
            Status::Stalled
        },
        polished: false,
    })
}

impl Sparse for crate::DenseProblem {
    fn sparse(&self) -> Result<SparseProgram, Error> {
        Ok(self.to_sparse())
    }
}
