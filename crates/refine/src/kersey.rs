//! Kersey's variational refinement: split, interpolation, balls, smoothing, Algorithm 4.1.
