//! What a run achieved, and how two labels' runs compare: the outcome every comparison,
//! sequential test and aggregate of floorcast is built on (`docs/statistics.md`).
//!
//! A comparison is at a **coverage level** (default [`DEFAULT_COVERAGE`]): a run *achieves* the
//! outcome when it ended with at least that fraction of the explorable area explored, and its
//! time is then its exploration time. A run that ended below the level (an early stop, the time
//! limit, stuck, frontiers unreachable, or "complete" on a building it saw too little of) or that
//! failed has not achieved it, and can never make its label look better:
//!
//! - Its order against its partner (the other label's run on the same building, seed and start
//!   pose) is known whenever the partner achieved: a run that stopped will never reach the level
//!   (its time to it is infinite), and one cut off by the time limit would have needed longer
//!   than the limit, which the partner did not. It is a loss. When both did not achieve, the
//!   order is unknown: a tie. This is Gehan's scoring of censored pairs (a comparison counts
//!   only where the data order the two), as in the paired tests of Woolson and Lachenbruch.
//! - In numbers (log ratios, means, intervals, the sequential test), such a run takes the pair's
//!   **horizon**: the larger of the two runs' time limits (and of their end times), the
//!   penalised runtime of algorithm benchmarks (PAR-1). It is never less than the partner's
//!   time, so the run never wins; and when both runs had the same time limit it is the least
//!   time consistent with the data (a run cut off needed more than the limit, one that stopped
//!   would never have got there), so a loss shown is a lower bound on the true one.
//!
//! The outcome of a pair is `x = ln t_ref - ln t` (positive: the label is faster), computed as a
//! difference of logarithms so that swapping the two labels negates it exactly.

use std::collections::BTreeMap;

pub use crate::measure::{coverage_text, Measure};
use floorcast_worker::RunSummary;
use sim_core::explore::EndReason;

use crate::StoredResult;

/// The default coverage level: a run achieves the outcome with at least 99 % of the explorable
/// area explored at its end.
pub const DEFAULT_COVERAGE: f64 = 0.99;

/// The time limit assumed for a run whose settings hold none usable (floorcast's default).
const DEFAULT_TIME_LIMIT_S: f64 = 14_400.0;

/// Checks a coverage level (a grid's `coverage`, `report --coverage`): a fraction in (0, 1].
pub fn check_coverage(coverage: f64) -> Result<(), String> {
    if coverage.is_finite() && coverage > 0.0 && coverage <= 1.0 {
        Ok(())
    } else {
        Err(format!(
            "{coverage} is not a coverage level (expected a fraction of the explorable area, more than 0 and at most 1, e.g. 0.99)"
        ))
    }
}

/// Explored fractions closer than this (0.5 percentage points) count as the same when both runs
/// of a pair fell short of the coverage level ([`Pair::charged_s`]).
pub const SAME_FRACTION: f64 = 0.005;

/// The end classes in the order tables list them (`sim_core`'s [`EndReason`] names).
pub fn end_classes() -> [&'static str; 5] {
    EndReason::ALL.map(EndReason::as_str)
}

/// The end class of a stored summary (the "no frontiers" of summaries written before the
/// classes existed reads as "complete": [`RunSummary`]'s reading).
pub fn end_class(s: &RunSummary) -> &'static str {
    s.end_reason.as_str()
}

/// The labels of `labels` then those of `results` not among them, in the order they appear.
pub fn label_order(results: &[StoredResult], labels: &[String]) -> Vec<String> {
    let mut order: Vec<String> = labels.to_vec();
    for r in results {
        if !order.contains(&r.label) {
            order.push(r.label.clone());
        }
    }
    order
}

