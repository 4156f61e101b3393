//! curvefit: strip (under construction).
