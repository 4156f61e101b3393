//! Progress of a long solve, told to an observer the caller passes to
//! [`solve_observed`](crate::solve_observed). The library does no I/O: what to do with an event
//! is the caller's (the `curvefit` binary prints one line on standard error when a solve runs
//! past a second and standard error is a terminal).

/// What an observer is told.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum Progress {
    /// An iteration of Newton's method on Φ ([`crate::NEWTON`], the solver for bounds given as
    /// cubic pieces) begins.
    Newton {
        /// The iteration, from 1.
        iteration: usize,
        /// The largest f'' jump at a data site, relative to max|f''| (½‖∇Φ‖∞ / max|f''|): the
        /// iteration stops when it is at its rounding level.
        jump: f64,
        /// Cells solved so far (every evaluation of Φ solves the cell of each data interval).
        cell_solves: usize,
    },
    /// A sweep of the exchange ([`crate::EXCHANGE`], the solver for polyline bounds and the
    /// fallback of Newton on Φ) has checked the curve against the strip.
    Sweep {
        /// The sweep, from 1.
        sweep: usize,
        /// How far the curve still leaves the strip, relative to the value scale (the sweeps
        /// stop below 1e-12).
        excursion: f64,
        /// Active points (contacts with a bound) of the current curve.
        contacts: usize,
    },
}