/// What one stored run achieved at a coverage level.
#[derive(Debug, Clone, PartialEq)]
pub struct RunOutcome {
    /// Its building as the comparison names it (its name, or its content hash).
    pub building: String,
    pub seed: u64,
    /// The start pose's bits (from the summary; unknown for a failed job).
    pub start: Option<[u64; 3]>,
    /// The exploration time if the run reached the coverage level, else `None`.
    pub achieved_s: Option<f64>,
    /// Why not, if not: the end class ("early stop", "time limit", ...), or "failed".
    pub not_achieved: Option<String>,
    /// The explored fraction at its end (`None` for a failed job).
    pub explored_fraction: Option<f64>,
    /// The run's time limit, or its end time if later: the least time it may be charged.
    pub horizon_s: f64,
    /// Its end time (its exploration time), if it has one.
    pub end_s: Option<f64>,
    /// A run that did not achieve the outcome: its progress curve `(time_s, explored_fraction)`,
    /// to find when it reached a lower fraction (a pair where both fell short); `None` without
    /// one.
    pub curve: Option<std::sync::Arc<[(f64, f64)]>>,
}

impl RunOutcome {
    /// The first time the run had `fraction` explored: from its curve, else its end time if it
    /// ended with at least that much; `None` if it never had.
    pub fn time_to(&self, fraction: f64) -> Option<f64> {
        let f = self.explored_fraction?;
        if f + 1e-12 < fraction {
            return None;
        }
        self.curve
            .as_deref()
            .and_then(|c| c.iter().find(|(_, x)| *x + 1e-12 >= fraction).map(|p| p.0))
            .filter(|t| *t > 0.0)
            .or(self.end_s)
    }
}

/// Whether a run with summary `s` achieved the outcome: at least `coverage` explored, with an
/// exploration time.
pub fn achieves(s: &RunSummary, coverage: f64) -> bool {
    let t = s.exploration_time_s;
    s.explored_fraction >= coverage && t.is_finite() && t > 0.0
}

/// The outcome of `r` at `coverage`, its building named by `building` (time to the end).
pub fn outcome_of(r: &StoredResult, coverage: f64, building: &str) -> RunOutcome {
    outcome_by(r, coverage, building, Measure::End)
}

/// The outcome of `r` at `coverage` by `measure`. With [`Measure::Coverage`] a run that
/// achieved the outcome is timed by the first sample of its progress curve at the coverage
/// level (its end time when it stored no curve).
pub fn outcome_by(r: &StoredResult, coverage: f64, building: &str, measure: Measure) -> RunOutcome {
    let summary = r.summary.as_ref().filter(|_| r.status.is_ok());
    let usable = |t: &f64| t.is_finite() && *t > 0.0;
    let limit = summary
        .map(|s| s.settings.time_limit_s)
        .filter(usable)
        .or(Some(r.settings.time_limit_s).filter(usable))
        .unwrap_or(DEFAULT_TIME_LIMIT_S);
    let mut out = RunOutcome {
        building: building.to_string(),
        seed: r.seed,
        start: None,
        achieved_s: None,
        not_achieved: Some("failed".into()),
        explored_fraction: None,
        horizon_s: limit,
        end_s: None,
        curve: None,
    };
    if let Some(s) = summary {
        let t = s.exploration_time_s;
        out.start = Some(s.start.map(f64::to_bits));
        out.explored_fraction = Some(s.explored_fraction).filter(|f| f.is_finite());
        if t.is_finite() && t > 0.0 {
            out.horizon_s = limit.max(t);
            out.end_s = Some(t);
        }
        if achieves(s, coverage) {
            let at = match measure {
                Measure::End => None,
                Measure::Coverage => r
                    .progress
                    .as_deref()
                    .and_then(|p| crate::metric::time_to_fraction(p, coverage))
                    .filter(|x| x.is_finite() && *x > 0.0),
            };
            out.achieved_s = Some(at.unwrap_or(t).min(t));
            out.not_achieved = None;
        } else {
            out.not_achieved = Some(end_class(s).to_string());
            out.curve = r.progress.as_deref().map(|p| {
                p.iter()
                    .map(|x| (x.time_s, x.explored_fraction))
                    .collect::<Vec<_>>()
                    .into()
            });
        }
    }
    out
}

