//! Verification cases for `strip`.
use super::Case;

/// The cases of this area.
pub fn cases() -> Vec<Case> {
    Vec::new()
}
