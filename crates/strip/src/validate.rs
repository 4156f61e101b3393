//! Validation of a [`Problem`]: lengths, finiteness, magnitudes, increasing sites and polylines.

use crate::error::Error;
use crate::types::{Bound, Problem, Side, MAX_MAGNITUDE};

/// Checks the input; every error names the user's field and index.
pub(crate) fn validate(p: &Problem) -> Result<(), Error> {
    let n = p.t.len();
    if n < 2 {
        return Err(Error::TooFewPoints { len: n });
    }
    if p.y.len() != n {
        return Err(Error::LengthMismatch {
            field: "y",
            expected: n,
            found: p.y.len(),
        });
    }
    for (field, v) in [("t", &p.t), ("y", &p.y)] {
        if let Some(index) = v.iter().position(|x| !x.is_finite()) {
            return Err(Error::NonFinite { field, index });
        }
        if let Some(index) = v.iter().position(|x| x.abs() > MAX_MAGNITUDE) {
            return Err(Error::TooLarge {
                field,
                index,
                max: MAX_MAGNITUDE,
            });
        }
    }
    for i in 1..n {
        if p.t[i] <= p.t[i - 1] {
            return Err(Error::NonIncreasingSites { index: i });
        }
    }
    for (k, s) in p.end_slopes.iter().enumerate() {
        if s.is_some_and(|v| !v.is_finite()) {
            return Err(Error::NonFinite {
                field: "end_slopes",
                index: k,
            });
        }
    }
    for (side, b, name) in [
        (Side::Lower, &p.lower, "lower.pieces"),
        (Side::Upper, &p.upper, "upper.pieces"),
    ] {
        match b {
            Bound::None => {}
            Bound::Pieces(c) => {
                if c.len() != n - 1 {
                    return Err(Error::LengthMismatch {
                        field: name,
                        expected: n - 1,
                        found: c.len(),
                    });
                }
                if let Some(index) = c.iter().position(|x| x.iter().any(|v| !v.is_finite())) {
                    return Err(Error::NonFinite { field: name, index });
                }
                if let Some(index) = c
                    .iter()
                    .position(|x| x.iter().any(|v| v.abs() > MAX_MAGNITUDE))
                {
                    return Err(Error::TooLarge {
                        field: name,
                        index,
                        max: MAX_MAGNITUDE,
                    });
                }
            }
            Bound::Polyline(v) => {
                let name = if side == Side::Lower {
                    "lower.polyline"
                } else {
                    "upper.polyline"
                };
                if let Some(index) = v.iter().position(|x| x.iter().any(|c| !c.is_finite())) {
                    return Err(Error::NonFinite { field: name, index });
                }
                if let Some(index) = v
                    .iter()
                    .position(|x| x.iter().any(|c| c.abs() > MAX_MAGNITUDE))
                {
                    return Err(Error::TooLarge {
                        field: name,
                        index,
                        max: MAX_MAGNITUDE,
                    });
                }
                if v.len() < 2 {
                    return Err(Error::PolylineDoesNotCover { side });
                }
                for k in 1..v.len() {
                    if v[k][0] <= v[k - 1][0] {
                        return Err(Error::NonIncreasingPolyline { side, index: k });
                    }
                }
                if v[0][0] > p.t[0] || v[v.len() - 1][0] < p.t[n - 1] {
                    return Err(Error::PolylineDoesNotCover { side });
                }
            }
        }
    }
    Ok(())
}