/// One pair: the label's run and the reference's.
#[derive(Debug, Clone, PartialEq)]
pub struct Pair {
    pub label: RunOutcome,
    pub reference: RunOutcome,
}

impl Pair {
    /// The pair's horizon: the larger of the two runs' horizons.
    pub fn horizon_s(&self) -> f64 {
        self.label.horizon_s.max(self.reference.horizon_s)
    }

    /// The times the comparison charges, `(reference, label)`: a run's time if it achieved the
    /// outcome, else the pair's horizon; when neither did, [`Pair::both_short_s`].
    pub fn charged_s(&self) -> (f64, f64) {
        let h = self.horizon_s();
        match (self.reference.achieved_s, self.label.achieved_s) {
            (None, None) => self.both_short_s(),
            (r, l) => (r.unwrap_or(h), l.unwrap_or(h)),
        }
    }

    /// The times charged when neither run achieved the outcome, `(reference, label)`, scored
    /// by how much each explored, then by time: with explored fractions within
    /// [`SAME_FRACTION`] of each other, each run's time to the lesser of the two fractions
    /// (both reached it); else the run that explored more wins, charged its time to the other's
    /// fraction, and the other the pair's horizon. A failed job (nothing explored) loses to a
    /// run that explored; two failed jobs, or a run without a time, tie (the horizon each).
    pub fn both_short_s(&self) -> (f64, f64) {
        let h = self.horizon_s();
        let (r, l) = (&self.reference, &self.label);
        let (fr, fl) = (
            r.explored_fraction.unwrap_or(0.0),
            l.explored_fraction.unwrap_or(0.0),
        );
        if (fr - fl).abs() <= SAME_FRACTION {
            let least = fr.min(fl);
            match (r.time_to(least), l.time_to(least)) {
                (Some(a), Some(b)) => (a, b),
                _ => (h, h),
            }
        } else if fr > fl {
            (r.time_to(fl).unwrap_or(h), h)
        } else {
            (h, l.time_to(fr).unwrap_or(h))
        }
    }

    /// `ln t_ref - ln t` of the charged times: positive when the label is faster; negative
    /// whenever only the reference achieved the outcome.
    pub fn log_ratio(&self) -> f64 {
        let (r, l) = self.charged_s();
        r.ln() - l.ln()
    }
}

/// The pairs of two labels' runs, and the runs left without a partner.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Pairing {
    pub pairs: Vec<Pair>,
    /// The label's runs without a reference run on the same building, seed and start.
    pub unpaired: usize,
}

/// Pairs `mine` (a label's runs) with `theirs` (the reference's) by building, seed and start
/// pose. A run whose start pose is unknown (a failed job has no summary) pairs when it is the
/// only run of its side on that building and seed and the other side has exactly one there.
/// Pairs come in the order of (building, seed, start).
pub fn pair(mine: Vec<RunOutcome>, theirs: Vec<RunOutcome>) -> Pairing {
    type Group = (Vec<RunOutcome>, Vec<RunOutcome>);
    let mut groups: BTreeMap<(String, u64), Group> = BTreeMap::new();
    for r in mine {
        groups
            .entry((r.building.clone(), r.seed))
            .or_default()
            .0
            .push(r);
    }
    for r in theirs {
        groups
            .entry((r.building.clone(), r.seed))
            .or_default()
            .1
            .push(r);
    }
    let mut out = Pairing::default();
    for (_, (mut a, mut b)) in groups {
        if a.len() == 1 && b.len() == 1 {
            let (x, y) = (a.pop(), b.pop());
            if let (Some(x), Some(y)) = (x, y) {
                if x.start.is_none() || y.start.is_none() || x.start == y.start {
                    out.pairs.push(Pair {
                        label: x,
                        reference: y,
                    });
                } else {
                    out.unpaired += 1;
                }
            }
            continue;
        }
        a.sort_by_key(|r| r.start);
        for x in a {
            let k = x
                .start
                .and_then(|s| b.iter().position(|y| y.start == Some(s)));
            match k {
                Some(k) => {
                    let y = b.swap_remove(k);
                    out.pairs.push(Pair {
                        label: x,
                        reference: y,
                    });
                }
                None => out.unpaired += 1,
            }
        }
    }
    out
}

