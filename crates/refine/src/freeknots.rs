//! Optimal free knots (beyond Kersey §4): minimize E over the knots for fixed total parameter length.
