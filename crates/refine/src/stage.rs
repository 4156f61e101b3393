//! One fixed-knot problem of a stage of Algorithm 4.1 and what a solver returns for it: the
//! types every solver module imports (this module imports none of them).

use divdiff::{Knots, Points};

use crate::certify::Certificate;
use crate::constraint::Constraint;
use crate::options::SolveOptions;
use crate::problem::Problem;

/// One fixed-knot problem: data `q` attached at `data_vertex` of a curve with `knots`, under
/// `constraint` (stage 0: the problem's; later stages: interpolation) and, in stage 0, the
/// problem's derivative constraints.
pub(crate) struct FixedProblem<'a> {
    pub knots: &'a Knots,
    pub q: &'a Points,
    pub data_vertex: &'a [usize],
    pub constraint: &'a Constraint,
    /// The problem (its derivative constraints apply when `derivatives` is set).
    pub problem: &'a Problem,
    /// Whether the problem's tangents and end conditions apply (stage 0).
    pub derivatives: bool,
    /// The data vertices are 0, stride, 2·stride, … (stride = k + 1).
    pub stride: usize,
    /// The knots are exactly the k-level split (3.1) of the data knots (each data span divided
    /// into `stride` equal sub-spans), so the closed forms of [`crate::uniform`] apply.
    pub uniform_spans: bool,
    /// The previous knot iteration's answer (its points and data multipliers): the condensed
    /// method first polishes from it, else starts its working set with the constraints active
    /// in it ([`crate::backend::working_set`]); `None`: no such answer.
    pub warm: Option<(&'a Points, &'a [Vec<f64>])>,
    /// The previous knot iteration's points when nothing reads them any more: a solve that
    /// writes every coordinate of its points may write them there instead of into memory the
    /// allocator zeroes first (the streaming interpolation of [`crate::fast`]: zeroing its
    /// 8·10⁵ points was ~7 % of the default three knot updates at n = 10⁵, k = 7). Empty:
    /// none.
    pub recycled: std::cell::Cell<Option<Points>>,
    /// The tuning of the solvers.
    pub options: &'a SolveOptions,
}

impl FixedProblem<'_> {
    /// The kinds of this stage: the data constraint, and the derivative constraints in stage 0.
    pub(crate) fn kinds(&self) -> Vec<Box<dyn crate::constraint::Kind + '_>> {
        let mut out = vec![self.constraint.kind()];
        if self.derivatives {
            out.extend(self.problem.kinds().into_iter().skip(1));
        }
        out
    }

    /// Whether a derivative constraint applies.
    pub(crate) fn has_derivatives(&self) -> bool {
        self.kinds().iter().any(|k| k.on_derivatives())
    }
}

/// What one fixed-knot solve returns.
pub(crate) struct FixedSolution {
    pub points: Points,
    /// The data constraint's multipliers (one entry per data point, in the convention of
    /// [`crate::Refinement::multipliers`]); `None`: the reactions −(Hp)_{i_k} of interpolation,
    /// filled in by the certificate.
    pub multipliers: Option<Vec<Vec<f64>>>,
    /// Inner iterations (interior-point iterations, multiplier updates; 1 per linear solve).
    pub iterations: usize,
    /// The derivative constraints' (cone dual, force), in the order of their rows.
    pub derivative: Vec<(Vec<f64>, Vec<f64>)>,
    /// The certificate of exactly these points and multipliers, when the solver already
    /// computed it to accept them (and the multipliers it reports).
    pub certificate: Option<(Certificate, crate::Multipliers)>,
}

impl FixedSolution {
    /// A solution with nothing but its points, multipliers and iteration count.
    pub(crate) fn new(
        points: Points,
        multipliers: Option<Vec<Vec<f64>>>,
        iterations: usize,
    ) -> Self {
        FixedSolution {
            points,
            multipliers,
            iterations,
            derivative: Vec::new(),
            certificate: None,
        }
    }
}
