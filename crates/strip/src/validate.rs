//! Validation of a [`Problem`]: lengths, finiteness, magnitudes, increasing sites and polylines.

use crate::error::{bound_field, Error};
use crate::types::{Bound, Problem, Side, MAX_MAGNITUDE};

/// The first entry of `v` that is not finite, or whose magnitude exceeds [`MAX_MAGNITUDE`].
fn check_numbers(field: &'static str, v: impl Iterator<Item = f64> + Clone) -> Result<(), Error> {
    if let Some(index) = v.clone().position(|x| !x.is_finite()) {
        return Err(Error::NonFinite { field, index });
    }
    if let Some((index, got)) = v.enumerate().find(|(_, x)| x.abs() > MAX_MAGNITUDE) {
        return Err(Error::TooLarge {
            field,
            index,
            limit: MAX_MAGNITUDE,
            got,
        });
    }
    Ok(())
}

/// Checks the input; every error names the user's field and index.
pub(crate) fn validate(p: &Problem) -> Result<(), Error> {
    let n = p.t.len();
    if n < 2 {
        return Err(Error::TooFew {
            field: "t",
            minimum: 2,
            got: n,
        });
    }
    if p.y.len() != n {
        return Err(Error::WrongLength {
            field: "y",
            expected: n,
            got: p.y.len(),
        });
    }
    check_numbers("t", p.t.iter().copied())?;
    check_numbers("y", p.y.iter().copied())?;
    for i in 1..n {
        if p.t[i] <= p.t[i - 1] {
            return Err(Error::NonIncreasing {
                field: "t",
                index: i,
            });
        }
    }
    // entries are indexed as given: [start, end]
    for (k, s) in p.end_slopes.iter().enumerate() {
        if let Some(v) = s {
            if !v.is_finite() {
                return Err(Error::NonFinite {
                    field: "end_slopes",
                    index: k,
                });
            }
            if v.abs() > MAX_MAGNITUDE {
                return Err(Error::TooLarge {
                    field: "end_slopes",
                    index: k,
                    limit: MAX_MAGNITUDE,
                    got: *v,
                });
            }
        }
    }
    for (side, b) in [(Side::Lower, &p.lower), (Side::Upper, &p.upper)] {
        let field = bound_field(b, side);
        match b {
            Bound::None => {}
            Bound::Pieces(c) => {
                if c.len() != n - 1 {
                    return Err(Error::WrongLength {
                        field,
                        expected: n - 1,
                        got: c.len(),
                    });
                }
                for (index, piece) in c.iter().enumerate() {
                    if piece.iter().any(|v| !v.is_finite()) {
                        return Err(Error::NonFinite { field, index });
                    }
                    if let Some(got) = piece.iter().find(|v| v.abs() > MAX_MAGNITUDE) {
                        return Err(Error::TooLarge {
                            field,
                            index,
                            limit: MAX_MAGNITUDE,
                            got: *got,
                        });
                    }
                }
            }
            Bound::Polyline(v) => {
                for (index, q) in v.iter().enumerate() {
                    if q.iter().any(|c| !c.is_finite()) {
                        return Err(Error::NonFinite { field, index });
                    }
                    if let Some(got) = q.iter().find(|c| c.abs() > MAX_MAGNITUDE) {
                        return Err(Error::TooLarge {
                            field,
                            index,
                            limit: MAX_MAGNITUDE,
                            got: *got,
                        });
                    }
                }
                if v.len() < 2 {
                    return Err(Error::TooFew {
                        field,
                        minimum: 2,
                        got: v.len(),
                    });
                }
                for k in 1..v.len() {
                    if v[k][0] <= v[k - 1][0] {
                        return Err(Error::NonIncreasing { field, index: k });
                    }
                }
                if v[0][0] > p.t[0] {
                    return Err(Error::InvalidValue {
                        field,
                        index: 0,
                        reason: "the polyline starts after the first data site (it must cover [t_1, t_n])",
                    });
                }
                if v[v.len() - 1][0] < p.t[n - 1] {
                    return Err(Error::InvalidValue {
                        field,
                        index: v.len() - 1,
                        reason:
                            "the polyline ends before the last data site (it must cover [t_1, t_n])",
                    });
                }
            }
        }
    }
    Ok(())
}
