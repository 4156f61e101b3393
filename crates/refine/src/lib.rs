//! curvefit: refine (under construction).
