//! The vocabulary of `strip`: the problem, its bounds and options, and the solution.

/// Which bound.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Side {
    /// The lower bound e.
    Lower,
    /// The upper bound d.
    Upper,
}

impl std::fmt::Display for Side {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Side::Lower => "lower",
            Side::Upper => "upper",
        })
    }
}

impl Side {
    pub(crate) fn other(self) -> Side {
        match self {
            Side::Lower => Side::Upper,
            Side::Upper => Side::Lower,
        }
    }
}

/// The candidate shape in one interval (Theorem 2.1).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Shape {
    /// Constraints inactive: one Hermite cubic.
    Free,
    /// One touching point on the given bound.
    Touch(Side),
    /// One subarc on the given bound.
    Subarc(Side),
    /// A touching pair: first the given bound, then the other.
    Pair(Side),
}

impl Shape {
    pub(crate) fn unknowns(self) -> usize {
        match self {
            Shape::Free => 0,
            Shape::Touch(_) => 1,
            Shape::Subarc(_) | Shape::Pair(_) => 2,
        }
    }
    pub(crate) const ALL: [Shape; 7] = [
        Shape::Free,
        Shape::Touch(Side::Lower),
        Shape::Touch(Side::Upper),
        Shape::Subarc(Side::Lower),
        Shape::Subarc(Side::Upper),
        Shape::Pair(Side::Lower),
        Shape::Pair(Side::Upper),
    ];
}

/// How much of the candidate enumeration is skipped.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Pruning {
    /// Every candidate is built; the feasible one of least energy wins.
    None,
    /// The seed's §3 rules: a feasible inactive candidate is the answer; if a touching-point or
    /// subarc candidate is feasible, touching pairs are not examined.
    Seed,
    /// Stop at the first feasible candidate that carries the optimality certificate (f''' jumps
    /// with the right sign at every contact). Default: provably the same answer, fastest.
    #[default]
    Certificate,
}

/// A bound of the strip.
#[derive(Clone, Debug, PartialEq, Default)]
pub enum Bound {
    /// No bound on this side.
    #[default]
    None,
    /// One cubic per data interval \[t_i, t_{i+1}\]: c0 + c1 s + c2 s² + c3 s³ in s = t − t_i
    /// (linear bounds have c2 = c3 = 0; bounds may jump at the data sites).
    Pieces(Vec<[f64; 4]>),
    /// A continuous polyline (t, value), strictly increasing in t and covering \[t_1, t_n\];
    /// its vertices become extra grid points with free values (§4, problem (10)).
    Polyline(Vec<[f64; 2]>),
}

impl Bound {
    /// Piecewise-linear interpolation of a continuous function on `cells` equal cells of
    /// \[t0, t1\] — the approximations e_m, d_m of §4 (Theorem 4.1: as the grid refines, the
    /// solutions converge in W^{2,2}).
    pub fn from_fn(f: impl Fn(f64) -> f64, t0: f64, t1: f64, cells: usize) -> Bound {
        let m = cells.max(1);
        Bound::Polyline(
            (0..=m)
                .map(|k| {
                    let t = if k == m {
                        t1
                    } else {
                        t0 + (t1 - t0) * k as f64 / m as f64
                    };
                    [t, f(t)]
                })
                .collect(),
        )
    }
}

/// A strip-interpolation problem: minimize ∫f''² subject to f(t_i) = y_i, lower ≤ f ≤ upper.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Problem {
    /// Data sites t_1 < … < t_n.
    pub t: Vec<f64>,
    /// Data values y_i.
    pub y: Vec<f64>,
    /// Lower bound e.
    pub lower: Bound,
    /// Upper bound d.
    pub upper: Bound,
    /// Optional prescribed slopes f'(t_1), f'(t_n) (natural ends where `None`).
    pub end_slopes: [Option<f64>; 2],
}

impl Problem {
    /// The bound of `side` at x (the piece of the data interval holding x, the right one at a
    /// site); −∞ / +∞ where that side has none.
    pub(crate) fn bound_at(&self, side: Side, x: f64) -> f64 {
        self.on_bound(
            side,
            x,
            |infinite| infinite,
            |c, t0| crate::piece::cubic3(c, x - t0).0,
            |a, b| line_at(a, b, x),
        )
    }

    /// [`Problem::bound_at`] as its rounded value (the same) and the error of that rounding, to
    /// first order ([`crate::compensated`]: of the piece's Horner scheme or the polyline's
    /// interpolation); ±∞ and 0 where a side is unbounded.
    pub(crate) fn bound_at_compensated(&self, side: Side, x: f64) -> (f64, f64) {
        self.on_bound(
            side,
            x,
            |infinite| (infinite, 0.0),
            |c, t0| crate::compensated::cubic(c, t0, x),
            |a, b| crate::compensated::line(a, b, x),
        )
    }

