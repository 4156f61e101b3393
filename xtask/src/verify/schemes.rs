//! Verification cases for `schemes`.
use super::Case;

/// The cases of this area.
pub fn cases() -> Vec<Case> {
    Vec::new()
}