/// The outcomes of `label`'s runs in `subset` at `coverage`, buildings named by `building`.
pub fn outcomes<'a>(
    subset: impl IntoIterator<Item = &'a StoredResult>,
    label: &str,
    coverage: f64,
    building: impl Fn(&StoredResult) -> String,
) -> Vec<RunOutcome> {
    outcomes_by(subset, label, coverage, building, Measure::End)
}

/// [`outcomes`] by `measure`.
pub fn outcomes_by<'a>(
    subset: impl IntoIterator<Item = &'a StoredResult>,
    label: &str,
    coverage: f64,
    building: impl Fn(&StoredResult) -> String,
    measure: Measure,
) -> Vec<RunOutcome> {
    subset
        .into_iter()
        .filter(|r| r.label == label)
        .map(|r| outcome_by(r, coverage, &building(r), measure))
        .collect()
}

/// The pairs of `label` with `reference` in `subset` at `coverage` (buildings by name).
pub fn paired<'a>(
    subset: impl IntoIterator<Item = &'a StoredResult> + Clone,
    label: &str,
    reference: &str,
    coverage: f64,
) -> Pairing {
    paired_by(subset, label, reference, coverage, Measure::End)
}

/// [`paired`] by `measure`.
pub fn paired_by<'a>(
    subset: impl IntoIterator<Item = &'a StoredResult> + Clone,
    label: &str,
    reference: &str,
    coverage: f64,
    measure: Measure,
) -> Pairing {
    let name = |r: &StoredResult| r.building.clone();
    pair(
        outcomes_by(subset.clone(), label, coverage, name, measure),
        outcomes_by(subset, reference, coverage, name, measure),
    )
}

/// What a comparison says of its pairs besides the numbers: how many achieved the outcome on
/// each side, why the others did not, and how much each side explored.
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize)]
pub struct PairCounts {
    /// Pairs where both runs achieved the outcome.
    pub both_achieved: usize,
    /// Pairs where only the reference did (losses of the label by not achieving it).
    pub label_only_not_achieved: usize,
    /// Pairs where only the label did.
    pub reference_only_not_achieved: usize,
    /// Pairs where neither did (scored by explored fraction, then time: [`Pair::both_short_s`]).
    pub neither_achieved: usize,
    /// The label's paired runs that did not achieve the outcome, by end class ("failed" for
    /// failed jobs).
    pub label_not_achieved: BTreeMap<String, usize>,
    /// The same for the reference.
    pub reference_not_achieved: BTreeMap<String, usize>,
    /// Mean and least explored fraction at the end of the label's paired runs (not failed).
    pub label_coverage_mean: Option<f64>,
    pub label_coverage_min: Option<f64>,
    /// The same for the reference.
    pub reference_coverage_mean: Option<f64>,
    pub reference_coverage_min: Option<f64>,
}

