//! curvefit: divdiff (under construction).
