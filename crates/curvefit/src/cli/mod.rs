//! The `curvefit` command-line tool: framework shared by every subcommand.
//!
//! Every subcommand reads a JSON problem from a file path or `-` (stdin), writes the JSON result
//! to `-o FILE` (default stdout) and, with `--svg FILE`, a picture. Bad input gives exit code 2,
//! one line on stderr naming the field (and index), and no output file.

use std::fmt::Display;

/// A bad-input error: the field path (e.g. `points[3]`, `constraint.radii[2]`) and what is wrong.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct InputError {
    /// Path of the offending field, with indices.
    pub field: String,
    /// What is wrong with it.
    pub message: String,
}

impl InputError {
    /// A new error for `field`.
    pub fn new(field: impl Into<String>, message: impl Display) -> Self {
        InputError {
            field: field.into(),
            message: message.to_string(),
        }
    }
}

impl Display for InputError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.field.is_empty() {
            write!(f, "{}", self.message)
        } else {
            write!(f, "{}: {}", self.field, self.message)
        }
    }
}

impl std::error::Error for InputError {}

/// One subcommand: a JSON problem in, a JSON solution (and optionally a picture) out.
pub trait Command {
    /// The JSON problem (`#[serde(deny_unknown_fields)]`, documented defaults).
    type Problem: serde::de::DeserializeOwned;
    /// The JSON result.
    type Solution: serde::Serialize;
    /// Validates and solves; errors name the field path and index.
    fn solve(problem: &Self::Problem) -> Result<Self::Solution, InputError>;
    /// The picture for `--svg`, or `None`.
    fn svg(problem: &Self::Problem, solution: &Self::Solution) -> Option<String>;
}
