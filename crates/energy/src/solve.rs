//! O(N) solves of (H ⊗ I_d + M) x = b: banded (open) and cyclic (closed).
