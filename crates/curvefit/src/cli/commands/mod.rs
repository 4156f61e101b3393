//! One file per subcommand: its [`Command`](super::Command) (the solve is the library's
//! [`crate::spec`] entry point) and its picture.

pub mod natural;
pub mod refine;
pub mod strip;
pub mod surface;

use crate::spec::{InputError, Rows};

/// `--points FILE.csv` into a problem's `points`, which must not be given twice.
fn set_points(points: &mut Rows, csv: super::input::Csv) -> Result<(), InputError> {
    if !points.is_empty() {
        return Err(InputError::new(
            "points",
            "given both in the problem and by --points",
        ));
    }
    *points = Rows(csv.points);
    Ok(())
}
