//! Exact solver for the fixed-knot convex refinement problems (conic constraints on banded stencils).
