//! The (2m+2)-point n-ary interpolating rules of Khan et al. (seed 001, (3.13); math.md §3).

use divdiff::{Points, Topology};
use num_bigint::BigInt;
use num_rational::BigRational;

use crate::rational::{lagrange_weights, rational_to_f64};
use crate::Error;

/// Largest number of stencil points 2m + 2 accepted by [`NaryScheme::new`]. The weights grow
/// like binomial coefficients, so wider stencils are numerically useless in `f64` anyway.
pub const MAX_SCHEME_POINTS: usize = 32;

/// Largest arity n accepted by [`NaryScheme::new`].
pub const MAX_ARITY: usize = 64;

/// Largest number of output coordinates (points × dimension) one call of
/// [`NaryScheme::subdivide`] or [`NaryScheme::subdivide_grid`] may produce (8 GiB of `f64`).
pub const MAX_SUBDIVISION_COORDS: usize = 1 << 30;

/// The (2m+2)-point n-ary interpolating subdivision scheme (Khan et al., (3.13)):
///
/// p^{k+1}_{n i + a} = Σ_{j=−m}^{m+1} L_j(a/n) p^k_{i+j},  a = 0, …, n − 1,
///
/// where L_j is the Lagrange basis on the nodes −m, …, m+1. Residue a = 0 is the identity
/// (the scheme interpolates), and every rule reproduces polynomials of degree ≤ 2m + 1.
///
/// The weights are derived as exact rationals ([`NaryScheme::exact_rule`]) and rounded correctly
/// to `f64` ([`NaryScheme::rule`]). Away from the ends (and the seam of a closed polygon), for
/// d ≤ 3 and 2m + 2 ≤ 8, the kernel applies each pair of mirrored rules (residues a and n − a)
/// in the equivalent symmetric form Σ h⁺_j (p_j + p_{P−1−j}) ± h⁻_j (p_j − p_{P−1−j}), whose
/// coefficients h± = (w_a\[j\] ± w_a\[P−1−j\])/2 are likewise exact rationals rounded once; this halves
/// the multiplications, and the results agree with direct application of [`NaryScheme::rule`] to
/// a few ulps (tested against a direct reference).
///
/// **Open polygons.** Near the ends of an open polygon p_0..p_{N−1} the centred stencil would
/// need points that do not exist. There the new points of span [i, i+1] use the *one-sided*
/// stencil of the same width: the Lagrange interpolant through the 2m + 2 consecutive points
/// p_s..p_{s+2m+1} with s = min(max(i − m, 0), N − 2m − 2), evaluated at i + a/n
/// ([`NaryScheme::boundary_rule`] with t = i − s). This keeps reproduction of polynomials of
/// degree 2m + 1 up to the ends and keeps the end points fixed. A polygon with fewer than 2m + 2
/// points uses the interpolant through all of its N points (degree N − 1).
///
/// ```
/// use divdiff::{Points, Topology};
/// use subdivision::NaryScheme;
/// let four_point = NaryScheme::new(4, 2)?;
/// let w = four_point.rule(1);
/// assert!((w[0] + 1.0 / 16.0).abs() < 1e-16 && (w[1] - 9.0 / 16.0).abs() < 1e-16);
/// // One level on a closed square: 4 new points, the old ones kept.
/// let square = Points::from_rows(&[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])?;
/// let fine = four_point.subdivide(&square, Topology::Closed, 1)?;
/// assert_eq!(fine.len(), 8);
/// assert!((fine.point(1)[0] - 0.5).abs() < 1e-15 && (fine.point(1)[1] + 0.125).abs() < 1e-15);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Debug)]
pub struct NaryScheme {
    m: usize,
    arity: usize,
    /// `exact[t][a]`: the Lagrange basis on nodes 0..2m+1 evaluated at t + a/n, t = 0..=2m.
    /// The centred rule is t = m.
    exact: Vec<Vec<Vec<BigRational>>>,
    /// The same, correctly rounded, flat: index `(t * arity + a) * points + j`.
    floats: Vec<f64>,
    /// Symmetric form of the centred rules for the interior kernel, per residue a = 1..=n/2:
    /// half-sums (w_a[j] + w_a[P−1−j])/2 then half-differences (w_a[j] − w_a[P−1−j])/2,
    /// j < P/2, each exact then rounded (flat, `2 · (P/2)` entries per residue). The rule of
    /// residue n − a is the mirror of residue a's, so both come from the same sums and
    /// differences of mirrored points.
    symmetric: Vec<f64>,
}

