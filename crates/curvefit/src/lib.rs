//! curvefit facade.