    /// The cubic piece of `side`'s bound that holds x, with the data site it is written about
    /// (s = t − t_i); `None` where that side is a polyline or unbounded.
    pub(crate) fn bound_piece(&self, side: Side, x: f64) -> Option<([f64; 4], f64)> {
        self.on_bound(side, x, |_| None, |c, t0| Some((*c, t0)), |_, _| None)
    }

    /// What evaluates the bound of `side` at x: `none` with ±∞ where it has none, `piece` with
    /// the cubic of the data interval holding x and that interval's start, `segment` with the
    /// ends of the polyline's segment there.
    fn on_bound<T>(
        &self,
        side: Side,
        x: f64,
        none: impl FnOnce(f64) -> T,
        piece: impl FnOnce(&[f64; 4], f64) -> T,
        segment: impl FnOnce([f64; 2], [f64; 2]) -> T,
    ) -> T {
        let b = if side == Side::Lower {
            &self.lower
        } else {
            &self.upper
        };
        match b {
            Bound::None => none(if side == Side::Lower {
                f64::NEG_INFINITY
            } else {
                f64::INFINITY
            }),
            Bound::Pieces(p) => {
                let n = self.t.len();
                let i = self.t.partition_point(|v| *v <= x).clamp(1, n - 1) - 1;
                piece(&p[i], self.t[i])
            }
            Bound::Polyline(v) => {
                let k = polyline_segment(v, x);
                segment(v[k - 1], v[k])
            }
        }
    }
}

/// The outer minimization method.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Method {
    /// Newton's method on the tridiagonal Hessian of Φ (implicitly differentiated per cell), with
    /// a backtracking line search; O(n) per iteration. Default. Polyline bounds are solved by the
    /// exchange whatever the method (see the crate documentation).
    #[default]
    Newton,
    /// argmin's BFGS with a Moré–Thuente line search, as in the seed (dense n×n inverse Hessian:
    /// for small n; cubic pieces only — polyline bounds with BFGS are refused). It stops when Φ
    /// no longer changes, with f'' still jumping at the sites by ~1e-8 of its size; Newton's
    /// method then finishes the jumps to rounding from its point (same iteration limit).
    Bfgs,
}

/// Default iteration limit of Newton's method (then the exchange takes over) or BFGS.
pub const DEFAULT_MAX_ITERATIONS: usize = 200;
/// Default gradient tolerance of Newton's method on Φ: stop when ‖∇Φ‖∞ ≤ tol · 2 max|f''| (each
/// component ∂Φ/∂z_i = 2(f''(t_i−) − f''(t_i+)) is twice the f'' jump at a data site, so this is
/// the C² defect relative to the size of f''), in the normalized frame of [`solve()`](crate::solve()).
/// The default asks for the rounding level itself ([`C2_ROUNDING`]): Newton's method then runs
/// until a full step no longer reduces the jumps. An answer is accepted only when its jumps are
/// at their rounding level, whatever this tolerance (see [`C2_ROUNDING`]).
pub const DEFAULT_GRADIENT_TOL: f64 = C2_ROUNDING;
/// The rounding level of an f'' jump, relative to the terms it is computed from. At a break b
/// (a data site or an extra knot) f'' is computed from each side from the Hermite data of the
/// piece there (values v₀, v₁ and slopes m₀, m₁ at its ends, length L):
/// f''(b+) = (6(v₁ − v₀)/L − 4m₀ − 2m₁)/L. Each datum is a floating-point number, known to a
/// relative u = 2⁻⁵³ at best (the data, a bound evaluated at a contact, a slope), and the formula
/// adds a rounding of u per operation on terms of the same size, so a computed f''(b±) is only
/// determined to about 8u·R± with R = (6(|v₀| + |v₁|)/L + 4|m₀| + 2|m₁|)/L (the magnitudes of
/// its terms), and the jump to 8u·(R₋ + R₊). The jump is *C² to rounding* when
/// |f''(b−) − f''(b+)| ≤ `C2_ROUNDING` · (max|f''| + R₋ + R₊), `C2_ROUNDING` = 8u = 4ε; the
/// max|f''| term covers the scaling and summation of the two sides (a few u of max|f''|). For
/// pieces of unit order R is of the order of max|f''| and the test asks for ~1e-15 relative; a
/// piece of length L next to a contact close to a site (Remark 4.2's margin ε puts a contact
/// ~√ε from a shifted site) is resolved only to u·|v|/L², and the test allows that much.
/// Answers of Newton on Φ are returned only when every jump passes this test and the gap is at
/// most 1e-9; the exchange's splines share one f'' value (moment) per knot, so they are C² by
/// construction.
pub const C2_ROUNDING: f64 = 4.0 * f64::EPSILON;
/// Default margin ε of Remark 4.2, relative to the local strip width: data on a bound are moved
/// inside by ε·width.
pub const DEFAULT_BOUNDARY_MARGIN: f64 = 1e-7;
/// Feasibility tolerance of a candidate in an interval, relative to the value scale V (the
/// largest deviation of the data, the end slopes or the bounds from the line through the first
/// and last data point; see the crate documentation).
pub const FEASIBILITY_TOL: f64 = 1e-10;
/// The returned pieces satisfy the strip to this fraction of the value scale V, plus the
/// rounding allowance [`ROUNDING_TOL`] (checked exactly on every cubic piece in the caller's
/// frame; a larger violation is [`Error::StripViolated`](crate::Error::StripViolated)). Ten times [`FEASIBILITY_TOL`]: room
/// for the rounding of the map back from the normalized frame.
pub const RESULT_FEASIBILITY_TOL: f64 = 1e-9;
/// Rounding allowance of the returned pieces relative to the magnitude of the values
/// M = max|y_i| + |ℓ'|·(t_n − t_1) + V (ℓ the line through the first and last data point):
/// values of size M carry rounding errors of this order whatever the solver does. (The check
/// that the pieces join also allows this fraction of Σ|c_k|h^k + |f'|·|t|, the terms of each
/// end value and the rounding of its abscissa.)
pub const ROUNDING_TOL: f64 = 1e-14;
/// Relative tolerance of the f'' continuity equations solved for the extra knots.
pub const CONTACT_TOL: f64 = 1e-12;