/// The exact one-sided rules for `count` nodes: `[t][a]` is the Lagrange basis on the nodes
/// 0..count evaluated at t + a/n, for t = 0..count−1 (t = count − 1 only matters for a = 0).
fn rule_table(count: usize, arity: usize) -> Vec<Vec<Vec<BigRational>>> {
    (0..count.saturating_sub(1).max(1))
        .map(|t| {
            (0..arity)
                .map(|a| {
                    let x = BigRational::new(BigInt::from(t * arity + a), BigInt::from(arity));
                    lagrange_weights(0, count, &x)
                })
                .collect()
        })
        .collect()
}

fn flatten(table: &[Vec<Vec<BigRational>>]) -> Vec<f64> {
    table
        .iter()
        .flatten()
        .flatten()
        .map(rational_to_f64)
        .collect()
}

impl NaryScheme {
    /// The scheme with `points` = 2m + 2 stencil points and arity n = `arity`.
    ///
    /// # Errors
    /// [`Error::TooFew`] if `points` or `arity` is below 2, [`Error::InvalidValue`] if `points`
    /// is odd, [`Error::TooLarge`] if `points` exceeds [`MAX_SCHEME_POINTS`] or `arity`
    /// exceeds [`MAX_ARITY`].
    pub fn new(points: usize, arity: usize) -> Result<Self, Error> {
        if points < 2 {
            return Err(Error::TooFew {
                field: "points",
                minimum: 2,
                got: points,
            });
        }
        if !points.is_multiple_of(2) {
            return Err(Error::InvalidValue {
                field: "points",
                index: 0,
                reason: "the number of stencil points must be even (2m + 2)",
            });
        }
        if points > MAX_SCHEME_POINTS {
            return Err(Error::TooLarge {
                field: "points",
                limit: MAX_SCHEME_POINTS,
                got: points,
            });
        }
        check_arity(arity)?;
        let exact = rule_table(points, arity);
        let floats = flatten(&exact);
        let m = (points - 2) / 2;
        let half = BigRational::new(BigInt::from(1), BigInt::from(2));
        let mut symmetric = Vec::with_capacity(arity * points);
        for w in &exact[m][1..=arity / 2] {
            for j in 0..points / 2 {
                symmetric.push(rational_to_f64(&((&w[j] + &w[points - 1 - j]) * &half)));
            }
            for j in 0..points / 2 {
                symmetric.push(rational_to_f64(&((&w[j] - &w[points - 1 - j]) * &half)));
            }
        }
        Ok(NaryScheme {
            m,
            arity,
            exact,
            floats,
            symmetric,
        })
    }

    /// The stencil half-width m (the scheme has 2m + 2 points).
    pub fn m(&self) -> usize {
        self.m
    }

    /// The number of stencil points 2m + 2.
    pub fn points(&self) -> usize {
        2 * self.m + 2
    }

    /// The arity n: each level multiplies the number of spans by n.
    pub fn arity(&self) -> usize {
        self.arity
    }

    /// The offsets −m, …, m + 1 of the centred rule: weight l of [`NaryScheme::rule`] multiplies
    /// p^k_{i + offsets\[l\]}.
    pub fn offsets(&self) -> Vec<isize> {
        (-(self.m as isize)..=(self.m as isize + 1)).collect()
    }

    /// The exact centred rule for residue `a` (weights on p^k_{i−m}, …, p^k_{i+m+1}).
    ///
    /// # Panics
    /// If `a >= self.arity()`.
    pub fn exact_rule(&self, a: usize) -> &[BigRational] {
        &self.exact[self.m][a]
    }

    /// The centred rule for residue `a`, correctly rounded to `f64`.
    ///
    /// # Panics
    /// If `a >= self.arity()`.
    pub fn rule(&self, a: usize) -> &[f64] {
        let p = self.points();
        let start = (self.m * self.arity + a) * p;
        &self.floats[start..start + p]
    }

    /// The exact one-sided rule used near the ends of open polygons: the Lagrange basis on the
    /// nodes 0, …, 2m+1 evaluated at t + a/n, for t = 0, …, 2m (t = m is the centred rule).
    ///
    /// # Panics
    /// If `t > 2m` or `a >= self.arity()`.
    pub fn boundary_rule(&self, t: usize, a: usize) -> &[BigRational] {
        &self.exact[t][a]
    }

    /// Number of points after `levels` levels applied to `count` points, or `None` on overflow.
    pub fn refined_count(&self, count: usize, topology: Topology, levels: usize) -> Option<usize> {
        let mut c = count;
        for _ in 0..levels {
            c = match topology {
                Topology::Closed => c.checked_mul(self.arity)?,
                Topology::Open => c.checked_sub(1)?.checked_mul(self.arity)?.checked_add(1)?,
            };
        }
        Some(c)
    }

