//! Path planning.
