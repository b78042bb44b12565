//! Expands experiment grids into jobs, schedules them over workers, stores and aggregates
//! results.
//!
//! The scheduling logic is [`schedule::Scheduler`], a state machine without IO or clock: events
//! and the current time in, actions out. The transport around it is thin.

pub mod schedule;
