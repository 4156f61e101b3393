//! Tensor-product surfaces of the (2m+2)-point n-ary scheme on regular quad grids (Khan et al.
//! §4, (4.1)–(4.2)), and their output as an OBJ quad mesh.

use std::fmt::Write as _;

use divdiff::{Points, Topology};
use num_rational::BigRational;

use crate::nary::{NaryScheme, MAX_SUBDIVISION_COORDS};
use crate::Error;

/// A regular quad grid of `rows × cols` points in R^d, stored row-major: grid point (i, j) is
/// `points.point(i * cols + j)`. Each direction is open or closed (periodic): `closed_rows`
/// makes the row index i wrap (row `rows − 1` is joined to row 0), `closed_cols` the column
/// index j.
#[derive(Clone, Debug, PartialEq)]
pub struct QuadGrid {
    rows: usize,
    cols: usize,
    points: Points,
    closed_rows: bool,
    closed_cols: bool,
}

fn topology(closed: bool) -> Topology {
    if closed {
        Topology::Closed
    } else {
        Topology::Open
    }
}

impl QuadGrid {
    /// A grid from its points (row-major) and shape.
    ///
    /// # Errors
    /// [`Error::TooFew`] if `rows` or `cols` is below 2, [`Error::TooLarge`] (`rows`) if
    /// `rows × cols` overflows, [`Error::WrongLength`] (`points`) if
    /// `points.len() != rows * cols`.
    pub fn new(
        rows: usize,
        cols: usize,
        points: Points,
        closed_rows: bool,
        closed_cols: bool,
    ) -> Result<Self, Error> {
        for (field, value) in [("rows", rows), ("cols", cols)] {
            if value < 2 {
                return Err(Error::TooFew {
                    field,
                    minimum: 2,
                    got: value,
                });
            }
        }
        let expected = rows.checked_mul(cols).ok_or(Error::TooLarge {
            field: "rows",
            limit: usize::MAX / cols,
            got: rows,
        })?;
        if points.len() != expected {
            return Err(Error::WrongLength {
                field: "points",
                expected,
                got: points.len(),
            });
        }
        Ok(QuadGrid {
            rows,
            cols,
            points,
            closed_rows,
            closed_cols,
        })
    }

    /// Number of rows (range of the first index i).
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// Number of columns (range of the second index j).
    pub fn cols(&self) -> usize {
        self.cols
    }

    /// Whether the row index wraps (the surface is closed in the i direction).
    pub fn closed_rows(&self) -> bool {
        self.closed_rows
    }

    /// Whether the column index wraps (the surface is closed in the j direction).
    pub fn closed_cols(&self) -> bool {
        self.closed_cols
    }

    /// The grid points, row-major.
    pub fn points(&self) -> &Points {
        &self.points
    }

    /// Grid point (i, j).
    ///
    /// # Panics
    /// If `i >= rows` or `j >= cols`.
    pub fn point(&self, i: usize, j: usize) -> &[f64] {
        assert!(i < self.rows && j < self.cols, "grid index out of range");
        self.points.point(i * self.cols + j)
    }

    /// The quads of the mesh as 0-based point indices (i, j), (i, j+1), (i+1, j+1), (i+1, j),
    /// including the wrapping quads of closed directions.
    pub fn quads(&self) -> Vec<[usize; 4]> {
        let span_rows = if self.closed_rows {
            self.rows
        } else {
            self.rows - 1
        };
        let span_cols = if self.closed_cols {
            self.cols
        } else {
            self.cols - 1
        };
        let at = |i: usize, j: usize| (i % self.rows) * self.cols + (j % self.cols);
        let mut quads = Vec::with_capacity(span_rows * span_cols);
        for i in 0..span_rows {
            for j in 0..span_cols {
                quads.push([at(i, j), at(i, j + 1), at(i + 1, j + 1), at(i + 1, j)]);
            }
        }
        quads
    }
}

/// One two-dimensional rule of the tensor-product scheme (4.2):
/// p^{k+1}_{n i + a, n j + b} = Σ_l weights\[l\] · p^k_{i + offsets\[l\].0, j + offsets\[l\].1}.
#[derive(Clone, Debug, PartialEq)]
pub struct SurfaceRule {
    /// The residues (a, b).
    pub residue: (usize, usize),
    /// The offsets (r, s), r and s in −m..=m+1, row-major (r outer).
    pub offsets: Vec<(isize, isize)>,
    /// The exact weights: the products L_r(a/n) L_s(b/n) of the curve rules.
    pub weights: Vec<BigRational>,
}

