//! The progress line of a long solve: once a solve has run for [`QUIET_FOR`], one line on
//! standard error (for `refine` the stage, knot iteration, solver iteration and residual; for
//! `strip` the exchange's sweep, excursion and contacts; the elapsed time), rewritten in place at
//! most every [`EVERY`] and cleared when the solve ends. Only when standard error is a terminal
//! and `--quiet` is not given; the events come from the libraries' observers
//! ([`refine::Progress`], [`strip::Progress`]), the printing is the binary's.

use std::io::Write;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// A solve shorter than this prints nothing.
pub const QUIET_FOR: Duration = Duration::from_secs(1);
/// The line is rewritten at most this often.
pub const EVERY: Duration = Duration::from_millis(100);

#[derive(Default)]
struct State {
    /// (stage, knot iteration, knot iterations) of the current fixed-knot solve.
    solve: Option<(usize, usize, usize)>,
    last: Option<Instant>,
    printed: bool,
}

/// The line of one command's solve.
pub struct Line {
    label: &'static str,
    start: Instant,
    state: Mutex<State>,
}

impl Line {
    /// A line for the subcommand `label`, its clock started now.
    pub fn new(label: &'static str) -> Arc<Line> {
        Arc::new(Line {
            label,
            start: Instant::now(),
            state: Mutex::new(State::default()),
        })
    }

    /// The observer that updates this line.
    pub fn observer(self: &Arc<Self>) -> refine::Observer {
        let line = Arc::clone(self);
        refine::Observer::new(move |e| line.event(e))
    }

    /// The text for `event` (no terminal control characters), given the current solve.
    pub fn text(
        label: &str,
        solve: Option<(usize, usize, usize)>,
        event: &refine::Progress,
        elapsed: Duration,
    ) -> String {
        let mut s = format!("{label}:");
        if let Some((stage, it, of)) = solve {
            s += &format!(" stage {stage}, knot iteration {it}/{of},");
        }
        if let refine::Progress::Iteration {
            solver,
            iteration,
            residual,
        } = event
        {
            s += &format!(" {solver} iteration {iteration}, residual {residual:.1e},");
        }
        s + &format!(" {:.1} s", elapsed.as_secs_f64())
    }

    /// The text for an iteration of `strip`'s Newton method or a sweep of its exchange.
    pub fn strip_text(label: &str, event: &strip::Progress, elapsed: Duration) -> String {
        let mut s = format!("{label}:");
        match *event {
            strip::Progress::Newton {
                iteration,
                jump,
                cell_solves,
            } => {
                s += &format!(
                    " {} iteration {iteration}, f'' jump {jump:.1e} of max|f''|, {cell_solves} cell solves,",
                    strip::NEWTON
                );
            }
            strip::Progress::Sweep {
                sweep,
                excursion,
                contacts,
            } => {
                s += &format!(
                    " {} sweep {sweep}, excursion {excursion:.1e}, {contacts} contacts,",
                    strip::EXCHANGE
                );
            }
            _ => {}
        }
        s + &format!(" {:.1} s", elapsed.as_secs_f64())
    }

    fn event(&self, event: &refine::Progress) {
        self.update(
            |st| {
                if let refine::Progress::Solve {
                    stage,
                    knot_iteration,
                    knot_iterations,
                } = *event
                {
                    st.solve = Some((stage, knot_iteration, knot_iterations));
                }
            },
            |st, elapsed| Self::text(self.label, st.solve, event, elapsed),
        );
    }

    /// Updates the line for an iteration or sweep of `strip`.
    pub fn strip_event(&self, event: &strip::Progress) {
        self.update(
            |_| {},
            |_, elapsed| Self::strip_text(self.label, event, elapsed),
        );
    }

    /// Records an event (`note`) and, once the solve has run for [`QUIET_FOR`] and the line is
    /// at least [`EVERY`] old, rewrites it with `text`.
    fn update(&self, note: impl FnOnce(&mut State), text: impl FnOnce(&State, Duration) -> String) {
        let Ok(mut st) = self.state.lock() else {
            return;
        };
        note(&mut st);
        let now = Instant::now();
        let elapsed = now - self.start;
        if elapsed < QUIET_FOR || st.last.is_some_and(|t| now - t < EVERY) {
            return;
        }
        st.last = Some(now);
        let text = text(&st, elapsed);
        // Carriage return, the text, erase to the end of the line. A failed write to the
        // terminal only loses the line.
        let _ = write!(std::io::stderr().lock(), "\r{text}\x1b[K");
        st.printed = true;
    }

    /// Clears the line, if one was printed.
    pub fn finish(&self) {
        if self.state.lock().is_ok_and(|st| st.printed) {
            let _ = write!(std::io::stderr().lock(), "\r\x1b[K");
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_line_names_stage_iteration_residual_and_time() {
        let e = refine::Progress::Iteration {
            solver: "condensed working set",
            iteration: 12,
            residual: 3.14e-5,
        };
        let t = Line::text("refine", Some((0, 1, 3)), &e, Duration::from_millis(2345));
        assert_eq!(
            t,
            "refine: stage 0, knot iteration 1/3, condensed working set iteration 12, residual 3.1e-5, 2.3 s"
        );
    }

    #[test]
    fn the_strip_line_names_sweep_excursion_contacts_and_time() {
        let e = strip::Progress::Sweep {
            sweep: 7,
            excursion: 2.5e-6,
            contacts: 14_200,
        };
        let t = Line::strip_text("strip", &e, Duration::from_millis(4049));
        assert_eq!(
            t,
            "strip: dual active-set exchange sweep 7, excursion 2.5e-6, 14200 contacts, 4.0 s"
        );
    }

    #[test]
    fn the_strip_line_names_newton_iteration_jump_and_cell_solves() {
        let e = strip::Progress::Newton {
            iteration: 12,
            jump: 3.31e-4,
            cell_solves: 61_000,
        };
        let t = Line::strip_text("strip", &e, Duration::from_millis(1960));
        assert_eq!(
            t,
            "strip: Newton on Φ iteration 12, f'' jump 3.3e-4 of max|f''|, 61000 cell solves, 2.0 s"
        );
    }
}
