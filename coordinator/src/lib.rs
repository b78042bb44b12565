//! Expands experiment grids and schedules jobs. (Grows with the experiment-grid issue.)