    /// Applies `levels` levels of the scheme to a closed (periodic) or open polygon in R^d.
    ///
    /// A closed polygon of N points becomes N n^levels points; an open one (N − 1) n^levels + 1
    /// (its end points are kept). Old points keep their positions: point i of level k is point
    /// n i of level k + 1.
    ///
    /// # Errors
    /// [`Error::TooFew`] (`points`) for fewer than 2 points, [`Error::TooLarge`] (`levels`) if
    /// the result would exceed [`MAX_SUBDIVISION_COORDS`] coordinates, [`Error::NonFinite`]
    /// (`points`) if the result overflows the `f64` range.
    pub fn subdivide(
        &self,
        points: &Points,
        topology: Topology,
        levels: usize,
    ) -> Result<Points, Error> {
        check_count(points.len())?;
        self.check_size(points.len(), points.dim(), topology, levels, "levels")?;
        let dim = points.dim();
        let mut current = points.coords().to_vec();
        let mut next = Vec::new();
        for _ in 0..levels {
            self.level_raw(dim, &current, topology, &mut next);
            std::mem::swap(&mut current, &mut next);
        }
        Points::new(dim, current).map_err(Error::from_output)
    }

    /// One level into a caller-owned buffer (resized as needed, so repeated calls of the same
    /// size do not allocate): `out` receives the refined points, vertex-major, dimension
    /// `points.dim()`.
    ///
    /// # Errors
    /// As [`NaryScheme::subdivide`] with one level (no finiteness check of the output).
    pub fn subdivide_level_into(
        &self,
        points: &Points,
        topology: Topology,
        out: &mut Vec<f64>,
    ) -> Result<(), Error> {
        check_count(points.len())?;
        self.check_size(points.len(), points.dim(), topology, 1, "levels")?;
        self.level_raw(points.dim(), points.coords(), topology, out);
        Ok(())
    }

    pub(crate) fn check_size(
        &self,
        count: usize,
        dim: usize,
        topology: Topology,
        levels: usize,
        field: &'static str,
    ) -> Result<usize, Error> {
        let sizes = self
            .refined_count(count, topology, levels)
            .and_then(|n| Some((n, n.checked_mul(dim)?)));
        match sizes {
            Some((n, coords)) if coords <= MAX_SUBDIVISION_COORDS => Ok(n),
            other => Err(Error::TooLarge {
                field,
                limit: MAX_SUBDIVISION_COORDS,
                got: other.map_or(usize::MAX, |(_, coords)| coords),
            }),
        }
    }

    /// One level on raw vertex-major coordinates (`coords.len()` a multiple of `dim`, at least
    /// 2 points — checked by the callers). `dim` may be large: the surface code refines whole
    /// grid rows as single "points".
    pub(crate) fn level_raw(
        &self,
        dim: usize,
        coords: &[f64],
        topology: Topology,
        out: &mut Vec<f64>,
    ) {
        let count = coords.len() / dim;
        match topology {
            Topology::Closed => {
                out.resize(count * self.arity * dim, 0.0);
                match dim {
                    1 => self.closed_level::<1>(1, coords, out),
                    2 => self.closed_level::<2>(2, coords, out),
                    3 => self.closed_level::<3>(3, coords, out),
                    _ => self.closed_level::<0>(dim, coords, out),
                }
            }
            Topology::Open => {
                out.resize(((count - 1) * self.arity + 1) * dim, 0.0);
                match dim {
                    1 => self.open_level::<1>(1, coords, out),
                    2 => self.open_level::<2>(2, coords, out),
                    3 => self.open_level::<3>(3, coords, out),
                    _ => self.open_level::<0>(dim, coords, out),
                }
            }
        }
    }

    /// The range of spans i whose centred stencil i−m..i+m+1 lies inside 0..count (no wrap,
    /// no end shift): i in m..count−m−1. Empty when the polygon is shorter than the stencil.
    fn interior_range(&self, count: usize) -> std::ops::Range<usize> {
        let m = self.m;
        if count > 2 * m + 1 {
            m..count - m - 1
        } else {
            0..0
        }
    }