impl NaryScheme {
    /// The n² two-dimensional masks of the tensor-product scheme (4.2), residues (a, b) in
    /// row-major order, each the outer product of the curve rules for a and b.
    pub fn surface_rules(&self) -> Vec<SurfaceRule> {
        let offsets = self.offsets();
        let mut rules = Vec::with_capacity(self.arity() * self.arity());
        for a in 0..self.arity() {
            for b in 0..self.arity() {
                let (wa, wb) = (self.exact_rule(a), self.exact_rule(b));
                let mut offs = Vec::with_capacity(wa.len() * wb.len());
                let mut weights = Vec::with_capacity(wa.len() * wb.len());
                for (r, x) in offsets.iter().zip(wa) {
                    for (s, y) in offsets.iter().zip(wb) {
                        offs.push((*r, *s));
                        weights.push(x * y);
                    }
                }
                rules.push(SurfaceRule {
                    residue: (a, b),
                    offsets: offs,
                    weights,
                });
            }
        }
        rules
    }

    /// Applies `levels` levels of the tensor-product scheme to a quad grid. Each direction is
    /// refined by the curve scheme (closed directions periodically, open directions with the
    /// one-sided end stencils of [`NaryScheme`]); the result equals applying the 2-D masks of
    /// [`NaryScheme::surface_rules`] in the interior.
    ///
    /// # Errors
    /// [`Error::TooLarge`] (`levels`) if the result would exceed [`MAX_SUBDIVISION_COORDS`]
    /// coordinates; [`Error::NonFinite`] (`points`) if it overflows the `f64` range.
    pub fn subdivide_grid(&self, grid: &QuadGrid, levels: usize) -> Result<QuadGrid, Error> {
        let (tr, tc) = (topology(grid.closed_rows), topology(grid.closed_cols));
        let dim = grid.points.dim();
        let new_rows = self.check_size(grid.rows, 1, tr, levels, "levels")?;
        let new_cols = self.check_size(grid.cols, 1, tc, levels, "levels")?;
        let total = new_rows
            .checked_mul(new_cols)
            .and_then(|c| c.checked_mul(dim))
            .unwrap_or(usize::MAX);
        if total > MAX_SUBDIVISION_COORDS {
            return Err(Error::TooLarge {
                field: "levels",
                limit: MAX_SUBDIVISION_COORDS,
                got: total,
            });
        }
        let (mut rows, mut cols) = (grid.rows, grid.cols);
        let mut current = grid.points.coords().to_vec();
        let mut along_cols = Vec::new();
        let mut row_out = Vec::new();
        let mut next = Vec::new();
        for _ in 0..levels {
            // Along j: each grid row is an R^d polygon of `cols` points.
            let cols2 = self.check_size(cols, 1, tc, 1, "levels")?;
            along_cols.clear();
            along_cols.reserve(rows * cols2 * dim);
            for row in current.chunks_exact(cols * dim) {
                self.level_raw(dim, row, tc, &mut row_out);
                along_cols.extend_from_slice(&row_out);
            }
            // Along i: a whole row of cols2 · d numbers is one "point"; refining that sequence
            // of rows is exactly the curve rule applied to every column at once.
            self.level_raw(cols2 * dim, &along_cols, tr, &mut next);
            rows = self.check_size(rows, 1, tr, 1, "levels")?;
            cols = cols2;
            std::mem::swap(&mut current, &mut next);
        }
        debug_assert_eq!(current.len(), total);
        QuadGrid::new(
            rows,
            cols,
            Points::new(dim, current).map_err(Error::from_output)?,
            grid.closed_rows,
            grid.closed_cols,
        )
    }
}

/// The grid as Wavefront OBJ text: one `v x y z` line per point (row-major; points in R^2 get
/// z = 0) and one `f` line per quad (1-based indices, see [`QuadGrid::quads`]). Coordinates are
/// printed in Rust's shortest round-trip form.
///
/// ```
/// use divdiff::Points;
/// use subdivision::{quad_mesh_obj, QuadGrid};
/// let p = Points::from_rows(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 1.0]])?;
/// let grid = QuadGrid::new(2, 2, p, false, false)?;
/// let obj = quad_mesh_obj(&grid)?;
/// assert!(obj.contains("v 1 1 1\n") && obj.contains("f 1 2 4 3\n"));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// # Errors
/// [`Error::Unsupported`] (`points`) for points outside R^2 and R^3.
pub fn quad_mesh_obj(grid: &QuadGrid) -> Result<String, Error> {
    let dim = grid.points.dim();
    if !(2..=3).contains(&dim) {
        return Err(Error::Unsupported {
            field: "points",
            reason: "OBJ output needs points in R^2 or R^3",
        });
    }
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# curvefit tensor-product subdivision surface: {} x {} points",
        grid.rows, grid.cols
    );
    for p in grid.points.iter() {
        let z = if dim == 3 { p[2] } else { 0.0 };
        let _ = writeln!(s, "v {} {} {}", p[0], p[1], z);
    }
    for q in grid.quads() {
        let _ = writeln!(s, "f {} {} {} {}", q[0] + 1, q[1] + 1, q[2] + 1, q[3] + 1);
    }
    Ok(s)
}
