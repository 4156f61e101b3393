//! Progress of a long solve, reported to an observer the caller supplies
//! ([`crate::SolveOptions::progress`]). The library does no I/O: what to do with an event
//! (print a status line, update a bar, ignore it) is the caller's; the `curvefit` binary prints
//! one line on standard error when a solve runs past a second and standard error is a terminal.

use std::sync::Arc;

/// What an observer is told.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum Progress {
    /// A fixed-knot solve of Algorithm 4.1 starts: `stage` 0 is part 1 (the k-level step),
    /// stage l ≥ 1 the l-th further level; `knot_iteration` 0 solves on the initial knots,
    /// i ≥ 1 after the i-th knot update, of `knot_iterations` in all.
    Solve {
        /// The stage (0: the near-interpolatory k-level step).
        stage: usize,
        /// The knot iteration (0: the initial knots).
        knot_iteration: usize,
        /// The knot updates of the stage.
        knot_iterations: usize,
    },
    /// One iteration of an exact strategy's interior-point method ([`crate::SolveOptions`]'s
    /// `conic`): its relative KKT residual ([`conic::Residuals::total`]).
    Iteration {
        /// The strategy running (an entry of the exact solver's list, e.g. "condensed working
        /// set").
        solver: &'static str,
        /// The iteration of this run of the method.
        iteration: usize,
        /// The iterate's relative KKT residual.
        residual: f64,
    },
}

/// A progress observer: called with every [`Progress`] event, on the solving thread. Keep it
/// cheap (it runs once per interior-point iteration).
#[derive(Clone)]
pub struct Observer(Arc<dyn Fn(&Progress) + Send + Sync>);

impl Observer {
    /// An observer calling `f`.
    pub fn new(f: impl Fn(&Progress) + Send + Sync + 'static) -> Self {
        Observer(Arc::new(f))
    }

    /// Reports `event`.
    pub fn report(&self, event: &Progress) {
        (self.0)(event);
    }
}

impl std::fmt::Debug for Observer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Observer(..)")
    }
}

/// Two observers are equal when they are the same closure (options compare by identity here).
impl PartialEq for Observer {
    fn eq(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.0, &other.0)
    }
}

/// Reports `event` to `observer`, if any.
pub(crate) fn report(observer: Option<&Observer>, event: Progress) {
    if let Some(o) = observer {
        o.report(&event);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Mutex;

    /// A balls problem with two knot updates reports each fixed-knot solve in order and the
    /// interior-point iterations between them, with finite residuals.
    #[test]
    fn the_observer_sees_every_solve_and_iteration() {
        let n = 24;
        let q = divdiff::Points::new(
            2,
            (0..n)
                .flat_map(|i| {
                    let t = std::f64::consts::TAU * i as f64 / n as f64;
                    let r = 1.0 + 0.3 * (i % 2) as f64;
                    [r * t.cos(), r * t.sin()]
                })
                .collect(),
        )
        .unwrap();
        let events = Arc::new(Mutex::new(Vec::new()));
        let seen = Arc::clone(&events);
        let problem = crate::Problem::new(q)
            .with_k(3)
            .with_knot_iterations(2)
            .with_constraint(crate::Constraint::Balls(vec![0.05; n]))
            .with_options(
                crate::SolveOptions::default()
                    .with_progress(move |e| seen.lock().unwrap().push(*e)),
            );
        problem.solve().unwrap();
        let events = events.lock().unwrap();
        let solves: Vec<(usize, usize, usize)> = events
            .iter()
            .filter_map(|e| match *e {
                Progress::Solve {
                    stage,
                    knot_iteration,
                    knot_iterations,
                } => Some((stage, knot_iteration, knot_iterations)),
                _ => None,
            })
            .collect();
        assert_eq!(solves, [(0, 0, 2), (0, 1, 2), (0, 2, 2)]);
        let residuals: Vec<f64> = events
            .iter()
            .filter_map(|e| match *e {
                Progress::Iteration { residual, .. } => Some(residual),
                _ => None,
            })
            .collect();
        assert!(!residuals.is_empty());
        assert!(residuals.iter().all(|r| r.is_finite()), "{residuals:?}");
    }
}
