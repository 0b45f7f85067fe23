//! Algebraic trajectory functions with exact derivatives (issue 4; being built).