    /// Interior spans by the fixed-size kernel when (dimension, stencil) is one of the common
    /// pairs, else by the general window kernel. Returns nothing; fills `out` blocks lo..hi.
    fn interior(&self, dim: usize, src: &[f64], out: &mut [f64], range: std::ops::Range<usize>) {
        let (n, p) = (self.arity, self.points());
        let rules = &self.floats[self.m * n * p..(self.m + 1) * n * p];
        macro_rules! fixed {
            ($(($d:literal, $p:literal)),*) => {
                match (dim, p) {
                    $(($d, $p) => interior_fixed::<$d, $p>(self.m, n, &self.symmetric, src, out, range),)*
                    _ => interior_general(dim, self.m, n, p, rules, src, out, range),
                }
            };
        }
        fixed!(
            (1, 2),
            (1, 4),
            (1, 6),
            (1, 8),
            (2, 2),
            (2, 4),
            (2, 6),
            (2, 8),
            (3, 2),
            (3, 4),
            (3, 6),
            (3, 8)
        );
    }

    fn closed_level<const D: usize>(&self, dim: usize, src: &[f64], out: &mut [f64]) {
        let count = src.len() / dim;
        let (m, n, p) = (self.m, self.arity, self.points());
        let rules = &self.floats[self.m * n * p..(self.m + 1) * n * p];
        let range = self.interior_range(count);
        self.interior(dim, src, out, range.clone());
        // The spans near the seam: periodic indices.
        let mut idx = vec![0usize; p];
        for i in (0..range.start).chain(range.end..count) {
            let block = &mut out[i * n * dim..(i + 1) * n * dim];
            let (first, rest) = block.split_at_mut(dim);
            first.copy_from_slice(&src[i * dim..(i + 1) * dim]);
            for (j, slot) in idx.iter_mut().enumerate() {
                *slot = (i + j + count * (m + 1) - m) % count;
            }
            for (a, dst) in rest.chunks_exact_mut(dim).enumerate() {
                combine_indexed::<D>(dim, &rules[(a + 1) * p..(a + 2) * p], src, &idx, dst);
            }
        }
    }

    fn open_level<const D: usize>(&self, dim: usize, src: &[f64], out: &mut [f64]) {
        let count = src.len() / dim;
        let n = self.arity;
        let short;
        // Stencil width and rule table: the scheme's own unless the polygon is shorter.
        let (p, table, range): (usize, &[f64], _) = if count >= self.points() {
            let range = self.interior_range(count);
            self.interior(dim, src, out, range.clone());
            (self.points(), &self.floats, range)
        } else {
            short = flatten(&rule_table(count, n));
            (count, &short, 0..0)
        };
        let m = (p - 2) / 2;
        // The spans near the ends: one-sided stencils shifted inside the polygon.
        for i in (0..range.start).chain(range.end.max(range.start)..count - 1) {
            let start = i.saturating_sub(m).min(count - p);
            let t = i - start;
            let window = &src[start * dim..(start + p) * dim];
            let block = &mut out[i * n * dim..(i + 1) * n * dim];
            let (first, rest) = block.split_at_mut(dim);
            first.copy_from_slice(&src[i * dim..(i + 1) * dim]);
            for (a, dst) in rest.chunks_exact_mut(dim).enumerate() {
                let r = (t * n + a + 1) * p;
                combine_window::<D>(dim, &table[r..r + p], window, dst);
            }
        }
        let last = (count - 1) * n * dim;
        out[last..last + dim].copy_from_slice(&src[(count - 1) * dim..]);
    }
}

/// Interior spans with compile-time dimension `D` and stencil width `P`: the loops unroll and
/// the bounds checks fold into one slice check per span. The rules are applied in symmetric form
/// (see `NaryScheme::symmetric`): with S_j = p_j + p_{P−1−j} and D_j = p_j − p_{P−1−j},
/// new_a = Σ hs_j S_j + hd_j D_j and new_{n−a} = Σ hs_j S_j − hd_j D_j, which halves the
/// multiplications (the mirror of residue a is residue n − a, by the symmetry of the nodes).
fn interior_fixed<const D: usize, const P: usize>(
    m: usize,
    n: usize,
    symmetric: &[f64],
    src: &[f64],
    out: &mut [f64],
    range: std::ops::Range<usize>,
) {
    let h = P / 2;
    let pairs: Vec<([f64; P], [f64; P])> = symmetric
        .chunks_exact(2 * h)
        .map(|c| {
            let (mut hs, mut hd) = ([0.0; P], [0.0; P]);
            hs[..h].copy_from_slice(&c[..h]);
            hd[..h].copy_from_slice(&c[h..]);
            (hs, hd)
        })
        .collect();
    let need_differences = n > 2;
    if range.is_empty() {
        return;
    }
    // Zipped iterators over the input windows and the output blocks: no per-span index
    // arithmetic, and each window is re-sliced to the constant length P·D so that the indexing
    // below needs no bounds checks.
    for i in range {
        let win = &src[(i - m) * D..];
        let block = &mut out[i * n * D..];
        let win = &win[..P * D];
        // Built element by element (no zero-fill, no memset/memcpy calls for these tiny arrays;
        // entries j ≥ P/2 are unused constants).
        let sum: [[f64; D]; P] = std::array::from_fn(|j| {
            std::array::from_fn(|c| {
                if j < h {
                    win[j * D + c] + win[(P - 1 - j) * D + c]
                } else {
                    0.0
                }
            })
        });
        let dif: [[f64; D]; P] = std::array::from_fn(|j| {
            std::array::from_fn(|c| {
                if need_differences && j < h {
                    win[j * D + c] - win[(P - 1 - j) * D + c]
                } else {
                    0.0
                }
            })
        });
        for c in 0..D {
            block[c] = win[m * D + c];
        }
        for (q, (hs, hd)) in pairs.iter().enumerate() {
            let (a, mirror) = (q + 1, n - q - 1);
            let mut u = [0.0f64; D];
            for j in 0..h {
                for c in 0..D {
                    u[c] += hs[j] * sum[j][c];
                }
            }
            if a == mirror {
                for c in 0..D {
                    block[a * D + c] = u[c];
                }
            } else {
                let mut v = [0.0f64; D];
                for j in 0..h {
                    for c in 0..D {
                        v[c] += hd[j] * dif[j][c];
                    }
                }
                for c in 0..D {
                    block[a * D + c] = u[c] + v[c];
                    block[mirror * D + c] = u[c] - v[c];
                }
            }
        }
    }
}

