//! Runs floorcast jobs. (Grows with the experiment-grid issue.)
