//! curvefit: energy (under construction).