/// Interior spans for any dimension and stencil width.
#[allow(clippy::too_many_arguments)]
fn interior_general(
    dim: usize,
    m: usize,
    n: usize,
    p: usize,
    rules: &[f64],
    src: &[f64],
    out: &mut [f64],
    range: std::ops::Range<usize>,
) {
    for i in range {
        let window = &src[(i - m) * dim..(i + m + 2) * dim];
        let block = &mut out[i * n * dim..(i + 1) * n * dim];
        let (first, rest) = block.split_at_mut(dim);
        first.copy_from_slice(&src[i * dim..(i + 1) * dim]);
        for (a, dst) in rest.chunks_exact_mut(dim).enumerate() {
            combine_window::<0>(dim, &rules[(a + 1) * p..(a + 2) * p], window, dst);
        }
    }
}

/// The arity n must lie in 2..=[`MAX_ARITY`] (for schemes and masks alike).
pub(crate) fn check_arity(arity: usize) -> Result<(), Error> {
    if arity < 2 {
        return Err(Error::TooFew {
            field: "arity",
            minimum: 2,
            got: arity,
        });
    }
    if arity > MAX_ARITY {
        return Err(Error::TooLarge {
            field: "arity",
            limit: MAX_ARITY,
            got: arity,
        });
    }
    Ok(())
}

fn check_count(count: usize) -> Result<(), Error> {
    if count < 2 {
        return Err(Error::TooFew {
            field: "points",
            minimum: 2,
            got: count,
        });
    }
    Ok(())
}

/// dst = Σ_j w_j · window[j] (points of dimension `dim`; `D` = dim as a constant, or 0 for
/// a run-time dimension, where the sum is accumulated as axpy's over whole rows).
#[inline(always)]
fn combine_window<const D: usize>(dim: usize, w: &[f64], window: &[f64], dst: &mut [f64]) {
    if D > 0 {
        let mut acc = [0.0f64; D];
        for (&wj, q) in w.iter().zip(window.chunks_exact(D)) {
            for c in 0..D {
                acc[c] += wj * q[c];
            }
        }
        dst.copy_from_slice(&acc);
    } else {
        dst.fill(0.0);
        for (&wj, q) in w.iter().zip(window.chunks_exact(dim)) {
            for (d, &v) in dst.iter_mut().zip(q) {
                *d += wj * v;
            }
        }
    }
}

/// As [`combine_window`] with the stencil's points given by index (periodic wrap).
#[inline(always)]
fn combine_indexed<const D: usize>(
    dim: usize,
    w: &[f64],
    src: &[f64],
    idx: &[usize],
    dst: &mut [f64],
) {
    if D > 0 {
        let mut acc = [0.0f64; D];
        for (&wj, &k) in w.iter().zip(idx) {
            for c in 0..D {
                acc[c] += wj * src[k * D + c];
            }
        }
        dst.copy_from_slice(&acc);
    } else {
        dst.fill(0.0);
        for (&wj, &k) in w.iter().zip(idx) {
            for (d, &v) in dst.iter_mut().zip(&src[k * dim..(k + 1) * dim]) {
                *d += wj * v;
            }
        }
    }
}