impl PairCounts {
    pub fn of(pairs: &[Pair]) -> PairCounts {
        let mut c = PairCounts::default();
        for p in pairs {
            match (
                p.label.achieved_s.is_some(),
                p.reference.achieved_s.is_some(),
            ) {
                (true, true) => c.both_achieved += 1,
                (false, true) => c.label_only_not_achieved += 1,
                (true, false) => c.reference_only_not_achieved += 1,
                (false, false) => c.neither_achieved += 1,
            }
            if let Some(why) = &p.label.not_achieved {
                *c.label_not_achieved.entry(why.clone()).or_default() += 1;
            }
            if let Some(why) = &p.reference.not_achieved {
                *c.reference_not_achieved.entry(why.clone()).or_default() += 1;
            }
        }
        let stats = |side: &dyn Fn(&Pair) -> Option<f64>| {
            let xs: Vec<f64> = pairs.iter().filter_map(side).collect();
            let mean = (!xs.is_empty()).then(|| xs.iter().sum::<f64>() / xs.len() as f64);
            (mean, xs.into_iter().reduce(f64::min))
        };
        (c.label_coverage_mean, c.label_coverage_min) = stats(&|p| p.label.explored_fraction);
        (c.reference_coverage_mean, c.reference_coverage_min) =
            stats(&|p| p.reference.explored_fraction);
        c
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(building: &str, seed: u64, start: Option<u64>, achieved: Option<f64>) -> RunOutcome {
        RunOutcome {
            building: building.into(),
            seed,
            start: start.map(|s| [s, 0, 0]),
            achieved_s: achieved,
            not_achieved: achieved.is_none().then(|| "early stop".to_string()),
            explored_fraction: Some(if achieved.is_some() { 1.0 } else { 0.3 }),
            horizon_s: 1000.0,
            end_s: Some(achieved.unwrap_or(500.0)),
            curve: None,
        }
    }

    /// Every combination of achieved and not: the charged times, the sign of the outcome, and
    /// its exact negation when the sides swap.
    #[test]
    fn a_run_that_does_not_achieve_never_wins_and_swapping_negates() {
        // (label, reference, expected sign of ln t_ref - ln t)
        let cases: [(Option<f64>, Option<f64>, f64); 5] = [
            (Some(100.0), Some(200.0), 1.0),
            (Some(300.0), Some(200.0), -1.0),
            (None, Some(999.0), -1.0),
            (Some(999.0), None, 1.0),
            (None, None, 0.0),
        ];
        for (l, r, sign) in cases {
            let p = Pair {
                label: run("a", 1, Some(1), l),
                reference: run("a", 1, Some(1), r),
            };
            let x = p.log_ratio();
            assert_eq!(x.signum() * sign.abs(), sign, "{l:?} {r:?}: {x}");
            let swapped = Pair {
                label: p.reference.clone(),
                reference: p.label.clone(),
            };
            assert_eq!(swapped.log_ratio(), -x, "{l:?} {r:?}");
        }
    }

    #[test]
    fn pairs_by_building_seed_and_start_and_failed_jobs_when_unambiguous() {
        let mine = vec![
            run("a", 1, Some(1), Some(10.0)),
            run("a", 2, None, None), // a failed job: start unknown, alone on (a, 2)
            run("a", 3, Some(1), Some(10.0)),
            run("a", 3, Some(2), Some(10.0)),
            run("a", 4, Some(1), Some(10.0)), // no partner
            run("b", 1, Some(5), Some(10.0)), // the partner started elsewhere
        ];
        let theirs = vec![
            run("a", 1, Some(1), Some(20.0)),
            run("a", 2, Some(7), Some(20.0)),
            run("a", 3, Some(2), Some(20.0)),
            run("a", 3, Some(1), Some(20.0)),
            run("b", 1, Some(6), Some(20.0)),
        ];
        let p = pair(mine, theirs);
        assert_eq!(p.pairs.len(), 4);
        assert_eq!(p.unpaired, 2);
        for q in &p.pairs {
            assert!(q.label.start.is_none() || q.label.start == q.reference.start);
        }
        let c = PairCounts::of(&p.pairs);
        assert_eq!(c.both_achieved, 3);
        assert_eq!(c.label_only_not_achieved, 1);
        assert_eq!(c.label_not_achieved["early stop"], 1);
        assert_eq!(c.label_coverage_min, Some(0.3));
        assert_eq!(c.reference_coverage_mean, Some(1.0));
    }

    #[test]
    fn coverage_levels_are_checked() {
        for ok in [0.5, 0.99, 1.0] {
            assert!(check_coverage(ok).is_ok());
        }
        for bad in [0.0, -0.1, 1.01, f64::NAN, f64::INFINITY] {
            assert!(check_coverage(bad).is_err(), "{bad}");
        }
    }
}