/// Solver options.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Options {
    /// Outer method.
    pub method: Method,
    /// Candidate pruning in each interval (all choices give the same answer).
    pub pruning: Pruning,
    /// Maximum iterations of Newton's method or BFGS (see [`DEFAULT_MAX_ITERATIONS`]).
    pub max_iterations: usize,
    /// Gradient tolerance (see [`DEFAULT_GRADIENT_TOL`]).
    pub gradient_tol: f64,
    /// Margin ε (see [`DEFAULT_BOUNDARY_MARGIN`]).
    pub boundary_margin: f64,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            method: Method::Newton,
            pruning: Pruning::Certificate,
            max_iterations: DEFAULT_MAX_ITERATIONS,
            gradient_tol: DEFAULT_GRADIENT_TOL,
            boundary_margin: DEFAULT_BOUNDARY_MARGIN,
        }
    }
}

/// What an extra knot is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum KnotKind {
    /// A single touching point (f = bound, f' = bound').
    Touch(Side),
    /// Start of a subarc on the bound.
    SubarcStart(Side),
    /// End of a subarc on the bound.
    SubarcEnd(Side),
}

/// An extra knot of the solution.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExtraKnot {
    /// Where.
    pub t: f64,
    /// What.
    pub kind: KnotKind,
    /// The data interval \[t_i, t_{i+1}\] it lies in (i, 0-based).
    pub interval: usize,
}

