//! Verification cases for `refine`.
use super::Case;

/// The cases of this area.
pub fn cases() -> Vec<Case> {
    Vec::new()
}