/// The solution: an exact C² piecewise cubic.
#[derive(Clone, Debug, PartialEq)]
pub struct Solution {
    /// Breakpoints (data sites and extra knots), increasing.
    pub breaks: Vec<f64>,
    /// `coefficients[j]` = \[c0, c1, c2, c3\] of the cubic on \[breaks\[j\], breaks\[j+1\]\] in
    /// s = t − breaks\[j\].
    pub coefficients: Vec<[f64; 4]>,
    /// Slopes z_i = f'(t_i) at the data sites.
    pub slopes: Vec<f64>,
    /// The data sites (the grid of problem (5)).
    pub grid: Vec<f64>,
    /// f at the data sites (the data, except where Remark 4.2 moved a value inside).
    pub grid_values: Vec<f64>,
    /// The shape of the solution in each data interval (Theorem 2.1). For answers of the
    /// exchange (polyline bounds) only `Free` or `Touch` (the side of the first contact in the
    /// interval): the contacts are in [`Solution::extra_knots`].
    pub shapes: Vec<Shape>,
    /// The extra knots with their kinds, sorted by t. Answers of the exchange list every
    /// contact as a touching point (at a polyline vertex, inside a segment, or one of a run that
    /// holds f on a segment).
    pub extra_knots: Vec<ExtraKnot>,
    /// ∫ f''².
    pub energy: f64,
    /// ‖f''‖_{L²} = √energy.
    pub norm: f64,
    /// Final gradient norm ‖∇Φ‖₂ in the caller's units (∂Φ/∂z_i); 0 for answers of the
    /// exchange, whose multipliers all have the right sign.
    pub gradient_norm: f64,
    /// The estimated distance to the optimum in the units of ∫f''²: Newton's decrement
    /// ½ gᵀH⁻¹g (≈ Φ − min Φ, from above), or for the exchange, whose energy lies below the
    /// optimum, what holding every contact up by its remaining excursion would cost
    /// (2 Σ |f''' jump| × excursion, to first order). An answer formed again in the caller's
    /// frame (through its points, on its subarcs' bounds: [`crate::solve()`]) carries the
    /// latter, whichever method found it.
    pub newton_decrement: f64,
    /// The optimality gap: `newton_decrement` over ∫f''². At most 1e-9 for every answer (a larger
    /// gap is refused with [`Error::NotConverged`](crate::Error::NotConverged) carrying it); measured ≤ 5·10⁻¹¹ on the
    /// generator's channels.
    pub gap: f64,
    /// Sweeps of the exchange (1 for Newton or BFGS).
    pub rounds: usize,
    /// Newton or BFGS iterations, or dual steps of the exchange.
    pub iterations: usize,
    /// Per-interval solves (all iterations and line-search trials), or spline solves of the
    /// exchange.
    pub cell_solves: usize,
    /// Candidates examined in those solves (per-interval candidates, or points the exchange
    /// added).
    pub candidates: usize,
    /// Data points moved inside by the margin because they lay on a bound (Remark 4.2; cubic
    /// pieces only: polyline problems keep them on the bound).
    pub shifted_data: Vec<usize>,
    /// Data intervals whose chosen candidate lacks the optimality certificate (empty for linear
    /// bounds and for answers of the exchange; see [`Pruning::Certificate`]).
    pub uncertified: Vec<usize>,
    /// The largest violation of the strip by the returned pieces in the caller's units (exact
    /// extrema of every cubic piece; ≤ 0 when the pieces are inside, 0 without bounds). At most
    /// [`RESULT_FEASIBILITY_TOL`]·V + [`ROUNDING_TOL`]·M, else [`solve()`](crate::solve()) returns
    /// [`Error::StripViolated`](crate::Error::StripViolated).
    pub violation: f64,
}

impl Solution {
    fn locate(&self, t: f64) -> usize {
        let n = self.coefficients.len();
        match self.breaks.binary_search_by(|b| b.total_cmp(&t)) {
            Ok(j) => j.min(n - 1),
            Err(j) => j.saturating_sub(1).min(n - 1),
        }
    }
    /// The k-th derivative (k = 0..3) of f at t (clamped to the piece containing t; the right
    /// piece at a break).
    pub fn derivative(&self, t: f64, k: usize) -> f64 {
        let j = self.locate(t);
        let c = &self.coefficients[j];
        let s = t - self.breaks[j];
        match k {
            0 => c[0] + s * (c[1] + s * (c[2] + s * c[3])),
            1 => c[1] + s * (2.0 * c[2] + 3.0 * s * c[3]),
            2 => 2.0 * c[2] + 6.0 * s * c[3],
            3 => 6.0 * c[3],
            _ => 0.0,
        }
    }
    /// f(t).
    pub fn eval(&self, t: f64) -> f64 {
        self.derivative(t, 0)
    }
}

/// Largest magnitude accepted for any input number: squares and cubes of differences of such
/// numbers stay far from overflow, leaving room for badly spaced sites.
pub const MAX_MAGNITUDE: f64 = 1e100;

/// The value at t of a polyline (linear interpolation; constant extrapolation of the end
/// segments' lines outside its range).
pub(crate) fn polyline_at(p: &[[f64; 2]], t: f64) -> f64 {
    let k = polyline_segment(p, t);
    line_at(p[k - 1], p[k], t)
}

/// The line through a and b at t, a₁ + ((b₁ − a₁)(t − a₀))/(b₀ − a₀).
pub(crate) fn line_at(a: [f64; 2], b: [f64; 2], t: f64) -> f64 {
    a[1] + (b[1] - a[1]) * (t - a[0]) / (b[0] - a[0])
}

/// The segment \[p\[k − 1\], p\[k\]\] of a polyline that [`polyline_at`] evaluates at t.
fn polyline_segment(p: &[[f64; 2]], t: f64) -> usize {
    p.partition_point(|v| v[0] <= t).clamp(1, p.len() - 1)
}
